// Cost of the compensation component, printed as percentiles and as a
// fraction of a 125 us (8 kHz) and a 1 ms (1 kHz) servo period.
//
//   truecut_comp_bench [--calls N] [--cycles N] [--path-cycles N] [--wall-seconds S]
//                      [--no-load] [--no-fifo]
//
// 1. The component's per-cycle logic alone (rt::comp::step(), the code
//    truecut_comp.so runs between its pin reads and writes), with the field
//    in cache (a smooth path: consecutive cycles touch the same cells) and
//    cold (random points in a field far larger than the caches), next to a
//    plain trilinear lookup of the same field (the FANUC-style baseline) and
//    the component running on that trilinear field. Variants are measured in
//    interleaved blocks in the same run. Each call is timed alone with the
//    TSC; the timer's own cost is printed and not subtracted.
// 2. A whole servo cycle in simulated time: siggen -> truecut_comp (joint
//    mode: forward kinematics, correction, inverse kinematics) -> five
//    pos_loop joints, against the same chain without the component.
// 3. The same chain on the wall clock at 8 kHz, servo thread on CPU 1 under
//    SCHED_FIFO 80 (when permitted), a load on CPU 0.
// 4. truecut_comp's servo function alone in the HAL shim (one Executor::step()
//    of a thread that runs only the component: its update, the executor's
//    call), on each path of issue 19 point 7 (tests/rt/comp_cycle_paths.hpp,
//    the paths whose instructions rt_test_truecut_comp_callgrind counts):
//    plain, cross-fade in progress, joint mode with A/C turning, fault
//    (TCP outside the grid, fading out). Paths in interleaved blocks; the
//    last row is the step of a thread without a function (the executor's share).
#include <pthread.h>
#include <sched.h>
#include <x86intrin.h>

#include <sys/mman.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "comp_cycle_paths.hpp"
#include "truecut/rt/comp.hpp"
#include "truecut/rt/duration_histogram.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/rt/field_file.hpp"
#include "truecut/rt/hal_file.hpp"

using namespace truecut;
using Vec3 = Eigen::Vector3d;

namespace {

// ---- timing -----------------------------------------------------------

double g_ns_per_tick = 1.0;

void calibrate_tsc() {
  const auto t0 = std::chrono::steady_clock::now();
  const uint64_t c0 = __rdtsc();
  while (std::chrono::steady_clock::now() - t0 < std::chrono::milliseconds(200)) {
  }
  const uint64_t c1 = __rdtsc();
  const double ns =
      std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count();
  g_ns_per_tick = ns / double(c1 - c0);
}

inline uint64_t ticks() {
  _mm_lfence();
  const uint64_t t = __rdtsc();
  _mm_lfence();
  return t;
}

void print_header() {
  std::printf("  %-44s %9s %9s %9s %9s | %8s %8s %9s\n", "", "median", "p99", "p99.99", "max",
              "med/125", "med/1ms", "p9999/125");
  std::printf("  %-44s %9s %9s %9s %9s | %8s %8s %9s\n", "", "us", "us", "us", "us", "%", "%", "%");
}

void print_row(const char* name, const rt::DurationHistogram& h) {
  const double med = double(h.percentile_ns(0.5)), p99 = double(h.percentile_ns(0.99)),
               p9999 = double(h.percentile_ns(0.9999)), mx = double(h.max_ns());
  std::printf("  %-44s %9.3f %9.3f %9.3f %9.3f | %8.3f %8.4f %9.3f\n", name, med * 1e-3, p99 * 1e-3,
              p9999 * 1e-3, mx * 1e-3, 100.0 * med / 125'000.0, 100.0 * med / 1'000'000.0,
              100.0 * p9999 / 125'000.0);
}

// ---- fields -------------------------------------------------------------

rt::CorrectionField make_field(std::array<int32_t, 3> dims, double spacing_mm,
                               rt::FieldInterpolation interpolation) {
  rt::FieldGrid g;
  g.origin_mm = Vec3::Zero();
  g.spacing_mm = Vec3::Constant(spacing_mm);
  g.dims = dims;
  rt::FieldLayer layer;
  layer.tool = 1;
  layer.nodes.resize(static_cast<std::size_t>(g.node_count()));
  for (int32_t k = 0; k < dims[2]; ++k)
    for (int32_t j = 0; j < dims[1]; ++j)
      for (int32_t i = 0; i < dims[0]; ++i) {
        const Vec3 p = g.node_position_mm(i, j, k);
        layer.nodes[static_cast<std::size_t>(g.index(i, j, k))] = {
            0.05 * std::sin(0.05 * p.x()), 0.04 * std::cos(0.07 * p.y()),
            0.03 * std::sin(0.03 * (p.x() + p.z())), 1.0};
      }
  return rt::CorrectionField(g, {std::move(layer)}, interpolation);
}

// ---- 1. the component alone ----------------------------------------------

struct Xorshift {
  uint64_t s = 0x9E3779B97F4A7C15ull;
  double next01() {
    s ^= s << 13;
    s ^= s >> 7;
    s ^= s << 17;
    return double(s >> 11) * 0x1.0p-53;
  }
};

// A point source: a smooth path (warm) or uniform random points (cold).
struct Points {
  Vec3 extent_mm = Vec3::Ones();
  bool random = false;
  Xorshift rng;
  double t = 0.0;
  Vec3 next() {
    if (random)
      return {rng.next01() * extent_mm.x(), rng.next01() * extent_mm.y(),
              rng.next01() * extent_mm.z()};
    t += 1e-3;  // 1 kHz
    const Vec3 c = 0.5 * extent_mm;
    return c + Vec3(0.3 * extent_mm.x() * std::cos(0.2 * t),
                    0.3 * extent_mm.y() * std::sin(0.2 * t),
                    0.2 * extent_mm.z() * std::sin(0.05 * t));
  }
};

volatile double g_sink;

struct ComponentVariant {
  rt::comp::CompState state;
  const rt::CorrectionField* field;
  rt::comp::CompLimits limits{10.0, 1e6, 0.0};
  explicit ComponentVariant(const rt::CorrectionField* f) : field(f) {
    rt::comp::CycleInput in;
    in.enable = true;
    in.tool = 1;
    in.tcp_mm = Vec3::Constant(1.0);
    in.candidate = f;
    rt::comp::step(state, in, limits, 1e-3);
  }
  void run(const Vec3& p) {
    rt::comp::CycleInput in;
    in.enable = true;
    in.tool = 1;
    in.tcp_mm = p;
    g_sink = rt::comp::step(state, in, limits, 1e-3).correction_mm.x();
  }
};

void bench_component(std::size_t calls) {
  // 161 x 161 x 81 nodes at 1 mm: 2.1 M nodes, 67 MB of node values and 69 MB
  // of B-spline coefficients per field, far beyond any cache.
  const std::array<int32_t, 3> dims{161, 161, 81};
  std::printf("building two %d x %d x %d fields (tricubic, trilinear) ...\n", dims[0], dims[1],
              dims[2]);
  const auto cubic = make_field(dims, 1.0, rt::FieldInterpolation::kTricubicBspline);
  const auto linear = make_field(dims, 1.0, rt::FieldInterpolation::kTrilinear);
  const Vec3 extent(dims[0] - 1, dims[1] - 1, dims[2] - 1);

  ComponentVariant comp_cubic(&cubic), comp_linear(&linear);
  enum Kind { kComponentCubic, kComponentLinear, kLookupCubic, kLookupLinear, kTimerOnly };
  struct Variant {
    std::string name;
    Kind kind;
    rt::DurationHistogram h;
    Points points;
  };
  std::vector<Variant> v;
  auto add = [&](const char* name, Kind kind, bool cold) {
    Variant x{std::string(name) + (kind == kTimerOnly ? ""
                                   : cold             ? ", cold"
                                                      : ", warm"),
              kind,
              {},
              {}};
    x.points.extent_mm = extent;
    x.points.random = cold;
    v.push_back(std::move(x));
  };
  for (bool cold : {false, true}) {
    add("component, tricubic field", kComponentCubic, cold);
    add("component, trilinear field", kComponentLinear, cold);
    add("lookup tricubic (evaluate)", kLookupCubic, cold);
    add("lookup trilinear (FANUC-style)", kLookupLinear, cold);
  }
  add("timer alone (rdtsc pair)", kTimerOnly, false);

  const std::size_t block = 10'000;
  for (std::size_t done = 0; done < calls; done += block) {
    for (Variant& x : v) {
      // Idle between blocks (not measured) keeps a SCHED_FIFO measuring
      // thread far below the kernel's real-time throttling budget.
      std::this_thread::sleep_for(std::chrono::milliseconds(3));
      for (std::size_t i = 0; i < block; ++i) {
        const Vec3 p = x.points.next();
        uint64_t t0 = 0, t1 = 0;
        switch (x.kind) {
          case kComponentCubic:
            t0 = ticks();
            comp_cubic.run(p);
            t1 = ticks();
            break;
          case kComponentLinear:
            t0 = ticks();
            comp_linear.run(p);
            t1 = ticks();
            break;
          case kLookupCubic:
            t0 = ticks();
            g_sink = cubic.evaluate_tricubic(1, p).correction_mm.x();
            t1 = ticks();
            break;
          case kLookupLinear:
            t0 = ticks();
            g_sink = cubic.evaluate_trilinear(1, p).correction_mm.x();
            t1 = ticks();
            break;
          case kTimerOnly:
            t0 = ticks();
            t1 = ticks();
            break;
        }
        x.h.add(static_cast<int64_t>(std::llround(double(t1 - t0) * g_ns_per_tick)));
      }
    }
  }
  std::printf("\n1. Per call, %zu calls per variant, interleaved blocks of %zu:\n", calls, block);
  print_header();
  for (const Variant& x : v)
    print_row(x.name.c_str(), x.h);
}

// ---- 2./3. the whole servo cycle ------------------------------------------

std::string chain(int64_t period_ns, const std::string& field_file) {
  std::string s = "loadrt threads name1=servo-thread period1=" + std::to_string(period_ns) + "\n";
  // The TCP stays inside the field's grid: |x|, |y| < 55 mm, |z| < 18 mm.
  s += "loadrt siggen names=path,lift,tilt\nloadrt pos_loop names=x,y,z,a,c\n";
  s += "setp path.amplitude 40\nsetp path.frequency 0.2\nsetp lift.amplitude 15\n";
  s += "setp lift.frequency 0.3\nsetp tilt.amplitude 20\nsetp tilt.frequency 0.1\n";
  const char* j[] = {"x", "y", "z", "a", "c"};
  const char* src[] = {"path.cosine", "path.sine", "lift.triangle", "tilt.sine", "tilt.sawtooth"};
  if (!field_file.empty()) {
    s += "loadrt truecut_comp names=comp mode=joint field=" + field_file + "\n";
    s += "setp comp.enable 1\nsetp comp.tool 1\nsetp comp.z-rot-point 40\nsetp comp.fade-time 0\n";
    for (int i = 0; i < 5; ++i) {
      s += std::string("net ") + j[i] + "-in " + src[i] + " => comp.joint-" + j[i] + "\n";
      s +=
          std::string("net ") + j[i] + "-cmd comp.joint-" + j[i] + "-out => " + j[i] + ".pos-cmd\n";
    }
  } else {
    for (int i = 0; i < 5; ++i)
      s += std::string("net ") + j[i] + "-cmd " + src[i] + " => " + j[i] + ".pos-cmd\n";
  }
  s += "addf path.update servo-thread\naddf lift.update servo-thread\n";
  s += "addf tilt.update servo-thread\n";
  if (!field_file.empty()) s += "addf comp.update servo-thread\n";
  for (const char* n : j)
    s += std::string("addf ") + n + ".update servo-thread\n";
  return s;
}

rt::hal::HalOptions hal_options() {
  rt::hal::HalOptions o;
  o.component_path = {TRUECUT_COMPONENT_DIR};
  o.output_dir = std::filesystem::temp_directory_path();
  return o;
}

rt::hal::ThreadStats run_chain(const std::string& field_file, uint64_t cycles, int64_t period_ns,
                               const rt::hal::WallClockOptions* wall,
                               std::vector<std::string>* notes = nullptr) {
  rt::hal::Hal h(hal_options());
  rt::hal::load_hal_text(h, chain(period_ns, field_file), "bench.hal");
  rt::hal::Executor ex(h);
  rt::hal::RunLimits lim;
  lim.max_cycles = cycles;
  const rt::hal::RunReport r = wall ? ex.run_wall_clock(lim, *wall) : ex.run_simulated(lim);
  if (notes) *notes = r.notes;
  return r.threads.at(0);
}

// ---- 4. the servo function per path -----------------------------------------

void bench_paths(uint64_t cycles) {
  using truecut::test::comp::cycle_path_name;
  using truecut::test::comp::CyclePath;
  using truecut::test::comp::CyclePathRig;
  const auto dir = std::filesystem::temp_directory_path() /
                   ("truecut_comp_bench_paths-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  struct Path {
    CyclePath path;
    std::unique_ptr<CyclePathRig> rig;
    rt::DurationHistogram h;
  };
  std::vector<Path> paths;
  for (CyclePath p : truecut::test::comp::kAllCyclePaths) {
    std::filesystem::create_directories(dir / cycle_path_name(p));
    // The cross-fade and the fade-out last past the whole run (1 ms cycles).
    const double fade_s = 2.0 * double(cycles) * 1e-3 + 10.0;
    paths.push_back(
        {p,
         std::make_unique<CyclePathRig>(p, dir / cycle_path_name(p), fade_s, hal_options()),
         {}});
  }
  // The executor's own share of a step: the same thread without a function.
  rt::hal::Hal empty_hal(hal_options());
  rt::hal::load_hal_text(empty_hal, "loadrt threads name1=servo-thread period1=1000000\n",
                         "empty.hal");
  rt::hal::Executor empty(empty_hal);
  rt::DurationHistogram empty_h;
  const uint64_t block = 10'000;
  uint64_t n = 0;
  for (uint64_t done = 0; done < cycles; done += block)
    for (Path& x : paths) {
      std::this_thread::sleep_for(std::chrono::milliseconds(3));  // see bench_component()
      for (uint64_t i = 0; i < block; ++i) {
        x.rig->drive(n + i);
        const uint64_t t0 = ticks();
        x.rig->executor().step();
        const uint64_t t1 = ticks();
        x.h.add(static_cast<int64_t>(std::llround(double(t1 - t0) * g_ns_per_tick)));
      }
      n += block;
    }
  for (uint64_t done = 0; done < cycles; done += block) {
    std::this_thread::sleep_for(std::chrono::milliseconds(3));
    for (uint64_t i = 0; i < block; ++i) {
      const uint64_t t0 = ticks();
      empty.step();
      const uint64_t t1 = ticks();
      empty_h.add(static_cast<int64_t>(std::llround(double(t1 - t0) * g_ns_per_tick)));
    }
  }
  std::printf(
      "\n4. truecut_comp's servo function per path (HAL shim, one executor step), %llu cycles "
      "per path, interleaved blocks of %llu:\n",
      static_cast<unsigned long long>(cycles), static_cast<unsigned long long>(block));
  print_header();
  for (Path& x : paths) {
    const std::string why = x.rig->check();
    print_row(
        (std::string(cycle_path_name(x.path)) + (why.empty() ? "" : " (NOT IN ITS STATE)")).c_str(),
        x.h);
    if (!why.empty()) std::printf("    %s\n", why.c_str());
  }
  print_row("executor step without a function", empty_h);
  paths.clear();
  std::filesystem::remove_all(dir);
}

void load_cpu(int cpu, std::atomic<bool>& stop) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  pthread_setaffinity_np(pthread_self(), sizeof set, &set);
  std::vector<double> buf(4 << 20, 1.0);
  std::size_t i = 0;
  double acc = 0;
  while (!stop.load(std::memory_order_relaxed)) {
    for (int k = 0; k < 4096; ++k, i = (i + 4099) % buf.size())
      acc += buf[i] * 1.0000001;
    buf[i % buf.size()] = acc;
  }
}

void bench_cycle(uint64_t cycles, double wall_seconds, bool load) {
  // 121 x 121 x 61 nodes at 1 mm around the machine origin (29 MB payload).
  const auto dir = std::filesystem::temp_directory_path();
  const auto cubic_file = dir / "truecut_comp_bench_cubic.tcf";
  const auto linear_file = dir / "truecut_comp_bench_linear.tcf";
  for (auto [file, interp] : {std::pair{cubic_file, rt::FieldInterpolation::kTricubicBspline},
                              std::pair{linear_file, rt::FieldInterpolation::kTrilinear}}) {
    rt::CorrectionField f = make_field({121, 121, 61}, 1.0, interp);
    // Centred on the workpiece origin, where the path runs.
    rt::FieldGrid shifted = f.grid();
    shifted.origin_mm = Vec3(-60.0, -60.0, -30.0);
    rt::FieldLayer layer{1, std::vector<rt::FieldNode>(f.nodes(1).begin(), f.nodes(1).end())};
    rt::write_field_file(file, rt::CorrectionField(shifted, {std::move(layer)}, interp),
                         {"", "truecut_comp_bench"});
  }
  if (cycles > 0) {
    std::printf(
        "\n2. Whole servo cycle, simulated time, %llu cycles (siggen x3, [truecut_comp "
        "joint mode], pos_loop x5):\n",
        static_cast<unsigned long long>(cycles));
    print_header();
    auto pause = [] { std::this_thread::sleep_for(std::chrono::milliseconds(500)); };  // see above
    pause();
    const auto none = run_chain("", cycles, 125'000, nullptr);
    pause();
    const auto cubic = run_chain(cubic_file.string(), cycles, 125'000, nullptr);
    pause();
    const auto linear = run_chain(linear_file.string(), cycles, 125'000, nullptr);
    print_row("cycle without component", none.compute);
    print_row("cycle with truecut_comp, tricubic field", cubic.compute);
    print_row("cycle with truecut_comp, trilinear field", linear.compute);
  }

  if (wall_seconds > 0) {
    std::atomic<bool> stop{false};
    std::thread loader;
    if (load) loader = std::thread(load_cpu, 0, std::ref(stop));
    rt::hal::WallClockOptions w;
    w.cpu = 1;
    w.fifo_priority = 80;
    const uint64_t n = static_cast<uint64_t>(wall_seconds * 8000);
    std::vector<std::string> notes;
    const auto wall = run_chain(cubic_file.string(), n, 125'000, &w, &notes);
    stop = true;
    if (loader.joinable()) loader.join();
    std::printf("\n3. Whole servo cycle, wall clock, 8 kHz, %llu cycles, %s:\n",
                static_cast<unsigned long long>(n), load ? "load on CPU 0" : "no load");
    for (const auto& note : notes)
      std::printf("  (%s)\n", note.c_str());
    print_header();
    print_row("compute, cycle with truecut_comp (tricubic)", wall.compute);
    print_row("wake-up latency", wall.latency);
    std::printf("  overruns: %llu of %llu cycles\n", static_cast<unsigned long long>(wall.overruns),
                static_cast<unsigned long long>(wall.cycles));
  }
  std::filesystem::remove(cubic_file);
  std::filesystem::remove(linear_file);
}

}  // namespace

int main(int argc, char** argv) {
  std::size_t calls = 1'000'000;
  uint64_t cycles = 400'000;
  uint64_t path_cycles = 1'000'000;
  double wall_seconds = 10.0;
  bool load = true, fifo = true;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--calls" && i + 1 < argc)
      calls = std::strtoull(argv[++i], nullptr, 10);
    else if (a == "--cycles" && i + 1 < argc)
      cycles = std::strtoull(argv[++i], nullptr, 10);
    else if (a == "--path-cycles" && i + 1 < argc)
      path_cycles = std::strtoull(argv[++i], nullptr, 10);
    else if (a == "--wall-seconds" && i + 1 < argc)
      wall_seconds = std::atof(argv[++i]);
    else if (a == "--no-load")
      load = false;
    else if (a == "--no-fifo")
      fifo = false;
    else {
      std::fprintf(stderr,
                   "usage: truecut_comp_bench [--calls N] [--cycles N] [--path-cycles N] "
                   "[--wall-seconds S] [--no-load] [--no-fifo]\n");
      return 2;
    }
  }
  calibrate_tsc();
  std::printf("TSC: %.4f ns per tick\n", g_ns_per_tick);
  // Parts 1 and 2 run in a thread pinned to CPU 1 under SCHED_FIFO 80 (when
  // permitted), as the servo thread would, so that other processes do not
  // preempt the measurement.
  std::thread measure([&] {
    if (fifo) {
      cpu_set_t set;
      CPU_ZERO(&set);
      CPU_SET(1, &set);
      const int rc_cpu = pthread_setaffinity_np(pthread_self(), sizeof set, &set);
      sched_param sp{};
      sp.sched_priority = 80;
      const int rc_fifo = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
      const int rc_lock = mlockall(MCL_CURRENT | MCL_FUTURE);
      std::printf("measuring thread: %s, %s, %s\n", rc_cpu == 0 ? "on CPU 1" : "not pinned",
                  rc_fifo == 0 ? "SCHED_FIFO 80" : "normal scheduling (SCHED_FIFO refused)",
                  rc_lock == 0 ? "memory locked" : "memory not locked");
    }
    bench_component(calls);
    bench_cycle(cycles, 0.0, false);
    if (path_cycles > 0) bench_paths(path_cycles);
    if (fifo) munlockall();
  });
  measure.join();
  if (wall_seconds > 0) bench_cycle(0, wall_seconds, load);
  return 0;
}
