#include "test_paths.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include <unistd.h>

namespace truecut::test {

std::filesystem::path source_dir() {
  return TRUECUT_SOURCE_DIR;
}
std::filesystem::path binary_dir() {
  return TRUECUT_BINARY_DIR;
}
std::filesystem::path component_dir() {
  return TRUECUT_COMPONENT_DIR;
}
std::filesystem::path test_component_dir() {
  return binary_dir() / "test-components";
}
std::filesystem::path cli_path() {
  return TRUECUT_CLI;
}
std::filesystem::path data_dir() {
  return source_dir() / "data";
}

std::filesystem::path scratch_dir() {
  const auto* unit = ::testing::UnitTest::GetInstance();
  const auto* info = unit->current_test_info();
  const auto* suite = unit->current_test_suite();
  // Outside a test (SetUpTestSuite) the folder is the process's own: ctest
  // runs every case of a suite as a separate process, several at a time.
  std::string name = info    ? std::string(info->test_suite_name()) + "." + info->name()
                     : suite ? std::string(suite->name()) + ".suite-" + std::to_string(::getpid())
                             : "scratch-" + std::to_string(::getpid());
  for (char& c : name)
    if (c == '/') c = '_';
  auto dir = binary_dir() / "test-scratch" / name;
  // Emptied on the first call in a test only, so helpers may call it again.
  static std::string emptied_for;
  if (emptied_for != name) {
    std::filesystem::remove_all(dir);
    emptied_for = name;
  }
  std::filesystem::create_directories(dir);
  return dir;
}

std::string read_file(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace truecut::test
