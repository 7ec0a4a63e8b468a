// Compares two listings in rs274's layout call by call: names and
// non-numeric text exactly, numbers within what rs274's printed precision
// allows (half a unit of its last printed digit, plus 1e-6).
#pragma once

#include <cmath>
#include <cstdlib>
#include <optional>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace truecut::interp::testing {

struct ListedCall {
  std::string name;
  std::string args;
  std::string block;  // the second column: "....." or the N word's digits
};

// The calls of a listing; lines that are not `<n> N<block> NAME(...)` are
// ignored (rs274 prints (print,...) text and errors there). <block> is
// "....." or the digits of the block's N word, padded to six characters (a
// longer one runs into the name).
inline std::vector<ListedCall> parse_listing(const std::string& text) {
  static const std::regex line(R"(^\s*\d+ N(\.\.\.\.\.|\d+)\s*([A-Z_0-9]+)\((.*)\)\s*$)");
  std::vector<ListedCall> out;
  std::istringstream in(text);
  std::string s;
  std::smatch m;
  while (std::getline(in, s))
    if (std::regex_match(s, m, line)) out.push_back({m[2], m[3], m[1]});
  return out;
}

struct Numbers {
  std::string shape;  // the text with every number replaced by '#'
  std::vector<double> values;
  std::vector<int> decimals;
};

inline Numbers split_numbers(const std::string& s) {
  static const std::regex number(R"(-?\d+(\.(\d+))?)");
  Numbers n;
  auto begin = std::sregex_iterator(s.begin(), s.end(), number);
  size_t last = 0;
  for (auto it = begin; it != std::sregex_iterator(); ++it) {
    n.shape += s.substr(last, it->position() - last) + "#";
    n.values.push_back(std::strtod(it->str().c_str(), nullptr));
    n.decimals.push_back(static_cast<int>((*it)[2].length()));
    last = it->position() + it->length();
  }
  n.shape += s.substr(last);
  return n;
}

// First difference between rs274's listing `expected` and truecut's `actual`.
inline std::optional<std::string> compare_listings(const std::vector<ListedCall>& expected,
                                                   const std::vector<ListedCall>& actual) {
  const size_t n = std::min(expected.size(), actual.size());
  for (size_t i = 0; i < n; ++i) {
    const auto& e = expected[i];
    const auto& a = actual[i];
    auto where = [&] {
      return "call " + std::to_string(i + 1) + ": rs274 N" + e.block + " " + e.name + "(" + e.args +
             ") vs truecut N" + a.block + " " + a.name + "(" + a.args + ")";
    };
    if (e.name != a.name || e.block != a.block) return where();
    if (e.name == "COMMENT" || e.name == "MESSAGE") {
      if (e.args != a.args) return where();
      continue;
    }
    const Numbers en = split_numbers(e.args), an = split_numbers(a.args);
    if (en.shape != an.shape || en.values.size() != an.values.size()) return where();
    for (size_t k = 0; k < en.values.size(); ++k) {
      const double tol = 0.5 * std::pow(10.0, -en.decimals[k]) + 1e-6;
      if (std::fabs(en.values[k] - an.values[k]) > tol) return where();
    }
  }
  if (expected.size() != actual.size())
    return "rs274 made " + std::to_string(expected.size()) + " calls, truecut " +
           std::to_string(actual.size()) +
           (n < expected.size() ? "; next rs274 call " + expected[n].name
                                : "; next truecut call " + actual[n].name);
  return std::nullopt;
}

}  // namespace truecut::interp::testing
