// Merges STL corners with bit-identical coordinates into one vertex through
// an open-addressing hash table (no per-entry allocation; ~3 corners per
// vertex on a closed mesh, so the table stays small).
#pragma once

#include <Eigen/Core>

#include <array>
#include <bit>
#include <cstdint>
#include <type_traits>
#include <vector>

namespace truecut::offline::mesh_io {

template <class Scalar>
class VertexWelder {
  using Bits = std::conditional_t<sizeof(Scalar) == 4, std::uint32_t, std::uint64_t>;
  using Key = std::array<Bits, 3>;
  static constexpr std::uint32_t kEmpty = 0xffffffffu;

 public:
  explicit VertexWelder(std::size_t expected_vertices) {
    std::size_t capacity = 1024;
    while (capacity < 2 * expected_vertices)
      capacity *= 2;
    slots_.assign(capacity, kEmpty);
    keys_.reserve(expected_vertices);
  }

  // Index of the vertex at (x, y, z), appended when new. Coordinates must be
  // finite; −0 and +0 are the same vertex.
  std::uint32_t add(Scalar x, Scalar y, Scalar z) {
    // Adding +0 turns −0 into +0 and leaves every other value unchanged.
    const Key key{std::bit_cast<Bits>(Scalar(x + Scalar(0))),
                  std::bit_cast<Bits>(Scalar(y + Scalar(0))),
                  std::bit_cast<Bits>(Scalar(z + Scalar(0)))};
    std::size_t mask = slots_.size() - 1;
    for (std::size_t i = hash(key) & mask;; i = (i + 1) & mask) {
      std::uint32_t s = slots_[i];
      if (s == kEmpty) {
        s = static_cast<std::uint32_t>(keys_.size());
        slots_[i] = s;
        keys_.push_back(key);
        if (2 * keys_.size() > slots_.size()) grow();
        return s;
      }
      if (keys_[s] == key) {
        ++merged_;
        return s;
      }
    }
  }

  std::size_t merged() const { return merged_; }
  std::size_t size() const { return keys_.size(); }

  std::vector<Eigen::Vector3d> vertices() const {
    std::vector<Eigen::Vector3d> out;
    out.reserve(keys_.size());
    for (const Key& k : keys_) {
      out.emplace_back(std::bit_cast<Scalar>(k[0]), std::bit_cast<Scalar>(k[1]),
                       std::bit_cast<Scalar>(k[2]));
    }
    return out;
  }

 private:
  static std::size_t hash(const Key& k) {
    std::uint64_t h = 0x9e3779b97f4a7c15ull;
    for (Bits b : k) {
      h ^= static_cast<std::uint64_t>(b);
      h *= 0xbf58476d1ce4e5b9ull;
      h ^= h >> 31;
    }
    return static_cast<std::size_t>(h);
  }

  void grow() {
    std::vector<std::uint32_t> old(2 * slots_.size(), kEmpty);
    old.swap(slots_);
    std::size_t mask = slots_.size() - 1;
    for (std::uint32_t s = 0; s < keys_.size(); ++s) {
      std::size_t i = hash(keys_[s]) & mask;
      while (slots_[i] != kEmpty)
        i = (i + 1) & mask;
      slots_[i] = s;
    }
  }

  std::vector<std::uint32_t> slots_;
  std::vector<Key> keys_;
  std::size_t merged_ = 0;
};

}  // namespace truecut::offline::mesh_io
