// `truecut field`'s pipeline on a closed solid at several sizes: a cylinder
// R 30 mm, H 40 mm with a hemispherical cap (the shape and size with which
// issue 20 found the pipeline slow), its nominal at about N facets, a point
// cloud scan of 5.5 points per facet (the model-adaptation source's ratio,
// 624,436 points to 113,906 facets) with a planted error and 5 µm of noise,
// and a ball-end ring program over wall and cap. Prints every stage's wall
// time, the peak resident memory and the whole; asserts nothing.
//
//   build/field_solid_scale [--sequential] [--threads N] [--digest] [--write DIR] [FACETS ...]
//
// FACETS default to 10000 100000. --sequential runs the stages one after the
// other (FieldPipelineOptions::concurrent_stages = false: every stage's own
// time), --threads N limits TBB to N threads, --digest prints a hash of every
// stage's result (to check that a change to the code leaves them unchanged).
// --write DIR also writes each size's inputs as files (DIR/FACETS/nominal.stl,
// scan.ply, rings.ngc, tools.tbl) for timing `truecut field` itself; the
// command to run is printed.
#include "truecut/interp/interpreter.hpp"
#include "truecut/offline/field_pipeline.hpp"
#include "truecut/offline/mesh_io.hpp"

#include <sys/resource.h>
#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

using namespace truecut::offline;
namespace interp = truecut::interp;

namespace {

constexpr double kR = 30.0, kH = 40.0, kBallR = 3.0;
constexpr double kPi = std::numbers::pi;

// Around: n segments; wall: rows of about the segment length; cap: n/4
// latitude rings; the bottom: a fan. Surfaces: wall 1, cap 2, bottom 3.
struct Solid {
  TriangleMesh mesh;
  std::vector<std::int32_t> ids;
};

Solid cylinder_with_cap(int around) {
  Solid s;
  auto& v = s.mesh.vertices_mm;
  const int rows = std::max(1, int(std::lround(kH / (2 * kPi * kR / around)))),
            rings = std::max(2, around / 4);
  auto ring = [&](double r, double z) {
    const auto first = static_cast<std::uint32_t>(v.size());
    for (int i = 0; i < around; ++i)
      v.emplace_back(r * std::cos(2 * kPi * i / around), r * std::sin(2 * kPi * i / around), z);
    return first;
  };
  std::vector<std::uint32_t> first;
  for (int j = 0; j <= rows; ++j)
    first.push_back(ring(kR, kH * j / rows));
  for (int j = 1; j < rings; ++j) {
    const double phi = 0.5 * kPi * j / rings;  // from the equator up
    first.push_back(ring(kR * std::cos(phi), kH + kR * std::sin(phi)));
  }
  const auto top = static_cast<std::uint32_t>(v.size());
  v.emplace_back(0, 0, kH + kR);
  const auto bottom = static_cast<std::uint32_t>(v.size());
  v.emplace_back(0, 0, 0);
  auto quad_band = [&](std::uint32_t lo, std::uint32_t hi, std::int32_t id) {
    for (int i = 0; i < around; ++i) {
      const std::uint32_t a = lo + i, b = lo + (i + 1) % around, c = hi + (i + 1) % around,
                          d = hi + i;
      s.mesh.triangles.push_back({a, b, c});
      s.mesh.triangles.push_back({a, c, d});
      s.ids.push_back(id);
      s.ids.push_back(id);
    }
  };
  for (std::size_t j = 0; j + 1 < first.size(); ++j)
    quad_band(first[j], first[j + 1], j < std::size_t(rows) ? 1 : 2);
  for (int i = 0; i < around; ++i) {
    s.mesh.triangles.push_back({first.back() + i, first.back() + (i + 1) % around, top});
    s.ids.push_back(2);
    s.mesh.triangles.push_back({bottom, first[0] + (i + 1) % around, first[0] + i});
    s.ids.push_back(3);
  }
  return s;
}

// The machined part: radially 20 µm oversize at the bottom growing to 40 µm
// at the top of the wall, 40 µm over the cap; area-uniform points with 5 µm
// of noise along the normal.
std::vector<Eigen::Vector3d> scan_cloud(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.005);
  const double wall = 2 * kPi * kR * kH, cap = 2 * kPi * kR * kR, disc = kPi * kR * kR;
  std::vector<Eigen::Vector3d> p;
  p.reserve(n);
  while (p.size() < n) {
    const double pick = u(rng) * (wall + cap + disc), t = 2 * kPi * u(rng);
    const Eigen::Vector3d radial(std::cos(t), std::sin(t), 0);
    if (pick < wall) {
      const double z = kH * u(rng), e = 0.02 + 0.02 * z / kH + noise(rng);
      p.push_back((kR + e) * radial + Eigen::Vector3d(0, 0, z));
    } else if (pick < wall + cap) {
      const double sin_phi = u(rng), cos_phi = std::sqrt(1 - sin_phi * sin_phi);
      const double r = kR + 0.04 + noise(rng);
      p.push_back(r * cos_phi * radial + Eigen::Vector3d(0, 0, kH + r * sin_phi));
    } else {
      const double r = kR * std::sqrt(u(rng));
      p.push_back(r * radial + Eigen::Vector3d(0, 0, noise(rng)));
    }
  }
  return p;
}

// Ball end mill R 3 (tip programmed): rings 0.5 mm apart down the wall and
// over the cap, each a full circle in two G2 halves.
std::string ring_program() {
  std::string s = "G21 G17 G40 G49 G80 G90 G94\nT1 M6\nG43 H1\nF2000\nG0 X0 Y0 Z100\n";
  auto circle = [&](double r, double z_tip) {
    char b[256];
    std::snprintf(b, sizeof b,
                  "G0 X%.4f Y0\nG0 Z%.4f\nG2 X%.4f Y0 I%.4f J0\nG2 X%.4f Y0 I%.4f J0\n", r, z_tip,
                  -r, -r, r, r);
    s += b;
  };
  const double step = 0.5;
  for (double phi = 0.5 * kPi - step / kR; phi > 0; phi -= step / kR)  // cap, top down
    circle((kR + kBallR) * std::cos(phi), kH + (kR + kBallR) * std::sin(phi) - kBallR);
  for (double z = kH; z >= 0.5; z -= step)  // wall
    circle(kR + kBallR, z - kBallR);
  return s + "G0 Z100\nM30\n";
}

double cpu_s() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

double peak_rss_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;
}

// FNV-1a over the bytes of the results, stage by stage.
class Digest {
 public:
  template <class T>
  Digest& add(const T* data, std::size_t n) {
    const auto* b = reinterpret_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n * sizeof(T); ++i)
      h_ = (h_ ^ b[i]) * 0x100000001b3ull;
    return *this;
  }
  template <class T>
  Digest& add(const std::vector<T>& v) {
    return add(v.data(), v.size());
  }
  std::uint64_t value() const { return h_; }

 private:
  std::uint64_t h_ = 0xcbf29ce484222325ull;
};

void print_digests(const FieldPipelineResult& r) {
  Digest errors;
  errors.add(r.errors.vectors_mm)
      .add(r.errors.status)
      .add(r.errors.normal_mm)
      .add(r.errors.sphere_case)
      .add(r.errors.points_in_sphere)
      .add(r.errors.support_begin)
      .add(r.errors.support_point)
      .add(r.errors.support_weight);
  Digest significance;
  significance.add(&r.significance.pooled_noise_mm, 1);
  for (const auto& s : r.significance.surfaces)
    significance.add(&s.compensated, 1)
        .add(&s.noise_mm, 1)
        .add(&s.mean_normal_mm, 1)
        .add(&s.scan_points, 1);
  if (r.registration) significance.add(r.registration->scan_to_nominal.matrix().data(), 16);
  Digest truss;
  truss.add(r.truss.displacement_mm).add(r.truss.supported).add(r.adapted.vertices_mm);
  Digest placement;
  placement.add(r.placement.cut);
  for (const ToolPlacement& tp : r.placement.tools)
    for (const PointPlacement& pp : tp.points)
      placement.add(&pp.point, 1)
          .add(&pp.sample, 1)
          .add(pp.tcp_mm.data(), 3)
          .add(pp.axis.data(), 3)
          .add(&pp.distance_mm, 1);
  Digest fit;
  for (const std::int32_t tool : r.fit->field.tools()) {
    const auto nodes = r.fit->field.nodes(tool);
    fit.add(nodes.data(), nodes.size());
  }
  for (const FieldFitLayerStats& s : r.fit->layers)
    fit.add(&s.residual_rms_mm, 1).add(&s.residual_max_mm, 1).add(&s.unknown_nodes, 1);
  Digest matrix;
  matrix.add(r.smoothed_matrix_mm).add(r.field_vectors_mm);
  std::printf(
      "  digests: errors %016llx significance %016llx truss %016llx placement %016llx "
      "fit %016llx matrix %016llx\n",
      (unsigned long long)errors.value(), (unsigned long long)significance.value(),
      (unsigned long long)truss.value(), (unsigned long long)placement.value(),
      (unsigned long long)fit.value(), (unsigned long long)matrix.value());
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<long> sizes;
  bool sequential = false, digest = false;
  std::string write_dir;
  std::unique_ptr<tbb::global_control> threads;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--sequential") == 0) {
      sequential = true;
    } else if (std::strcmp(argv[i], "--digest") == 0) {
      digest = true;
    } else if (std::strcmp(argv[i], "--write") == 0 && i + 1 < argc) {
      write_dir = argv[++i];
    } else if (std::strcmp(argv[i], "--threads") == 0 && i + 1 < argc) {
      threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                      std::size_t(std::atol(argv[++i])));
    } else {
      sizes.push_back(std::atol(argv[i]));
    }
  }
  if (sizes.empty()) sizes = {10000, 100000};
  interp::InterpreterOptions io;
  io.tools = interp::ToolTable::parse("T1 P1 D6 Z50\n", "tools.tbl");
  const std::string program_text = ring_program();
  const interp::CanonProgram program =
      interp::Interpreter(std::move(io)).run_text(program_text, "rings.ngc");
  for (const long facets : sizes) {
    // facets ≈ around · (2 rows + 2 rings + 2) with rows ≈ around · H / (2πR)
    // and rings = around / 4.
    const double k = 2 * kH / (2 * kPi * kR) + 0.5;
    const int around = std::max(8, int(std::lround(std::sqrt(double(facets) / k))));
    const Solid solid = cylinder_with_cap(around);
    TriangleMesh scan;
    scan.vertices_mm = scan_cloud(std::size_t(5.5 * double(solid.mesh.triangles.size())), 7);
    if (!write_dir.empty()) {
      const std::filesystem::path dir =
          std::filesystem::path(write_dir) / std::to_string(solid.mesh.triangles.size());
      std::filesystem::create_directories(dir);
      write_mesh(dir / "nominal.stl", solid.mesh);
      PointCloud cloud;
      cloud.points_mm = scan.vertices_mm;
      write_point_cloud(dir / "scan.ply", cloud);
      std::ofstream(dir / "rings.ngc") << program_text;
      std::ofstream(dir / "tools.tbl") << "T1 P1 D6 Z50\n";
      std::printf(
          "  inputs written; the same job through the command line:\n"
          "  truecut field %s/nominal.stl %s/scan.ply --program %s/rings.ngc --tools %s/tools.tbl "
          "--method sphere --sphere-radius 1 --corner-radius 1=3 --cutting-length 1=10 --out OUT\n",
          dir.c_str(), dir.c_str(), dir.c_str(), dir.c_str());
    }
    FieldPipelineInputs in;
    in.nominal = &solid.mesh;
    in.scan = &scan;
    in.program = &program;
    in.tools = {{1, kBallR, kBallR, 10.0}};
    in.triangle_surface_ids = solid.ids;
    FieldPipelineOptions o;
    o.method = ErrorMethod::kSphere;
    o.sphere.radius_mm = 1.0;
    o.datum_surfaces = {3};
    o.concurrent_stages = !sequential;
    std::printf("\n--- %zu facets, %zu scan points ---\n", solid.mesh.triangles.size(),
                scan.vertices_mm.size());
    const auto t0 = std::chrono::steady_clock::now();
    // With the stages one after the other, the process's CPU time between
    // two reports is the later stage's (both threads).
    double cpu_before = cpu_s();
    const double cpu_start = cpu_before;
    const FieldPipelineResult r = run_field_pipeline(
        in, o, [&](const std::string& stage, double s, const std::string& detail) {
          const double cpu = cpu_s();
          if (sequential)
            std::printf("  %-34s %8.3f s  cpu %7.3f s  %s\n", stage.c_str(), s, cpu - cpu_before,
                        detail.c_str());
          else
            std::printf("  %-34s %8.3f s  %s\n", stage.c_str(), s, detail.c_str());
          cpu_before = cpu;
          std::fflush(stdout);
        });
    const double total =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf(
        "  whole pipeline %.3f s wall, cpu %.3f s, peak resident %.0f MB; %zu points, %zu valid\n",
        total, cpu_s() - cpu_start, peak_rss_mb(), r.points.size(), r.error_statistics.valid);
    if (digest) print_digests(r);
  }
}
