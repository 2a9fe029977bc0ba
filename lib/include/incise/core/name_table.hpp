#pragma once
/// \file name_table.hpp
/// One table of names per enum: the single list from which a value is parsed, printed
/// (to_string), listed in "expected one of ..." messages and checked against the docs. A table
/// lives with its enum's owner (e.g. solver::kPreconditionerNames next to solver::Preconditioner).

#include <array>
#include <cstddef>
#include <cstring>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace incise {

/// `one of "a", "b", "c"`: the form in which messages list admissible names.
inline std::string one_of(const std::vector<std::string>& names) {
  std::string s = "one of ";
  for (std::size_t i = 0; i < names.size(); ++i) s += (i ? ", \"" : "\"") + names[i] + "\"";
  return s;
}

/// Names of the values of `Enum`, in the order they are listed. Each value and each name occurs
/// once. Declare an instance as `inline constexpr NameTable<E, N> kENames{{{{E::kA, "a"}, ...}}};`.
template <class Enum, std::size_t N>
struct NameTable {
  std::array<std::pair<Enum, const char*>, N> entries;

  /// Name of `e`; "?" for a value missing from the table.
  constexpr const char* name(Enum e) const {
    for (const auto& entry : entries)
      if (entry.first == e) return entry.second;
    return "?";
  }
  /// The value called `name`, or nullopt.
  std::optional<Enum> find(const std::string& name) const {
    for (const auto& entry : entries)
      if (name == entry.second) return entry.first;
    return std::nullopt;
  }
  /// All names, in table order.
  std::vector<std::string> names() const {
    std::vector<std::string> out;
    for (const auto& entry : entries) out.emplace_back(entry.second);
    return out;
  }
  /// `one of "a", "b"` for messages.
  std::string one_of() const { return incise::one_of(names()); }
};

}  // namespace incise
