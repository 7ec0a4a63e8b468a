// Tests that need a program from outside the project (an oracle: LinuxCNC's
// rs274, headless Chromium, ...). When the oracle is missing the test is
// skipped with a message saying what to install; with the environment
// variable TRUECUT_REQUIRE_ORACLES=1 (CI sets it) it fails instead, so a
// missing oracle never passes unnoticed.
//
//   if (!found) TRUECUT_ORACLE_MISSING("Chromium: install the Debian package chromium");
//
// Like GTEST_SKIP/GTEST_FAIL it returns from the current (void) function
// (a helper's skip or failure counts for the test that called it).
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <optional>
#include <string>

namespace truecut::test {

// True when TRUECUT_REQUIRE_ORACLES=1: a missing oracle is a failure.
bool oracles_required();

// The message for a missing oracle: `what_to_install` (what is missing and
// what provides it), and how the environment turns the skip into a failure.
std::string oracle_missing(const std::string& what_to_install);

// What a missing oracle makes of the test: a skip, or a (fatal) failure
// when TRUECUT_REQUIRE_ORACLES=1.
::testing::TestPartResult::Type oracle_missing_result();

// `name` as the shell would find it on PATH (an executable regular file),
// or nullopt.
std::optional<std::filesystem::path> find_on_path(const std::string& name);

}  // namespace truecut::test

// One statement (no if/else, so an unbraced `if` around it draws no
// dangling-else warning), made like GTEST_SKIP() and GTEST_FAIL().
#define TRUECUT_ORACLE_MISSING(what_to_install)                                      \
  return GTEST_MESSAGE_AT_(__FILE__, __LINE__,                                       \
                           ::truecut::test::oracle_missing(what_to_install).c_str(), \
                           ::truecut::test::oracle_missing_result())
