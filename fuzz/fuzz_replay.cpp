// A libFuzzer target's entry point run on files, without libFuzzer: each
// reader's seeds (fuzz/seeds.sh) replayed by ctest in every build, the
// sanitizer build included, so the targets keep compiling and their inputs
// keep passing. Exploring new inputs is tools/fuzz.sh's job (clang).
//   fuzz_replay_TARGET FILE|FOLDER...
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>
#include <vector>

#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

namespace fs = std::filesystem;

int main(int argc, char** argv) {
  std::vector<fs::path> inputs;
  for (int i = 1; i < argc; ++i) {
    const fs::path arg = argv[i];
    std::error_code ec;
    if (fs::is_directory(arg, ec)) {
      for (const auto& entry : fs::recursive_directory_iterator(arg))
        if (entry.is_regular_file()) inputs.push_back(entry.path());
    } else if (fs::is_regular_file(arg, ec)) {
      inputs.push_back(arg);
    } else {
      std::fprintf(stderr, "%s: %s: no such file or folder\n", argv[0], argv[i]);
      return 2;
    }
  }
  if (inputs.empty()) {
    std::fprintf(stderr, "usage: %s FILE|FOLDER... (at least one input)\n", argv[0]);
    return 2;
  }
  std::sort(inputs.begin(), inputs.end());
  for (const auto& path : inputs) {
    std::error_code size_error;
    std::vector<char> bytes(fs::file_size(path, size_error));
    std::ifstream in(path, std::ios::binary);
    if (size_error || !in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()))) {
      std::fprintf(stderr, "%s: cannot read %s\n", argv[0], path.c_str());
      return 2;
    }
    // Named first: a crash or sanitizer report ends the process right after.
    std::fprintf(stderr, "%s (%zu bytes)\n", path.c_str(), bytes.size());
    LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
  }
  // Where as_file wrote the inputs of readers that take a path.
  std::error_code ec;
  fs::remove_all(truecut::fuzz::scratch_dir(), ec);
  std::printf("%zu inputs replayed, none crashed\n", inputs.size());
  return 0;
}
