#pragma once
/// \file param_names.hpp
/// gtest parameter names of material-parameterized suites (one definition for every suite that
/// instantiates over material::registered_material_names()).

#include <gtest/gtest.h>

#include <string>

namespace incise::test {

/// `name` as a gtest parameter name: '-' replaced by '_' (veronda-westmann → veronda_westmann).
inline std::string gtest_name(std::string name) {
  for (char& ch : name)
    if (ch == '-') ch = '_';
  return name;
}

/// Name generator for INSTANTIATE_TEST_SUITE_P over material registry names.
inline std::string material_param_name(const ::testing::TestParamInfo<std::string>& info) {
  return gtest_name(info.param);
}

}  // namespace incise::test
