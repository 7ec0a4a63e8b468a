// How much faster than real time the soft-CNC loop machines each benchmark
// part (truecut run MACHINE PROGRAM): planned program time / wall time, on
// the part's machine with its hidden physics.
//
//   soft_cnc_bench [--fine] [--cut-threads N]   (default: coarse parts, 0.3 mm
//                                               dexels, one cutting thread per CPU)
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

#include <unistd.h>

#include "truecut/sim/benchmark_parts.hpp"
#include "truecut/sim/soft_cnc.hpp"

int main(int argc, char** argv) {
  using namespace truecut;
  namespace fs = std::filesystem;
  bool fine = false;
  int cut_threads = 0;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--fine") == 0) {
      fine = true;
    } else if (std::strcmp(argv[i], "--cut-threads") == 0 && i + 1 < argc) {
      cut_threads = std::atoi(argv[++i]);
    } else {
      std::fprintf(stderr, "usage: soft_cnc_bench [--fine] [--cut-threads N]\n");
      return 2;
    }
  }
  const fs::path root =
      fs::temp_directory_path() / ("truecut_soft_cnc_bench_" + std::to_string(::getpid()));
  std::printf("%-13s %10s %10s %12s %8s\n", "part", "program s", "wall s", "x real time",
              "dexel mm");
  for (sim::PartId id :
       {sim::PartId::kImplant, sim::PartId::kBenchmark004, sim::PartId::kFreeform}) {
    sim::PartOptions o;
    if (!fine) {
      o.mesh_edge_mm = 1.0;
      o.stepover_mm = 1.0;
      o.point_spacing_mm = 1.0;
      o.step_down_mm = 2.0;
    }
    const sim::BenchmarkPart part = sim::make_part(id, o);
    const fs::path dir = root / std::string(sim::part_name(id));
    sim::write_part(part, dir);
    sim::SoftCncJob job;
    job.machine = dir / "machine.json";
    job.program = dir / "program.ngc";
    job.nominal = dir / "nominal.stl";
    job.part = dir / "part.json";
    job.tools = dir / "tools.tbl";
    job.out_dir = dir / "run";
    job.dexel_spacing_mm = id == sim::PartId::kImplant ? 0.1 : 0.3;
    job.cut_threads = cut_threads;
    job.component_path = {TRUECUT_COMPONENT_DIR};
    const sim::SoftCncResult r = sim::run_soft_cnc(job);
    std::printf("%-13s %10.1f %10.2f %12.1f %8.2f%s\n", std::string(sim::part_name(id)).c_str(),
                r.simulated_s, r.wall_s, r.wall_s > 0 ? r.simulated_s / r.wall_s : 0.0,
                job.dexel_spacing_mm, r.finished ? "" : "  (did not finish)");
    std::fflush(stdout);
  }
  fs::remove_all(root);
  return 0;
}
