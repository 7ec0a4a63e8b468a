// Running LinuxCNC from the tests (test_linuxcnc_*.cpp): what is needed, and
// a LinuxCNC command run with the modules built here loadable by name
// (tests/support/linuxcnc/halrun_private.sh; docs/linuxcnc.md).
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "oracle.hpp"
#include "run_process.hpp"
#include "test_paths.hpp"

namespace truecut::test {

// What a test needs to run LinuxCNC; empty when everything is there.
inline std::string linuxcnc_missing() {
  if (std::string(TRUECUT_LINUXCNC_MODULE_DIR).empty())
    return "LinuxCNC development files (the module was not built): install linuxcnc-uspace and "
           "linuxcnc-uspace-dev (tools/install-deps.sh) and configure again";
  for (const char* p : {"halrun", "halstreamer", "halsampler", "rtapi_app", "linuxcnc"})
    if (!find_on_path(p)) return std::string("LinuxCNC's ") + p + ": install linuxcnc-uspace";
  for (const char* p : {"unshare", "runuser", "mount"})
    if (!find_on_path(p)) return std::string(p) + ": install util-linux";
  if (::geteuid() != 0)
    return "root, to run halrun in a private mount namespace with the modules built here "
           "(tests/support/linuxcnc/halrun_private.sh)";
  // The private mount namespace has a /tmp of its own, which hides a build
  // folder there (halrun_private.sh refuses it).
  std::error_code ec;
  const std::string build = std::filesystem::weakly_canonical(binary_dir(), ec).string() + "/";
  if (build.rfind("/tmp/", 0) == 0)
    return "a build folder outside /tmp (this one is " + build +
           "; LinuxCNC runs in a private mount namespace whose own /tmp hides it): clone and "
           "build elsewhere";
  return {};
}

// Runs `command` in `work` (which nobody must be able to write) as the user
// nobody, with the truecut modules in LinuxCNC's module folder.
inline ProcessResult run_linuxcnc_private(const std::filesystem::path& work,
                                          const std::vector<std::string>& command) {
  std::vector<std::string> argv = {
      "/bin/sh", TRUECUT_SOURCE_DIR "/tests/support/linuxcnc/halrun_private.sh",
      std::string(TRUECUT_LINUXCNC_MODULE_DIR) + ":" + TRUECUT_LINUXCNC_TEST_MODULE_DIR,
      work.string()};
  argv.insert(argv.end(), command.begin(), command.end());
  return run_process(argv);
}

}  // namespace truecut::test
