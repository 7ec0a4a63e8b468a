// The one exception the mesh and point-cloud readers and writers throw.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>

namespace truecut::offline {

// what() reads "FILE: message", where the message names the element (vertex,
// face, facet, line) and index that is wrong.
class MeshIoError : public std::runtime_error {
 public:
  MeshIoError(const std::filesystem::path& file, const std::string& message)
      : std::runtime_error(file.string() + ": " + message), file_(file) {}

  const std::filesystem::path& file() const { return file_; }

 private:
  std::filesystem::path file_;
};

}  // namespace truecut::offline
