// Benchmark store and dashboard (`incise bench`), on synthetic Google Benchmark JSON files.

#include <incise/certify/bench_dashboard.hpp>
#include <incise/certify/svg_plot.hpp>
#include <incise/core/error.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "incise_test/seed.hpp"

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;
using namespace incise::certify;

// Synthetic Google Benchmark output: `reps` repetition entries per benchmark, values spread by
// ±spread around `mean` (deterministic), plus a user counter FLOP/s = 1e9 / time.
Json gbench(const std::vector<std::pair<std::string, double>>& means, int reps, double spread) {
  Json j;
  j["context"] = {{"date", "2026-11-27T03:00:00+00:00"},
                  {"num_cpus", 2},
                  {"incise_cpu", "Synthetic CPU"},
                  {"incise_blas", "/usr/lib/libblas.so.3"}};
  j["benchmarks"] = Json::array();
  for (const auto& [name, mean] : means) {
    for (int r = 0; r < reps; ++r) {
      const double t = mean + spread * (reps > 1 ? (2.0 * r / (reps - 1) - 1.0) : 0.0);
      j["benchmarks"].push_back({{"name", name},
                                 {"run_name", name},
                                 {"run_type", "iteration"},
                                 {"repetitions", reps},
                                 {"repetition_index", r},
                                 {"iterations", 1000},
                                 {"real_time", t},
                                 {"cpu_time", t},
                                 {"time_unit", "us"},
                                 {"FLOP/s", 1e9 / t}});
    }
  }
  return j;
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

void write(const fs::path& p, const Json& j) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << j.dump(1);
}

class BenchStore : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        fs::temp_directory_path() /
        ("incise_bench_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
         "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(BenchStore, RepetitionNoiseDecidesFlags) {
  // Three runs of two benchmarks with 5 repetitions (spread ±1 us around 100 us). In the last
  // run BM_Slow got 20 % slower (far beyond noise) and BM_Steady moved by 0.1 us (within noise).
  write(dir_ / "runs/20261125T000000Z_aaaaaaa/fem_bench.json",
        gbench({{"BM_Slow", 100}, {"BM_Steady", 100}}, 5, 1.0));
  write(dir_ / "runs/20261126T000000Z_bbbbbbb/fem_bench.json",
        gbench({{"BM_Slow", 100}, {"BM_Steady", 100}}, 5, 1.0));
  write(dir_ / "runs/20261127T000000Z_ccccccc/fem_bench.json",
        gbench({{"BM_Slow", 120}, {"BM_Steady", 100.1}}, 5, 1.0));
  const auto runs = load_bench_runs((dir_ / "runs").string());
  ASSERT_EQ(runs.size(), 3u);
  EXPECT_EQ(runs[2].commit, "ccccccc");
  EXPECT_EQ(runs[2].context.at("incise_cpu"), "Synthetic CPU");
  const BenchValue& v = runs[0].values.at("BM_Slow | cpu_time (ns)");
  EXPECT_EQ(v.repetitions, 5);
  EXPECT_NEAR(v.value, 100e3, 1e-9);  // us → ns; exact arithmetic on small integers
  EXPECT_GT(v.stddev, 0.0);

  const auto cmp = compare_last_two(runs, DashboardOptions{});
  ASSERT_EQ(cmp.size(), 4u);  // 2 benchmarks × (time, FLOP/s)
  for (const auto& c : cmp) {
    SCOPED_TRACE(c.key);
    EXPECT_TRUE(c.measured_noise);
    EXPECT_EQ(c.flagged, c.key.rfind("BM_Slow", 0) == 0);
  }
  const std::string html = dashboard_html(runs, DashboardOptions{});
  EXPECT_NE(html.find("2 of 4 counters changed beyond noise"), std::string::npos);
  EXPECT_NE(html.find("regression"), std::string::npos);
  // One small chart per benchmark: FLOP/s = 1e9/time is the time chart's caption, not a chart.
  EXPECT_EQ(count(html, "<svg class=\"incise-plot\""), 2u);
  EXPECT_NE(html.find("Synthetic CPU"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);  // static page, no JS
}

TEST_F(BenchStore, DefaultNoiseWithoutRepetitions) {
  // Single repetition: the stated default (5 %) decides. +3 % stays, +10 % is flagged.
  write(dir_ / "runs/20261126T000000Z_aaaaaaa/a_bench.json",
        gbench({{"BM_A", 100}, {"BM_B", 100}}, 1, 0));
  write(dir_ / "runs/20261127T000000Z_bbbbbbb/a_bench.json",
        gbench({{"BM_A", 103}, {"BM_B", 110}}, 1, 0));
  const auto runs = load_bench_runs((dir_ / "runs").string());
  const auto cmp = compare_last_two(runs, DashboardOptions{});
  for (const auto& c : cmp) {
    SCOPED_TRACE(c.key);
    EXPECT_FALSE(c.measured_noise);
    EXPECT_DOUBLE_EQ(c.threshold, 0.05);
    EXPECT_EQ(c.flagged, c.key.rfind("BM_B", 0) == 0);
  }
}

TEST_F(BenchStore, AggregatesOnlyOutput) {
  Json j;
  j["benchmarks"] = {{{"name", "BM_X_mean"},
                      {"run_name", "BM_X"},
                      {"run_type", "aggregate"},
                      {"aggregate_name", "mean"},
                      {"repetitions", 3},
                      {"cpu_time", 10.0},
                      {"time_unit", "ns"},
                      {"items_per_second", 1e8}},
                     {{"name", "BM_X_stddev"},
                      {"run_name", "BM_X"},
                      {"run_type", "aggregate"},
                      {"aggregate_name", "stddev"},
                      {"repetitions", 3},
                      {"cpu_time", 0.5},
                      {"time_unit", "ns"},
                      {"items_per_second", 1e6}}};
  BenchRun run;
  add_benchmark_json(j.dump(), "x.json", run);
  const BenchValue& v = run.values.at("BM_X | items_per_second");
  EXPECT_DOUBLE_EQ(v.value, 1e8);
  EXPECT_DOUBLE_EQ(v.stddev, 1e6);
  EXPECT_EQ(v.repetitions, 3);
}

TEST_F(BenchStore, RejectsNonBenchmarkJson) {
  BenchRun run;
  EXPECT_THROW(add_benchmark_json("{\"foo\": 1}", "x.json", run), incise::ParseError);
  EXPECT_THROW(add_benchmark_json("{not json", "x.json", run), incise::ParseError);
}

TEST_F(BenchStore, EmptyStoreGivesAPage) {
  const std::string html = dashboard_html(load_bench_runs((dir_ / "runs").string()), {});
  EXPECT_NE(html.find("No runs stored yet"), std::string::npos);
}

TEST_F(BenchStore, ConstantCountersAreTabledNotTrended) {
  // Two runs; per benchmark: time varies, FLOP/s = 1e9/time (a rate from time), flops_per_tet
  // = 281 everywhere (constant), and noise_counter varies independently of time.
  auto with_counters = [](Json j, double noise) {
    for (auto& b : j["benchmarks"]) {
      b["flops_per_tet"] = 281;
      b["noise_counter"] = noise + b["repetition_index"].get<int>();
    }
    return j;
  };
  write(dir_ / "runs/20261126T000000Z_aaaaaaa/fem_bench.json",
        with_counters(gbench({{"Element/a", 100}, {"Element/b", 50}}, 3, 1.0), 1.0));
  write(dir_ / "runs/20261127T000000Z_bbbbbbb/fem_bench.json",
        with_counters(gbench({{"Element/a", 101}, {"Element/b", 50}}, 3, 2.0), 5.0));
  const auto runs = load_bench_runs((dir_ / "runs").string());
  const auto display = classify_counters(runs);
  ASSERT_EQ(display.size(), 8u);  // 2 benchmarks × (time, FLOP/s, flops_per_tet, noise_counter)
  for (const char* b : {"Element/a", "Element/b"}) {
    SCOPED_TRACE(b);
    const std::string k = std::string(b) + " | ";
    EXPECT_EQ(display.at(k + "cpu_time (ns)"), CounterDisplay::kTrend);
    EXPECT_EQ(display.at(k + "FLOP/s"), CounterDisplay::kFromTime);
    EXPECT_EQ(display.at(k + "flops_per_tet"), CounterDisplay::kConstant);
    EXPECT_EQ(display.at(k + "noise_counter"), CounterDisplay::kTrend);
  }
  const std::string html = dashboard_html(runs, DashboardOptions{});
  EXPECT_EQ(count(html, "<svg class=\"incise-plot\""), 4u);  // time and noise_counter, ×2
  EXPECT_EQ(count(html, "<figure class=\"trend\">"), 4u);
  // The constant counter: listed once per benchmark in the module's table, never charted.
  EXPECT_NE(html.find("2 constant counters of fem_bench"), std::string::npos);
  const auto table = html.find("<table class=\"constant\">");
  ASSERT_NE(table, std::string::npos);
  EXPECT_EQ(count(html.substr(table, html.find("</table>", table) - table),
                  "<td>flops_per_tet</td><td>281</td>"),
            2u);
  EXPECT_EQ(html.find("aria-label=\"Element/a | flops_per_tet\""), std::string::npos);
  EXPECT_NE(html.find("aria-label=\"Element/a | noise_counter\""), std::string::npos);
  // A counter that is constant within each run but differs between runs is trended.
  write(dir_ / "runs/20261128T000000Z_ccccccc/fem_bench.json",
        with_counters(gbench({{"Element/a", 100}}, 1, 0.0), 1.0));
  auto j = gbench({{"Element/a", 100}}, 1, 0.0);
  j["benchmarks"][0]["flops_per_tet"] = 282;
  write(dir_ / "runs/20261129T000000Z_ddddddd/fem_bench.json", j);
  EXPECT_EQ(
      classify_counters(load_bench_runs((dir_ / "runs").string())).at("Element/a | flops_per_tet"),
      CounterDisplay::kTrend);
}

TEST(BenchUnits, CountersInHumanUnits) {
  // The examples: 3.6e7 ns and MFLOP_per_s = 7440 (Google Benchmark's console wrote
  // "MFLOP_per_s=7.44k/s").
  const CounterUnit t = counter_unit("cpu_time (ns)");
  EXPECT_EQ(format_si(3.6e7 * t.scale, t.unit), "36.0 ms");
  EXPECT_EQ(format_si(99.495e3 * t.scale, t.unit), "99.5 \xC2\xB5s");
  EXPECT_EQ(format_si(1.5 * t.scale, t.unit), "1.50 ns");
  EXPECT_EQ(format_si(2.5, "s"), "2.50 s");
  const CounterUnit f = counter_unit("MFLOP_per_s");
  EXPECT_EQ(f.label, "MFLOP/s");
  EXPECT_EQ(f.unit, "FLOP/s");
  EXPECT_EQ(format_si(7440 * f.scale, f.unit), "7.44 GFLOP/s");
  const CounterUnit tets = counter_unit("tets_per_s");
  EXPECT_EQ(tets.label, "tets/s");
  EXPECT_EQ(format_si(1.9e7 * tets.scale, tets.unit), "19.0 M/s");
  EXPECT_EQ(format_si(12.3, tets.unit), "12.3/s");
  EXPECT_EQ(counter_unit("items_per_second").label, "items/s");
  EXPECT_EQ(format_si(2.77e7, counter_unit("bytes_per_second").unit), "27.7 MB/s");
  const CounterUnit pct = counter_unit("pct_vector_add");
  EXPECT_EQ(pct.label, "% of vector add");
  EXPECT_EQ(format_si(82.91, pct.unit), "82.9 %");
  EXPECT_EQ(format_si(1234.4, pct.unit), "1234 %");  // no prefix on percentages
  const CounterUnit mb = counter_unit("MB_L_values");
  EXPECT_EQ(format_si(12.5 * mb.scale, mb.unit), "12.5 MB");
  EXPECT_EQ(format_si(3.0 * counter_unit("MFlop_factor").scale, "FLOP"), "3.00 MFLOP");
  EXPECT_EQ(counter_unit("update_Hz").unit, "Hz");
  EXPECT_EQ(counter_unit("nnz_L").unit, "");
  EXPECT_EQ(format_si(1.2e6, ""), "1.20 M");
  EXPECT_EQ(format_si(999.96, ""), "1.00 k");  // rounding carries into the next prefix
  EXPECT_EQ(format_si(281, ""), "281");
  EXPECT_EQ(format_si(9.996, ""), "10.0");
  EXPECT_EQ(format_si(99.96, ""), "100");
  EXPECT_EQ(format_si(0.35, ""), "0.35");  // small plain numbers get no milli prefix
  EXPECT_EQ(format_si(-0.0123, "s"), "-12.3 ms");
  EXPECT_EQ(format_si(0.0, "s"), "0 s");
}

TEST_F(BenchStore, DashboardShowsHumanUnitsNotRawValuesOrRatesOfRates) {
  auto j = gbench({{"Assembly/linear", 36000}}, 3, 100.0);  // 36 ms in us
  for (auto& b : j["benchmarks"]) b["MFLOP_per_s"] = 7440.0 * 36000 / b["cpu_time"].get<double>();
  write(dir_ / "runs/20261126T000000Z_aaaaaaa/fem_bench.json", j);
  const std::string html = dashboard_html(load_bench_runs((dir_ / "runs").string()), {});
  EXPECT_NE(html.find("CPU time 36.0 ms (35.9 ms \xE2\x80\x93 36.1 ms)"), std::string::npos);
  EXPECT_NE(html.find("MFLOP/s 7.44 GFLOP/s"), std::string::npos);
  EXPECT_EQ(html.find("_per_s"), std::string::npos);
  EXPECT_EQ(html.find("e+0"), std::string::npos);  // no raw scientific values
}

TEST_F(BenchStore, BandFromRepetitions) {
  // Five repetitions 100 ± 1 us (99, 99.5, 100, 100.5, 101): median 100 us, band 99..101 us.
  write(dir_ / "runs/20261126T000000Z_aaaaaaa/fem_bench.json", gbench({{"BM_X", 100}}, 5, 1.0));
  const auto runs = load_bench_runs((dir_ / "runs").string());
  const BenchValue& v = runs[0].values.at("BM_X | cpu_time (ns)");
  EXPECT_EQ(v.samples.size(), 5u);
  EXPECT_DOUBLE_EQ(v.median, 100e3);
  EXPECT_DOUBLE_EQ(v.min, 99e3);
  EXPECT_DOUBLE_EQ(v.max, 101e3);
  EXPECT_EQ(v.module, "fem_bench");
  const std::string html = dashboard_html(runs, {});
  EXPECT_EQ(count(html, "<polygon class=\"band\""), 1u);
  EXPECT_NE(html.find("CPU time 100 \xC2\xB5s (99.0 \xC2\xB5s \xE2\x80\x93 101 \xC2\xB5s)"),
            std::string::npos);
  // Even number of repetitions: the median is the mean of the middle two (as Google
  // Benchmark's "median" aggregate): 99, 99+2/3, 100+1/3, 101 → 100.
  BenchRun even;
  add_benchmark_json(gbench({{"BM_Y", 100}}, 4, 1.0).dump(), "y_bench.json", even);
  EXPECT_NEAR(even.values.at("BM_Y | cpu_time (ns)").median, 100e3, 1e-9);
  // Aggregates only: the median row is the median, min/max unknown (no band).
  Json j;
  j["benchmarks"] = {{{"name", "BM_Z_mean"},
                      {"run_name", "BM_Z"},
                      {"run_type", "aggregate"},
                      {"aggregate_name", "mean"},
                      {"repetitions", 3},
                      {"cpu_time", 10.0},
                      {"time_unit", "ns"}},
                     {{"name", "BM_Z_median"},
                      {"run_name", "BM_Z"},
                      {"run_type", "aggregate"},
                      {"aggregate_name", "median"},
                      {"repetitions", 3},
                      {"cpu_time", 9.5},
                      {"time_unit", "ns"}}};
  BenchRun agg;
  add_benchmark_json(j.dump(), "z_bench.json", agg);
  const BenchValue& z = agg.values.at("BM_Z | cpu_time (ns)");
  EXPECT_DOUBLE_EQ(z.value, 10.0);
  EXPECT_DOUBLE_EQ(z.median, 9.5);
  EXPECT_TRUE(std::isnan(z.min) && std::isnan(z.max));
}

TEST_F(BenchStore, TwoRunsOfOneCommitAreLabelledDistinctly) {
  write(dir_ / "runs/20261202T142727Z_8decf77/a_bench.json", gbench({{"BM_A", 100}}, 1, 0));
  write(dir_ / "runs/20261202T143510Z_8decf77/a_bench.json", gbench({{"BM_A", 100}}, 1, 0));
  auto runs = load_bench_runs((dir_ / "runs").string());
  EXPECT_EQ(run_labels(runs), (std::vector<std::string>{"2026-12-02 14:27", "2026-12-02 14:35"}));
  const std::string html = dashboard_html(runs, {});
  EXPECT_NE(html.find("<th>2026-12-02 14:27</th><th>2026-12-02 14:35</th>"), std::string::npos);
  // Same minute: seconds added to those two only; same second (other commit): the folder name.
  write(dir_ / "runs/20261202T143559Z_8decf77/a_bench.json", gbench({{"BM_A", 100}}, 1, 0));
  write(dir_ / "runs/20261202T143559Z_9abcdef/a_bench.json", gbench({{"BM_A", 100}}, 1, 0));
  runs = load_bench_runs((dir_ / "runs").string());
  EXPECT_EQ(run_labels(runs),
            (std::vector<std::string>{"2026-12-02 14:27", "2026-12-02 14:35:10",
                                      "20261202T143559Z_8decf77", "20261202T143559Z_9abcdef"}));
}

TEST_F(BenchStore, EnvironmentOfEveryRunIsTabled) {
  auto j1 = gbench({{"BM_A", 100}}, 1, 0);
  j1["context"]["incise_compiler"] = "g++ 12.2.0";
  j1["context"]["incise_blas"] = "/usr/lib/openblas/libblas.so.3";
  auto j2 = j1;
  j2["context"]["incise_compiler"] = "clang 14";
  auto j3 = j2;
  j3["context"]["incise_blas"] = "none loaded";
  write(dir_ / "runs/20261126T000000Z_aaaaaaa/a_bench.json", j1);
  write(dir_ / "runs/20261127T000000Z_bbbbbbb/a_bench.json", j2);
  write(dir_ / "runs/20261127T000000Z_bbbbbbb/b_bench.json", j3);
  const auto runs = load_bench_runs((dir_ / "runs").string());
  // Values that differ between the binaries of one run name them.
  EXPECT_EQ(runs[1].context.at("incise_blas"),
            "/usr/lib/openblas/libblas.so.3 (a_bench); none loaded (b_bench)");
  EXPECT_EQ(runs[1].context.at("num_cpus"), "2");  // the same in both binaries
  // Numbers measured by each process: their range.
  auto j4 = j3;
  j4["context"]["incise_vector_add_mflops"] = "6450.5";
  j3["context"]["incise_vector_add_mflops"] = "6847";
  BenchRun mixed;
  add_benchmark_json(j3.dump(), "x_bench.json", mixed);
  add_benchmark_json(j4.dump(), "y_bench.json", mixed);
  EXPECT_EQ(mixed.context.at("incise_vector_add_mflops"), "6450.5 \xE2\x80\x93 6847 (2 binaries)");
  const std::string html = dashboard_html(runs, {});
  EXPECT_NE(html.find("<tr><th>incise_compiler</th><td>g++ 12.2.0</td>"
                      "<td class=\"changed\">clang 14</td></tr>"),
            std::string::npos);
}

TEST(BenchFilter, ValidatedAsGoogleBenchmarkReadsIt) {
  for (const char* ok : {"", "all", "BM_.*", "-Element", "Element/(linear|neohookean)/force$",
                         "^Material/[a-z]+/stress\\+derivative$"})
    EXPECT_NO_THROW(validate_benchmark_filter(ok)) << ok;
  for (const char* bad : {"(", "[", "a{2,1}", "-", "-(", "Element/(linear"}) {
    SCOPED_TRACE(bad);
    try {
      validate_benchmark_filter(bad);
      ADD_FAILURE() << "accepted";
    } catch (const incise::UsageError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("--filter '") + bad + "'"),
                std::string::npos)
          << e.what();
    }
  }
}

TEST(SvgPlot, IncludeZeroAndBand) {
  // 100 and 101 on an axis from zero: a tick at 0, the 1 % step ≤ 1 % of the plot height.
  Series s{"", {0, 1}, {100, 101}, {}, false};
  s.band_lo = {99, 100};
  s.band_hi = {101, 102};
  PlotOptions o;
  o.include_zero = true;
  o.compact = true;
  o.y_format = [](double v) { return format_si(v, "s"); };
  const std::string svg = svg_line_plot({s}, o);
  EXPECT_NE(svg.find(">0 s</text>"), std::string::npos);
  EXPECT_EQ(count(svg, "<polygon class=\"band\""), 1u);
  o.include_zero = false;
  EXPECT_EQ(svg_line_plot({s}, o).find(">0 s</text>"), std::string::npos);
}

TEST(SvgPlot, LogAxesSkipNonPositiveAndEscapeText) {
  Series s{"a<b", {1, 10, 100, -1}, {1e-3, 1e-5, 0.0, 1}, {}, false};
  PlotOptions o;
  o.title = "x & y";
  o.log_x = o.log_y = true;
  const std::string svg = svg_line_plot({s}, o);
  EXPECT_NE(svg.find("x &amp; y"), std::string::npos);
  EXPECT_NE(svg.find("a&lt;b"), std::string::npos);
  std::size_t circles = 0;
  for (std::size_t p = svg.find("<circle"); p != std::string::npos; p = svg.find("<circle", p + 1))
    ++circles;
  EXPECT_EQ(circles, 2u);  // (100, 0) and (−1, 1) are not plottable on log axes
  EXPECT_NE(svg_line_plot({}, o).find("no data"), std::string::npos);
}

}  // namespace
