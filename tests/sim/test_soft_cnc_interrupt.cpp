// A soft-CNC run ended by SIGINT or SIGTERM leaves none of its files (issue
// 23: the complete run.ini and soft_cnc.hal stayed in the output folder).
// The signal comes from the first servo cycle (SoftCncJob::cycle_probe), in
// a child process; the parent looks at the folder. (The cutting component's
// machined.{stl,ply}.tmp, written at unload, are in the host's table through
// the component ABI: tests/rt/test_component_pending_files.cpp and
// CuttingComponent.ItsTemporaryFilesAreInTheHostsTableWhileItWrites.)
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "test_paths.hpp"
#include "truecut/rt/interrupt_cleanup.hpp"
#include "truecut/sim/benchmark_parts.hpp"
#include "truecut/sim/soft_cnc.hpp"

namespace {

namespace fs = std::filesystem;
using namespace truecut;

int g_probe_signal = 0;  // raised by the first servo cycle (child process)

// A coarse implant and a one-pass facing program with its tool T2.
fs::path write_job(const fs::path& dir) {
  sim::PartOptions o;
  o.mesh_edge_mm = 2;
  o.stepover_mm = 2;
  o.point_spacing_mm = 2;
  o.step_down_mm = 5;
  sim::write_part(sim::make_part(sim::PartId::kImplant, o), dir);
  std::ofstream(dir / "face.ngc") << "G21 G17 G40 G49 G80 G90 G94\nG54\nT2 M6\nG43 H2\n"
                                     "S12000 M3\nG0 X-5 Y0 Z20\nG1 Z17 F600\nG1 X5\nG0 Z20\n"
                                     "M5 G49 M30\n";
  return dir;
}

}  // namespace

TEST(SoftCncInterrupt, AnInterruptedRunLeavesNoneOfItsFiles) {
  const fs::path part = write_job(test::scratch_dir() / "part");
  for (const int sig : {SIGINT, SIGTERM}) {
    const fs::path out = part.parent_path() / (sig == SIGINT ? "int" : "term");
    const pid_t pid = fork();
    if (pid == 0) {
      rt::remove_pending_files_on_signals();
      sim::SoftCncJob job = sim::part_folder_job(part, out, "machine_ideal.json", "face.ngc");
      job.dexel_spacing_mm = 0.5;
      job.component_path = {test::component_dir()};
      g_probe_signal = sig;
      job.cycle_probe = [](void*, int) { raise(g_probe_signal); };
      try {
        sim::run_soft_cnc(job);
      } catch (...) {
        _exit(3);
      }
      _exit(4);  // not reached: the signal ends the process
    }
    int status = 0;
    waitpid(pid, &status, 0);
    ASSERT_TRUE(WIFSIGNALED(status)) << "exit " << WEXITSTATUS(status);
    EXPECT_EQ(sig, WTERMSIG(status));
    ASSERT_TRUE(fs::is_directory(out)) << "the run got as far as its folder";
    for (const char* f : {"run.ini", "soft_cnc.hal", "trace.csv.tmp", "trace.csv"})
      EXPECT_FALSE(fs::exists(out / f)) << f;
  }
}
