#include "mesh_io/stl_detect.hpp"

#include "mesh_io/byte_order.hpp"

#include <cctype>

namespace truecut::offline::mesh_io {

bool looks_like_text(std::string_view head) {
  for (char ch : head) {
    auto c = static_cast<unsigned char>(ch);
    if ((c < 0x20 && c != '\t' && c != '\n' && c != '\r' && c != '\f' && c != '\v') || c == 0x7f) {
      return false;
    }
  }
  return true;
}

bool starts_with_solid(std::string_view head) {
  std::size_t i = 0;
  while (i < head.size() && std::isspace(static_cast<unsigned char>(head[i]))) {
    ++i;
  }
  std::string_view word = head.substr(i, 5);
  if (word.size() < 5) return false;
  for (std::size_t k = 0; k < 5; ++k) {
    if (std::tolower(static_cast<unsigned char>(word[k])) != "solid"[k]) return false;
  }
  return true;
}

bool binary_stl_size_matches(std::string_view head, std::uint64_t file_size) {
  if (head.size() < kStlPreambleBytes) return false;
  auto facets = load<std::uint32_t>(head.data() + kStlHeaderBytes, ByteOrder::kLittle);
  return file_size == kStlPreambleBytes + std::uint64_t{kStlFacetBytes} * facets;
}

bool stl_is_ascii(std::string_view head, std::uint64_t file_size) {
  if (!starts_with_solid(head)) return false;
  if (!looks_like_text(head)) return false;
  // A text file whose bytes 80–83 happen to encode a matching facet count
  // would need a size above 27 GB (every byte ≥ 0x20): a match means binary.
  return !binary_stl_size_matches(head, file_size);
}

}  // namespace truecut::offline::mesh_io
