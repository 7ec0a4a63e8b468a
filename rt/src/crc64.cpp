#include <array>
#include <bit>
#include <cstring>

#include "truecut/rt/field_file.hpp"

namespace truecut::rt {
namespace {

constexpr uint64_t kReflectedPolynomial = 0xC96C5795D7870F42ull;  // 0x42F0E1EBA9EA3693 reversed

// Slicing by 8 (eight bytes a step): kTables[0] is the byte-wise table,
// kTables[k][b] the CRC of byte b followed by k zero bytes.
using Tables = std::array<std::array<uint64_t, 256>, 8>;

constexpr Tables make_tables() {
  Tables t{};
  for (uint64_t byte = 0; byte < 256; ++byte) {
    uint64_t crc = byte;
    for (int bit = 0; bit < 8; ++bit)
      crc = (crc & 1) ? (crc >> 1) ^ kReflectedPolynomial : crc >> 1;
    t[0][byte] = crc;
  }
  for (std::size_t k = 1; k < 8; ++k)
    for (std::size_t byte = 0; byte < 256; ++byte)
      t[k][byte] = (t[k - 1][byte] >> 8) ^ t[0][t[k - 1][byte] & 0xFF];
  return t;
}

constexpr Tables kTables = make_tables();

uint64_t load_le(const char* p) noexcept {
  uint64_t v = 0;
  if constexpr (std::endian::native == std::endian::little) {
    std::memcpy(&v, p, sizeof v);
  } else {
    for (int i = 7; i >= 0; --i)
      v = (v << 8) | static_cast<unsigned char>(p[i]);
  }
  return v;
}

}  // namespace

void Crc64::update(std::string_view bytes) noexcept {
  uint64_t crc = state_;
  const char* p = bytes.data();
  std::size_t n = bytes.size();
  for (; n >= 8; n -= 8, p += 8) {
    crc ^= load_le(p);
    crc = kTables[7][crc & 0xFF] ^ kTables[6][(crc >> 8) & 0xFF] ^ kTables[5][(crc >> 16) & 0xFF] ^
          kTables[4][(crc >> 24) & 0xFF] ^ kTables[3][(crc >> 32) & 0xFF] ^
          kTables[2][(crc >> 40) & 0xFF] ^ kTables[1][(crc >> 48) & 0xFF] ^ kTables[0][crc >> 56];
  }
  for (; n > 0; --n, ++p)
    crc = kTables[0][(crc ^ static_cast<unsigned char>(*p)) & 0xFF] ^ (crc >> 8);
  state_ = crc;
}

}  // namespace truecut::rt
