// The exit-status table of the `incise` program (lib/cli/cli_util.hpp Exit, docs/cli.md "Exit
// status"): report_exception, which main.cpp applies to whatever a command throws, maps each kind
// of exception to its status and writes one line naming the command. The statuses 0-3 are also
// asserted end to end through the program (the cli_* tests listed in docs/cli.md); status 70 has
// no input that reaches it (it is a bug), so it is asserted here only.

#include <gtest/gtest.h>

#include <incise/core/error.hpp>

#include <new>
#include <sstream>
#include <stdexcept>

#include "cli_util.hpp"

namespace incise::cli {
namespace {

int status_of(const std::exception_ptr& e, std::string& line) {
  std::ostringstream err;
  const int status = report_exception(e, "incise run", err);
  line = err.str();
  return status;
}

TEST(ExitStatus, TableValuesAreTheDocumentedCodes) {
  EXPECT_EQ(exit_code(Exit::kOk), 0);
  EXPECT_EQ(exit_code(Exit::kBadInput), 1);
  EXPECT_EQ(exit_code(Exit::kUsage), 2);
  EXPECT_EQ(exit_code(Exit::kNumericalFailure), 3);
  EXPECT_EQ(exit_code(Exit::kInternal), 70);
}

TEST(ExitStatus, CommandLineErrorIsUsage) {
  std::string line;
  EXPECT_EQ(status_of(std::make_exception_ptr(CommandLineError("--scale expects a number")), line),
            2);
  EXPECT_EQ(line, "incise run: --scale expects a number\n");
}

TEST(ExitStatus, BadFileFolderOrSceneIsBadInput) {
  std::string line;
  EXPECT_EQ(status_of(std::make_exception_ptr(ParseError("a.json", 5, "/mesh: expected")), line),
            1);
  EXPECT_EQ(line, "incise run: a.json:5: /mesh: expected\n");
  EXPECT_EQ(status_of(std::make_exception_ptr(BadInputError("--data x: not a folder")), line), 1);
  EXPECT_EQ(status_of(std::make_exception_ptr(ParameterError("nu >= 0.5")), line), 1);
  // The library's UsageError (a precondition a bad scene broke) is bad input, not a CLI usage
  // error: only CommandLineError and CLI11's parse errors are status 2.
  EXPECT_EQ(status_of(std::make_exception_ptr(UsageError("sizes differ")), line), 1);
}

TEST(ExitStatus, AnyOtherExceptionIsInternalAndSaysSo) {
  std::string line;
  EXPECT_EQ(status_of(std::make_exception_ptr(std::logic_error("index 7 out of range")), line), 70);
  EXPECT_EQ(line, "incise run: internal error: index 7 out of range\n");
  EXPECT_EQ(status_of(std::make_exception_ptr(std::bad_alloc()), line), 70);
  EXPECT_NE(line.find("internal error"), std::string::npos);
  EXPECT_EQ(status_of(std::make_exception_ptr(42), line), 70);
  EXPECT_EQ(line, "incise run: internal error: an exception of unknown type\n");
}

}  // namespace
}  // namespace incise::cli
