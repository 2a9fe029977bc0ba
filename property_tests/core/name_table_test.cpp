// NameTable (core/name_table.hpp): one list of names per enum, read both ways.

#include <incise/core/name_table.hpp>

#include <gtest/gtest.h>

namespace {

enum class Colour { kRed, kGreen, kBlue };

constexpr incise::NameTable<Colour, 2> kColourNames{{{
    {Colour::kRed, "red"},
    {Colour::kGreen, "green"},
}}};

TEST(NameTable, NamesAndValuesMapBothWays) {
  static_assert(kColourNames.name(Colour::kGreen)[0] == 'g', "name() is usable at compile time");
  for (const auto& [value, name] : kColourNames.entries) {
    EXPECT_EQ(kColourNames.find(name), value);
    EXPECT_STREQ(kColourNames.name(value), name);
  }
  EXPECT_EQ(kColourNames.names(), (std::vector<std::string>{"red", "green"}));
}

TEST(NameTable, UnknownNameOrValue) {
  EXPECT_FALSE(kColourNames.find("blue").has_value());
  EXPECT_FALSE(kColourNames.find("Red").has_value());  // names are exact
  EXPECT_STREQ(kColourNames.name(Colour::kBlue), "?");
}

TEST(NameTable, OneOfListsTheNamesQuotedInTableOrder) {
  EXPECT_EQ(kColourNames.one_of(), "one of \"red\", \"green\"");
  EXPECT_EQ(incise::one_of({"x"}), "one of \"x\"");
}

}  // namespace
