#include "args.hpp"

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <system_error>

namespace truecut::cli {

namespace {

// A range's bound as a person writes it: 1e-09, 0.001, 1000000000.
std::string bound_text(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.10g", v);
  return b;
}

}  // namespace

ParsedArgs::ParsedArgs(const std::vector<std::string>& argv, const std::vector<OptionSpec>& specs) {
  for (size_t i = 0; i < argv.size(); ++i) {
    const std::string& a = argv[i];
    if (a.size() < 3 || a.rfind("--", 0) != 0) {
      if (a.size() > 1 && a[0] == '-' && a != "-") throw UsageError("unknown option '" + a + "'");
      positionals_.push_back(a);
      continue;
    }
    std::string name = a.substr(2), val;
    bool has_inline = false;
    if (auto eq = name.find('='); eq != std::string::npos) {
      val = name.substr(eq + 1);
      name = name.substr(0, eq);
      has_inline = true;
    }
    const OptionSpec* spec = nullptr;
    for (const auto& s : specs)
      if (s.name == name) spec = &s;
    if (!spec) throw UsageError("unknown option '--" + name + "'");
    if (!spec->repeatable && values_.count(name)) throw UsageError("--" + name + " given twice");
    if (spec->takes_value) {
      if (!has_inline) {
        if (i + 1 >= argv.size()) throw UsageError("--" + name + " needs a value");
        val = argv[++i];
      }
      // No option means anything by an empty value (an unset shell
      // variable, most likely): `--out ""` would be the current folder's
      // name "" to every later step.
      if (val.empty()) throw UsageError("--" + name + " needs a value, not an empty one");
    } else if (has_inline) {
      throw UsageError("--" + name + " takes no value");
    }
    values_.emplace(name, val);
  }
}

std::optional<std::string> ParsedArgs::value(const std::string& name) const {
  auto it = values_.find(name);
  if (it == values_.end()) return std::nullopt;
  return it->second;
}

std::vector<std::string> ParsedArgs::values(const std::string& name) const {
  std::vector<std::string> out;
  auto [b, e] = values_.equal_range(name);
  for (auto it = b; it != e; ++it)
    out.push_back(it->second);
  return out;
}

double ParsedArgs::number(const std::string& name, double fallback, double min, double max) const {
  auto v = value(name);
  if (!v) return fallback;
  char* end = nullptr;
  double d = std::strtod(v->c_str(), &end);
  if (v->empty() || *end != '\0') throw UsageError("--" + name + " '" + *v + "' is not a number");
  if (!(d >= min && d <= max))
    throw UsageError("--" + name + " " + *v + " is outside " + bound_text(min) + ".." +
                     bound_text(max));
  return d;
}

long ParsedArgs::integer(const std::string& name, long fallback, long min, long max) const {
  auto v = value(name);
  if (!v) return fallback;
  char* end = nullptr;
  errno = 0;
  long n = std::strtol(v->c_str(), &end, 10);
  if (v->empty() || *end != '\0') throw UsageError("--" + name + " '" + *v + "' is not an integer");
  // Beyond a long, strtol returns its limit (and ERANGE): out of range too.
  if (errno == ERANGE || n < min || n > max)
    throw UsageError("--" + name + " " + *v + " is outside " + std::to_string(min) + ".." +
                     std::to_string(max));
  return n;
}

void refuse_output_over_input(const std::string& output_option, const std::string& output,
                              const std::vector<std::optional<std::string>>& inputs) {
  for (const auto& input : inputs) {
    if (!input) continue;
    std::error_code ec;
    if (std::filesystem::equivalent(output, *input, ec) && !ec)
      throw UsageError("--" + output_option + " " + output + " is the input " + *input +
                       ": writing it would replace what is being read; choose another file");
  }
}

}  // namespace truecut::cli
