// Readable names for value-parameterised tests (INSTANTIATE_TEST_SUITE_P's
// fourth argument): ctest lists a case by this name instead of an index or
// the parameter's bytes.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>

namespace truecut::test {

// `text` as a test name: letters and digits kept, every other run of
// characters one '_', none at either end ("effects.backlash: must be >= 0"
// -> "effects_backlash_must_be_0").
inline std::string test_name(std::string_view text) {
  std::string name;
  bool gap = false;
  for (const char c : text) {
    const bool keep = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9');
    if (!keep) {
      gap = !name.empty();
      continue;
    }
    if (gap) name += '_';
    gap = false;
    name += c;
  }
  return name.empty() ? std::string("empty") : name;
}

// A number as a test name: "%g" with '.' as 'p' and '-' as 'm' (0.05 -> "0p05").
inline std::string test_name(double value) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", value);
  std::string name;
  for (const char* c = buf; *c; ++c)
    name += *c == '.' ? 'p' : *c == '-' ? 'm' : *c == '+' ? 'P' : *c;
  return name;
}

}  // namespace truecut::test
