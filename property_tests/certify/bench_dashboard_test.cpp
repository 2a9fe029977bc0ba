// Benchmark store and dashboard (`incise bench`), on synthetic Google Benchmark JSON files.

#include <incise/certify/bench_dashboard.hpp>
#include <incise/certify/svg_plot.hpp>
#include <incise/core/error.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

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
  // One trend chart per benchmark and counter.
  std::size_t charts = 0;
  for (std::size_t p = html.find("<svg class=\"incise-plot\""); p != std::string::npos;
       p = html.find("<svg class=\"incise-plot\"", p + 1))
    ++charts;
  EXPECT_EQ(charts, 4u);
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
