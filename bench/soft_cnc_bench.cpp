// How much faster than real time the soft-CNC loop machines each benchmark
// part (truecut run MACHINE PROGRAM): planned program time / wall time, on
// the part's machine with its hidden physics, by stage: before the first
// cycle (checking and planning the program, loading the wiring with its
// cutting model), the machining loop, and after it (the machined mesh and
// the files).
//
//   soft_cnc_bench [--fine] [--sweep] [--cut-threads N]
//     default   coarse parts (mesh edge, stepover and point spacing 1 mm,
//               step-down 2 mm), dexels 0.1 mm on the implant, 0.3 mm on the others
//     --fine    the default part resolution (as `truecut part NAME`)
//     --sweep   each part coarse, coarse with dexels half as far apart, and
//               at the default resolution: how each stage grows
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

#include "truecut/sim/benchmark_parts.hpp"
#include "truecut/sim/soft_cnc.hpp"

namespace {

using namespace truecut;
namespace fs = std::filesystem;

struct Case {
  bool fine;
  double dexel_scale;  // of the part's default dexel spacing
};

double default_spacing_mm(sim::PartId id) {
  return id == sim::PartId::kImplant ? 0.1 : 0.3;
}

// The dexel count from the cutting component's load message.
long dexels_in(const std::string& messages) {
  const auto at = messages.find(" dexels from ");
  if (at == std::string::npos) return -1;
  auto begin = messages.rfind(' ', at - 1);
  return std::atol(messages.c_str() + (begin == std::string::npos ? 0 : begin + 1));
}

void run_case(sim::PartId id, const Case& c, int cut_threads, const fs::path& root) {
  sim::PartOptions o;
  if (!c.fine) {
    o.mesh_edge_mm = 1.0;
    o.stepover_mm = 1.0;
    o.point_spacing_mm = 1.0;
    o.step_down_mm = 2.0;
  }
  const sim::BenchmarkPart part = sim::make_part(id, o);
  const fs::path dir = root / std::string(sim::part_name(id));
  fs::remove_all(dir);
  sim::write_part(part, dir);
  sim::SoftCncJob job = sim::part_folder_job(dir, dir / "run");
  job.dexel_spacing_mm = default_spacing_mm(id) * c.dexel_scale;
  job.cut_threads = cut_threads;
  job.component_path = {TRUECUT_COMPONENT_DIR};
  std::string messages;
  job.message_sink = [&](const std::string& line) { messages += line; };
  const sim::SoftCncResult r = sim::run_soft_cnc(job);
  const double command_s = r.load_wall_s + r.wall_s + r.unload_wall_s;
  std::printf("%-13s %-7s %6.2f %9ld %10.1f %8.2f %8.2f %8.2f %8.2f %7.1f %7.1f%s\n",
              std::string(sim::part_name(id)).c_str(), c.fine ? "default" : "coarse",
              job.dexel_spacing_mm, dexels_in(messages), r.simulated_s, r.load_wall_s, r.wall_s,
              r.unload_wall_s, command_s, r.wall_s > 0 ? r.simulated_s / r.wall_s : 0.0,
              command_s > 0 ? r.simulated_s / command_s : 0.0,
              r.finished ? "" : "  (did not finish)");
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  bool fine = false, sweep = false;
  int cut_threads = 0;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--fine") == 0) {
      fine = true;
    } else if (std::strcmp(argv[i], "--sweep") == 0) {
      sweep = true;
    } else if (std::strcmp(argv[i], "--cut-threads") == 0 && i + 1 < argc) {
      cut_threads = std::atoi(argv[++i]);
    } else {
      std::fprintf(stderr, "usage: soft_cnc_bench [--fine] [--sweep] [--cut-threads N]\n");
      return 2;
    }
  }
  const std::vector<Case> cases = sweep ? std::vector<Case>{{false, 1.0}, {false, 0.5}, {true, 1.0}}
                                        : std::vector<Case>{{fine, 1.0}};
  const fs::path root =
      fs::temp_directory_path() / ("truecut_soft_cnc_bench_" + std::to_string(::getpid()));
  std::printf("%-13s %-7s %6s %9s %10s %8s %8s %8s %8s %7s %7s\n", "part", "parts", "dexel",
              "dexels", "program s", "load s", "loop s", "write s", "all s", "x loop", "x all");
  for (sim::PartId id : {sim::PartId::kImplant, sim::PartId::kBenchmark004, sim::PartId::kFreeform})
    for (const Case& c : cases)
      run_case(id, c, cut_threads, root);
  fs::remove_all(root);
  return 0;
}
