#include <incise/certify/bench_dashboard.hpp>

#include <incise/certify/svg_plot.hpp>
#include <incise/core/error.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace incise::certify {

namespace {

using Json = nlohmann::json;

const std::set<std::string> kNotCounters = {"name",
                                            "family_index",
                                            "per_family_instance_index",
                                            "run_name",
                                            "run_type",
                                            "repetitions",
                                            "repetition_index",
                                            "threads",
                                            "iterations",
                                            "real_time",
                                            "cpu_time",
                                            "time_unit",
                                            "aggregate_name",
                                            "aggregate_unit",
                                            "label",
                                            "error_occurred",
                                            "error_message",
                                            "big_o",
                                            "rms",
                                            "complexity_n"};

double to_ns(double t, const std::string& unit) {
  if (unit == "us") return t * 1e3;
  if (unit == "ms") return t * 1e6;
  if (unit == "s") return t * 1e9;
  return t;  // "ns"
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// +1 higher is better, −1 lower is better, 0 no preferred direction.
int direction(const std::string& key) {
  const std::string counter = lower(key.substr(key.rfind("| ") + 2));
  if (counter == "cpu_time (ns)") return -1;
  for (const char* rate : {"per_second", "/s", "hz", "flop", "tets"})
    if (counter.find(rate) != std::string::npos) return 1;
  return 0;
}

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ParseError(path, 0, "cannot open benchmark result file");
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

struct Samples {
  std::map<std::string, std::vector<double>> per_counter;  // iteration entries
  std::map<std::string, double> agg_mean, agg_stddev;      // aggregate entries
  int agg_reps = 0;
};

}  // namespace

void add_benchmark_json(const std::string& json_text, const std::string& file, BenchRun& run) {
  Json j;
  try {
    j = Json::parse(json_text);
  } catch (const Json::parse_error& e) {
    throw ParseError(file, 0, std::string("not valid JSON: ") + e.what());
  }
  if (!j.is_object() || !j.contains("benchmarks") || !j["benchmarks"].is_array())
    throw ParseError(file, 0,
                     "expected Google Benchmark JSON output (an object with a \"benchmarks\" "
                     "array, from --benchmark_format=json)");
  if (run.context.empty() && j.contains("context") && j["context"].is_object()) {
    for (auto it = j["context"].begin(); it != j["context"].end(); ++it) {
      if (it->is_string())
        run.context[it.key()] = it->get<std::string>();
      else if (it->is_number() || it->is_boolean())
        run.context[it.key()] = it->dump();
    }
  }
  std::map<std::string, Samples> by_name;
  for (const Json& b : j["benchmarks"]) {
    if (!b.is_object() || !b.contains("name")) continue;
    if (b.value("error_occurred", false)) continue;
    const std::string name = b.value("run_name", b["name"].get<std::string>());
    const std::string run_type = b.value("run_type", "iteration");
    Samples& s = by_name[name];
    std::map<std::string, double> counters;
    if (b.contains("cpu_time") && b["cpu_time"].is_number())
      counters["cpu_time (ns)"] = to_ns(b["cpu_time"].get<double>(), b.value("time_unit", "ns"));
    for (auto it = b.begin(); it != b.end(); ++it)
      if (it->is_number() && !kNotCounters.count(it.key())) counters[it.key()] = it->get<double>();
    if (run_type == "aggregate") {
      const std::string agg = b.value("aggregate_name", "");
      if (agg == "mean") {
        for (const auto& kv : counters) s.agg_mean[kv.first] = kv.second;
        s.agg_reps = b.value("repetitions", 0);
      } else if (agg == "stddev") {
        for (const auto& kv : counters) s.agg_stddev[kv.first] = kv.second;
      }
    } else {
      for (const auto& kv : counters) s.per_counter[kv.first].push_back(kv.second);
    }
  }
  for (const auto& [name, s] : by_name) {
    if (!s.per_counter.empty()) {
      for (const auto& [counter, v] : s.per_counter) {
        BenchValue bv;
        bv.repetitions = static_cast<int>(v.size());
        double mean = 0;
        for (double x : v) mean += x;
        mean /= static_cast<double>(v.size());
        bv.value = mean;
        if (v.size() >= 2) {
          double ss = 0;
          for (double x : v) ss += (x - mean) * (x - mean);
          bv.stddev = std::sqrt(ss / static_cast<double>(v.size() - 1));
        }
        bv.unit = counter == "cpu_time (ns)" ? "ns" : "";
        run.values[name + " | " + counter] = bv;
      }
    } else {
      for (const auto& [counter, mean] : s.agg_mean) {
        BenchValue bv;
        bv.value = mean;
        bv.repetitions = s.agg_reps;
        auto sd = s.agg_stddev.find(counter);
        if (sd != s.agg_stddev.end() && s.agg_reps >= 2) bv.stddev = sd->second;
        bv.unit = counter == "cpu_time (ns)" ? "ns" : "";
        run.values[name + " | " + counter] = bv;
      }
    }
  }
  run.files.push_back(file);
}

std::vector<BenchRun> load_bench_runs(const std::string& runs_dir) {
  std::vector<BenchRun> runs;
  std::error_code ec;
  if (!std::filesystem::is_directory(runs_dir, ec)) return runs;
  std::vector<std::filesystem::path> dirs;
  for (const auto& e : std::filesystem::directory_iterator(runs_dir))
    if (e.is_directory()) dirs.push_back(e.path());
  std::sort(dirs.begin(), dirs.end());
  for (const auto& d : dirs) {
    std::vector<std::filesystem::path> files;
    for (const auto& e : std::filesystem::directory_iterator(d))
      if (e.is_regular_file() && e.path().extension() == ".json") files.push_back(e.path());
    if (files.empty()) continue;
    std::sort(files.begin(), files.end());
    BenchRun run;
    run.id = d.filename().string();
    const auto us = run.id.find('_');
    run.date = run.id.substr(0, us);
    run.commit = us == std::string::npos ? "" : run.id.substr(us + 1);
    for (const auto& f : files) add_benchmark_json(read_text(f.string()), f.string(), run);
    runs.push_back(std::move(run));
  }
  return runs;
}

std::vector<BenchComparison> compare_last_two(const std::vector<BenchRun>& runs,
                                              const DashboardOptions& options) {
  std::vector<BenchComparison> out;
  if (runs.size() < 2) return out;
  const BenchRun& a = runs[runs.size() - 2];
  const BenchRun& b = runs.back();
  for (const auto& [key, vb] : b.values) {
    auto it = a.values.find(key);
    if (it == a.values.end()) continue;
    const BenchValue& va = it->second;
    BenchComparison c;
    c.key = key;
    c.previous = va.value;
    c.last = vb.value;
    const double scale = std::abs(va.value);
    c.relative_change = scale > 0 ? (vb.value - va.value) / scale : 0.0;
    c.measured_noise = va.stddev >= 0 && vb.stddev >= 0;
    c.threshold =
        c.measured_noise && scale > 0
            ? std::max(options.min_threshold,
                       3.0 * std::sqrt(va.stddev * va.stddev + vb.stddev * vb.stddev) / scale)
            : options.default_noise;
    c.flagged = std::abs(c.relative_change) > c.threshold;
    c.higher_is_better = direction(key) >= 0;
    out.push_back(c);
  }
  return out;
}

std::string dashboard_html(const std::vector<BenchRun>& runs, const DashboardOptions& options) {
  std::ostringstream os;
  os << html_page_begin(options.title);
  os << "<h1>" << html_escape(options.title) << "</h1>\n";
  os << "<p>" << runs.size() << " stored run(s). Values are means over repetitions; error bars "
     << "are ±1 sample standard deviation where repetitions were run. Changes between the last "
     << "two runs are flagged when they exceed 3&sigma; of the combined repetition noise (at "
     << "least " << format_number(100 * options.min_threshold) << " %), or "
     << format_number(100 * options.default_noise)
     << " % when a run has no repetitions (stated default).</p>\n";
  if (runs.empty()) {
    os << "<p>No runs stored yet: run <code>incise bench</code>.</p>\n" << html_page_end();
    return os.str();
  }
  const BenchRun& last = runs.back();
  os << "<h2>Last run: " << html_escape(last.id) << "</h2>\n<table>\n";
  for (const char* k :
       {"incise_cpu", "incise_blas", "incise_compiler", "incise_build_type", "incise_eigen",
        "incise_vector_add_mflops", "incise_fma_peak_mflops_nominal", "num_cpus", "mhz_per_cpu",
        "library_build_type", "host_name", "date"}) {
    auto it = last.context.find(k);
    if (it != last.context.end())
      os << "<tr><th>" << k << "</th><td>" << html_escape(it->second) << "</td></tr>\n";
  }
  os << "</table>\n";

  const auto cmp = compare_last_two(runs, options);
  os << "<h2>Last two runs compared</h2>\n";
  if (cmp.empty()) {
    os << "<p>Fewer than two runs with common benchmarks.</p>\n";
  } else {
    int flagged = 0;
    for (const auto& c : cmp) flagged += c.flagged;
    os << "<p id=\"flag-count\">" << flagged << " of " << cmp.size() << " counters changed beyond "
       << "noise between " << html_escape(runs[runs.size() - 2].id) << " and "
       << html_escape(last.id) << ".</p>\n";
    os << "<table id=\"comparison\">\n<tr><th>benchmark | counter</th><th>previous</th>"
       << "<th>last</th><th>change</th><th>noise threshold</th><th>verdict</th></tr>\n";
    for (const auto& c : cmp) {
      const int dir = direction(c.key);
      std::string verdict = "within noise";
      if (c.flagged) {
        const bool up = c.relative_change > 0;
        verdict = dir == 0 ? "changed" : (up == (dir > 0) ? "improvement" : "regression");
      }
      os << "<tr" << (c.flagged ? " class=\"flag\"" : "") << "><td>" << html_escape(c.key)
         << "</td><td>" << format_number(c.previous) << "</td><td>" << format_number(c.last)
         << "</td><td>" << format_number(100 * c.relative_change) << " %</td><td>"
         << format_number(100 * c.threshold) << " % ("
         << (c.measured_noise ? "3&sigma; measured" : "default") << ")</td><td>" << verdict
         << "</td></tr>\n";
    }
    os << "</table>\n";
  }

  os << "<h2>Trends</h2>\n<div class=\"plots\">\n";
  std::set<std::string> keys;
  for (const auto& r : runs)
    for (const auto& kv : r.values) keys.insert(kv.first);
  std::vector<std::string> categories;
  for (const auto& r : runs)
    categories.push_back(r.date.substr(0, std::min<std::size_t>(8, r.date.size())) + " " +
                         r.commit.substr(0, 7));
  for (const auto& key : keys) {
    Series s;
    s.label = key.substr(key.rfind("| ") + 2);
    for (std::size_t i = 0; i < runs.size(); ++i) {
      auto it = runs[i].values.find(key);
      if (it == runs[i].values.end()) continue;
      s.x.push_back(static_cast<double>(i));
      s.y.push_back(it->second.value);
      s.y_err.push_back(it->second.stddev >= 0 ? it->second.stddev : 0.0);
    }
    PlotOptions po;
    po.title = key;
    po.x_label = "run (date, commit)";
    po.y_label = s.label;
    po.x_categories = categories;
    os << "<figure class=\"trend\">" << svg_line_plot({s}, po) << "</figure>\n";
  }
  os << "</div>\n" << html_page_end();
  return os.str();
}

}  // namespace incise::certify
