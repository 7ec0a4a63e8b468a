#!/usr/bin/env bash
# Installs the Debian packages truecut builds and tests with, if any are
# missing. The tests also compare against LinuxCNC's rs274 (linuxcnc-uspace),
# headless Chromium and git (tests/support/oracle.hpp); linuxcnc-uspace-dev
# (the HAL headers) lets the build make truecut_comp a LinuxCNC module,
# which tests/rt/test_linuxcnc_module.cpp runs in halrun (docs/linuxcnc.md);
# valgrind counts truecut_comp's instructions per servo cycle
# (tests/rt/test_truecut_comp_callgrind.cpp, docs/performance.md); clang and
# its libFuzzer runtime build the fuzzing targets that tools/test.sh
# --sanitize runs briefly (tools/fuzz.sh, docs/reliability.md).
set -euo pipefail
packages=(cmake g++ make pkg-config libeigen3-dev libembree-dev libboost-dev libtbb-dev
          libgtest-dev libgmock-dev libbenchmark-dev nlohmann-json3-dev libssl-dev
          libpng-dev chromium linuxcnc-uspace linuxcnc-uspace-dev git valgrind
          clang libclang-rt-14-dev)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  echo "installing: ${missing[*]}" >&2
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
