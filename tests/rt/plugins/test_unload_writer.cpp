// test_unload_writer: a HAL component that writes a file at unload, as the
// cutting component writes the machined part, and is ended by a signal
// halfway through it.
//   loadrt test_unload_writer to-host=0|1 signal=0|1
// It links its own copy of truecut's rt library (as the cutting component
// does), so a PendingFile it makes lands in that copy's table unless a
// PendingFilesToHost (to-host=1) sends it to the host's. At unload it opens
// OUTPUT_DIR/unload.txt through an AtomicFileWriter (unload.txt.tmp), writes
// half of it and, with signal=1, raises SIGTERM before the rename.
#include <signal.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <string>

#include "truecut/rt/atomic_write.hpp"
#include "truecut/rt/hal_abi.h"
#include "truecut/rt/interrupt_cleanup.hpp"

namespace {

struct Settings {
  bool to_host = false;
  bool signal = false;
};

bool flag(const char* arg, const char* key, bool* value) {
  const std::size_t n = std::strlen(key);
  if (std::strncmp(arg, key, n) != 0 || arg[n] != '=' || (arg[n + 1] != '0' && arg[n + 1] != '1') ||
      arg[n + 2] != '\0')
    return false;
  *value = arg[n + 1] == '1';
  return true;
}

}  // namespace

extern "C" TC_COMPONENT_EXPORT int truecut_component_init(const tc_hal_api_t* api, tc_hal_t* hal,
                                                          int argc, const char* const* argv,
                                                          void** module_state) {
  if (api->abi_version != TC_HAL_ABI_VERSION) return -EINVAL;
  auto* s = static_cast<Settings*>(api->alloc(hal, sizeof(Settings)));
  if (s == nullptr) return -ENOMEM;
  for (int i = 0; i < argc; ++i)
    if (!flag(argv[i], "to-host", &s->to_host) && !flag(argv[i], "signal", &s->signal)) {
      api->set_error(hal, "test_unload_writer takes to-host=0|1 signal=0|1");
      return -EINVAL;
    }
  const int id = api->component_new(hal, "test_unload_writer");
  if (id < 0) return id;
  api->component_ready(hal, id);
  *module_state = s;
  return 0;
}

extern "C" TC_COMPONENT_EXPORT void truecut_component_exit(const tc_hal_api_t* api, tc_hal_t* hal,
                                                           void* module_state) {
  const auto* s = static_cast<const Settings*>(module_state);
  try {
    const truecut::rt::PendingFilesToHost to_host(s->to_host ? api : nullptr, hal);
    truecut::rt::AtomicFileWriter file(std::filesystem::path(api->output_dir(hal)) / "unload.txt");
    file.write("half of the file");
    if (s->signal) raise(SIGTERM);
    file.write(", and the rest\n");
    file.commit();
  } catch (const std::exception& e) {
    api->message(hal, TC_HAL_MSG_ERR, e.what());
  }
}
