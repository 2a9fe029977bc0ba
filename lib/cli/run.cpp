// `incise run SCENE [--summary-json PATH] [--progress auto|bar|lines|none] [--memory-mb N] ...`:
// parse and build a scene (docs/scenes.md), run its solver with progress (stderr), print a
// summary (stdout: iterations, flops, time, final residual, probes, what was built and what it
// cost), write the scene's outputs. Exit 0 converged, 1 bad scene or file, 2 usage, 3 no
// converged solution (cli_util.hpp Exit).
//
// Nothing is written before the scene has been parsed and built completely; the library writes
// the outputs (scene/scene_outputs.hpp), this file prints.

#include <incise/certify/frame_plot.hpp>
#include <incise/core/atomic_file.hpp>
#include <incise/core/error.hpp>
#include <incise/core/timer.hpp>
#include <incise/scene/delaunay_scene.hpp>
#include <incise/scene/scene_outputs.hpp>
#include <incise/scene/scene_parser.hpp>
#include <incise/scene/scene_runner.hpp>
#include <incise/scene/solution_file.hpp>

#include <CLI/CLI.hpp>

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <sstream>

#include "cli_util.hpp"
#include "commands.hpp"

namespace incise::cli {

// run_delaunay.cpp: a Delaunay cutting scene (scene/delaunay_scene.hpp).
int run_delaunay_scene_command(const std::string& scene_path, const std::string& summary_json,
                               const std::string& progress, const std::string& csv,
                               std::ostream& out, std::ostream& err);

namespace {

std::string join_vec(const Vec3& v) {
  std::ostringstream os;
  if (!v.allFinite()) return "[not finite]";
  os << std::setprecision(6) << "[" << v[0] << ", " << v[1] << ", " << v[2] << "]";
  return os.str();
}

/// A result number as printed: the value, or "not finite" (no NaN or inf is printed).
std::string num(double v) {
  if (!std::isfinite(v)) return "not finite";
  std::ostringstream os;
  os << v;
  return os.str();
}

/// The residual, energy, inversion, flops and time lines of a relaxation or cutting run.
void print_residual_summary(std::ostream& out, const scene::SceneSpec& spec,
                            const scene::BuiltScene& built, const scene::SceneRunResult& res) {
  const auto& rep = res.report;
  const double fnorm = res.external_force_norm;
  if (!rep.message.empty()) out << "message:         " << rep.message << "\n";
  out << "final residual:  ||r|| = " << num(rep.residual_norm)
      << " N, ||r||/||f_ext|| = " << num(std::isfinite(fnorm) ? rep.residual_norm / fnorm : fnorm)
      << " (tolerance " << spec.solver.tolerance << ", ||f_ext|| = " << num(fnorm)
      << " N, the 2-norm of the nodal load vector)\n";
  out << "energy:          " << num(rep.energy) << " J\n";
  if (res.inverted_elements >= 0)
    out << "inverted:        " << res.inverted_elements << " of " << built.problem->num_elements()
        << " elements (det F <= 0)"
        << (spec.material.allow_inversion ? ", allowed by the scene (material.allow_inversion)"
                                          : "")
        << "\n";
  if (res.cut_steps.empty())
    out << "flops:           " << static_cast<double>(rep.flops) / 1e6 << " MFLOP (counted)\n";
  else
    out << "flops:           not counted (CHOLMOD and the augmented updates are timed)\n";
  if (!res.cut_steps.empty()) {
    const scene::FrameTimes t = scene::frame_times(res);
    out << "frame time:      median " << 1e3 * t.frame.median << " ms, p95 " << 1e3 * t.frame.p95
        << " ms, max " << 1e3 * t.frame.max << " ms over " << t.frame.count
        << " solves (cut median " << 1e3 * t.cut.median << " ms, update median "
        << 1e3 * t.update.median << " ms, swap max " << 1e3 * t.swap.max << " ms)\n";
  }
  out << "solver time:     " << rep.seconds << " s";
  if (rep.seconds > 0 && rep.flops > 0)
    out << " (" << static_cast<double>(rep.flops) / rep.seconds / 1e6 << " MFLOP/s)";
  out << "\n";
  out << "solver CPU:      " << rep.cpu_seconds << " s (process, all threads)\n";
  if (res.has_reference)
    out << "energy error:    ||u - u_ref||_K / ||u_ref||_K = " << num(res.relative_energy_error)
        << " (K at u_ref)\n";
}

struct RunOptions {
  std::string scene_path, summary_json, progress = "auto", write_solution, reference, csv;
  std::string memory_mb, max_iterations;  // empty: the scene's
};

/// `value` as an integer in [lo, hi]; CommandLineError naming the option otherwise.
std::int64_t integer_option(const std::string& value, const char* name, std::int64_t lo,
                            std::int64_t hi) {
  char* end = nullptr;
  errno = 0;
  const std::int64_t v = std::strtoll(value.c_str(), &end, 10);
  if (value.empty() || *end != '\0' || errno == ERANGE || v < lo || v > hi)
    throw CommandLineError(std::string(name) + " expects an integer in [" + std::to_string(lo) +
                           ", " + std::to_string(hi) + "], got '" + value + "'");
  return v;
}

int run_scene(RunOptions& opt, Context& ctx) {
  reject_extras(ctx.extras, "run", [&](const std::string& a) {
    return "expected one scene file, got '" + opt.scene_path + "' and '" + a + "'";
  });
  std::ostream& out = ctx.out;
  std::ostream& err = ctx.log.error();
  std::ostream& progress_out = ctx.log.info();
  const bool verbose = ctx.log.verbosity() == Verbosity::kVerbose;
  const std::string& scene_path = opt.scene_path;
  const std::string& summary_json = opt.summary_json;
  const std::string& write_solution = opt.write_solution;
  const std::string& reference = opt.reference;
  std::string progress = opt.progress;
  if (progress != "auto" && progress != "bar" && progress != "lines" && progress != "none")
    throw CommandLineError("--progress expects auto, bar, lines or none, got '" + progress + "'");
  const std::int64_t memory_mb =
      opt.memory_mb.empty()
          ? 0
          : integer_option(opt.memory_mb, "--memory-mb", 1, std::numeric_limits<int>::max());
  const std::int64_t max_iterations =
      opt.max_iterations.empty()
          ? 0
          : integer_option(opt.max_iterations, "--max-iterations", 1, 100000000);
  if (ctx.log.verbosity() == Verbosity::kQuiet) progress = "none";
  if (progress == "auto") progress = isatty(STDERR_FILENO) ? "bar" : "lines";

  // A Delaunay cutting scene (thesis ch. 5) has its own parser, runner and outputs.
  if (scene::is_delaunay_scene(scene_path)) {
    if (memory_mb > 0 || max_iterations > 0 || !write_solution.empty() || !reference.empty())
      throw CommandLineError(
          "--memory-mb, --max-iterations, --write-solution and --reference are not for a "
          "Delaunay cutting scene");
    return run_delaunay_scene_command(scene_path, summary_json, progress, opt.csv, out, err);
  }

  // Parse and build everything first: errors stop the run before any file is written.
  Timer total;
  scene::SceneSpec spec = scene::load_scene(scene_path);
  if (memory_mb > 0) spec.limits.memory_mb = memory_mb;
  if (max_iterations > 0) spec.solver.max_iterations = static_cast<int>(max_iterations);
  if (!opt.csv.empty()) spec.outputs.csv = opt.csv;
  scene::BuiltScene built = scene::build_scene(spec);
  // A reference is read (and checked against the problem) before anything runs.
  VecX reference_u;
  if (!reference.empty()) {
    if (built.needle != nullptr || !spec.tools.empty() ||
        spec.solver.method == scene::SolverSpec::Method::kAugmented)
      throw CommandLineError(
          "--reference: only a relaxation scene (cg, nonlinear-cg, newton, "
          "dynamic-ss22 without tools) records an energy-norm error");
    reference_u = scene::read_solution(reference);
    if (reference_u.size() != built.problem->size())
      throw BadInputError("--reference " + reference + ": " + std::to_string(reference_u.size()) +
                          " values, but the scene has " + std::to_string(built.problem->size()) +
                          " DOFs (written for another mesh?)");
  }

  progress_out << "scene: " << scene_path << (spec.name.empty() ? "" : "  (" + spec.name + ")")
               << "\n";
  const bool needle_run = built.is_needle();
  const bool needle3d_run = built.needle3d != nullptr;
  progress_out << "solver: " << scene::to_string(spec.solver.method) << ", tolerance "
               << spec.solver.tolerance
               << (needle_run
                       ? " (eps of (6.9), eps_round " + num(spec.solver.tolerance_round) + ")"
                       : std::string(" (||r|| <= tol ||f_ext||)"));
  if (needle_run)
    progress_out << ", needle insertion: " << built.needle_plan.size() << " updates, budget "
                 << spec.solver.max_iterations << " iterations per solve\n";
  else if (spec.solver.method == scene::SolverSpec::Method::kAugmented)
    progress_out << (spec.tools.empty()
                         ? ", direct solve\n"
                         : ", interactive cut: " + std::to_string(built.sweep_triangles.size()) +
                               " sweep triangles, an augmented update per " +
                               scene::to_string(spec.solver.solve_every) + "\n");
  else
    progress_out << ", budget " << spec.solver.max_iterations << " iterations\n";

  // Progress: fraction of the way (in log10 of the residual) from ||r_0|| to the threshold.
  const double threshold =
      needle_run ? 0.0 : spec.solver.tolerance * built.problem->external_force_norm();
  double r0 = -1;
  int last_decile = -1;
  Timer bar_timer;  // redraw the bar at most every 0.1 s
  scene::FrameWriter frames(built);
  auto observer = [&](const solver::IterationInfo& info) {
    if (r0 < 0) r0 = info.residual_norm;
    double frac = 0;
    if (r0 > threshold && info.residual_norm > 0)
      frac = std::log(r0 / info.residual_norm) / std::log(r0 / threshold);
    frac = std::min(1.0, std::max(0.0, frac));
    if (progress == "bar" && (bar_timer.seconds() >= 0.1 || frac >= 1.0)) {
      bar_timer.restart();
      const int width = 30, filled = static_cast<int>(frac * width);
      progress_out << "\r[" << std::string(static_cast<std::size_t>(filled), '#')
                   << std::string(static_cast<std::size_t>(width - filled), '.') << "] it "
                   << std::setw(6) << info.iteration << "  |r|/|f| = " << std::scientific
                   << std::setprecision(2)
                   << info.residual_norm / std::max(built.problem->external_force_norm(), 1e-300)
                   << std::defaultfloat << std::setprecision(6) << std::flush;
    } else if (progress == "lines") {
      const int decile = static_cast<int>(frac * 10);
      if (decile > last_decile || verbose) {  // -v: every iteration
        last_decile = decile;
        progress_out << "progress " << std::setw(3) << decile * 10 << "%: iteration "
                     << info.iteration << ", |r| = " << info.residual_norm << " N (target "
                     << threshold << " N)\n";
      }
    }
    frames.iteration(info);
  };
  // Interactive cutting run ("augmented" with tools): one line (or bar frame) per solve.
  auto cut_observer = [&](const scene::CutStepRow& row, std::size_t total_steps,
                          const interactive::AugmentedCutSession& session) {
    frames.cut_step(row, session);
    if (progress == "bar") {
      const double frac = total_steps ? double(row.step) / double(total_steps) : 1.0;
      const int width = 30, filled = static_cast<int>(frac * width);
      progress_out << "\r[" << std::string(static_cast<std::size_t>(filled), '#')
                   << std::string(static_cast<std::size_t>(width - filled), '.') << "] step "
                   << std::setw(4) << row.step << "/" << total_steps << "  m = " << std::setw(5)
                   << row.m << std::flush;
    } else if (progress == "lines") {
      progress_out << "step " << row.step << "/" << total_steps << ": " << row.status
                   << ", m = " << row.m << ", GMRES " << row.gmres_iterations << " it, update "
                   << row.seconds_update * 1e3 << " ms\n";
    }
  };
  // Needle scene: one line (or bar frame) per update.
  auto needle_progress = [&](const scene::NeedleUpdateRow& row, std::size_t total_updates) {
    if (progress == "bar") {
      const double frac = total_updates ? double(row.update + 1) / double(total_updates) : 1.0;
      const int width = 30, filled = static_cast<int>(frac * width);
      progress_out << "\r[" << std::string(static_cast<std::size_t>(filled), '#')
                   << std::string(static_cast<std::size_t>(width - filled), '.') << "] update "
                   << std::setw(5) << row.update << "/" << total_updates - 1 << "  depth "
                   << std::fixed << std::setprecision(2) << row.depth * 1e3 << " mm"
                   << std::defaultfloat << std::setprecision(6) << std::flush;
    } else if (progress == "lines") {
      progress_out << "update " << row.update << "/" << total_updates - 1 << ": depth "
                   << num(row.depth * 1e3) << " mm, stick " << row.sticking << ", slip "
                   << row.slipping << ", rearrangements " << row.rearrangements << ", CG "
                   << row.cg_iterations << " it, update " << row.seconds * 1e3 << " ms, "
                   << row.status << "\n";
    }
  };
  auto needle_observer = [&](const scene::NeedleUpdateRow& row, std::size_t total_updates,
                             const needle::NeedleInsertion& insertion) {
    frames.needle_update(row, total_updates, insertion);
    needle_progress(row, total_updates);
  };
  auto needle3d_observer = [&](const scene::NeedleUpdateRow& row, std::size_t total_updates,
                               const needle::NeedleInsertion3D& insertion) {
    frames.needle_update(row, total_updates, insertion);
    needle_progress(row, total_updates);
  };
  const scene::SceneRunResult res =
      scene::run_scene(built, observer, cut_observer, needle_observer, needle3d_observer,
                       reference.empty() ? nullptr : &reference_u);
  if (progress == "bar") progress_out << "\n";

  const auto& rep = res.report;
  out << "\n== summary\n";
  out << "method:          " << res.method_detail << "\n";
  out << "result:          " << solver::to_string(rep.status) << "\n";
  if (needle_run) {
    long rearrangements = 0, max_cg = 0;
    for (const auto& r : res.needle_updates) {
      rearrangements += r.rearrangements;
      max_cg = std::max(max_cg, r.max_cg_iterations);
    }
    out << "updates:         " << res.needle_updates.size() << " of " << built.needle_plan.size()
        << ", " << rearrangements << " rearrangements, " << rep.inner_iterations
        << " CG iterations (longest solve " << max_cg << ")\n";
    if (!rep.message.empty()) out << "message:         " << rep.message << "\n";
    if (!res.needle_updates.empty()) {
      const auto& last = res.needle_updates.back();
      out << "final needle:    tip [" << num(last.tip.x()) << ", " << num(last.tip.y())
          << (needle3d_run ? ", " + num(last.tip.z()) : std::string()) << "] m, depth "
          << num(last.depth) << " m, " << last.sticking << " sticking, " << last.slipping
          << " slipping needle nodes; force on the material [" << num(last.needle_force.x()) << ", "
          << num(last.needle_force.y())
          << (needle3d_run ? ", " + num(last.needle_force.z()) : std::string()) << "] N\n";
      if (needle3d_run)
        out << "needle surface:  " << last.surface_faces << " faces, " << num(last.surface_area)
            << " m^2\n";
    }
    const char* cells = needle3d_run ? " tetrahedra" : " triangles";
    out << "final mesh:      " << built.mesh.num_points() << " nodes, " << built.mesh.num_cells()
        << cells << "\n";
    out << "energy:          " << num(rep.energy) << " J\n";
    if (res.inverted_elements >= 0)
      out << "inverted:        " << res.inverted_elements << " of " << built.mesh.num_cells()
          << cells << (needle3d_run ? " (deformed volume <= 0)" : " (deformed area <= 0)")
          << (spec.material.allow_inversion ? ", allowed by the scene (material.allow_inversion)"
                                            : "")
          << "\n";
    out << "flops:           " << static_cast<double>(rep.flops) / 1e6 << " MFLOP (counted)\n";
    out << "solver time:     " << rep.seconds << " s";
    if (rep.seconds > 0 && !res.needle_updates.empty())
      out << " (" << static_cast<double>(res.needle_updates.size()) / rep.seconds << " updates/s)";
    out << "\n";
  } else if (res.cut_steps.empty()) {
    out << "iterations:      " << rep.iterations;
    if (rep.inner_iterations > 0) out << " (inner " << rep.inner_iterations << ")";
    out << "\n";
  } else {
    int triangles = 0;
    for (const auto& c : res.cut_steps) triangles += c.triangles;
    out << "solves:          " << rep.iterations << " (initial + " << rep.iterations - 1
        << (spec.solver.solve_every == scene::SolverSpec::SolveEvery::kSegment ? " path segments"
                                                                               : " sweep triangles")
        << ", " << triangles << " sweep triangles cut), " << rep.inner_iterations
        << " GMRES iterations in all\n";
  }
  if (!needle_run) print_residual_summary(out, spec, built, res);
  for (const auto& p : res.probes) {
    out << "probe " << p.name << ":  displacement " << join_vec(p.value) << " m";
    if (p.reference)
      out << ", reference " << join_vec(*p.reference) << ", relative error "
          << num(100 * p.relative_error) << " %";
    out << "\n";
    if (!p.note.empty()) out << "  note: " << p.note << "\n";
  }
  if (!res.cut_steps.empty()) {
    // Per solve: m = replaced columns, GMRES iterations on the Schur system, update time
    // (column replacements + augmented solve; wall and thread CPU), cut time.
    out << "\n== augmented cut steps\n";
    out << "  step  tool  tris  faces  +nodes  nodes   tets     m  GMRES  rel.res    update ms  "
           "(cpu)  cut ms  status\n";
    for (const auto& c : res.cut_steps) {
      out << "  " << std::setw(4) << c.step << "  " << std::setw(4) << c.tool << "  "
          << std::setw(4) << c.triangles << "  " << std::setw(5) << c.faces_dissected << "  "
          << std::setw(6) << c.new_nodes << "  " << std::setw(5) << c.nodes << "  " << std::setw(5)
          << c.tetrahedra << "  " << std::setw(4) << c.m << "  " << std::setw(5)
          << c.gmres_iterations << "  " << std::scientific << std::setprecision(1) << std::setw(8)
          << c.gmres_relative_residual << std::fixed << std::setprecision(3) << std::setw(11)
          << c.seconds_update * 1e3 << " " << std::setw(6) << c.cpu_seconds_update * 1e3
          << std::setw(8) << c.seconds_cut * 1e3 << "  " << c.status << "\n"
          << std::defaultfloat << std::setprecision(6);
    }
  }
  out << "\n== built (what the scene names)\n";
  for (const auto& s : built.steps) {
    out << "  " << s.what << "\n      " << s.seconds * 1e3 << " ms, "
        << static_cast<double>(s.bytes) / 1024.0 << " KiB";
    if (s.flops >= 0) out << ", " << static_cast<double>(s.flops) / 1e6 << " MFLOP";
    out << "\n";
  }
  out << "== not built\n";
  for (const auto& s : built.not_built) out << "  " << s << "\n";

  std::vector<std::string> written =
      scene::write_outputs(built, res, {summary_json, total.seconds(), frames.frames()});
  // Interactive cutting run with a trace CSV: the per-frame time plot beside it (issue 17).
  if (!res.cut_steps.empty() && !spec.outputs.csv.empty()) {
    const std::string plot = certify::frame_plot_path(spec.outputs.csv);
    write_file_atomic(
        plot, certify::frame_time_svg(
                  res, "frame time per step: " + (spec.name.empty() ? scene_path : spec.name)));
    written.push_back(plot);
  }
  if (!write_solution.empty()) {
    if (res.u.allFinite()) {
      scene::write_solution(write_solution, res.u);
      written.push_back(write_solution);
    } else {
      err << "incise run: --write-solution " << write_solution
          << " not written: the final displacement is not finite\n";
    }
  }
  if (!written.empty()) {
    out << "== wrote\n";
    for (const auto& w : written) out << "  " << w << "\n";
  }
  if (!rep.ok()) {
    err << "incise run: no converged solution: " << rep.brief() << "\n";
    return exit_code(Exit::kNumericalFailure);
  }
  return exit_code(Exit::kOk);
}

}  // namespace

Command add_run_command(CLI::App& root) {
  auto opt = std::make_shared<RunOptions>();
  CLI::App* app = root.add_subcommand(
      "run", "run a scene file (docs/scenes.md): summary on stdout, progress on stderr");
  app->add_option("SCENE", opt->scene_path, "the scene (JSON, docs/scenes.md)")->required();
  app->add_option("--summary-json", opt->summary_json, "write the run's summary as JSON here")
      ->type_name("PATH");
  app->add_option("--progress", opt->progress,
                  "auto (bar on a terminal, else lines), bar, lines or none; on stderr")
      ->type_name("MODE");
  app->add_option("--memory-mb", opt->memory_mb,
                  "memory budget of the build in MiB (overrides the scene's limits.memory_mb; "
                  "default half the physical memory)")
      ->type_name("N");
  app->add_option("--max-iterations", opt->max_iterations,
                  "iteration cap (overrides solver.max_iterations)")
      ->type_name("N");
  app->add_option("--csv", opt->csv, "write the per-iteration trace here (overrides outputs.csv)")
      ->type_name("FILE");
  app->add_option("--write-solution", opt->write_solution,
                  "write the final displacement (for --reference)")
      ->type_name("FILE");
  app->add_option("--reference", opt->reference,
                  "a solution written by --write-solution: the trace gets the relative "
                  "energy-norm error per iteration")
      ->type_name("FILE");
  return {app, [opt](Context& ctx) { return run_scene(*opt, ctx); }};
}

}  // namespace incise::cli
