#include "truecut/rt/number_format.hpp"

#include <charconv>

namespace truecut::rt {

std::string format_shortest(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);  // shortest exact round trip
  return std::string(buf, r.ptr);
}

std::string format_fixed(double v, int decimals) {
  std::string s = format_printf("%.*f", decimals, v);
  if (!s.empty() && s.front() == '-' && s.find_first_not_of("-0.") == std::string::npos)
    s.erase(0, 1);
  return s;
}

std::string format_hex64(std::uint64_t v) {
  char buf[17];
  const auto r = std::to_chars(buf, buf + sizeof buf, v, 16);
  const std::string digits(buf, r.ptr);
  return std::string(16 - digits.size(), '0') + digits;
}

std::string utc_timestamp(std::time_t t) {
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

std::string utc_timestamp_now() {
  return utc_timestamp(std::time(nullptr));
}

}  // namespace truecut::rt
