// The surface-diagnosis tests' shared fixture (test_diagnosis_surface.cpp):
// the implant parts machined by every case, and the re-machinings the cases
// have done so far (diagnose_surface's work_dir/runs/<key>), in one folder of
// the build tree, so that a case run in its own process (ctest runs each
// case as one) does not re-machine what another case already has.
//
// Nothing here is ever half-written for a reader in another process: a part
// folder or a run is written in a private folder, then renamed into place
// in one step (the first writer wins; a later one drops its copy). A case
// diagnoses in its own work folder, seeded with the published runs and
// publishing its new ones when done: no two processes write the same folder.
// The ctest fixture `surface_diagnosis` (surface_diagnosis_fixture.cpp)
// empties the folder and writes the parts before the cases run, so a
// rebuilt simulator never meets runs of the previous one; a case run on its
// own empties it when it is older than the executable or a component.
#pragma once

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include <unistd.h>

#include "test_paths.hpp"
#include "truecut/sim/benchmark_parts.hpp"
#include "truecut/sim/machine_description.hpp"

namespace truecut::analysis::test {

namespace surface_fixture {

namespace fs = std::filesystem;

// The shared folder: parts/ (part, part5, part_short_flute) and runs/.
inline fs::path root() {
  return truecut::test::binary_dir() / "test-fixtures" / "surface_diagnosis";
}

// The coarse implant of the surface cases (docs/parts.md).
inline sim::PartOptions part_options() {
  sim::PartOptions o;
  o.mesh_edge_mm = 0.25;
  o.stepover_mm = 0.8;
  o.point_spacing_mm = 1.0;
  o.step_down_mm = 2.0;
  return o;
}

// A private folder next to `target`, for writing what is then renamed to it.
inline fs::path private_sibling(const fs::path& target) {
  static int n = 0;
  return target.parent_path() / (".tmp-" + target.filename().string() + "-" +
                                 std::to_string(::getpid()) + "-" + std::to_string(n++));
}

// Renames the finished folder `from` to `to`, unless `to` is already there
// (then `from` is removed): readers see all of `to` or nothing.
inline void publish(const fs::path& from, const fs::path& to) {
  std::error_code ec;
  fs::rename(from, to, ec);
  if (ec) fs::remove_all(from, ec);
}

// The three parts, as the cases machine them:
//   part              the implant;
//   part5             the same with a 5-axis finish of the +Y face (A = 90°,
//                     the tool's flat end on the face, TRAORI) after the
//                     3-axis operations, on a machine with 100 mm more Z
//                     travel (at A = 90° the spindle comes 60 mm closer to the
//                     table than the 3-axis program needs);
//   part_short_flute  the implant cut by a Ø2 end mill with 2 mm of flute
//                     (= the step-down): each level of the shaft is cut once,
//                     by the flank at its own height. With the long-reach
//                     tool's 20 mm flute every lower level sweeps the whole
//                     wall above it again, and the last level (contact 0.5 mm
//                     above the clamp, where the shaft hardly bends) leaves
//                     the wall: a workpiece deflection then never reaches the
//                     machined surface.
inline void write_parts(const sim::BenchmarkPart& part, const fs::path& dir) {
  sim::write_part(part, dir / "part");
  sim::BenchmarkPart five = part;
  const auto end = five.program.rfind("M5\n");
  five.program.insert(end,
                      "(OPERATION: SHAFT_Y_FACE_A90)\nT2 M6\nG43 H2\nS12000 M3\nTRAORI\n"
                      "G0 X0 Y30 Z17 A90 C0\nG0 X0 Y2 Z17\nG1 X0 Y0.8 Z17 F200\n"
                      "G1 X0 Y0.8 Z2.5 F400\nG0 X0 Y30 Z2.5\nG0 X0 Y30 Z25 A0 C0\nTRAFOOF\n");
  sim::write_part(five, dir / "part5");
  auto m5 = sim::read_machine_description(dir / "part5" / "machine_ideal.json");
  m5.machine.joints[sim::kZ].min -= 100.0;
  sim::write_machine_description(dir / "part5" / "machine_ideal.json", m5);
  sim::BenchmarkPart short_flute = part;
  for (auto& t : short_flute.metadata.tools)
    if (t.number == 1) t.flute_length_mm = part.options.step_down_mm;
  sim::write_part(short_flute, dir / "part_short_flute");
}

// Whether `dir` was written after the running executable and the
// components were built (runs of an older simulator are not reused).
inline bool newer_than_the_build(const fs::path& dir) {
  std::error_code ec;
  const auto written = fs::last_write_time(dir, ec);
  if (ec) return false;
  auto built = fs::last_write_time(fs::read_symlink("/proc/self/exe"), ec);
  if (ec) return false;
  for (const auto& f : fs::directory_iterator(truecut::test::component_dir(), ec))
    built = std::max(built, fs::last_write_time(f.path()));
  return written >= built;
}

// root()/parts, written if not there yet (the ctest fixture writes it first;
// a test executable run on its own writes it itself, and starts afresh when
// the folder is older than the build).
inline fs::path parts(const sim::BenchmarkPart& part) {
  const fs::path dir = root() / "parts";
  if (fs::exists(dir) && !newer_than_the_build(dir)) fs::remove_all(root());
  if (!fs::exists(dir)) {
    fs::create_directories(root());
    const fs::path tmp = private_sibling(dir);
    write_parts(part, tmp);
    publish(tmp, dir);
  }
  return dir;
}

// The published runs copied into `work_dir`/runs (hard links where the
// file system allows: the runs are never changed once published).
inline void seed(const fs::path& work_dir) {
  const fs::path shared = root() / "runs";
  if (!fs::exists(shared)) return;
  for (const auto& run : fs::directory_iterator(shared)) {
    const std::string key = run.path().filename().string();
    if (key.starts_with(".")) continue;  // being published
    const fs::path to = work_dir / "runs" / key;
    if (fs::exists(to)) continue;
    const fs::path tmp = private_sibling(to);
    fs::create_directories(tmp);
    for (const auto& f : fs::directory_iterator(run.path())) {
      std::error_code ec;
      fs::create_hard_link(f.path(), tmp / f.path().filename(), ec);
      if (ec) fs::copy_file(f.path(), tmp / f.path().filename());
    }
    publish(tmp, to);
  }
}

// The finished runs of `work_dir` (those with their "done" mark) that are
// not published yet, published.
inline void share(const fs::path& work_dir) {
  const fs::path mine = work_dir / "runs";
  if (!fs::exists(mine)) return;
  const fs::path shared = root() / "runs";
  fs::create_directories(shared);
  for (const auto& run : fs::directory_iterator(mine)) {
    const std::string key = run.path().filename().string();
    if (key.starts_with(".") || !fs::exists(run.path() / "done")) continue;
    const fs::path to = shared / key;
    if (fs::exists(to)) continue;
    const fs::path tmp = private_sibling(to);
    fs::copy(run.path(), tmp, fs::copy_options::recursive);
    publish(tmp, to);
  }
}

}  // namespace surface_fixture
}  // namespace truecut::analysis::test
