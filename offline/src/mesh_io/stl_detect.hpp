// Telling ASCII from binary STL. Many CAD systems write binary files whose
// 80-byte header starts with "solid", so the keyword alone decides nothing:
// the facet count in bytes 80–83 must also disagree with the file size, or
// the bytes must not look like text.
#pragma once

#include <cstdint>
#include <string_view>

namespace truecut::offline::mesh_io {

constexpr std::size_t kStlHeaderBytes = 80;
constexpr std::size_t kStlPreambleBytes = 84;  // header + uint32 facet count
constexpr std::size_t kStlFacetBytes = 50;     // normal, 3 corners (float32), uint16

// How many bytes of the file's start the functions below want to see.
constexpr std::size_t kStlSniffBytes = 1024;

// True when the bytes contain no control characters other than blanks and
// line ends (bytes ≥ 0x80 are allowed, for UTF-8 solid names).
bool looks_like_text(std::string_view head);

bool starts_with_solid(std::string_view head);

// True when the file size is exactly 84 + 50·(facet count in bytes 80–83).
bool binary_stl_size_matches(std::string_view head, std::uint64_t file_size);

// `head` is the first min(file size, kStlSniffBytes) bytes.
bool stl_is_ascii(std::string_view head, std::uint64_t file_size);

}  // namespace truecut::offline::mesh_io
