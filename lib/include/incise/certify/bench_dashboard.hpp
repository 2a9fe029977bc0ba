#pragma once
/// \file bench_dashboard.hpp
/// The benchmark results store and its static dashboard (`incise bench`).
///
/// Layout: `DIR/runs/<YYYYmmddTHHMMSSZ>_<commit>/<binary>.json`, one Google Benchmark JSON file
/// (`--benchmark_format=json`) per benchmark binary and run. Run folders sort chronologically
/// by name. The dashboard `DIR/index.html` compares the last two runs and shows, per module (the
/// binary a benchmark comes from), small trend charts across the stored runs: the median over
/// repetitions with the min..max band of the repetitions, y axes from zero, human units. Only
/// counters that vary are charted (see classify_counters); the environment of each run (the
/// `incise_*` context entries, core/environment.hpp) is tabulated per run.
///
/// Noise: when a benchmark was repeated (`--benchmark_repetitions`), its value is the mean of the
/// repetitions and its noise the sample standard deviation (from the per-repetition entries, or
/// the "stddev" aggregate when only aggregates were reported). A change between the last two runs
/// is flagged when |Δ| > 3·σ_Δ with σ_Δ = √(σ_prev² + σ_last²); when either run has no measured
/// noise, a stated default relative noise (DashboardOptions::default_noise) replaces 3σ_Δ/|prev|.
/// Measured thresholds are floored at DashboardOptions::min_threshold, because repetitions in
/// one process underestimate run-to-run variation (frequency scaling, other load).

#include <map>
#include <string>
#include <vector>

namespace incise::certify {

/// One benchmark counter in one run.
struct BenchValue {
  double value = 0.0;    ///< mean over repetitions (counter units, or ns for "time")
  double stddev = -1.0;  ///< sample standard deviation over repetitions; −1 when not measured
  int repetitions = 1;   ///< repetitions contributing
  std::string unit;      ///< "ns" for the time, "" for counters (see counter_unit)
  /// Median, smallest and largest over the repetitions (the per-repetition rows; the median is
  /// Google Benchmark's "median" aggregate row when only aggregates were written, and min/max are
  /// then NaN). With one repetition all three equal `value`.
  double median = 0.0, min = 0.0, max = 0.0;
  std::vector<double> samples;  ///< per-repetition values (empty when only aggregates)
  std::string module;           ///< the binary it came from: JSON file name without ".json"
};

/// One stored run: all binaries' results of one `incise bench` invocation.
struct BenchRun {
  std::string id;      ///< folder name "<date>_<commit>"
  std::string date;    ///< from the id
  std::string commit;  ///< from the id
  /// Google Benchmark context merged over the run's files: a key with one value in every file
  /// has that value; numbers that differ between binaries (incise_vector_add_mflops, measured
  /// by each process) read "min – max (N binaries)"; other values that differ (e.g.
  /// incise_blas: only binaries that link CHOLMOD map a BLAS) read "v1 (a_bench, b_bench); v2
  /// (c_bench)"; the per-binary start times "date" and "incise_date_utc" keep the earliest.
  std::map<std::string, std::string> context;
  /// Context of each file, by module.
  std::map<std::string, std::map<std::string, std::string>> module_context;
  /// key "<benchmark name> | <counter>" → value
  std::map<std::string, BenchValue> values;
  std::vector<std::string> files;  ///< JSON files read
};

/// Change of one counter between the last two runs.
struct BenchComparison {
  std::string key;
  double previous = 0.0;
  double last = 0.0;
  double relative_change = 0.0;  ///< (last − previous)/|previous|
  double threshold = 0.0;        ///< relative change above which it is flagged
  bool measured_noise = false;   ///< threshold from repetitions (true) or the default (false)
  bool flagged = false;
  bool higher_is_better = true;  ///< rates: higher is better; time: lower is better
};

/// Dashboard settings.
struct DashboardOptions {
  /// Relative noise assumed when a run has no repetitions (5 %: typical run-to-run variation of
  /// single-repetition microbenchmarks on a shared machine).
  double default_noise = 0.05;
  /// Lower bound on a measured relative threshold (2 %: below the run-to-run variation we see
  /// between identical runs of the element benchmarks on the shared 2-core machine).
  double min_threshold = 0.02;
  std::string title = "incise benchmark dashboard";
};

/// Parses one Google Benchmark JSON document into `run`: its values (module = `file`'s name
/// without the directory and ".json") and its context (merged into run.context as described
/// there). Throws ParseError naming `file` for a document that is not Google Benchmark JSON.
void add_benchmark_json(const std::string& json_text, const std::string& file, BenchRun& run);

/// Reads every run folder under `runs_dir` (sorted by name). Folders without JSON files are
/// skipped; malformed JSON throws ParseError naming the file.
std::vector<BenchRun> load_bench_runs(const std::string& runs_dir);

/// Compares the last two runs over the keys both contain.
std::vector<BenchComparison> compare_last_two(const std::vector<BenchRun>& runs,
                                              const DashboardOptions& options);

/// Checks a `--benchmark_filter` regular expression the way Google Benchmark 1.7 reads it
/// (benchmark_register.cc): "" and "all" mean every benchmark, a leading '-' negates, the rest is
/// a POSIX extended regular expression (std::regex::extended, as the library is built with
/// std::regex). Throws UsageError naming the expression and what is wrong with it.
void validate_benchmark_filter(const std::string& filter);

/// How the dashboard shows a counter of a benchmark.
enum class CounterDisplay {
  kTrend,     ///< varies across runs or repetitions: a trend chart
  kConstant,  ///< one value in every repetition of every run: listed once in a table
  kFromTime,  ///< a rate = k / cpu time with one k everywhere (counter × time constant to
              ///< 1e-9 relative): the time chart shows it; its last value is in the caption
};

/// Classifies every key "<benchmark> | <counter>" of the runs. Equality is relative to 1e-9:
/// Google Benchmark writes doubles with 17 significant digits, so one computed value repeats
/// exactly and a product of two of them to ~1e-15; any timing noise is ≥ 1e-4.
std::map<std::string, CounterDisplay> classify_counters(const std::vector<BenchRun>& runs);

/// How a counter is labelled and scaled for display.
struct CounterUnit {
  std::string label;   ///< e.g. "CPU time", "MFLOP/s", "tets/s", "% of vector add", "nnz_L"
  std::string unit;    ///< SI base unit of the displayed value: "s", "FLOP/s", "/s", "B", "%", ""
  double scale = 1.0;  ///< displayed base value = counter value × scale (MFLOP → FLOP: 1e6)
};

/// Unit of a counter, from Google Benchmark's and incise's naming conventions: "cpu_time (ns)"
/// → s (×1e-9); "items_per_second", "bytes_per_second"; "<X>_per_s" → X/s with an SI-prefixed X
/// (MFLOP, MB) rescaled to its base; "pct_<X>" → %; "<X>_Hz" → Hz; "<X>_s" → s; "MB_<X>" → B;
/// "MFlop_<X>"/"MFLOP_<X>" → FLOP; anything else is a plain number.
CounterUnit counter_unit(const std::string& counter);

/// `value` (in base units) with 3 significant digits and an SI prefix: 3.6e-2 s → "36.0 ms",
/// 7.44e9 FLOP/s → "7.44 GFLOP/s", 1.2e6 → "1.20 M"; "%" and values in [1, 1000) get no prefix;
/// NaN → "—".
std::string format_si(double value, const std::string& unit);

/// Labels of the runs for axes and tables, distinct for distinct runs: the UTC date-time of the
/// run folder ("2026-12-02 14:27"), with seconds when two runs share the minute, with the
/// folder name when two runs share the second.
std::vector<std::string> run_labels(const std::vector<BenchRun>& runs);

/// The dashboard page: the environment of each run (one column per run, a value that changed
/// since the previous run highlighted), the comparison of the last two runs (flagged rows
/// first, marked), and per module a grid of small inline-SVG charts (one per benchmark and
/// counter classified kTrend: median line, min..max band of the repetitions, y axis from zero,
/// human units) and a table of the constant counters.
std::string dashboard_html(const std::vector<BenchRun>& runs, const DashboardOptions& options);

}  // namespace incise::certify
