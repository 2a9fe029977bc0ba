#pragma once
/// \file bench_dashboard.hpp
/// The benchmark results store and its static dashboard (`incise bench`).
///
/// Layout: `DIR/runs/<YYYYmmddTHHMMSSZ>_<commit>/<binary>.json`, one Google Benchmark JSON file
/// (`--benchmark_format=json`) per benchmark binary and run. Run folders sort chronologically
/// by name. The dashboard `DIR/index.html` shows, for every benchmark and counter (time per
/// iteration, items/s, bytes/s and every user counter such as FLOP/s, tets/s, Hz), a trend chart
/// across the stored runs, and compares the last two runs.
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
  std::string unit;      ///< "ns", "/s", or the counter's name-implied unit
};

/// One stored run: all binaries' results of one `incise bench` invocation.
struct BenchRun {
  std::string id;                              ///< folder name "<date>_<commit>"
  std::string date;                            ///< from the id
  std::string commit;                          ///< from the id
  std::map<std::string, std::string> context;  ///< Google Benchmark context (first file), incl.
                                               ///< incise_cpu, incise_blas
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

/// Parses one Google Benchmark JSON document into `run` (values and, if empty, context).
/// Throws ParseError naming `file` for a document that is not Google Benchmark JSON.
void add_benchmark_json(const std::string& json_text, const std::string& file, BenchRun& run);

/// Reads every run folder under `runs_dir` (sorted by name). Folders without JSON files are
/// skipped; malformed JSON throws ParseError naming the file.
std::vector<BenchRun> load_bench_runs(const std::string& runs_dir);

/// Compares the last two runs over the keys both contain.
std::vector<BenchComparison> compare_last_two(const std::vector<BenchRun>& runs,
                                              const DashboardOptions& options);

/// The dashboard page: context of the last run, the comparison table (flagged rows marked),
/// and one inline-SVG trend chart per key across runs.
std::string dashboard_html(const std::vector<BenchRun>& runs, const DashboardOptions& options);

}  // namespace incise::certify
