// Minimal command-line parsing for the truecut subcommands: `--name value`,
// `--name=value`, flags, positionals. Errors are UsageError (exit code 2).
#pragma once

#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace truecut::cli {

enum ExitCode { kExitOk = 0, kExitFailure = 1, kExitUsage = 2 };

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct OptionSpec {
  std::string name;  // without the leading --
  bool takes_value;
  bool repeatable = false;
};

class ParsedArgs {
 public:
  ParsedArgs(const std::vector<std::string>& argv, const std::vector<OptionSpec>& specs);
  bool flag(const std::string& name) const { return values_.count(name) > 0; }
  std::optional<std::string> value(const std::string& name) const;
  std::vector<std::string> values(const std::string& name) const;
  const std::vector<std::string>& positionals() const { return positionals_; }
  double number(const std::string& name, double fallback, double min, double max) const;
  long integer(const std::string& name, long fallback, long min, long max) const;

 private:
  std::multimap<std::string, std::string> values_;
  std::vector<std::string> positionals_;
};

}  // namespace truecut::cli
