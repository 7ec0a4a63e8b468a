// Shared by the libFuzzer targets: readers that take a path get the fuzzer's
// bytes through a file of this process (one per target process, rewritten
// for each input).
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

namespace truecut::fuzz {

inline std::string_view as_text(const uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// This process's folder for the files of as_file.
inline std::filesystem::path scratch_dir() {
  return std::filesystem::temp_directory_path() / ("truecut-fuzz-" + std::to_string(::getpid()));
}

// The bytes as a file named like `name` (its extension chooses the reader).
inline std::filesystem::path as_file(const uint8_t* data, std::size_t size,
                                     const std::string& name) {
  static const std::filesystem::path dir = [] {
    auto d = scratch_dir();
    std::filesystem::create_directories(d);
    return d;
  }();
  const auto file = dir / name;
  std::ofstream(file, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return file;
}

}  // namespace truecut::fuzz
