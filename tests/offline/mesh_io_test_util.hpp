// Helpers for the mesh I/O tests: writing hand-made bytes, small meshes, and
// checking error messages.
#pragma once

#include "truecut/offline/mesh_io.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>
#include <string_view>
#include <unordered_map>

namespace truecut::offline::test_util {

inline void write_bytes(const std::filesystem::path& file, std::string_view bytes) {
  std::ofstream out(file, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  ASSERT_TRUE(out.good()) << file;
}

// Appends a scalar in little- (default) or big-endian byte order.
template <class T>
void put(std::string& s, T value, bool big_endian = false) {
  char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  const bool host_big = std::endian::native == std::endian::big;
  if (big_endian != host_big) {
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i)
      std::swap(b[i], b[sizeof(T) - 1 - i]);
  }
  s.append(b, sizeof(T));
}

// Runs f, expecting a MeshIoError whose message holds every fragment.
template <class F>
std::string expect_error(F&& f, std::initializer_list<std::string_view> fragments) {
  try {
    f();
  } catch (const MeshIoError& e) {
    const std::string msg = e.what();
    for (std::string_view frag : fragments) {
      EXPECT_NE(msg.find(frag), std::string::npos) << "missing \"" << frag << "\" in: " << msg;
    }
    return msg;
  }
  ADD_FAILURE() << "no MeshIoError thrown";
  return {};
}

// A wavy height-field surface of nx × ny vertices with float-representable
// coordinates (multiples of 1/64), so binary STL round trips are exact.
inline TriangleMesh grid_mesh(int nx, int ny, bool normals = false) {
  TriangleMesh m;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const double z = static_cast<double>((i * 7 + j * 3) % 11) / 64.0;
      m.vertices_mm.emplace_back(0.5 * i, 0.25 * j, z);
      if (normals) m.normals.push_back(Eigen::Vector3d(0.125 * (i % 3), 0.0625, 1.0).normalized());
    }
  }
  for (int j = 0; j + 1 < ny; ++j) {
    for (int i = 0; i + 1 < nx; ++i) {
      const auto a = static_cast<std::uint32_t>(j * nx + i);
      const auto b = a + 1, c = a + nx, d = a + nx + 1;
      m.triangles.push_back({a, b, d});
      m.triangles.push_back({a, d, c});
    }
  }
  return m;
}

// The same mesh with vertices numbered in order of first use by the
// triangles, which is how an STL reader numbers them.
inline TriangleMesh by_first_use(const TriangleMesh& in) {
  TriangleMesh out;
  std::unordered_map<std::uint32_t, std::uint32_t> map;
  for (Triangle t : in.triangles) {
    for (auto& v : t) {
      auto [it, added] = map.emplace(v, static_cast<std::uint32_t>(out.vertices_mm.size()));
      if (added) out.vertices_mm.push_back(in.vertices_mm[v]);
      v = it->second;
    }
    out.triangles.push_back(t);
  }
  return out;
}

inline void expect_same(const std::vector<Eigen::Vector3d>& a,
                        const std::vector<Eigen::Vector3d>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i], b[i]) << "point " << i << ": " << a[i].transpose() << " vs "
                          << b[i].transpose();
  }
}

inline void expect_same(const TriangleMesh& a, const TriangleMesh& b) {
  expect_same(a.vertices_mm, b.vertices_mm);
  expect_same(a.normals, b.normals);
  ASSERT_EQ(a.triangles.size(), b.triangles.size());
  for (std::size_t i = 0; i < a.triangles.size(); ++i) {
    ASSERT_EQ(a.triangles[i], b.triangles[i]) << "triangle " << i;
  }
}

inline std::size_t files_in(const std::filesystem::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir))
    ++n;
  return n;
}

}  // namespace truecut::offline::test_util
