#include <array>

#include "truecut/rt/field_file.hpp"

namespace truecut::rt {
namespace {

constexpr uint64_t kReflectedPolynomial = 0xC96C5795D7870F42ull;  // 0x42F0E1EBA9EA3693 reversed

constexpr std::array<uint64_t, 256> make_table() {
  std::array<uint64_t, 256> table{};
  for (uint64_t byte = 0; byte < 256; ++byte) {
    uint64_t crc = byte;
    for (int bit = 0; bit < 8; ++bit)
      crc = (crc & 1) ? (crc >> 1) ^ kReflectedPolynomial : crc >> 1;
    table[byte] = crc;
  }
  return table;
}

constexpr std::array<uint64_t, 256> kTable = make_table();

}  // namespace

void Crc64::update(std::string_view bytes) noexcept {
  uint64_t crc = state_;
  for (const char ch : bytes)
    crc = kTable[(crc ^ static_cast<unsigned char>(ch)) & 0xFF] ^ (crc >> 8);
  state_ = crc;
}

}  // namespace truecut::rt
