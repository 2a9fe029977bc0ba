/// \file yeung2016_plots.cpp
/// Draws the analogues of Figs. 4, 5, 7, 10a, 11a and 11b of Yeung, Crouch & Pothen 2016 as SVG
/// files from the CSV files that run_experiments.sh writes (augmented_bench --table … --csv),
/// with the project's own SVG writer (scene/svg_plot.hpp).
///
/// Usage: yeung2016_plots DIR   (reads DIR/<mesh>_<deform|cut>.csv, writes DIR/fig*.svg)
///        yeung2016_plots --table FILE.csv [--update-times FILE2.csv] [--max-m M]
///          prints FILE's per-step Markdown table (update and refactorization + solve in wall
///          and process-CPU time, their ratios) and the range and median of both speed-ups
///          over the steps ≥ 1 with m ≤ M (default 100) — the tables of README.md. FILE2: the
///          same run with --no-exact, whose update times (not disturbed by the reference
///          refactorizations in between) are then used for the speed-ups.
///        yeung2016_plots --summary DIR
///          prints the "All meshes" table (one row per CSV in DIR, steps ≥ 1, CPU times).
///
/// Rates are 1 / process CPU time of one update (resp. one refactorization + solve, one
/// Jacobi-PCG solve): wall time on the shared measurement machine is inflated by other jobs.
/// PCG points are drawn only for solves that reached ‖r‖ ≤ 1e-10‖f‖ within their budget.

#include <incise/certify/svg_plot.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace {

using incise::certify::PlotOptions;
using incise::certify::Series;

struct Table {
  std::string name;  // mesh description from the CSV's first line
  std::string meta;  // the whole first line (mesh, kind, sizes, solver settings)
  double nodes = 0;
  std::map<std::string, std::vector<double>> col;
  bool ok = false;
  const std::vector<double>& operator[](const std::string& c) const {
    static const std::vector<double> empty;
    auto it = col.find(c);
    return it == col.end() ? empty : it->second;
  }
  size_t rows() const { return (*this)["step"].size(); }
};

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(item);
  return out;
}

Table read_table(const std::string& path) {
  Table t;
  std::ifstream in(path);
  if (!in) return t;
  std::string line;
  if (!std::getline(in, line) || line.size() < 2 || line[0] != '#') return t;
  t.meta = line.substr(2);
  const std::vector<std::string> meta = split(line.substr(2));
  if (meta.size() >= 3) {
    t.name = meta[0];
    t.nodes = std::stod(meta[2]);
  }
  if (!std::getline(in, line)) return t;
  const std::vector<std::string> header = split(line);
  while (std::getline(in, line)) {
    const std::vector<std::string> v = split(line);
    if (v.size() != header.size()) continue;
    for (size_t i = 0; i < v.size(); ++i) t.col[header[i]].push_back(std::stod(v[i]));
  }
  t.ok = t.rows() > 0;
  return t;
}

/// y = 1/column over the steps (rates in Hz); entries ≤ 0 (not measured) are skipped.
Series rate_series(const Table& t, const std::string& column, const std::string& label,
                   bool only_converged_pcg = false) {
  Series s;
  s.label = label;
  const auto& step = t["step"];
  const auto& v = t[column];
  const auto& conv = t["pcg_converged"];
  for (size_t i = 0; i < step.size() && i < v.size(); ++i) {
    if (!(v[i] > 0)) continue;
    if (only_converged_pcg && (i >= conv.size() || conv[i] < 0.5)) continue;
    s.x.push_back(step[i]);
    s.y.push_back(1.0 / v[i]);
  }
  return s;
}

Series column_series(const Table& t, const std::string& column, const std::string& label,
                     size_t first_row = 0) {
  Series s;
  s.label = label;
  const auto& step = t["step"];
  const auto& v = t[column];
  for (size_t i = first_row; i < step.size() && i < v.size(); ++i) {
    s.x.push_back(step[i]);
    s.y.push_back(v[i]);
  }
  return s;
}

void write_svg(const std::string& path, const std::vector<Series>& series,
               const PlotOptions& options) {
  std::ofstream out(path);
  out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << incise::certify::svg_line_plot(series, options) << "\n";
  std::printf("wrote %s\n", path.c_str());
}

/// Rates of one experiment: augmented update, refactorization + solve (with analysis; and
/// numeric only when the pattern is kept), Jacobi-PCG.
void rate_figure(const std::string& dir, const std::string& file, const Table& t,
                 const std::string& title, const std::string& x_label,
                 const Table* direct = nullptr) {
  if (!t.ok) return;
  std::vector<Series> s;
  s.push_back(rate_series(t, "cpu_update", "augmented update (GMRES, HSJ)"));
  if (direct != nullptr && direct->ok && direct->name == t.name)
    s.push_back(rate_series(*direct, "cpu_update", "augmented update (GMRES, explicit H R^-1 J)"));
  s.push_back(rate_series(t, "cpu_refactor", "CHOLMOD analyze + factorize + solve"));
  Series num = rate_series(t, "cpu_numeric_refactor", "CHOLMOD factorize + solve (pattern kept)");
  if (!num.x.empty()) {
    num.dashed = true;
    s.push_back(num);
  }
  s.push_back(rate_series(t, "cpu_pcg", "Jacobi-PCG to 1e-10 (converged solves)", true));
  PlotOptions o;
  o.title = title + " — " + t.name + " (" + std::to_string(static_cast<long>(t.nodes)) + " nodes)";
  o.x_label = x_label;
  o.y_label = "update rate (Hz, 1/CPU time)";
  o.log_y = true;
  o.width = 640;
  o.height = 360;
  write_svg(dir + "/" + file, s, o);
}

}  // namespace

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t k = v.size() / 2;
  return v.size() % 2 == 1 ? v[k] : 0.5 * (v[k - 1] + v[k]);
}

// `timing` (optional, may equal `t`): a run of the same steps without the reference
// refactorizations in between (augmented_bench --no-exact), whose update times are used for
// the speed-ups: a 0.2 s factorization between two updates evicts the caches and the TLB and
// adds 0.3–1 ms to the next update (measured), which is the reference's cost, not the update's.
int print_table(const std::string& path, const std::string& timing_path, int max_m) {
  const Table t = read_table(path);
  const Table u = timing_path.empty() ? t : read_table(timing_path);
  if (!t.ok || !u.ok) {
    std::fprintf(stderr, "%s: no rows (expected the CSV of augmented_bench --table ... --csv)\n",
                 (!t.ok ? path : timing_path).c_str());
    return 1;
  }
  const bool separate = !timing_path.empty();
  for (size_t i = 0; separate && i < t.rows(); ++i) {
    if (i >= u.rows() || u["step"][i] != t["step"][i] || u["m"][i] != t["m"][i] ||
        u["n"][i] != t["n"][i]) {
      std::fprintf(stderr, "%s and %s do not describe the same steps (row %zu)\n", path.c_str(),
                   timing_path.c_str(), i);
      return 1;
    }
  }
  std::printf("`%s`: %s\n", path.c_str(), t.meta.c_str());
  if (separate) std::printf("update times from `%s`: %s\n", timing_path.c_str(), u.meta.c_str());
  // Numeric-only refactorization (deformation: pattern kept, analysis reused), wall and CPU;
  // absent (−1) for cuts and in CSVs written before its wall time was recorded.
  const auto& num_wall = t["t_numeric_refactor"];
  const auto& num_cpu = t["cpu_numeric_refactor"];
  std::printf(
      "\n| step | n | m | GMRES it | update ms wall / CPU | rate Hz (wall) |%s refactor + solve "
      "ms wall / CPU | speed-up wall / CPU | numeric refactor + solve ms wall / CPU | speed-up "
      "numeric wall / CPU | rel. error | backward error | ok |\n"
      "|---|---|---|---|---|---|%s---|---|---|---|---|---|---|\n",
      separate ? " update ms wall, between refactorizations |" : "", separate ? "---|" : "");
  std::vector<double> sw, sc, nw, nc;
  for (size_t i = 0; i < t.rows(); ++i) {
    const double tu = u["t_update"][i], cu = u["cpu_update"][i];
    const double tr = t["t_refactor"][i], cr = t["cpu_refactor"][i];
    const double ncpu = i < num_cpu.size() ? num_cpu[i] : -1;
    const double nwall = i < num_wall.size() ? num_wall[i] : -1;
    char numtxt[48] = "-", numsp[48] = "-", inter[48] = "";
    if (ncpu > 0) {
      if (nwall > 0) {
        std::snprintf(numtxt, sizeof numtxt, "%.1f / %.1f", 1e3 * nwall, 1e3 * ncpu);
        std::snprintf(numsp, sizeof numsp, "%.1f / %.1f", tu > 0 ? nwall / tu : 0.0,
                      cu > 0 ? ncpu / cu : 0.0);
      } else {
        std::snprintf(numtxt, sizeof numtxt, "- / %.1f", 1e3 * ncpu);
        std::snprintf(numsp, sizeof numsp, "- / %.1f", cu > 0 ? ncpu / cu : 0.0);
      }
    }
    if (separate) std::snprintf(inter, sizeof inter, " %.2f |", 1e3 * t["t_update"][i]);
    std::printf(
        "| %d | %d | %d | %d | %.2f / %.2f | %.0f |%s %.1f / %.1f | %.1f / %.1f | %s | %s | %.1e | "
        "%.1e | %s |\n",
        static_cast<int>(t["step"][i]), static_cast<int>(t["n"][i]), static_cast<int>(t["m"][i]),
        static_cast<int>(t["gmres_it"][i]), 1e3 * tu, 1e3 * cu, tu > 0 ? 1 / tu : 0.0, inter,
        1e3 * tr, 1e3 * cr, tu > 0 ? tr / tu : 0.0, cu > 0 ? cr / cu : 0.0, numtxt, numsp,
        t["rel_error"][i], t["backward_error"][i], t["ok"][i] > 0 ? "ok" : "FAIL");
    if (t["step"][i] >= 1 && t["m"][i] <= max_m && tu > 0 && cu > 0) {
      sw.push_back(tr / tu);
      sc.push_back(cr / cu);
      if (ncpu > 0 && nwall > 0) {
        nw.push_back(nwall / tu);
        nc.push_back(ncpu / cu);
      }
    }
  }
  auto range = [](const std::vector<double>& v) {
    char b[80];
    std::snprintf(b, sizeof b, "%.1f–%.1f (median %.1f)", *std::min_element(v.begin(), v.end()),
                  *std::max_element(v.begin(), v.end()), median(v));
    return std::string(b);
  };
  if (!sw.empty()) {
    std::printf(
        "\nSteps ≥ 1 with m ≤ %d (%zu): speed-up over refactorization + solve, wall %s, CPU %s.\n",
        max_m, sw.size(), range(sw).c_str(), range(sc).c_str());
  }
  if (!nw.empty()) {
    std::printf("Over the numeric-only refactorization + solve (pattern kept): wall %s, CPU %s.\n",
                range(nw).c_str(), range(nc).c_str());
  }
  return 0;
}

// The "All meshes" table of README.md: one row per CSV of run_experiments.sh that exists in
// `dir`, over all steps ≥ 1 (all m), CPU times; refactorization = analysis + factorization +
// solve. Explicit-matrix runs (direct_ prefix) follow the GMRES + HSJ row of the same mesh.
int print_summary(const std::string& dir) {
  std::vector<std::string> names;
  auto add = [&](const std::string& n) {
    names.push_back(n);
    names.push_back("direct_" + n);
  };
  for (const char* kind : {"deform", "cut"})
    for (int h : {16, 64, 256, 1024}) add("beam" + std::to_string(h) + "_" + kind);
  for (const char* kind : {"deform", "cut"})
    for (int b : {4, 8, 12, 16, 20}) add("brick" + std::to_string(b) + "_" + kind);
  add("liver_deform");
  add("liver_cut");
  std::printf(
      "| mesh | experiment | eq. 17 | nodes | n₀ | |L| (M) | max m | max GMRES it | max clos Ja2 "
      "| update CPU ms min–max | refactor CPU ms (median) | speed-up min–max | Jacobi-PCG CPU "
      "ms (converged/run) | max rel. error | max backward error |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  int printed = 0;
  for (const std::string& name : names) {
    const Table t = read_table(dir + "/" + name + ".csv");
    if (!t.ok) continue;
    const std::vector<std::string> meta = split(t.meta);
    auto field = [&](size_t i) { return i < meta.size() ? meta[i] : std::string("?"); };
    double max_m = 0, max_it = 0, max_clos = 0, max_err = 0, max_bw = 0;
    double upd_lo = 1e300, upd_hi = 0, sp_lo = 1e300, sp_hi = 0, pcg_lo = 1e300, pcg_hi = 0;
    int pcg_runs = 0, pcg_conv = 0;
    std::vector<double> refactor;
    for (size_t i = 0; i < t.rows(); ++i) {
      if (t["step"][i] < 1) continue;
      max_m = std::max(max_m, t["m"][i]);
      max_it = std::max(max_it, t["gmres_it"][i]);
      max_clos = std::max(max_clos, t["closure_ja2"][i]);
      max_err = std::max(max_err, t["rel_error"][i]);
      max_bw = std::max(max_bw, t["backward_error"][i]);
      const double cu = t["cpu_update"][i], cr = t["cpu_refactor"][i];
      upd_lo = std::min(upd_lo, cu);
      upd_hi = std::max(upd_hi, cu);
      if (cr > 0 && cu > 0) {
        refactor.push_back(cr);
        sp_lo = std::min(sp_lo, cr / cu);
        sp_hi = std::max(sp_hi, cr / cu);
      }
    }
    for (size_t i = 0; i < t.rows(); ++i) {
      if (t["step"][i] < 1 || !(t["cpu_pcg"][i] > 0)) continue;
      ++pcg_runs;
      pcg_conv += t["pcg_converged"][i] > 0.5 ? 1 : 0;
      pcg_lo = std::min(pcg_lo, t["cpu_pcg"][i]);
      pcg_hi = std::max(pcg_hi, t["cpu_pcg"][i]);
    }
    char pcg[64] = "-", sp[48] = "-", ref[32] = "-";
    if (pcg_runs > 0)
      std::snprintf(pcg, sizeof pcg, "%.0f–%.0f (%d/%d)", 1e3 * pcg_lo, 1e3 * pcg_hi, pcg_conv,
                    pcg_runs);
    if (!refactor.empty()) {
      std::snprintf(sp, sizeof sp, "%.0f–%.0f", sp_lo, sp_hi);
      std::snprintf(ref, sizeof ref, "%.0f", 1e3 * median(refactor));
    }
    std::printf(
        "| %s | %s | %s | %s | %s | %.2f | %.0f | %.0f | %.0f | %.2f–%.2f | %s | %s | %s | %.1e | "
        "%.1e |\n",
        field(0).c_str(), field(1).c_str(),
        name.rfind("direct_", 0) == 0 ? "explicit H R⁻¹ J" : "GMRES + HSJ", field(2).c_str(),
        field(4).c_str(), std::stod(field(5)) / 1e6, max_m, max_it, max_clos, 1e3 * upd_lo,
        1e3 * upd_hi, ref, sp, pcg, max_err, max_bw);
    ++printed;
  }
  if (printed == 0) {
    std::fprintf(stderr, "%s: no CSV files of run_experiments.sh\n", dir.c_str());
    return 1;
  }
  return 0;
}

int main(int argc, char** argv) {
  if (argc == 3 && std::string(argv[1]) == "--summary") return print_summary(argv[2]);
  if (argc >= 3 && std::string(argv[1]) == "--table") {
    std::string timing;
    int max_m = 100;
    for (int i = 3; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--update-times" && i + 1 < argc) {
        timing = argv[++i];
      } else if (a == "--max-m" && i + 1 < argc) {
        max_m = std::stoi(argv[++i]);
      } else {
        std::fprintf(stderr, "unknown option %s\n", a.c_str());
        return 2;
      }
    }
    return print_table(argv[2], timing, max_m);
  }
  if (argc != 2) {
    std::fprintf(stderr,
                 "usage: %s DIR (with the CSV files of run_experiments.sh)\n"
                 "       %s --table FILE.csv [--update-times FILE2.csv] [--max-m M]\n"
                 "       %s --summary DIR\n",
                 argv[0], argv[0], argv[0]);
    return 2;
  }
  const std::string dir = argv[1];
  auto load = [&](const std::string& n) { return read_table(dir + "/" + n + ".csv"); };
  const std::vector<int> beams = {16, 64, 256, 1024};
  const std::vector<int> bricks = {4, 8, 12, 16, 20};
  std::map<std::string, Table> tab;
  for (int h : beams)
    for (const char* k : {"deform", "cut"})
      tab["beam" + std::to_string(h) + "_" + k] = load("beam" + std::to_string(h) + "_" + k);
  for (int n : bricks)
    for (const char* k : {"deform", "cut"})
      tab["brick" + std::to_string(n) + "_" + k] = load("brick" + std::to_string(n) + "_" + k);
  tab["liver_deform"] = load("liver_deform");
  tab["liver_cut"] = load("liver_cut");
  // SchurSolver::kDirectCached runs (run_experiments.sh, "direct_" prefix).
  for (const char* n : {"beam1024_deform", "beam1024_cut", "brick16_deform", "brick16_cut",
                        "liver_deform", "liver_cut"})
    tab[std::string("direct_") + n] = load(std::string("direct_") + n);
  auto largest = [&](const std::string& prefix, const std::vector<int>& sizes,
                     const std::string& kind) -> const Table& {
    for (auto it = sizes.rbegin(); it != sizes.rend(); ++it) {
      const Table& t = tab[prefix + std::to_string(*it) + "_" + kind];
      if (t.ok) return t;
    }
    return tab[prefix + std::to_string(sizes.front()) + "_" + kind];
  };
  // The paper's Fig. 5b / 7b use the 9,537-node brick (n = 16).
  auto brick_fig = [&](const std::string& kind) -> const Table& {
    const Table& t = tab["brick16_" + kind];
    return t.ok ? t : largest("brick", bricks, kind);
  };

  // Fig. 4: |closure_L(J a₂)| during the cutting experiments.
  {
    std::vector<Series> s;
    for (const Table* t :
         std::vector<const Table*>{&largest("beam", beams, "cut"), &brick_fig("cut"),
                                   &largest("brick", bricks, "cut"), &tab["liver_cut"]}) {
      if (!t->ok) continue;
      bool dup = false;
      for (const auto& e : s) dup = dup || e.label == t->name;
      if (!dup) s.push_back(column_series(*t, "closure_ja2", t->name, 1));
    }
    PlotOptions o;
    o.title = "Fig. 4 analogue: |closure_L(J a2)| while cutting";
    o.x_label = "cut step (duplicated nodes)";
    o.y_label = "positions of L";
    o.log_y = true;
    o.width = 640;
    o.height = 360;
    write_svg(dir + "/fig4_closures.svg", s, o);
  }
  // Fig. 5: deformation rates; Fig. 7: cutting rates; Fig. 10a analogue: the liver.
  // The explicit-matrix runs are drawn where they are of the same mesh (rate_figure checks).
  rate_figure(dir, "fig5a_beam_deform.svg", largest("beam", beams, "deform"),
              "Fig. 5a analogue: deformation", "constrained nodes", &tab["direct_beam1024_deform"]);
  rate_figure(dir, "fig5b_brick_deform.svg", brick_fig("deform"), "Fig. 5b analogue: deformation",
              "constrained nodes", &tab["direct_brick16_deform"]);
  rate_figure(dir, "fig7a_beam_cut.svg", largest("beam", beams, "cut"), "Fig. 7a analogue: cutting",
              "cut step (duplicated nodes)", &tab["direct_beam1024_cut"]);
  rate_figure(dir, "fig7b_brick_cut.svg", brick_fig("cut"), "Fig. 7b analogue: cutting",
              "cut step (duplicated nodes)", &tab["direct_brick16_cut"]);
  rate_figure(dir, "fig10a_liver_cut.svg", tab["liver_cut"], "Fig. 10a analogue: cutting",
              "cut step (duplicated nodes)", &tab["direct_liver_cut"]);
  rate_figure(dir, "fig10_liver_deform.svg", tab["liver_deform"], "liver deformation",
              "constrained nodes", &tab["direct_liver_deform"]);
  // Fig. 11a: maximum GMRES iterations over the 16 steps vs mesh size.
  {
    std::vector<Series> s;
    for (const char* kind : {"deform", "cut"}) {
      for (int pass = 0; pass < 2; ++pass) {
        Series e;
        e.label = std::string(pass == 0 ? "beams, " : "bricks, ") + kind;
        e.dashed = pass == 1;
        const std::vector<int>& sizes = pass == 0 ? beams : bricks;
        for (int z : sizes) {
          const Table& t =
              tab[std::string(pass == 0 ? "beam" : "brick") + std::to_string(z) + "_" + kind];
          if (!t.ok) continue;
          const auto& it = t["gmres_it"];
          const auto& st = t["step"];
          double mx = 0;
          for (size_t i = 0; i < it.size(); ++i)
            if (st[i] <= 16) mx = std::max(mx, it[i]);
          e.x.push_back(t.nodes);
          e.y.push_back(mx);
        }
        s.push_back(e);
      }
    }
    PlotOptions o;
    o.title = "Fig. 11a analogue: max GMRES iterations (16 steps)";
    o.x_label = "nodes";
    o.y_label = "GMRES iterations";
    o.log_x = true;
    o.width = 640;
    o.height = 360;
    write_svg(dir + "/fig11a_gmres.svg", s, o);
  }
  // Fig. 11b: accuracy vs cut depth.
  {
    std::vector<Series> s;
    for (const Table* t : std::vector<const Table*>{&largest("beam", beams, "cut"),
                                                    &brick_fig("cut"), &tab["liver_cut"]}) {
      if (!t->ok) continue;
      s.push_back(column_series(*t, "backward_error", t->name + ": backward error", 1));
      Series r = column_series(*t, "rel_error", t->name + ": rel. difference to refactored", 1);
      r.dashed = true;
      s.push_back(r);
    }
    PlotOptions o;
    o.title = "Fig. 11b analogue: accuracy while cutting";
    o.x_label = "cut step (duplicated nodes)";
    o.y_label = "relative error";
    o.log_y = true;
    o.width = 640;
    o.height = 360;
    write_svg(dir + "/fig11b_error.svg", s, o);
  }
  return 0;
}
