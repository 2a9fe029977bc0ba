#include <gtest/gtest.h>
#include <incise/core/error.hpp>

namespace incise {

TEST(ParseError, NamesFileLineAndExpectation) {
  const ParseError e("beam.msh", 12, "expected 4 node indices");
  EXPECT_STREQ(e.what(), "beam.msh:12: expected 4 node indices");
  EXPECT_EQ(e.file(), "beam.msh");
  EXPECT_EQ(e.line(), 12);
}

TEST(ParseError, LineZeroMeansUnknown) {
  EXPECT_STREQ(ParseError("x.off", 0, "empty file").what(), "x.off: empty file");
}

TEST(Check, ThrowsTypedErrors) {
  EXPECT_THROW(INCISE_CHECK(1 == 2, "bad call"), UsageError);
  EXPECT_THROW(INCISE_CHECK_PARAM(false, "nu out of range"), ParameterError);
  EXPECT_NO_THROW(INCISE_CHECK(true, "fine"));
}

}  // namespace incise
