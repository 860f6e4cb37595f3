#pragma once
/// @file config_errors.hpp
/// What a configuration check rejects, for the config and parameter tests.

#include <gtest/gtest.h>

#include <string>

#include "semantic_exploration/core/config_error.hpp"

namespace semexp_test {

/// Runs `fn` and returns the parameter named by the semexp::ConfigError it throws ("" if none).
template <typename Fn>
std::string rejected(Fn fn) {
  try {
    fn();
  } catch (const semexp::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(e.parameter()), std::string::npos) << "message must name the parameter";
    return e.parameter();
  }
  return "";
}

}  // namespace semexp_test
