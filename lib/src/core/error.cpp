#include <incise/core/error.hpp>

#include <sstream>

namespace incise {

namespace {
std::string format_parse_error(const std::string& file, long line, const std::string& message) {
  std::ostringstream os;
  os << file;
  if (line > 0) os << ':' << line;
  os << ": " << message;
  return os.str();
}
}  // namespace

ParseError::ParseError(std::string file, long line, std::string message)
    : Error(format_parse_error(file, line, message)),
      file_(std::move(file)),
      line_(line),
      message_(std::move(message)) {}

namespace detail {
void throw_check_failure(const char* kind, const char* condition, const char* file, int line,
                         const std::string& message) {
  std::ostringstream os;
  os << message << " [" << kind << " '" << condition << "' failed at " << file << ':' << line
     << ']';
  if (std::string(kind) == "parameter") throw ParameterError(os.str());
  throw UsageError(os.str());
}
}  // namespace detail

}  // namespace incise
