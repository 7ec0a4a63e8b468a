// LinuxCNC's standalone interpreter `rs274` and its sample programs, for the
// tests that compare truecut with LinuxCNC. fetch_rs274.sh prefers an
// installed rs274 (Debian's linuxcnc-uspace: /usr/bin/rs274) and otherwise
// downloads and unpacks the package into the build folder.
//
//   std::string why;
//   const auto& rs274 = rs274_oracle(why);
//   if (!rs274) TRUECUT_ORACLE_MISSING(rs274_missing(why));
#pragma once

#include <algorithm>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "oracle.hpp"
#include "run_process.hpp"
#include "test_paths.hpp"

namespace truecut::interp::testing {

struct Rs274Oracle {
  std::filesystem::path program;  // wrapper script: a private HOME per run
  std::filesystem::path share;    // holds linuxcnc/ncfiles and doc/linuxcnc/examples
};

// Found (or fetched) once per test process; nullopt with the reason when
// it cannot be had.
inline const std::optional<Rs274Oracle>& rs274_oracle(std::string& why) {
  static std::string reason;
  static const std::optional<Rs274Oracle> oracle = []() -> std::optional<Rs274Oracle> {
    const auto dir = truecut::test::binary_dir() / "rs274-oracle";
    const auto r = truecut::test::run_process(
        {"/bin/bash", (truecut::test::source_dir() / "tests/interp/fetch_rs274.sh").string(),
         dir.string()});
    if (r.exit_code != 0) {
      reason = r.err.empty() ? "fetch_rs274.sh failed" : r.err;
      while (!reason.empty() && reason.back() == '\n')
        reason.pop_back();
      return std::nullopt;
    }
    return Rs274Oracle{dir / "rs274", dir / "share"};
  }();
  why = reason;
  return oracle;
}

// The .ngc files under `dir` (a folder of programs, such as LinuxCNC's
// samples), sorted.
// Directory symlinks are not followed (the package links nc_files to
// ncfiles) and remap_subs folders, subroutine libraries, are left out.
inline std::vector<std::filesystem::path> ngc_programs_under(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  std::vector<fs::path> out;
  if (!fs::exists(dir)) return out;
  for (auto it = fs::recursive_directory_iterator(dir); it != fs::recursive_directory_iterator();
       ++it) {
    if (it->is_directory() && it->path().filename() == "remap_subs") {
      it.disable_recursion_pending();
      continue;
    }
    if (it->is_regular_file() && it->path().extension() == ".ngc") out.push_back(it->path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

// What to install when rs274 is missing.
inline std::string rs274_missing(const std::string& why) {
  return "LinuxCNC's rs274 and its sample programs are not available (" + why +
         "): install the Debian package linuxcnc-uspace (tools/install-deps.sh installs it), or "
         "give tests/interp/fetch_rs274.sh apt-get and a package source to download it";
}

}  // namespace truecut::interp::testing
