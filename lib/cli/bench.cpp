// `incise bench [--filter RE] [--out DIR] [--bin-dir DIR] [--repetitions N] [--min-time S]
//               [--dashboard-only]`: runs the Google Benchmark binaries (`*_bench` under the
// build tree's benchmarks/ folder, found next to this executable, or under --bin-dir), stores
// their JSON under DIR/runs/<UTC date>_<commit>/<binary>.json and regenerates the static
// dashboard DIR/index.html (lib/scene bench_dashboard.hpp). CPU and BLAS come from each
// binary's own benchmark context.

#include <incise/certify/bench_dashboard.hpp>
#include <incise/certify/svg_plot.hpp>
#include <incise/core/error.hpp>

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "cli_util.hpp"
#include "commands.hpp"

extern char** environ;

namespace incise::cli {

namespace {

namespace fs = std::filesystem;

/// Executables named *_bench under `root`, sorted.
std::vector<fs::path> find_bench_binaries(const fs::path& root) {
  std::vector<fs::path> out;
  std::error_code ec;
  if (!fs::is_directory(root, ec)) return out;
  for (auto it = fs::recursive_directory_iterator(root, ec);
       it != fs::recursive_directory_iterator(); it.increment(ec)) {
    if (ec) break;
    const fs::path& p = it->path();
    const std::string name = p.filename().string();
    if (name.size() > 6 && name.compare(name.size() - 6, 6, "_bench") == 0 &&
        it->is_regular_file(ec) && access(p.c_str(), X_OK) == 0)
      out.push_back(p);
  }
  std::sort(out.begin(), out.end());
  return out;
}

/// Runs argv with inherited stdout/stderr; returns the exit status (−1 when it cannot start).
int run_process(const std::vector<std::string>& argv) {
  std::vector<char*> cargv;
  for (const auto& a : argv) cargv.push_back(const_cast<char*>(a.c_str()));
  cargv.push_back(nullptr);
  pid_t pid;
  if (posix_spawn(&pid, cargv[0], nullptr, nullptr, cargv.data(), environ) != 0) return -1;
  int status = 0;
  if (waitpid(pid, &status, 0) < 0) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::string utc_stamp() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%dT%H%M%SZ", &tm);
  return buf;
}

}  // namespace

int run_bench_command(const Args& args, std::ostream& out, std::ostream& err) {
  std::string filter, out_dir = "out/bench", bin_dir;
  int repetitions = 3;
  std::string min_time;
  bool dashboard_only = false;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--filter") {
      filter = option_value(args, i, "--filter");
    } else if (a == "--out") {
      out_dir = option_value(args, i, "--out");
    } else if (a == "--bin-dir") {
      bin_dir = option_value(args, i, "--bin-dir");
    } else if (a == "--repetitions") {
      const std::string v = option_value(args, i, "--repetitions");
      try {
        repetitions = std::stoi(v);
      } catch (const std::exception&) {
        repetitions = 0;
      }
      if (repetitions < 1 || repetitions > 100)
        throw UsageError("--repetitions expects an integer in [1, 100], got '" + v + "'");
    } else if (a == "--min-time") {
      min_time = option_value(args, i, "--min-time");
    } else if (a == "--dashboard-only") {
      dashboard_only = true;
    } else if (a == "--help" || a == "-h") {
      out << "usage: incise bench [--filter RE] [--out DIR] [--bin-dir DIR] [--repetitions N]\n"
             "                    [--min-time SECONDS] [--dashboard-only]\n"
             "Runs the *_bench binaries of the build tree (or --bin-dir), stores their JSON in\n"
             "DIR/runs/<date>_<commit>/ (default DIR: out/bench) and regenerates DIR/index.html.\n"
             "--repetitions (default 3) measures the noise used to flag changes.\n";
      return 0;
    } else {
      throw UsageError("unknown argument '" + a + "' (see incise bench --help)");
    }
  }
  int failures = 0;
  if (!dashboard_only) {
    fs::path root;
    if (!bin_dir.empty()) {
      root = bin_dir;
    } else {
      // <build>/lib/cli/incise → <build>/benchmarks
      const fs::path exe_dir = executable_dir();
      root = exe_dir.parent_path().parent_path() / "benchmarks";
    }
    const auto bins = find_bench_binaries(root);
    if (bins.empty())
      throw UsageError("no *_bench executables under " + root.string() +
                       " (build the benchmarks, e.g. cmake --build --preset release, or pass "
                       "--bin-dir DIR)");
    const std::string commit = git_commit();
    const fs::path run_dir = fs::path(out_dir) / "runs" / (utc_stamp() + "_" + commit);
    fs::create_directories(run_dir);
    out << "bench: " << bins.size() << " binaries under " << root.string() << ", results in "
        << run_dir.string() << "\n";
    for (const auto& b : bins) {
      const fs::path json = run_dir / (b.filename().string() + ".json");
      const fs::path tmp = json.string() + ".tmp";
      std::vector<std::string> argv = {b.string(), "--benchmark_out=" + tmp.string(),
                                       "--benchmark_out_format=json",
                                       "--benchmark_repetitions=" + std::to_string(repetitions)};
      if (!filter.empty()) argv.push_back("--benchmark_filter=" + filter);
      if (!min_time.empty()) argv.push_back("--benchmark_min_time=" + min_time);
      out << "bench: running " << b.filename().string() << std::endl;
      const int rc = run_process(argv);
      std::error_code ec;
      if (rc != 0) {
        ++failures;
        err << "incise bench: " << b.string() << " exited with status " << rc << "\n";
        fs::remove(tmp, ec);
        continue;
      }
      // Keep only files that hold results (a filter may match nothing in a binary).
      certify::BenchRun probe;
      bool has_results = false;
      try {
        std::ifstream in(tmp);
        std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        certify::add_benchmark_json(text, tmp.string(), probe);
        has_results = !probe.values.empty();
      } catch (const ParseError& e) {
        ++failures;
        err << "incise bench: " << e.what() << "\n";
      }
      if (has_results)
        fs::rename(tmp, json);
      else
        fs::remove(tmp, ec);
    }
    std::error_code ec;
    if (fs::is_empty(run_dir, ec)) {
      fs::remove(run_dir, ec);
      err << "incise bench: no benchmark matched; nothing stored\n";
    }
  }
  const auto runs = certify::load_bench_runs((fs::path(out_dir) / "runs").string());
  const certify::DashboardOptions opts;
  write_file_atomic((fs::path(out_dir) / "index.html").string(),
                    certify::dashboard_html(runs, opts));
  const auto cmp = certify::compare_last_two(runs, opts);
  int flagged = 0;
  for (const auto& c : cmp) {
    if (!c.flagged) continue;
    ++flagged;
    out << "bench: changed beyond noise: " << c.key << " " << certify::format_number(c.previous)
        << " -> " << certify::format_number(c.last) << " ("
        << certify::format_number(100 * c.relative_change) << " %)\n";
  }
  out << "bench: " << runs.size() << " stored run(s); " << flagged << " of " << cmp.size()
      << " counters changed beyond noise since the previous run\n";
  out << "bench: dashboard " << (fs::path(out_dir) / "index.html").string() << "\n";
  return failures == 0 ? 0 : 1;
}

}  // namespace incise::cli
