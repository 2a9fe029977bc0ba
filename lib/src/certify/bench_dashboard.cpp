#include <incise/certify/bench_dashboard.hpp>

#include <incise/certify/svg_plot.hpp>
#include <incise/core/error.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <regex>
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
  for (const char* rate : {"per_second", "per_s", "/s", "hz", "flop", "tets", "pct_"})
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
  std::map<std::string, std::vector<double>> per_counter;          // iteration entries
  std::map<std::string, double> agg_mean, agg_stddev, agg_median;  // aggregate entries
  int agg_reps = 0;
};

double median_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// run.context from run.module_context (see BenchRun::context).
void merge_context(BenchRun& run) {
  std::map<std::string, std::map<std::string, std::vector<std::string>>> by_key;  // key→value→mods
  for (const auto& [module, ctx] : run.module_context)
    for (const auto& [k, v] : ctx) by_key[k][v].push_back(module);
  run.context.clear();
  for (const auto& [k, values] : by_key) {
    if (values.size() == 1 || k == "date" || k == "incise_date_utc") {
      run.context[k] = values.begin()->first;  // the smallest: earliest for ISO dates
      continue;
    }
    // Numbers measured per process (incise_vector_add_mflops): their range.
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const auto& kv : values) {
      char* end = nullptr;
      const double x = std::strtod(kv.first.c_str(), &end);
      if (kv.first.empty() || *end != '\0' || !std::isfinite(x)) {
        lo = std::numeric_limits<double>::quiet_NaN();
        break;
      }
      lo = std::min(lo, x), hi = std::max(hi, x);
    }
    if (!std::isnan(lo)) {
      std::ostringstream range;
      range << lo << " \xE2\x80\x93 " << hi << " (" << run.module_context.size() << " binaries)";
      run.context[k] = range.str();
      continue;
    }
    std::string merged;
    for (const auto& [v, mods] : values) {
      if (!merged.empty()) merged += "; ";
      merged += v + " (";
      for (std::size_t i = 0; i < mods.size(); ++i) merged += (i ? ", " : "") + mods[i];
      merged += ")";
    }
    run.context[k] = merged;
  }
}

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
  std::string module = std::filesystem::path(file).filename().string();
  if (module.size() > 5 && module.compare(module.size() - 5, 5, ".json") == 0)
    module.resize(module.size() - 5);
  if (j.contains("context") && j["context"].is_object()) {
    auto& ctx = run.module_context[module];
    for (auto it = j["context"].begin(); it != j["context"].end(); ++it) {
      if (it->is_string())
        ctx[it.key()] = it->get<std::string>();
      else if (it->is_number() || it->is_boolean())
        ctx[it.key()] = it->dump();
    }
    merge_context(run);
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
      } else if (agg == "median") {
        for (const auto& kv : counters) s.agg_median[kv.first] = kv.second;
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
        bv.samples = v;
        bv.median = median_of(v);
        bv.min = *std::min_element(v.begin(), v.end());
        bv.max = *std::max_element(v.begin(), v.end());
        bv.module = module;
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
        const auto md = s.agg_median.find(counter);
        bv.median = md != s.agg_median.end() ? md->second : mean;
        bv.min = bv.max = std::numeric_limits<double>::quiet_NaN();
        bv.module = module;
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

void validate_benchmark_filter(const std::string& filter) {
  // benchmark_register.cc (1.7): "" and "all" select everything; a leading '-' negates.
  if (filter.empty() || filter == "all") return;
  const std::string spec = filter[0] == '-' ? filter.substr(1) : filter;
  if (spec.empty())
    throw UsageError("--filter '" + filter +
                     "': a leading '-' negates the regular expression that follows, and none "
                     "follows");
  try {
    const std::regex re(spec, std::regex::extended | std::regex::nosubs);
    (void)re;
  } catch (const std::regex_error& e) {
    throw UsageError("--filter '" + filter +
                     "' is not a POSIX extended regular expression (as Google Benchmark reads "
                     "--benchmark_filter): " +
                     e.what());
  }
}

std::map<std::string, CounterDisplay> classify_counters(const std::vector<BenchRun>& runs) {
  constexpr double kRel = 1e-9;  // see the header: 17-digit JSON doubles vs timing noise ≥ 1e-4
  auto all_equal = [](const std::vector<double>& v) {
    for (double x : v)
      if (!(std::abs(x - v.front()) <= kRel * std::max(std::abs(v.front()), 1e-300))) return false;
    return true;
  };
  std::set<std::string> keys;
  for (const auto& r : runs)
    for (const auto& kv : r.values) keys.insert(kv.first);
  std::map<std::string, CounterDisplay> out;
  for (const auto& key : keys) {
    const auto bar = key.rfind(" | ");
    const std::string time_key = key.substr(0, bar) + " | cpu_time (ns)";
    std::vector<double> all, products;
    bool paired = key != time_key;
    for (const auto& r : runs) {
      const auto it = r.values.find(key);
      if (it == r.values.end()) continue;
      const BenchValue& v = it->second;
      if (v.samples.empty())
        all.push_back(v.value);
      else
        all.insert(all.end(), v.samples.begin(), v.samples.end());
      const auto t = r.values.find(time_key);
      if (!paired || t == r.values.end() || v.samples.empty() ||
          t->second.samples.size() != v.samples.size()) {
        paired = false;
        continue;
      }
      for (std::size_t i = 0; i < v.samples.size(); ++i)
        products.push_back(v.samples[i] * t->second.samples[i]);
    }
    if (all_equal(all))
      out[key] = CounterDisplay::kConstant;
    else if (paired && !products.empty() && all_equal(products))
      out[key] = CounterDisplay::kFromTime;
    else
      out[key] = CounterDisplay::kTrend;
  }
  return out;
}

CounterUnit counter_unit(const std::string& counter) {
  auto ends_with = [&counter](const std::string& suffix) {
    return counter.size() > suffix.size() &&
           counter.compare(counter.size() - suffix.size(), suffix.size(), suffix) == 0;
  };
  auto starts_with = [&counter](const std::string& prefix) {
    return counter.size() > prefix.size() && counter.compare(0, prefix.size(), prefix) == 0;
  };
  // An SI-prefixed quantity "MFLOP", "MFlop", "MB", "kB", "GFLOP": its base unit and factor.
  auto prefixed = [](const std::string& x, std::string& base, double& scale) {
    if (x.size() < 2) return false;
    const std::string rest = x.substr(1);
    const double f = x[0] == 'k' ? 1e3 : x[0] == 'M' ? 1e6 : x[0] == 'G' ? 1e9 : 0.0;
    if (f == 0.0) return false;
    if (rest == "FLOP" || rest == "Flop" || rest == "flop")
      base = "FLOP";
    else if (rest == "B")
      base = "B";
    else
      return false;
    scale = f;
    return true;
  };
  if (counter == "cpu_time (ns)") return {"CPU time", "s", 1e-9};
  if (counter == "items_per_second") return {"items/s", "/s", 1.0};
  if (counter == "bytes_per_second") return {"bytes/s", "B/s", 1.0};
  for (const std::string suffix : {"_per_second", "_per_s"}) {
    if (!ends_with(suffix)) continue;
    const std::string x = counter.substr(0, counter.size() - suffix.size());
    std::string base;
    double scale = 1.0;
    if (prefixed(x, base, scale)) return {x + "/s", base + "/s", scale};
    return {x + "/s", "/s", 1.0};
  }
  if (starts_with("pct_")) {
    std::string what = counter.substr(4);
    std::replace(what.begin(), what.end(), '_', ' ');
    return {"% of " + what, "%", 1.0};
  }
  if (ends_with("_Hz")) return {counter, "Hz", 1.0};
  if (ends_with("_s")) return {counter, "s", 1.0};
  const auto us = counter.find('_');
  if (us != std::string::npos) {
    std::string base;
    double scale = 1.0;
    if (prefixed(counter.substr(0, us), base, scale)) return {counter, base, scale};
  }
  return {counter, "", 1.0};
}

std::string format_si(double value, const std::string& unit) {
  if (std::isnan(value)) return "\xE2\x80\x94";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  static const char* const kBig[] = {"", "k", "M", "G", "T", "P", "E"};
  static const char* const kSmall[] = {"", "m", "\xC2\xB5", "n", "p", "f"};
  const double a = std::abs(value);
  int group = 0;  // power of 1000
  if (a != 0.0 && unit != "%") {
    group = static_cast<int>(std::floor(std::log10(a) / 3.0));
    // Prefixes below 1 only for seconds ("36.0 ms"); other small numbers as they are.
    if (group < 0 && unit != "s") group = 0;
    group = std::max(-5, std::min(6, group));
  }
  // 3 significant digits; a mantissa that rounds to 1000 moves to the next prefix.
  if (group < 6 && unit != "%" && std::abs(value / std::pow(1000.0, group)) >= 999.5) ++group;
  const double m = value / std::pow(1000.0, group);
  const double am = std::abs(m);
  std::ostringstream os;
  if (am < 0.9995 && group == 0)
    os << std::setprecision(3) << m;  // 0, or a small plain number: 3 significant digits
  else
    os << std::fixed << std::setprecision(am >= 99.95 ? 0 : am >= 9.995 ? 1 : 2) << m;
  const std::string number = os.str();
  const std::string prefix = group >= 0 ? kBig[group] : kSmall[-group];
  if (unit == "%") return number + " %";
  if (prefix.empty() && (unit.empty() || unit[0] == '/')) return number + unit;
  return number + " " + prefix + unit;
}

std::vector<std::string> run_labels(const std::vector<BenchRun>& runs) {
  // "20261202T142727Z" → minute / second forms; anything else → the folder name.
  auto form = [](const BenchRun& r, int level) {
    const std::string& d = r.date;
    const bool stamp = d.size() == 16 && d[8] == 'T' && d[15] == 'Z' &&
                       std::all_of(d.begin(), d.begin() + 8, ::isdigit) &&
                       std::all_of(d.begin() + 9, d.begin() + 15, ::isdigit);
    if (!stamp || level >= 2) return r.id;
    std::string s = d.substr(0, 4) + "-" + d.substr(4, 2) + "-" + d.substr(6, 2) + " " +
                    d.substr(9, 2) + ":" + d.substr(11, 2);
    if (level == 1) s += ":" + d.substr(13, 2);
    return s;
  };
  std::vector<int> level(runs.size(), 0);
  std::vector<std::string> out(runs.size());
  for (int pass = 0; pass < 3; ++pass) {
    for (std::size_t i = 0; i < runs.size(); ++i) out[i] = form(runs[i], level[i]);
    bool changed = false;
    for (std::size_t i = 0; i < runs.size(); ++i)
      for (std::size_t k = 0; k < runs.size(); ++k)
        if (i != k && out[i] == out[k] && level[i] < 2) {
          ++level[i];
          changed = true;
          break;
        }
    if (!changed) break;
  }
  for (std::size_t i = 0; i < runs.size(); ++i) out[i] = form(runs[i], level[i]);
  return out;
}

namespace {

// "<benchmark> | <counter>" parts.
std::string bench_of(const std::string& key) {
  return key.substr(0, key.rfind(" | "));
}
std::string counter_of(const std::string& key) {
  return key.substr(key.rfind(" | ") + 3);
}

const char* const kEnvironmentKeys[] = {"incise_date_utc",
                                        "incise_host",
                                        "incise_cpu",
                                        "incise_cores",
                                        "incise_compiler",
                                        "incise_build_type",
                                        "incise_blas",
                                        "incise_eigen",
                                        "incise_vector_add_mflops",
                                        "incise_fma_peak_mflops_nominal",
                                        "host_name",
                                        "num_cpus",
                                        "mhz_per_cpu",
                                        "cpu_scaling_enabled",
                                        "library_build_type",
                                        "date"};

}  // namespace

std::string dashboard_html(const std::vector<BenchRun>& runs, const DashboardOptions& options) {
  std::ostringstream os;
  os << html_page_begin(options.title);
  os << "<style>\n.plots{gap:6px}\nfigure.trend{margin:0;width:236px;font-size:11px}\n"
        "figure.trend "
        "figcaption{line-height:1.25;overflow-wrap:anywhere}\n.changed{background:#fff3c0}\n"
        ".better{color:#006400}.worse{color:#b00000}\ntable.env td{max-width:260px;"
        "word-break:break-word}\n</style>\n";
  os << "<h1>" << html_escape(options.title) << "</h1>\n";
  os << "<p>" << runs.size() << " stored run(s). Each chart is one benchmark counter across "
     << "the runs: the line joins the medians over the repetitions of each run, the shaded band "
     << "spans their smallest to largest value, and the y axis starts at zero, so a height "
     << "compares as a ratio. Only counters that vary are charted; a rate that is a fixed "
     << "multiple of 1/time is given in the caption of the time chart, and counters with one "
     << "value everywhere are listed once per module. Changes between the last two runs "
     << "(means) are flagged when they exceed 3&sigma; of the combined repetition noise (at "
     << "least " << format_number(100 * options.min_threshold) << " %), or "
     << format_number(100 * options.default_noise)
     << " % when a run has no repetitions (stated default).</p>\n";
  if (runs.empty()) {
    os << "<p>No runs stored yet: run <code>incise bench</code>.</p>\n" << html_page_end();
    return os.str();
  }
  const std::vector<std::string> labels = run_labels(runs);

  // Environment, one column per run (the last 8).
  const std::size_t first = runs.size() > 8 ? runs.size() - 8 : 0;
  os << "<h2>Runs and their environment</h2>\n";
  if (first > 0) os << "<p>The last 8 of " << runs.size() << " runs; the charts show all.</p>\n";
  os << "<table class=\"env\" id=\"environment\">\n<tr><th>run (UTC)</th>";
  for (std::size_t i = first; i < runs.size(); ++i)
    os << "<th>" << html_escape(labels[i]) << "</th>";
  os << "</tr>\n<tr><th>folder</th>";
  for (std::size_t i = first; i < runs.size(); ++i)
    os << "<td>" << html_escape(runs[i].id) << "</td>";
  os << "</tr>\n<tr><th>commit</th>";
  for (std::size_t i = first; i < runs.size(); ++i)
    os << "<td>" << html_escape(runs[i].commit) << "</td>";
  os << "</tr>\n";
  for (const char* k : kEnvironmentKeys) {
    bool any = false;
    for (std::size_t i = first; i < runs.size(); ++i) any = any || runs[i].context.count(k);
    if (!any) continue;
    os << "<tr><th>" << k << "</th>";
    for (std::size_t i = first; i < runs.size(); ++i) {
      const auto it = runs[i].context.find(k);
      const std::string v = it == runs[i].context.end() ? "" : it->second;
      bool changed = false;
      if (i > first && std::string(k).find("date") == std::string::npos) {
        const auto p = runs[i - 1].context.find(k);
        changed = (p == runs[i - 1].context.end() ? "" : p->second) != v;
      }
      os << "<td" << (changed ? " class=\"changed\"" : "") << ">" << html_escape(v) << "</td>";
    }
    os << "</tr>\n";
  }
  os << "</table>\n";

  // Comparison of the last two runs.
  const auto cmp = compare_last_two(runs, options);
  std::map<std::string, const BenchComparison*> cmp_of;
  for (const auto& c : cmp) cmp_of[c.key] = &c;
  auto verdict_of = [](const BenchComparison& c) -> std::string {
    if (!c.flagged) return "within noise";
    const int dir = direction(c.key);
    const bool up = c.relative_change > 0;
    return dir == 0 ? "changed" : (up == (dir > 0) ? "improvement" : "regression");
  };
  auto row = [&](const BenchComparison& c) {
    const CounterUnit u = counter_unit(counter_of(c.key));
    std::ostringstream r;
    r << "<tr" << (c.flagged ? " class=\"flag\"" : "") << "><td>" << html_escape(bench_of(c.key))
      << "</td><td>" << html_escape(u.label) << "</td><td>"
      << html_escape(format_si(c.previous * u.scale, u.unit)) << "</td><td>"
      << html_escape(format_si(c.last * u.scale, u.unit)) << "</td><td>"
      << format_number(100 * c.relative_change) << " %</td><td>" << format_number(100 * c.threshold)
      << " % (" << (c.measured_noise ? "3&sigma; measured" : "default") << ")</td><td>"
      << verdict_of(c) << "</td></tr>\n";
    return r.str();
  };
  const char* header =
      "<tr><th>benchmark</th><th>counter</th><th>previous</th><th>last</th><th>change</th>"
      "<th>noise threshold</th><th>verdict</th></tr>\n";
  os << "<h2>Last two runs compared</h2>\n";
  if (cmp.empty()) {
    os << "<p>Fewer than two runs with common benchmarks.</p>\n";
  } else {
    int flagged = 0;
    for (const auto& c : cmp) flagged += c.flagged;
    os << "<p id=\"flag-count\">" << flagged << " of " << cmp.size() << " counters changed beyond "
       << "noise between " << html_escape(labels[runs.size() - 2]) << " and "
       << html_escape(labels.back()) << ".</p>\n";
    os << "<table id=\"comparison\">\n" << header;
    for (const auto& c : cmp)
      if (c.flagged) os << row(c);
    if (flagged == 0) os << "<tr><td colspan=\"7\">no change beyond noise</td></tr>\n";
    os << "</table>\n<details><summary>all " << cmp.size()
       << " compared counters</summary>\n<table id=\"comparison-all\">\n"
       << header;
    for (const auto& c : cmp) os << row(c);
    os << "</table>\n</details>\n";
  }

  // Small multiples per module.
  const auto display = classify_counters(runs);
  std::map<std::string, std::map<std::string, std::vector<std::string>>> modules;  // mod→bench→keys
  std::map<std::string, std::string> module_of;
  for (const auto& r : runs)
    for (const auto& [key, v] : r.values) module_of[bench_of(key)] = v.module;
  for (const auto& [key, d] : display)
    modules[module_of[bench_of(key)]][bench_of(key)].push_back(key);
  os << "<h2>Trends by module</h2>\n<p>";
  for (const auto& m : modules)
    os << "<a href=\"#module-" << html_escape(m.first) << "\">" << html_escape(m.first) << "</a> ("
       << m.second.size() << ") ";
  os << "</p>\n";
  auto last_value = [&runs](const std::string& key) -> const BenchValue* {
    for (auto r = runs.rbegin(); r != runs.rend(); ++r) {
      const auto it = r->values.find(key);
      if (it != r->values.end()) return &it->second;
    }
    return nullptr;
  };
  for (const auto& [module, benches] : modules) {
    os << "<h3 id=\"module-" << html_escape(module) << "\">" << html_escape(module) << "</h3>\n"
       << "<div class=\"plots\">\n";
    std::vector<std::string> constant_rows;
    for (const auto& [bench, keys] : benches) {
      // Time first, then the other counters by name.
      std::vector<std::string> ordered = keys;
      std::stable_partition(ordered.begin(), ordered.end(),
                            [](const std::string& k) { return counter_of(k) == "cpu_time (ns)"; });
      std::vector<std::string> from_time;
      for (const auto& key : ordered)
        if (display.at(key) == CounterDisplay::kFromTime) from_time.push_back(key);
      for (const auto& key : ordered) {
        const CounterUnit u = counter_unit(counter_of(key));
        const BenchValue* lv = last_value(key);
        if (display.at(key) == CounterDisplay::kConstant) {
          constant_rows.push_back(
              "<tr><td>" + html_escape(bench) + "</td><td>" + html_escape(u.label) + "</td><td>" +
              html_escape(format_si(lv->median * u.scale, u.unit)) + "</td></tr>\n");
          continue;
        }
        if (display.at(key) != CounterDisplay::kTrend) continue;
        Series s;
        for (std::size_t i = 0; i < runs.size(); ++i) {
          const auto it = runs[i].values.find(key);
          if (it == runs[i].values.end()) continue;
          s.x.push_back(static_cast<double>(i));
          s.y.push_back(it->second.median * u.scale);
          s.band_lo.push_back(it->second.min * u.scale);
          s.band_hi.push_back(it->second.max * u.scale);
        }
        PlotOptions po;
        po.title = bench + " | " + u.label;
        po.compact = true;
        po.include_zero = true;
        po.width = 236;
        po.height = 110;
        po.x_categories = labels;
        const std::string unit = u.unit;
        po.y_format = [unit](double v) { return format_si(v, unit); };
        os << "<figure class=\"trend\">" << svg_line_plot({s}, po) << "<figcaption><b>"
           << html_escape(bench) << "</b><br>" << html_escape(u.label) << " "
           << html_escape(format_si(lv->median * u.scale, u.unit));
        if (std::isfinite(lv->min) && lv->min != lv->max)
          os << " (" << html_escape(format_si(lv->min * u.scale, u.unit)) << " \xE2\x80\x93 "
             << html_escape(format_si(lv->max * u.scale, u.unit)) << ")";
        const auto c = cmp_of.find(key);
        if (c != cmp_of.end()) {
          const std::string v = verdict_of(*c->second);
          os << "<br><span class=\""
             << (v == "improvement"  ? "better"
                 : v == "regression" ? "worse"
                                     : "")
             << "\">" << (c->second->relative_change >= 0 ? "+" : "")
             << format_number(100 * c->second->relative_change) << " % since the previous run, "
             << v << "</span>";
        }
        if (counter_of(key) == "cpu_time (ns)" && !from_time.empty()) {
          os << "<br>";
          for (std::size_t k = 0; k < from_time.size(); ++k) {
            const CounterUnit fu = counter_unit(counter_of(from_time[k]));
            const BenchValue* fv = last_value(from_time[k]);
            os << (k ? " &middot; " : "") << html_escape(fu.label) << " "
               << html_escape(format_si(fv->median * fu.scale, fu.unit));
          }
        }
        os << "</figcaption></figure>\n";
      }
    }
    os << "</div>\n";
    if (!constant_rows.empty()) {
      os << "<details><summary>" << constant_rows.size() << " constant counters of "
         << html_escape(module)
         << " (one value in every run and repetition)</summary>\n<table class=\"constant\">\n"
         << "<tr><th>benchmark</th><th>counter</th><th>value</th></tr>\n";
      for (const auto& r : constant_rows) os << r;
      os << "</table>\n</details>\n";
    }
  }
  os << html_page_end();
  return os.str();
}

}  // namespace incise::certify
