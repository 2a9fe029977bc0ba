// `incise bench [--filter RE] [--out DIR] [--bin-dir DIR] [--repetitions N] [--min-time S]
//               [--dashboard-only] [--compare RUN_A RUN_B]`: runs the Google Benchmark binaries
// (`*_bench` under the build tree's benchmarks/ folder, found next to this executable, or under
// --bin-dir) whose benchmarks match RE, stores their JSON under
// DIR/runs/<UTC date>_<commit>/<binary>.json and regenerates the static dashboard DIR/index.html
// (certify/bench_dashboard.hpp). --compare hands two stored runs to Google Benchmark's own
// compare.py (Debian libbenchmark-tools), binary by binary. Exit status (cli_util.hpp Exit): 0 ok;
// 1 a binary or compare.py failed, a run, binary or tool not found; 2 usage (an invalid --filter
// or one that selects no benchmark included). docs/scenes.md, "incise bench".

#include <incise/certify/bench_dashboard.hpp>
#include <incise/certify/svg_plot.hpp>
#include <incise/core/error.hpp>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <thread>

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

/// Runs argv (looked up on PATH when it has no '/') with inherited stdout/stderr, or with its
/// stdout captured into `*captured` (and stderr discarded when `quiet`); returns the exit status
/// (−1 when it cannot start).
int run_process(const std::vector<std::string>& argv, std::string* captured = nullptr,
                bool quiet = false) {
  std::vector<char*> cargv;
  for (const auto& a : argv) cargv.push_back(const_cast<char*>(a.c_str()));
  cargv.push_back(nullptr);
  int fds[2] = {-1, -1};
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (captured) {
    if (pipe(fds) != 0) return -1;
    posix_spawn_file_actions_adddup2(&actions, fds[1], STDOUT_FILENO);
    posix_spawn_file_actions_addclose(&actions, fds[0]);
    posix_spawn_file_actions_addclose(&actions, fds[1]);
  }
  if (quiet) posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  pid_t pid;
  const int spawned = posix_spawnp(&pid, cargv[0], &actions, nullptr, cargv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (captured) {
    close(fds[1]);
    if (spawned == 0) {
      char buf[4096];
      ssize_t n;
      while ((n = read(fds[0], buf, sizeof buf)) > 0) captured->append(buf, static_cast<size_t>(n));
    }
    close(fds[0]);
  }
  if (spawned != 0) return -1;
  int status = 0;
  if (waitpid(pid, &status, 0) < 0) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/// Names of the benchmarks of `binary` that `filter` selects (Google Benchmark's own
/// --benchmark_list_tests, so the binary's regex engine decides); rc = the binary's exit status.
std::vector<std::string> list_benchmarks(const fs::path& binary, const std::string& filter,
                                         int& rc) {
  std::vector<std::string> argv = {binary.string(), "--benchmark_list_tests=true"};
  if (!filter.empty()) argv.push_back("--benchmark_filter=" + filter);
  std::string text;
  rc = run_process(argv, &text, true);
  std::vector<std::string> names;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) names.push_back(line);
  return names;
}

/// A stored run folder: an existing folder, a folder name under `runs`, "last" / "previous", or
/// a prefix of exactly one folder name. Throws ParseError naming the argument and what it
/// expected (exit 1).
fs::path resolve_run(const std::string& arg, const fs::path& runs) {
  std::error_code ec;
  if (fs::is_directory(arg, ec)) return arg;
  if (fs::is_directory(runs / arg, ec)) return runs / arg;
  std::vector<fs::path> all;
  if (fs::is_directory(runs, ec))
    for (const auto& e : fs::directory_iterator(runs))
      if (e.is_directory()) all.push_back(e.path());
  std::sort(all.begin(), all.end());
  if (arg == "last" && !all.empty()) return all.back();
  if (arg == "previous" && all.size() >= 2) return all[all.size() - 2];
  std::vector<fs::path> hits;
  for (const auto& p : all)
    if (p.filename().string().compare(0, arg.size(), arg) == 0) hits.push_back(p);
  if (hits.size() == 1) return hits[0];
  throw ParseError(arg, 0,
                   hits.empty() ? "no stored run of that name under " + runs.string() +
                                      " (expected a run folder, its name, a unique prefix of it, "
                                      "'last' or 'previous'; " +
                                      std::to_string(all.size()) + " runs stored)"
                                : "prefix of " + std::to_string(hits.size()) + " runs under " +
                                      runs.string() + "; give more of the name");
}

/// `--compare A B`: Google Benchmark's compare.py on each binary's JSON present in both runs.
int compare_runs(const std::string& a, const std::string& b, const fs::path& runs,
                 std::ostream& out, std::ostream& info, std::ostream& err) {
  const fs::path ra = resolve_run(a, runs), rb = resolve_run(b, runs);
  std::error_code ec;
  std::string tool = "/usr/share/benchmark/compare.py";  // Debian libbenchmark-tools
  const char* env_tool = std::getenv("INCISE_COMPARE_PY");
  if (env_tool && *env_tool) {
    if (!fs::is_regular_file(env_tool, ec)) {
      err << "incise bench: INCISE_COMPARE_PY=" << env_tool
          << ": no such file (expected the path of Google Benchmark's compare.py)\n";
      return exit_code(Exit::kBadInput);
    }
    tool = env_tool;
  } else if (!fs::is_regular_file(tool, ec)) {
    err << "incise bench: Google Benchmark's compare.py not found at " << tool
        << ": install the Debian package libbenchmark-tools, or set INCISE_COMPARE_PY to the "
           "path of compare.py\n";
    return exit_code(Exit::kBadInput);
  }
  std::vector<std::string> tried;
  // compare.py imports scipy.stats (Mann-Whitney U test) and numpy (gbench/report.py).
  std::string python;
  tried.clear();
  const char* env_python = std::getenv("INCISE_PYTHON");
  for (const std::string& c : {std::string(env_python ? env_python : ""), std::string("python3"),
                               std::string("/usr/bin/python3")}) {
    if (c.empty()) continue;
    tried.push_back(c);
    std::string ignored;
    if (run_process({c, "-c", "import scipy.stats, numpy"}, &ignored, true) == 0) {
      python = c;
      break;
    }
  }
  if (python.empty()) {
    std::string list;
    for (const auto& t : tried) list += (list.empty() ? "" : ", ") + t;
    err << "incise bench: compare.py needs Python 3 with scipy and numpy (its U test); none of "
        << list << " imports them: install the Debian packages python3-scipy python3-numpy, or "
        << "set INCISE_PYTHON to a python that has them\n";
    return exit_code(Exit::kBadInput);
  }
  std::vector<std::string> files_a, files_b;
  for (const auto& [dir, files] : {std::pair{ra, &files_a}, std::pair{rb, &files_b}}) {
    for (const auto& e : fs::directory_iterator(dir))
      if (e.is_regular_file() && e.path().extension() == ".json")
        files->push_back(e.path().filename().string());
    std::sort(files->begin(), files->end());
  }
  int failures = 0, compared = 0;
  for (const auto& f : files_a) {
    if (!std::binary_search(files_b.begin(), files_b.end(), f)) {
      out << "bench: " << f << " only in " << ra.string() << "; not compared\n";
      continue;
    }
    info << "bench: compare.py " << f << ": " << ra.filename().string() << " (baseline) vs "
         << rb.filename().string() << " (contender)" << std::endl;
    std::vector<std::string> argv = {python, tool};
    if (!isatty(STDOUT_FILENO)) argv.push_back("--no-color");
    for (const std::string& x : {std::string("benchmarks"), (ra / f).string(), (rb / f).string()})
      argv.push_back(x);
    const int rc = run_process(argv);
    ++compared;
    if (rc != 0) {
      ++failures;
      err << "incise bench: compare.py exited with status " << rc << " on " << f << "\n";
    }
  }
  for (const auto& f : files_b)
    if (!std::binary_search(files_a.begin(), files_a.end(), f))
      out << "bench: " << f << " only in " << rb.string() << "; not compared\n";
  if (compared == 0) {
    err << "incise bench: the runs " << ra.string() << " and " << rb.string()
        << " have no benchmark binary in common\n";
    return exit_code(Exit::kBadInput);
  }
  return exit_code(failures == 0 ? Exit::kOk : Exit::kBadInput);
}

std::string utc_stamp() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%dT%H%M%SZ", &tm);
  return buf;
}

struct BenchOptions {
  std::string filter, out_dir = "out/bench", bin_dir, repetitions = "3", min_time;
  std::vector<std::string> compare;  // two runs, or empty
  bool dashboard_only = false;
};

int bench_command(BenchOptions& opt, Context& ctx) {
  reject_extras(ctx.extras, "bench", [](const std::string& a) {
    return "unknown argument '" + a + "' (see incise bench --help)";
  });
  std::ostream& out = ctx.out;
  std::ostream& err = ctx.log.error();
  std::ostream& info = ctx.log.info();
  const std::string& filter = opt.filter;
  const std::string& out_dir = opt.out_dir;
  const std::string& bin_dir = opt.bin_dir;
  const std::string& min_time = opt.min_time;
  const bool dashboard_only = opt.dashboard_only, compare = !opt.compare.empty();
  int repetitions = 0;
  try {
    std::size_t used = 0;
    repetitions = std::stoi(opt.repetitions, &used);
    if (used != opt.repetitions.size()) repetitions = 0;
  } catch (const std::exception&) {
    repetitions = 0;
  }
  if (repetitions < 1 || repetitions > 100)
    throw CommandLineError("--repetitions expects an integer in [1, 100], got '" + opt.repetitions +
                           "'");
  try {
    certify::validate_benchmark_filter(filter);
  } catch (const UsageError& e) {
    throw CommandLineError(e.what());
  }
  if (compare && (dashboard_only || !filter.empty()))
    throw CommandLineError(
        "--compare takes no --filter or --dashboard-only (see incise bench "
        "--help)");
  if (compare)
    return compare_runs(opt.compare[0], opt.compare[1], fs::path(out_dir) / "runs", out, info, err);
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
      throw BadInputError("no *_bench executables under " + root.string() +
                          " (build the benchmarks, e.g. cmake --build --preset release, or pass "
                          "--bin-dir DIR)");
    // Ask each binary which of its benchmarks the filter selects; skip those with none.
    std::vector<std::pair<fs::path, std::size_t>> selected;
    std::size_t matched = 0;
    for (const auto& b : bins) {
      int rc = 0;
      const auto names = list_benchmarks(b, filter, rc);
      if (rc != 0) {
        ++failures;
        err << "incise bench: " << b.string() << " --benchmark_list_tests exited with status " << rc
            << "\n";
        continue;
      }
      if (names.empty()) continue;
      selected.emplace_back(b, names.size());
      matched += names.size();
    }
    if (matched == 0)
      throw CommandLineError(
          "no benchmark matches " +
          (filter.empty() ? std::string("(no --filter)") : "--filter '" + filter + "'") +
          " in the " + std::to_string(bins.size()) + " binaries under " + root.string() +
          "; nothing run or stored");
    const std::string commit = git_commit();
    // One folder per invocation: a second run within the same second waits for the next one.
    fs::path run_dir = fs::path(out_dir) / "runs" / (utc_stamp() + "_" + commit);
    for (std::error_code ec; fs::exists(run_dir, ec);) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      run_dir = fs::path(out_dir) / "runs" / (utc_stamp() + "_" + commit);
    }
    fs::create_directories(run_dir);
    out << "bench: " << matched << " benchmarks in " << selected.size() << " of " << bins.size()
        << " binaries under " << root.string() << ", results in " << run_dir.string() << "\n";
    for (const auto& [b, count] : selected) {
      const fs::path json = run_dir / (b.filename().string() + ".json");
      const fs::path tmp = json.string() + ".tmp";
      std::vector<std::string> argv = {b.string(), "--benchmark_out=" + tmp.string(),
                                       "--benchmark_out_format=json",
                                       "--benchmark_repetitions=" + std::to_string(repetitions)};
      if (!filter.empty()) argv.push_back("--benchmark_filter=" + filter);
      if (!min_time.empty()) argv.push_back("--benchmark_min_time=" + min_time);
      info << "bench: running " << b.filename().string() << " (" << count << " benchmarks)"
           << std::endl;
      const int rc = run_process(argv);
      std::error_code ec;
      if (rc != 0) {
        ++failures;
        err << "incise bench: " << b.string() << " exited with status " << rc << "\n";
        fs::remove(tmp, ec);
        continue;
      }
      try {
        std::ifstream in(tmp);
        std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        certify::BenchRun probe;
        certify::add_benchmark_json(text, json.string(), probe);
        fs::rename(tmp, json);
      } catch (const ParseError& e) {
        ++failures;
        err << "incise bench: " << b.string() << " wrote no usable result: " << e.what() << "\n";
        fs::remove(tmp, ec);
      }
    }
    std::error_code ec;
    if (fs::is_empty(run_dir, ec)) fs::remove(run_dir, ec);
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
    const auto u = certify::counter_unit(c.key.substr(c.key.rfind(" | ") + 3));
    out << "bench: changed beyond noise: " << c.key.substr(0, c.key.rfind(" | ")) << " " << u.label
        << " " << certify::format_si(c.previous * u.scale, u.unit) << " -> "
        << certify::format_si(c.last * u.scale, u.unit) << " ("
        << (c.relative_change >= 0 ? "+" : "") << certify::format_number(100 * c.relative_change)
        << " %)\n";
  }
  out << "bench: " << runs.size() << " stored run(s); " << flagged << " of " << cmp.size()
      << " counters changed beyond noise since the previous run\n";
  out << "bench: dashboard " << (fs::path(out_dir) / "index.html").string() << "\n";
  return exit_code(failures == 0 ? Exit::kOk : Exit::kBadInput);
}

}  // namespace

Command add_bench_command(CLI::App& root) {
  auto opt = std::make_shared<BenchOptions>();
  CLI::App* app = root.add_subcommand(
      "bench", "run the benchmarks, update the dashboard; or --compare two stored runs");
  app->add_option("--filter", opt->filter,
                  "run the benchmarks matching RE (Google Benchmark's --benchmark_filter: POSIX "
                  "extended regex, '-' negates); binaries with none are skipped")
      ->type_name("RE");
  app->add_option("--out", opt->out_dir,
                  "store the JSON in DIR/runs/<date>_<commit>/, the dashboard in DIR/index.html")
      ->type_name("DIR")
      ->capture_default_str();
  app->add_option("--bin-dir", opt->bin_dir,
                  "where the *_bench binaries are (default: the build tree's benchmarks/)")
      ->type_name("DIR");
  app->add_option("--repetitions", opt->repetitions, "repetitions of each benchmark (the noise)")
      ->type_name("N")
      ->capture_default_str();
  app->add_option("--min-time", opt->min_time, "Google Benchmark's --benchmark_min_time")
      ->type_name("SECONDS");
  app->add_flag("--dashboard-only", opt->dashboard_only,
                "only regenerate the dashboard from the stored runs");
  app->add_option("--compare", opt->compare,
                  "Google Benchmark's compare.py (Debian libbenchmark-tools, U test needs "
                  "python3-scipy) on the JSON of two stored runs: a run folder, its name under "
                  "DIR/runs, a unique prefix, 'last' or 'previous'")
      ->type_name("RUN_A RUN_B")
      ->expected(2);
  return {app, [opt](Context& ctx) { return bench_command(*opt, ctx); }};
}

}  // namespace incise::cli
