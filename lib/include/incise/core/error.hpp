#pragma once
/// \file error.hpp
/// Error types and check macros.
///
/// Exceptions are for misuse, bad files and bad parameters. Numerical outcomes (no convergence,
/// inverted element, indefinite tangent) are reported through status reports, never thrown.

#include <stdexcept>
#include <string>

namespace incise {

/// Base of every exception thrown by incise.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

/// A parameter outside its admissible range (e.g. Poisson ratio ν ≥ 0.5).
class ParameterError : public Error {
 public:
  explicit ParameterError(const std::string& what) : Error(what) {}
};

/// The library was called in a way its preconditions forbid (stale handle, wrong sizes).
class UsageError : public Error {
 public:
  explicit UsageError(const std::string& what) : Error(what) {}
};

/// Malformed input file. Carries the file name, the 1-based line (0 when unknown) and a
/// description of what was expected there. what() reads "FILE:LINE: MESSAGE".
class ParseError : public Error {
 public:
  ParseError(std::string file, long line, std::string message);
  const std::string& file() const { return file_; }
  long line() const { return line_; }
  const std::string& message() const { return message_; }

 private:
  std::string file_;
  long line_;
  std::string message_;
};

namespace detail {
[[noreturn]] void throw_check_failure(const char* kind, const char* condition, const char* file,
                                      int line, const std::string& message);
}  // namespace detail

}  // namespace incise

/// Always-on precondition check: throws incise::UsageError naming the condition and message.
#define INCISE_CHECK(cond, msg)                                                                  \
  do {                                                                                           \
    if (!(cond)) ::incise::detail::throw_check_failure("check", #cond, __FILE__, __LINE__, msg); \
  } while (0)

/// Parameter check: throws incise::ParameterError.
#define INCISE_CHECK_PARAM(cond, msg)                                                     \
  do {                                                                                    \
    if (!(cond))                                                                          \
      ::incise::detail::throw_check_failure("parameter", #cond, __FILE__, __LINE__, msg); \
  } while (0)

/// Debug-only assertion (compiled out with NDEBUG unless INCISE_PARANOID is set); throws
/// incise::UsageError so that tests can observe it.
#if !defined(NDEBUG) || defined(INCISE_PARANOID)
#define INCISE_ASSERT(cond, msg) INCISE_CHECK(cond, msg)
#define INCISE_DEBUG_CHECKS 1
#else
#define INCISE_ASSERT(cond, msg) \
  do {                           \
  } while (0)
#define INCISE_DEBUG_CHECKS 0
#endif
