#pragma once
/// \file outcome.hpp
/// The one shape of a numerical outcome report (docs/design.md §1.5): a status enum, a message
/// saying what happened and what the caller can do, `ok()` and `brief()`. Every report of the
/// library (solver, GMRES, factorization, augmented system, cut step, interactive step,
/// validation) derives from `Outcome<Status, kOk, kInitial>` with its own status enum, so callers
/// test and print every outcome the same way.

#include <string>

namespace incise {

/// Status and message of a numerical outcome. `Status` is an enum with a `to_string(Status)`
/// overload in its own namespace (found by argument-dependent lookup); `kOkValue` is the value
/// that means success, `kInitial` the status of a report nothing has filled in yet.
template <class Status, Status kOkValue, Status kInitial>
struct Outcome {
  Status status = kInitial;  ///< what happened; kOkValue on success
  std::string message;       ///< empty on success; otherwise what failed and what the caller can do

  /// True when status == kOkValue.
  bool ok() const { return status == kOkValue; }

  /// "name" of the status, or "name: message" when there is a message.
  std::string brief() const {
    std::string s = to_string(status);
    if (!message.empty()) s += ": " + message;
    return s;
  }
};

}  // namespace incise
