// Paths of the source and build trees, and scratch folders for tests.
#pragma once

#include <filesystem>
#include <string>

namespace truecut::test {

std::filesystem::path source_dir();
std::filesystem::path binary_dir();
std::filesystem::path component_dir();       // components built from the project
std::filesystem::path test_component_dir();  // components built only for tests
std::filesystem::path cli_path();            // the truecut executable
std::filesystem::path data_dir();            // the data sets in the repository (data/)
// A folder unique to the running test, emptied on the test's first call.
std::filesystem::path scratch_dir();
std::string read_file(const std::filesystem::path& file);

}  // namespace truecut::test
