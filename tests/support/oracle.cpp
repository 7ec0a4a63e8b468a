#include "oracle.hpp"

#include <cstdlib>
#include <sstream>

#include <unistd.h>

namespace truecut::test {

bool oracles_required() {
  const char* v = std::getenv("TRUECUT_REQUIRE_ORACLES");
  return v != nullptr && std::string(v) == "1";
}

std::string oracle_missing(const std::string& what_to_install) {
  return oracles_required()
             ? "oracle missing (TRUECUT_REQUIRE_ORACLES=1 makes this a failure): " + what_to_install
             : "oracle missing, skipped (TRUECUT_REQUIRE_ORACLES=1 makes this a failure): " +
                   what_to_install;
}

::testing::TestPartResult::Type oracle_missing_result() {
  return oracles_required() ? ::testing::TestPartResult::kFatalFailure
                            : ::testing::TestPartResult::kSkip;
}

std::optional<std::filesystem::path> find_on_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  if (path == nullptr) return std::nullopt;
  std::istringstream dirs(path);
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (dir.empty()) continue;
    const std::filesystem::path candidate = std::filesystem::path(dir) / name;
    std::error_code ec;
    if (std::filesystem::is_regular_file(candidate, ec) && ::access(candidate.c_str(), X_OK) == 0)
      return candidate;
  }
  return std::nullopt;
}

}  // namespace truecut::test
