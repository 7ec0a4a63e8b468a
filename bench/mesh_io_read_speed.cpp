// Read speed of the mesh and point-cloud readers at the model-adaptation
// benchmark's scale: 624,436 scan points, 113,896 nominal faces.
//
//   mesh_io_read_speed [SCRATCH_DIR]     (default: a folder under /tmp)
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "truecut/offline/mesh_io.hpp"
#include "truecut/offline/ply_io.hpp"
#include "truecut/offline/point_text_io.hpp"
#include "truecut/offline/stl_io.hpp"

using namespace truecut::offline;

namespace {

constexpr std::size_t kScanPoints = 624436;

template <class F>
double best_seconds(F&& f, int runs) {
  double best = 1e9;
  for (int i = 0; i < runs; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    best = std::min(best,
                    std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return best;
}

void print(const char* what, const std::filesystem::path& file, double seconds) {
  const double mb = static_cast<double>(std::filesystem::file_size(file)) / 1e6;
  std::printf("%-44s %7.1f MB  %7.1f ms  %6.0f MB/s\n", what, mb, seconds * 1e3, mb / seconds);
}

PointCloud scan_cloud() {
  PointCloud c;
  for (std::size_t i = 0; i < kScanPoints; ++i) {
    const double a = 0.001 * static_cast<double>(i), h = 1e-4 * static_cast<double>(i);
    c.points_mm.emplace_back(10 * std::cos(a), 10 * std::sin(a), h);
    c.normals.emplace_back(std::cos(a), std::sin(a), 0);
  }
  return c;
}

// A wavy height field of nx x ny vertices: 2 (nx-1)(ny-1) triangles.
TriangleMesh grid_mesh(int nx, int ny) {
  TriangleMesh m;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      m.vertices_mm.emplace_back(0.5 * i, 0.25 * j, ((i * 7 + j * 3) % 11) / 64.0);
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      const auto a = static_cast<std::uint32_t>(j * nx + i);
      m.triangles.push_back({a, a + 1, a + nx + 1});
      m.triangles.push_back({a, a + nx + 1, a + nx});
    }
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  const std::filesystem::path dir = argc > 1 ? std::filesystem::path(argv[1])
                                             : std::filesystem::temp_directory_path() /
                                                   ("truecut-mesh-io-" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const PointCloud cloud = scan_cloud();
  PointCloud got;
  write_ply(dir / "scan.ply", cloud);
  print("binary PLY, 624,436 pts, double xyz+normals", dir / "scan.ply",
        best_seconds([&] { got = read_point_cloud(dir / "scan.ply"); }, 3));
  write_point_text(dir / "scan.xyz", cloud);
  print("XYZ text, 624,436 pts with normals", dir / "scan.xyz",
        best_seconds([&] { got = read_point_cloud(dir / "scan.xyz"); }, 1));

  const TriangleMesh nominal = grid_mesh(93, 620);  // 113,896 faces
  TriangleMesh mesh;
  write_stl(dir / "nominal.stl", nominal);
  print("binary STL, 113,896 faces, welded", dir / "nominal.stl",
        best_seconds([&] { mesh = read_mesh(dir / "nominal.stl"); }, 3));
  write_stl(dir / "nominal_ascii.stl", nominal, StlEncoding::kAscii);
  print("ASCII STL, 113,896 faces, welded", dir / "nominal_ascii.stl",
        best_seconds([&] { mesh = read_mesh(dir / "nominal_ascii.stl"); }, 1));
  write_ply(dir / "nominal.ply", nominal);
  print("binary PLY, 113,896 faces", dir / "nominal.ply",
        best_seconds([&] { mesh = read_mesh(dir / "nominal.ply"); }, 3));
  const bool ok = got.points_mm.size() == kScanPoints && mesh.triangles.size() == 113896;
  if (argc <= 1) std::filesystem::remove_all(dir);
  if (!ok) std::fprintf(stderr, "mesh_io_read_speed: read back the wrong number of elements\n");
  return ok ? 0 : 1;
}
