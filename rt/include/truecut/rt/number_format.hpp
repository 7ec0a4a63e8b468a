// Numbers and times as text, the one set of helpers for every module's
// files and reports (the correction field's header, part programs, G-code
// rewrites, recordings, reports):
//
//   format_shortest(0.1)          "0.1"     the shortest text that reads back
//                                           to the same double
//   format_fixed(-0.0004, 3)      "0.000"   N decimals, never "-0.000"
//   format_printf("%.4g", 1.5e-5) "1.5e-05" printf of the arguments, any length
//   format_hex64(255)             "00000000000000ff"
//   utc_timestamp(0)              "1970-01-01T00:00:00Z"
//
// Not finite values are printed, not refused: format_shortest gives "nan",
// "-nan", "inf", "-inf" (std::to_chars); format_fixed and format_printf what
// printf gives ("nan", "-nan", "inf", "-inf"). Callers that must not print
// them check first.
//
// Host code only (allocates); not for servo-cycle functions.
#pragma once

#include <cstdint>
#include <cstdio>
#include <ctime>
#include <string>

namespace truecut::rt {

std::string format_shortest(double v);

// "%.*f" with `decimals`; a value that rounds to zero prints without its
// minus sign ("-0.000" -> "0.000", "-0" -> "0").
std::string format_fixed(double v, int decimals);

// snprintf(format, args...) as a string, never truncated.
template <typename... Args>
std::string format_printf(const char* format, Args... args) {
  const int n = std::snprintf(nullptr, 0, format, args...);
  if (n <= 0) return {};
  std::string s(static_cast<std::size_t>(n), '\0');
  std::snprintf(s.data(), s.size() + 1, format, args...);
  return s;
}

// 16 lower-case hex digits, zero-padded (checksums, hashes).
std::string format_hex64(std::uint64_t v);

// ISO 8601 in UTC to the second: "2026-11-26T18:06:34Z".
std::string utc_timestamp(std::time_t t);
std::string utc_timestamp_now();

}  // namespace truecut::rt
