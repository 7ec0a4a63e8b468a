#include "builtin_components.hpp"

#include "truecut/rt/hal.hpp"

namespace truecut::rt::hal {

const std::vector<BuiltinComponent>& builtin_components() {
  static const std::vector<BuiltinComponent> table = {
      {"siggen", builtin::siggen_init, builtin::siggen_exit},
      {"recorder", builtin::recorder_init, builtin::recorder_exit},
  };
  return table;
}

}  // namespace truecut::rt::hal
