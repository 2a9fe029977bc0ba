// certify::frame_time_svg / frame_plot_path (issue 17, "Output"): the per-frame time plot that
// `incise run` writes beside an interactive cutting run's trace CSV.
#include <incise/certify/frame_plot.hpp>

#include <gtest/gtest.h>

#include <string>

namespace incise::certify {
namespace {

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

scene::CutStepRow row(int step, double cut_ms, double update_ms) {
  scene::CutStepRow r;
  r.step = step;
  r.seconds_cut = 1e-3 * cut_ms;
  r.seconds_update = 1e-3 * update_ms;
  return r;
}

TEST(FramePlot, Issue17OnePointPerStepForCutUpdateAndFrameWithTheBudgetLine) {
  scene::SceneRunResult res;
  res.cut_steps = {row(0, 0, 500), row(1, 2, 10), row(2, 3, 37), row(3, 1, 150)};
  const std::string svg = frame_time_svg(res, "liver");
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u) << "a standalone SVG document";
  EXPECT_NE(svg.find("xmlns=\"http://www.w3.org/2000/svg\""), std::string::npos);
  EXPECT_NE(svg.find("liver (wall time; reported, not asserted)"), std::string::npos);
  // Three steps after the initial solve (step 0 is left out: 500 ms appears nowhere) in three
  // series, and the two ends of the dashed 33 ms line.
  EXPECT_EQ(count(svg, "<circle"), 3u * 3u + 2u);
  EXPECT_EQ(count(svg, "<polyline"), 4u);
  EXPECT_EQ(count(svg, "stroke-dasharray=\"5,3\" points="), 1u);  // the budget line only
  EXPECT_EQ(count(svg, "<title>33 ms budget (30 Hz): "), 2u);
  EXPECT_NE(svg.find("<title>frame = cut + update: 2, 40</title>"), std::string::npos) << svg;
  EXPECT_NE(svg.find("<title>frame = cut + update: 3, 151</title>"), std::string::npos);
  EXPECT_NE(svg.find("<title>cut: 1, 2</title>"), std::string::npos);
  EXPECT_NE(svg.find("<title>solver update (incl. swap): 3, 150</title>"), std::string::npos);
  EXPECT_EQ(svg.find("500"), std::string::npos);
}

TEST(FramePlot, Issue17StepsThatChangeNothingAreDrawnAtTheLogAxisFloor) {
  scene::SceneRunResult res;
  res.cut_steps = {row(0, 0, 20), row(1, 0.5, 1e-5), row(2, 1, 50)};
  const std::string svg = frame_time_svg(res, "cube");
  EXPECT_NE(svg.find("<title>solver update (incl. swap): 1, 0.1</title>"), std::string::npos)
      << svg;
  EXPECT_NE(svg.find("<title>frame = cut + update: 1, 0.5</title>"), std::string::npos);
}

TEST(FramePlot, Issue17NoStepAfterTheInitialSolveIsNoData) {
  scene::SceneRunResult res;
  res.cut_steps = {row(0, 0, 20)};
  const std::string svg = frame_time_svg(res, "cube");
  EXPECT_NE(svg.find("no data"), std::string::npos);
  EXPECT_EQ(count(svg, "<circle"), 0u);
}

TEST(FramePlot, Issue17PlotPathBesideTheCsv) {
  EXPECT_EQ(frame_plot_path("out/trace.csv"), "out/trace_frames.svg");
  EXPECT_EQ(frame_plot_path("trace"), "trace_frames.svg");
  EXPECT_EQ(frame_plot_path("a.csv.txt"), "a.csv.txt_frames.svg");
}

}  // namespace
}  // namespace incise::certify
