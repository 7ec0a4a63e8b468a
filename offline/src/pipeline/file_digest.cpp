#include "truecut/interp/sha256.hpp"
#include "truecut/offline/field_outputs.hpp"

namespace truecut::offline {

FileDigest digest_file(const std::string& role, const std::filesystem::path& file) {
  FileDigest d;
  d.role = role;
  d.path = file;
  d.sha256 = interp::sha256_file_hex(file);
  std::error_code ec;
  d.bytes = std::filesystem::file_size(file, ec);
  return d;
}

}  // namespace truecut::offline
