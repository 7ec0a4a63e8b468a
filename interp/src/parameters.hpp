// Numbered parameters (#1..#5601), named parameters (#<name>, local to the
// subroutine call; #<_name> global) and the read-only predefined names
// (#<_x>, #<_metric>, ...) which the interpreter supplies through a hook.
#pragma once

#include <array>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "truecut/interp/interpreter.hpp"

namespace truecut::interp {

class Parameters {
 public:
  static constexpr int kCount = 5602;
  static constexpr int kLocalCount = 30;  // #1..#30 are subroutine arguments

  Parameters();
  static bool valid_index(int index) { return index >= 1 && index < kCount; }
  double get(int index) const { return numbered_[index]; }
  void set(int index, double value) { numbered_[index] = value; }

  // Lower-case name without '#<' '>'. Predefined names are looked up first.
  std::optional<double> named(std::string_view name) const;
  bool is_predefined(std::string_view name) const;
  void set_named(const std::string& name, double value);

  // Subroutine call: saves #1..#30 and the named locals, then sets the
  // arguments (missing ones 0).
  void push_call(const std::vector<double>& args);
  // M98 (a Fanuc-style subprogram): a new call level with its own named
  // locals; #1..#30 are shared with the caller, as in rs274.
  void push_shared_call();
  void pop_call();
  int call_level() const { return static_cast<int>(frames_.size()) - 1; }
  // The numbered parameters and the named ones of the current call level.
  ParameterValues values() const;

  std::function<std::optional<double>(std::string_view)> predefined;

 private:
  struct Frame {
    std::array<double, kLocalCount> saved{};
    std::map<std::string, double, std::less<>> locals;
    bool restores_numbered = true;
  };
  std::vector<double> numbered_;
  std::map<std::string, double, std::less<>> globals_;
  std::vector<Frame> frames_;
};

}  // namespace truecut::interp
