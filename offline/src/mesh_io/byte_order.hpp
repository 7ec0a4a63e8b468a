// Loads and stores of little- or big-endian scalars at unaligned addresses.
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>

namespace truecut::offline::mesh_io {

enum class ByteOrder { kLittle, kBig };

constexpr ByteOrder host_byte_order() {
  return std::endian::native == std::endian::little ? ByteOrder::kLittle : ByteOrder::kBig;
}

template <class T>
T swap_bytes(T value) {
  static_assert(sizeof(T) == 1 || sizeof(T) == 2 || sizeof(T) == 4 || sizeof(T) == 8);
  if constexpr (sizeof(T) == 1) {
    return value;
  } else if constexpr (sizeof(T) == 2) {
    return std::bit_cast<T>(__builtin_bswap16(std::bit_cast<std::uint16_t>(value)));
  } else if constexpr (sizeof(T) == 4) {
    return std::bit_cast<T>(__builtin_bswap32(std::bit_cast<std::uint32_t>(value)));
  } else {
    return std::bit_cast<T>(__builtin_bswap64(std::bit_cast<std::uint64_t>(value)));
  }
}

template <class T>
T load(const char* p, ByteOrder order) {
  T value;
  std::memcpy(&value, p, sizeof(T));
  return order == host_byte_order() ? value : swap_bytes(value);
}

template <class T>
void store(char* p, T value, ByteOrder order) {
  if (order != host_byte_order()) value = swap_bytes(value);
  std::memcpy(p, &value, sizeof(T));
}

}  // namespace truecut::offline::mesh_io
