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

// Throws UsageError when the output `output_option` = `output` is the same
// file as one of `inputs` (named by any path, links included): the output
// would replace an input. Outputs that do not exist yet pass.
void refuse_output_over_input(const std::string& output_option, const std::string& output,
                              const std::vector<std::optional<std::string>>& inputs);

}  // namespace truecut::cli
