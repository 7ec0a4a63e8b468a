// Speed of the dexel cutting model on the benchmark parts: cut() calls per
// second for servo-cycle-sized moves (1 ms at the programs' feeds), and the
// time to build the model; each path replayed with a cut per cycle and
// sampled by swept distance (SweptCut, as the cutting component does).
//
//   cutting_bench [--spacing MM] [--cell MM] [--cycles N] [--threads N]
//
// freeform: ball R3 raster along x at F1500 (25 µm per cycle), tip from the
// contact point on the free-form (tip = p + R·n − R·axis), 5 µm below it so
// every cycle cuts; freeform-30: the same with the axis leaning 30° about y.
// implant: flat R1 peripheral pass around the shaft at F500
// (8.3 µm per cycle), 0.3 mm radial allowance. Then the machined mesh of
// the swept run, as the cutting component writes it at the end.
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

#include "truecut/sim/benchmark_parts.hpp"
#include "truecut/sim/cutting/dexel_model.hpp"
#include "truecut/sim/cutting/swept_cut.hpp"

using namespace truecut::sim;
using namespace truecut::sim::cutting;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// CPU time of this thread: the machine may be shared, so wall time overstates.
double thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

struct Path {
  CutterShape shape;
  std::vector<CutterPose> poses;
};

// `tilt_deg`: the tool axis leans that much about y (a 3+2 or 5-axis pass):
// its 20 mm of flutes then reach far across the part's dexels.
Path freeform_path(int cycles, double tilt_deg = 0) {
  Path p{{3, 3, 20}, {}};
  const double tilt = tilt_deg * std::numbers::pi / 180;
  const Eigen::Vector3d axis(std::sin(tilt), 0, std::cos(tilt));
  const double step = 1500.0 / 60 * 1e-3;  // mm per 1 ms cycle
  double x = -28, y = -10, dir = 1;
  for (int k = 0; k < cycles; ++k) {
    const Eigen::Vector3d n = freeform_normal(x, y);
    const Eigen::Vector3d contact(x, y, freeform_height_mm(x, y) - 0.005);
    p.poses.push_back({contact + 3 * n - 3 * axis, axis});
    x += dir * step;
    if (x > 28 || x < -28) {  // next pass, 0.5 mm over
      dir = -dir;
      y += 0.5;
    }
  }
  return p;
}

Path implant_path(int cycles) {
  Path p{{1, 0, 20}, {}};
  const double step = 500.0 / 60 * 1e-3;
  const double c = 0.8 + 1.0;  // tool centre 1 mm (R) off each face
  double s = 0;
  for (int k = 0; k < cycles; ++k, s += step) {
    const double side = std::fmod(s, 4 * 2 * c) / (2 * c);  // around a square of side 2c
    const double u = (side - std::floor(side)) * 2 * c - c;
    Eigen::Vector3d tip;
    switch (static_cast<int>(side)) {
      case 0:
        tip = {u, c, 10};
        break;
      case 1:
        tip = {c, -u, 10};
        break;
      case 2:
        tip = {-u, -c, 10};
        break;
      default:
        tip = {-c, u, 10};
        break;
    }
    p.poses.push_back({tip, Eigen::Vector3d::UnitZ()});
  }
  return p;
}

void run(const char* name, PartId id, const Path& path, double spacing, double cell, int threads) {
  const BenchmarkPart part = make_part(id);
  DexelOptions o;
  o.spacing_mm = spacing;
  o.cell_mm = cell;
  o.threads = threads;
  auto t0 = Clock::now();
  DexelModel model = DexelModel::build(part.mesh, part.triangle_surface, part.metadata.stock, o);
  const double build_s = seconds_since(t0);
  std::printf("%-11s %zu triangles, %zu dexels (spacing %.3g mm), built in %.2f s\n", name,
              part.mesh.triangles.size(), model.size(), spacing, build_s);
  const DexelModel fresh = model;
  for (const bool swept : {false, true}) {
    model = fresh;
    std::uint64_t touched = 0, substeps = 0;
    double removed = 0;
    t0 = Clock::now();
    const double cpu0 = thread_cpu_s();
    SweptCut sampler;
    auto add = [&](const Engagement& e) {
      touched += e.dexels_touched;
      substeps += e.substeps;
      removed += e.removed_mm3;
    };
    for (std::size_t k = 1; k < path.poses.size(); ++k)
      add(swept ? sampler.step(model, path.shape, path.poses[k])
                : model.cut(path.shape, path.poses[k - 1], path.poses[k], false));
    if (swept) add(sampler.finish(model));
    const double wall = seconds_since(t0);
    const double s = thread_cpu_s() - cpu0;
    // FNV-1a over the heights' bits: equal across thread counts.
    std::uint64_t hash = 1469598103934665603ull;
    for (std::size_t i = 0; i < model.size(); ++i) {
      const double h = model.height_mm(i);
      std::uint64_t bits;
      std::memcpy(&bits, &h, sizeof bits);
      hash = (hash ^ bits) * 1099511628211ull;
    }
    const double cycles = double(path.poses.size() - 1);
    std::printf(
        "%-11s %s %.0f cycles in %.3f s CPU (%.3f s wall): %.2f us per cycle (%.1f %% of a 1 ms "
        "servo period); %.2f instances and %.0f dexels lowered per cycle, %.9f mm3 removed, "
        "heights %016llx\n",
        name, swept ? "swept:    " : "per cycle:", cycles, s, wall, s / cycles * 1e6,
        s / cycles * 1e3 * 100, substeps / cycles, touched / cycles, removed,
        static_cast<unsigned long long>(hash));
    const auto t = model.thread_stats();
    if (t.jobs > 0)
      std::printf(
          "%-11s           %d threads: %llu instances shared (%.1f chunks each, %.1f %% run by the "
          "helper), %llu wake-ups, %.1f polls waiting per shared instance\n",
          name, model.threads(), static_cast<unsigned long long>(t.jobs),
          double(t.chunks) / double(t.jobs), 100.0 * double(t.worker_chunks) / double(t.chunks),
          static_cast<unsigned long long>(t.wakes), double(t.wait_spins) / double(t.jobs));
  }
  // The machined surface of the swept run (what the cutting component
  // writes at the end), best of three.
  double mesh_s = 1e9;
  std::size_t vertices = 0, triangles = 0;
  for (int k = 0; k < 3; ++k) {
    t0 = Clock::now();
    const auto mesh = model.machined_mesh();
    mesh_s = std::min(mesh_s, seconds_since(t0));
    vertices = mesh.vertices_mm.size();
    triangles = mesh.triangles.size();
  }
  std::printf("%-11s machined mesh: %zu vertices, %zu triangles in %.3f s wall (%d threads)\n",
              name, vertices, triangles, mesh_s, model.threads());
}

}  // namespace

int main(int argc, char** argv) {
  double spacing = 0.1, cell = 0;
  int cycles = 20000, threads = 1;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--spacing") && i + 1 < argc)
      spacing = std::atof(argv[++i]);
    else if (!std::strcmp(argv[i], "--cell") && i + 1 < argc)
      cell = std::atof(argv[++i]);
    else if (!std::strcmp(argv[i], "--cycles") && i + 1 < argc)
      cycles = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--threads") && i + 1 < argc)
      threads = std::atoi(argv[++i]);
    else {
      std::fprintf(stderr,
                   "usage: cutting_bench [--spacing MM] [--cell MM] [--cycles N] [--threads N]\n");
      return 2;
    }
  }
  if (!(spacing >= 0.01) || !(cell >= 0) || cycles < 2 || threads < 0) {
    std::fprintf(stderr,
                 "cutting_bench: --spacing must be >= 0.01, --cycles >= 2, --threads >= 0\n");
    return 2;
  }
  run("freeform", PartId::kFreeform, freeform_path(cycles), spacing, cell, threads);
  run("freeform-30", PartId::kFreeform, freeform_path(cycles, 30), spacing, cell, threads);
  run("implant", PartId::kImplant, implant_path(cycles), spacing, cell, threads);
  return 0;
}
