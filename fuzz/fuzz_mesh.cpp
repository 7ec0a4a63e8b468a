// Meshes and point clouds: STL (ASCII and binary), PLY (ASCII and binary),
// XYZ text. The first byte chooses the format, the rest is the file.
#include <cstdint>
#include <stdexcept>
#include <string>

#include "fuzz_input.hpp"
#include "truecut/offline/mesh_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  static const char* kNames[] = {"fuzz.stl", "fuzz.ply", "fuzz.xyz"};
  const char* name = kNames[data[0] % 3];
  const auto file = truecut::fuzz::as_file(data + 1, size - 1, name);
  try {
    if (data[0] % 3 == 2)
      truecut::offline::read_point_cloud(file);
    else
      truecut::offline::read_mesh(file);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
