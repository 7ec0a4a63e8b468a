// Offline stages at the model-adaptation source's scale (624,436 scan
// points, 113,896 nominal faces): registration, ray error vectors, sphere
// error vectors, and Embree's raw throughput for the same rays, on 1 thread
// and on all threads. Prints figures; asserts nothing.
//
// Then the whole `truecut field` pipeline (registration, ray error vectors,
// truss, tool path, tool-centre placement, field fit) on the same data with a
// ball-end raster program, stage by stage (wall and process CPU time).
//
//   build/offline_stages_bench [--repeat N] [--pipeline-only] [--resolution MM]
#include "truecut/interp/interpreter.hpp"
#include "truecut/offline/compensation_points.hpp"
#include "truecut/offline/error_vectors.hpp"
#include "truecut/offline/field_pipeline.hpp"
#include "truecut/offline/ray_scene.hpp"
#include "truecut/offline/registration.hpp"

#include <pthread.h>
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/task_scheduler_observer.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <functional>
#include <mutex>
#include <random>
#include <string>
#include <vector>

using namespace truecut::offline;
namespace interp = truecut::interp;
namespace rt = truecut::rt;

namespace {

// A warped free-form sheet, 46 × 309.5 mm, 92 × 619 quads = 113,896 faces.
constexpr int kNx = 92, kNy = 619;
constexpr double kSx = 46.0, kSy = 309.5;

double nominal_z(double x, double y) {
  return 3.0 * std::sin(x / 15.0) * std::cos(y / 40.0);
}
// The part as machined: 0.05 mm oversize and bent along y by up to 0.2 mm.
double machined_z(double x, double y) {
  const double t = y / kSy;
  return nominal_z(x, y) + 0.05 + 0.2 * t * t * (3 - t) / 2;
}

TriangleMesh sheet(int nx, int ny, const std::function<double(double, double)>& z) {
  TriangleMesh m;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const double x = kSx * i / nx, y = kSy * j / ny;
      m.vertices_mm.emplace_back(x, y, z(x, y));
    }
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

// 624,436 points on the machined sheet, σ = 0.03 mm along z.
std::vector<Eigen::Vector3d> scan_cloud() {
  std::mt19937_64 rng(624436);
  std::uniform_real_distribution<double> ux(0.0, kSx), uy(0.0, kSy);
  std::normal_distribution<double> noise(0.0, 0.03);
  std::vector<Eigen::Vector3d> p(624436);
  for (auto& q : p) {
    const double x = ux(rng), y = uy(rng);
    q = {x, y, machined_z(x, y) + noise(rng)};
  }
  return p;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Process CPU time of the best run, all threads together: on a shared
// machine it shows the work when the wall clock shows the load.
double g_cpu_s = 0.0;

// Best of `repeat` runs of f, wall-clock seconds; its CPU time in g_cpu_s.
double best_of(int repeat, const std::function<void()>& f) {
  double best = 1e300;
  for (int r = 0; r < repeat; ++r) {
    const std::clock_t c0 = std::clock();
    const auto t0 = std::chrono::steady_clock::now();
    f();
    const double wall = seconds_since(t0);
    if (wall < best) {
      best = wall;
      g_cpu_s = double(std::clock() - c0) / CLOCKS_PER_SEC;
    }
  }
  return best;
}

// Ball end mill R 3, axis +Z, raster along y every 1 mm across x, points
// every 0.5 mm: the tip is P + R·n − R·z for the contact point P (normal n).
std::string raster_program() {
  std::string g = "G21 G17 G40 G49 G80 G90 G94\nG54\nT1 M6\nG43 H1\n";
  char line[128];
  bool up = true;
  for (double x = 1.5; x <= kSx - 1.5 + 1e-9; x += 1.0) {
    for (int k = 0; k <= 619; ++k) {
      const double y = (up ? k : 619 - k) * 0.5;
      const double fx = 3.0 / 15.0 * std::cos(x / 15.0) * std::cos(y / 40.0);
      const double fy = -3.0 / 40.0 * std::sin(x / 15.0) * std::sin(y / 40.0);
      const Eigen::Vector3d n = Eigen::Vector3d(-fx, -fy, 1.0).normalized();
      const Eigen::Vector3d tip =
          Eigen::Vector3d(x, y, nominal_z(x, y)) + 3.0 * n - Eigen::Vector3d(0, 0, 3.0);
      if (k == 0) {
        std::snprintf(line, sizeof line, "G0 X%.4f Y%.4f Z10\nG1 Z%.4f F2000\n", tip.x(), tip.y(),
                      tip.z());
      } else {
        std::snprintf(line, sizeof line, "G1 X%.4f Y%.4f Z%.4f\n", tip.x(), tip.y(), tip.z());
      }
      g += line;
    }
    g += "G0 Z10\n";
    up = !up;
  }
  return g + "M30\n";
}

// CPU time of every thread that works for the pipeline: the main thread and
// TBB's workers (registered when they join the arena). On a loaded machine
// the wall clock shows the load; the busiest thread's CPU time and the
// total CPU time show the work: on an idle machine with N cores the run
// takes at least max(busiest thread, total / N).
class ThreadClocks : public tbb::task_scheduler_observer {
 public:
  ThreadClocks() {
    add_current();
    observe(true);
  }
  ~ThreadClocks() override { observe(false); }
  void on_scheduler_entry(bool) override { add_current(); }
  // CPU seconds per known thread, in the order they were registered.
  std::vector<double> read() {
    std::lock_guard lock(mutex_);
    std::vector<double> s;
    for (clockid_t c : clocks_) {
      timespec ts{};
      s.push_back(clock_gettime(c, &ts) == 0 ? double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec) : 0.0);
    }
    return s;
  }

 private:
  void add_current() {
    clockid_t c;
    if (pthread_getcpuclockid(pthread_self(), &c) != 0) return;
    std::lock_guard lock(mutex_);
    const pthread_t self = pthread_self();
    for (pthread_t t : threads_)
      if (pthread_equal(t, self)) return;
    threads_.push_back(self);
    clocks_.push_back(c);
  }
  std::mutex mutex_;
  std::vector<pthread_t> threads_;
  std::vector<clockid_t> clocks_;
};

struct CpuSplit {
  double total_s = 0.0;    // all threads
  double busiest_s = 0.0;  // the thread that worked most
};
CpuSplit cpu_between(const std::vector<double>& before, const std::vector<double>& after) {
  CpuSplit c;
  for (std::size_t i = 0; i < after.size(); ++i) {
    const double d = after[i] - (i < before.size() ? before[i] : 0.0);
    c.total_s += d;
    c.busiest_s = std::max(c.busiest_s, d);
  }
  return c;
}

double load_average() {
  double l[1] = {0.0};
  return getloadavg(l, 1) == 1 ? l[0] : -1.0;
}

void run_pipeline(const TriangleMesh& nominal, const TriangleMesh& scan_mesh, double resolution_mm,
                  int repeat) {
  const auto t0 = std::chrono::steady_clock::now();
  interp::InterpreterOptions io;
  io.tools = interp::ToolTable::parse("T1 P1 D6 Z60\n", "tools.tbl");
  const interp::CanonProgram program =
      interp::Interpreter(std::move(io)).run_text(raster_program(), "raster.ngc");
  std::printf("\n--- whole pipeline (truecut field), all threads ---\n");
  std::printf("interpreter, raster program of %zu calls: %.3f s (outside the pipeline)\n",
              program.calls.size(), seconds_since(t0));
  FieldPipelineInputs in;
  in.nominal = &nominal;
  in.scan = &scan_mesh;
  in.program = &program;
  in.tools = {{1, 3.0, 3.0, 12.0}};
  ThreadClocks clocks;

  // Stage by stage, one after the other: per-stage wall and CPU.
  FieldPipelineOptions sequential;
  sequential.fit.spacing_mm = resolution_mm;
  sequential.concurrent_stages = false;
  std::printf("stages one after the other (concurrent_stages = false), best of %d:\n", repeat);
  struct StageFigures {
    std::string name, detail;
    double wall_s = 1e300;
    CpuSplit cpu;
  };
  std::vector<StageFigures> stages;
  for (int r = 0; r < repeat; ++r) {
    std::vector<double> last = clocks.read();
    std::size_t k = 0;
    run_field_pipeline(in, sequential,
                       [&](const std::string& stage, double s, const std::string& d) {
                         const std::vector<double> now = clocks.read();
                         if (k >= stages.size()) stages.push_back({stage, d, 1e300, {}});
                         if (s < stages[k].wall_s) {
                           stages[k].wall_s = s;
                           stages[k].cpu = cpu_between(last, now);
                           stages[k].detail = d;
                         }
                         last = now;
                         ++k;
                       });
  }
  double sum_wall = 0, sum_cpu = 0, sum_busiest = 0;
  std::printf("  %-34s %8s %8s %8s\n", "stage", "wall s", "cpu s", "busiest");
  for (const StageFigures& f : stages) {
    std::printf("  %-34s %8.3f %8.3f %8.3f  %s\n", f.name.c_str(), f.wall_s, f.cpu.total_s,
                f.cpu.busiest_s, f.detail.c_str());
    sum_wall += f.wall_s;
    sum_cpu += f.cpu.total_s;
    sum_busiest += f.cpu.busiest_s;
  }
  std::printf("  %-34s %8.3f %8.3f %8.3f\n", "sum of the stages", sum_wall, sum_cpu, sum_busiest);

  // The pipeline as `truecut field` runs it: the scan and program chains
  // concurrently.
  FieldPipelineOptions o;
  o.fit.spacing_mm = resolution_mm;
  FieldPipelineResult best;
  CpuSplit best_cpu;
  std::printf("whole pipeline, concurrent stages (as truecut field runs it):\n");
  for (int r = 0; r < repeat; ++r) {
    const double load = load_average();
    const std::vector<double> before = clocks.read();
    const std::clock_t c0 = std::clock();
    FieldPipelineResult res = run_field_pipeline(in, o);
    const double process_cpu = double(std::clock() - c0) / CLOCKS_PER_SEC;
    const CpuSplit cpu = cpu_between(before, clocks.read());
    std::printf(
        "  run %d: wall %.3f s, cpu %.3f s (process %.3f s), busiest thread %.3f s, load "
        "average %.2f\n",
        r + 1, res.total_wall_s, cpu.total_s, process_cpu, cpu.busiest_s, load);
    if (r == 0 || res.total_wall_s < best.total_wall_s) {
      best = std::move(res);
      best_cpu = cpu;
    }
  }
  const int cores = tbb::info::default_concurrency();
  std::printf(
      "  on an idle machine with %d cores at least max(busiest thread, cpu / %d) = %.3f s wall\n",
      cores, cores, std::max(best_cpu.busiest_s, best_cpu.total_s / cores));
  // Fingerprints of results that must not change with an optimisation.
  unsigned long long placement_sum = 0;
  for (const ToolPlacement& tp : best.placement.tools)
    for (const PointPlacement& pp : tp.points)
      placement_sum = placement_sum * 1000003ull + pp.point * 7919ull + pp.sample;
  std::printf("placement fingerprint %016llx\n", placement_sum);
  if (best.registration) {
    const IcpResult& g = *best.registration;
    std::printf(
        "registration: %d iterations, rms %.6f -> %.6f mm, translation %.9f %.9f %.9f mm, "
        "rotation %.9f deg\n",
        g.iterations, g.rms_before_mm, g.rms_after_mm, g.transform.translation_mm.x(),
        g.transform.translation_mm.y(), g.transform.translation_mm.z(),
        g.transform.rotation_angle_deg);
  }
  double sum_normal = 0.0;
  for (std::size_t i = 0; i < best.errors.size(); ++i)
    sum_normal += best.errors.normal_mm[i];
  std::printf("error vectors: %zu valid, sum of normal components %.9f mm\n",
              best.error_statistics.valid, sum_normal);
  const rt::FieldGrid& g = best.fit->field.grid();
  double node_sum = 0.0;
  for (const rt::FieldNode& n : best.fit->field.nodes(1))
    node_sum += std::abs(n.dx_mm) + std::abs(n.dy_mm) + std::abs(n.dz_mm) + n.weight;
  std::printf(
      "whole pipeline: %.3f s; %zu points, %zu valid, %lld uncut; %zu path samples; field %d x "
      "%d x %d nodes at %.2f mm, %lld unknowns, residual RMS %.6f mm, node checksum %.9f\n",
      best.total_wall_s, best.points.size(), best.error_statistics.valid,
      static_cast<long long>(best.placement.uncut_points), best.path.samples.size(), g.dims[0],
      g.dims[1], g.dims[2], resolution_mm,
      static_cast<long long>(best.fit->layers[0].unknown_nodes),
      best.fit->layers[0].residual_rms_mm, node_sum);
}

}  // namespace

int main(int argc, char** argv) {
  int repeat = 3;
  bool pipeline_only = false;
  double resolution_mm = 1.0;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--repeat") && i + 1 < argc)
      repeat = std::max(1, std::atoi(argv[++i]));
    else if (!std::strcmp(argv[i], "--pipeline-only"))
      pipeline_only = true;
    else if (!std::strcmp(argv[i], "--resolution") && i + 1 < argc)
      resolution_mm = std::max(0.1, std::atof(argv[++i]));
  }
  const int cores = tbb::info::default_concurrency();
  std::printf("offline stages: RelWithDebInfo, best of %d, %d hardware threads\n", repeat, cores);

  const TriangleMesh nominal = sheet(kNx, kNy, nominal_z);
  std::vector<Eigen::Vector3d> cloud = scan_cloud();
  // The scanner's mesh of the same part: ~624k vertices.
  TriangleMesh scan_mesh = sheet(304, 2046, machined_z);
  Eigen::Isometry3d misplaced = Eigen::Isometry3d::Identity();
  misplaced.linear() =
      Eigen::AngleAxisd(0.3 * M_PI / 180, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  misplaced.translation() = Eigen::Vector3d(0.2, -0.1, 0.15);
  transform_points(misplaced, cloud);
  transform_points(misplaced, scan_mesh.vertices_mm);
  std::printf(
      "nominal: %zu faces, %zu vertices; scan cloud: %zu points; scan mesh: %zu faces, "
      "%zu vertices\n",
      nominal.triangles.size(), nominal.vertices_mm.size(), cloud.size(),
      scan_mesh.triangles.size(), scan_mesh.vertices_mm.size());

  if (pipeline_only) {
    run_pipeline(nominal, scan_mesh, resolution_mm, repeat);
    return 0;
  }
  for (int threads : {1, cores}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                              static_cast<std::size_t>(threads));
    std::printf("\n--- %d thread%s ---\n", threads, threads == 1 ? "" : "s");

    IcpResult icp;
    const double t_icp = best_of(repeat, [&] { icp = register_scan(nominal, cloud); });
    std::printf(
        "ICP (k-d tree of %zu points + %d iterations, %zu samples): %.3f s (cpu %.3f s); "
        "rms %.4f -> %.4f mm; angle %.4f deg, shift %.4f mm\n",
        cloud.size(), icp.iterations, icp.samples, t_icp, g_cpu_s, icp.rms_before_mm,
        icp.rms_after_mm, icp.transform.rotation_angle_deg, icp.transform.translation_mm.norm());

    TriangleMesh registered = scan_mesh;
    transform_points(icp.scan_to_nominal, registered.vertices_mm);
    std::vector<Eigen::Vector3d> registered_cloud = cloud;
    transform_points(icp.scan_to_nominal, registered_cloud);

    std::unique_ptr<RayScene> scene;
    const double t_scene = best_of(repeat, [&] { scene = std::make_unique<RayScene>(registered); });
    std::printf("Embree scene build (%zu faces): %.3f s (cpu %.3f s)\n",
                registered.triangles.size(), t_scene, g_cpu_s);

    const std::vector<std::int32_t> ids(nominal.triangles.size(), 0);
    const CompensationPoints points = compensation_points_at_vertices(nominal, ids);
    ErrorVectors e;
    for (RayBatch batch : {RayBatch::kSingle, RayBatch::kPacket16, RayBatch::kStream}) {
      RayMethodOptions o;
      o.batch = batch;
      const double t_rays =
          best_of(repeat, [&] { e = error_vectors_by_rays(nominal, points, *scene, o); });
      const ErrorVectorSummary s = summarize(e);
      const char* name = batch == RayBatch::kSingle     ? "rtcIntersect1"
                         : batch == RayBatch::kPacket16 ? "rtcIntersect16"
                                                        : "rtcIntersect1M";
      std::printf(
          "ray error vectors (%s, %zu points): %.3f s (cpu %.3f s); %zu valid, mean %.4f mm\n",
          name, points.size(), t_rays, g_cpu_s, s.valid, s.mean_normal_mm);
    }

    // The same rays as the stage casts: both ways from every point off the
    // edges, raw (no double refinement).
    std::vector<Ray> rays;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (e.status[i] == ErrorStatus::kNominalEdge) continue;
      const Eigen::Vector3d& p = points.positions_mm[i];
      const Eigen::Vector3d& n = points.normals[i];
      rays.push_back({p - 1e-3 * n, n, 0.0, 1.001});
      rays.push_back({p + 1e-3 * n, -n, 0.0, 1.001});
    }
    std::vector<RayHit> hits(rays.size());
    for (RayBatch batch : {RayBatch::kSingle, RayBatch::kPacket16, RayBatch::kStream}) {
      const double t_raw = best_of(repeat, [&] { scene->intersect(rays, hits, {batch, false}); });
      const char* name = batch == RayBatch::kSingle     ? "rtcIntersect1"
                         : batch == RayBatch::kPacket16 ? "rtcIntersect16"
                                                        : "rtcIntersect1M";
      std::printf("raw Embree, same %zu rays (%s): %.4f s (cpu %.4f s) = %.2f Mrays/s\n",
                  rays.size(), name, t_raw, g_cpu_s, rays.size() / t_raw / 1e6);
    }

    SphereMethodOptions so;
    so.radius_mm = 1.0;
    const double t_sphere = best_of(
        repeat, [&] { e = error_vectors_by_spheres(nominal, points, registered_cloud, so); });
    const ErrorVectorSummary ss = summarize(e, so.radius_mm);
    std::printf(
        "sphere error vectors (Rs %.1f mm, %zu points, %zu cloud points): %.3f s; %zu "
        "valid, median %.1f pt/mm^2 (cpu %.3f s)\n",
        so.radius_mm, points.size(), registered_cloud.size(), t_sphere, ss.valid,
        ss.median_density_per_mm2, g_cpu_s);
  }
  run_pipeline(nominal, scan_mesh, resolution_mm, repeat);
  return 0;
}
