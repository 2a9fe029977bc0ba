/// Sweep files (io/sweep_file.hpp): what `incise cut` and scripted cuts read. Valid files give
/// the events in order with the scale applied; every malformed line is a ParseError with the
/// file and the line.
#include <incise/core/error.hpp>
#include <incise/io/sweep_file.hpp>

#include <gtest/gtest.h>

#include "io_test_util.hpp"

namespace incise::io {
namespace {

using test::write_temp;

TEST(SweepFile, ReadsTrianglesEndsAndCommentsInOrderWithTheScale) {
  const std::string p = write_temp("sweep_ok.txt",
                                   "# header comment\n"
                                   "\n"
                                   "0 0 0  1 0 0  0 1 0   # first triangle\n"
                                   "end\n"
                                   "1 2 3 4 5 6 7 8 9\n");
  const std::vector<SweepEvent> ev = read_sweep_file(p, 0.5);
  ASSERT_EQ(ev.size(), 3u);
  EXPECT_FALSE(ev[0].end_incision);
  EXPECT_EQ(ev[0].line, 3);
  EXPECT_EQ(ev[0].triangle[1], Vec3(0.5, 0, 0));
  EXPECT_EQ(ev[0].triangle[2], Vec3(0, 0.5, 0));
  EXPECT_TRUE(ev[1].end_incision);
  EXPECT_EQ(ev[1].line, 4);
  EXPECT_EQ(ev[2].triangle[0], Vec3(0.5, 1.0, 1.5));  // exact: halving is exact in binary
  EXPECT_EQ(ev[2].triangle[2], Vec3(3.5, 4.0, 4.5));
  EXPECT_TRUE(read_sweep_file(write_temp("sweep_empty.txt", "# nothing\n\n")).empty());
}

void expect_error_at(const std::string& name, const std::string& text, long line,
                     const std::string& fragment) {
  const std::string p = write_temp(name, text);
  try {
    (void)read_sweep_file(p);
    ADD_FAILURE() << name << ": accepted";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.file(), p) << name;
    EXPECT_EQ(e.line(), line) << name << ": " << e.what();
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << name << ": " << e.what();
  }
}

TEST(SweepFile, MalformedLinesAreErrorsWithFileAndLine) {
  expect_error_at("sweep_8.txt", "end\n1 2 3 4 5 6 7 8\n", 2, "cz");
  expect_error_at("sweep_10.txt", "1 2 3 4 5 6 7 8 9 10\n", 1, "end of line");
  expect_error_at("sweep_split.txt", "1 2 3 4 5 6\n7 8 9\n", 1, "on one line");
  expect_error_at("sweep_nan.txt", "\n1 2 3 4 5 6 7 8 nan\n", 2, "finite");
  expect_error_at("sweep_inf.txt", "1 2 3 4 5 inf 7 8 9\n", 1, "finite");
  expect_error_at("sweep_word.txt", "0 0 0 1 0 0 0 1 0\nstop\n", 2, "or 'end'");
  expect_error_at("sweep_end_extra.txt", "end now\n", 1, "after 'end'");
}

TEST(SweepFile, OverflowAfterScalingAndBadScalesAreRejected) {
  const std::string p = write_temp("sweep_big.txt", "1e308 0 0 0 0 0 0 0 0\n");
  EXPECT_THROW((void)read_sweep_file(p, 10.0), ParseError);
  EXPECT_NO_THROW((void)read_sweep_file(p, 1.0));
  for (double s : {0.0, -1.0, std::numeric_limits<double>::infinity(),
                   std::numeric_limits<double>::quiet_NaN()})
    EXPECT_THROW((void)read_sweep_file(p, s), ParameterError) << s;
  EXPECT_THROW((void)read_sweep_file(test::temp_path("sweep_missing.txt")), ParseError);
}

}  // namespace
}  // namespace incise::io
