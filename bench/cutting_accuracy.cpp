// How accurate is the dexel cutting model on a benchmark part? The part's
// own program runs on the ideal machine: the planned tool poses, one per
// 1 ms servo cycle, exactly as the soft-CNC's interpolator hands them to an
// ideal machine (encoder = command = true pose). Each cycle's move is cut
// into the dexel model at every spacing asked for, and into a reference
// model that holds one dexel exactly at each probe point, along the probing
// normal: its height is the exact machined surface at that point (to the
// sweep tolerance, 1 µm by default). The CMM's points on the judged surfaces
// (measure::cmm_points_on_surfaces, face normals) are the probe points; the
// machined mesh of each spacing is probed there as the CMM probes it
// (measure::probe, no noise). Model error = probed − reference.
//
//   cutting_accuracy PART [--spacing MM[,MM...]] [--probe-spacing MM]
//                    [--mesh-edge MM] [--stepover MM] [--point-spacing MM]
//                    [--step-down MM] [--operations NAME[,NAME...]] [--list-over UM]
//
// --operations keeps only the named operations of the program (default:
// all); --list-over prints every point whose error exceeds UM. Prints, per spacing and surface, the
// error statistics in µm and the time the cutting took.
#include <time.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "truecut/interp/interpolator.hpp"
#include "truecut/interp/interpreter.hpp"
#include "truecut/interp/planner.hpp"
#include "truecut/sim/benchmark_parts.hpp"
#include "truecut/sim/cutting/dexel_model.hpp"
#include "truecut/sim/measure/cmm.hpp"
#include "truecut/sim/soft_cnc.hpp"

using namespace truecut;
using namespace truecut::sim;
using namespace truecut::sim::cutting;

namespace {

double thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

// The program with only the named operations (all when none are named): the
// motion lines (G0/G1/G2/G3) of the other operations are left out, their
// tool changes, spindle and mode lines kept.
std::string keep_operations(const std::string& program, const std::vector<std::string>& keep) {
  if (keep.empty()) return program;
  std::istringstream in(program);
  std::string out;
  bool keeping = true;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("(OPERATION: ", 0) == 0) {
      keeping = false;
      for (const auto& op : keep)
        keeping = keeping || line == "(OPERATION: " + op + ")";
    }
    const bool motion = line.rfind("G0 ", 0) == 0 || line.rfind("G1 ", 0) == 0 ||
                        line.rfind("G2 ", 0) == 0 || line.rfind("G3 ", 0) == 0;
    if (keeping || !motion) out += line + "\n";
  }
  return out;
}

// One tiny triangle per probe point, its first vertex on the point and its
// normal along the probing direction: DexelModel puts one dexel there.
offline::TriangleMesh probe_mesh(const std::vector<measure::CmmPoint>& points) {
  constexpr double kEdge = 1e-6;
  offline::TriangleMesh m;
  for (const auto& p : points) {
    const Eigen::Vector3d n = p.normal.normalized();
    const Eigen::Vector3d u = n.unitOrthogonal(), v = n.cross(u);
    const auto base = static_cast<std::uint32_t>(m.vertices_mm.size());
    m.vertices_mm.push_back(p.position_mm);
    m.vertices_mm.push_back(p.position_mm + kEdge * u);
    m.vertices_mm.push_back(p.position_mm + kEdge * v);
    m.triangles.push_back({base, base + 1, base + 2});
  }
  return m;
}

struct Stats {
  std::size_t n = 0, over_5um = 0, invalid = 0;
  double sum = 0, sum2 = 0, max_abs = 0;
  std::vector<double> abs_values;
  void add(double e_um) {
    ++n;
    sum += e_um;
    sum2 += e_um * e_um;
    max_abs = std::max(max_abs, std::abs(e_um));
    over_5um += std::abs(e_um) > 5.0;
    abs_values.push_back(std::abs(e_um));
  }
  double p95() {
    if (abs_values.empty()) return 0;
    std::sort(abs_values.begin(), abs_values.end());
    return abs_values[static_cast<std::size_t>(0.95 * double(abs_values.size() - 1))];
  }
};

int usage() {
  std::fprintf(stderr,
               "usage: cutting_accuracy PART [--spacing MM[,MM...]] [--probe-spacing MM]\n"
               "         [--mesh-edge MM] [--stepover MM] [--point-spacing MM] [--step-down MM]\n"
               "         [--operations NAME[,NAME...]] [--list-over UM]\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return usage();
  const auto id = part_from_name(argv[1]);
  if (!id) return usage();
  PartOptions po;
  std::vector<double> spacings{0.3, 0.1};
  double probe_spacing = 0.5;
  std::vector<std::string> operations;
  double list_over_um = -1;
  for (int i = 2; i < argc; ++i) {
    auto value = [&]() -> std::string { return i + 1 < argc ? argv[++i] : ""; };
    const std::string a = argv[i];
    if (a == "--spacing") {
      spacings.clear();
      for (const auto& s : split(value()))
        spacings.push_back(std::atof(s.c_str()));
    } else if (a == "--probe-spacing")
      probe_spacing = std::atof(value().c_str());
    else if (a == "--mesh-edge")
      po.mesh_edge_mm = std::atof(value().c_str());
    else if (a == "--stepover")
      po.stepover_mm = std::atof(value().c_str());
    else if (a == "--point-spacing")
      po.point_spacing_mm = std::atof(value().c_str());
    else if (a == "--step-down")
      po.step_down_mm = std::atof(value().c_str());
    else if (a == "--operations")
      operations = split(value());
    else if (a == "--list-over")
      list_over_um = std::atof(value().c_str());
    else
      return usage();
  }
  for (double s : spacings)
    if (!(s >= 0.01)) return usage();
  if (!(probe_spacing > 0)) return usage();

  const BenchmarkPart part = make_part(*id, po);
  std::printf("%s: mesh edge %g, stepover %g, point spacing %g, step-down %g mm; %zu triangles\n",
              argv[1], po.mesh_edge_mm, po.stepover_mm, po.point_spacing_mm, po.step_down_mm,
              part.mesh.triangles.size());

  // The probe points: the CMM's, on the surfaces the CMM judges.
  std::vector<std::int32_t> judged, ids(part.triangle_surface.begin(), part.triangle_surface.end());
  for (const auto& s : part.metadata.surfaces)
    if (s.compensate) judged.push_back(s.id);
  const std::vector<measure::CmmPoint> points =
      measure::cmm_points_on_surfaces(part.mesh, ids, probe_spacing, judged);
  DexelOptions ref_options;
  ref_options.spacing_mm = 1.0;  // one dexel per tiny triangle corner
  ref_options.cell_mm = 0.5;
  const offline::TriangleMesh ref_mesh = probe_mesh(points);
  const std::vector<int> ref_ids(ref_mesh.triangles.size(), 1);
  DexelModel reference = DexelModel::build(ref_mesh, ref_ids, part.metadata.stock, ref_options);
  std::vector<std::size_t> ref_dexel(points.size());
  for (std::size_t i = 0, d = 0; i < points.size(); ++i) {
    while (d < reference.size() && reference.position(d) != points[i].position_mm)
      ++d;
    if (d == reference.size()) {
      std::fprintf(stderr, "probe point %zu has no reference dexel\n", i);
      return 1;
    }
    ref_dexel[i] = d;
  }
  std::printf("%zu probe points (%g mm) on %zu judged surfaces\n", points.size(), probe_spacing,
              judged.size());

  std::vector<std::unique_ptr<DexelModel>> models;
  std::vector<double> cut_cpu_s(spacings.size(), 0.0);
  for (double s : spacings) {
    DexelOptions o;
    o.spacing_mm = s;
    const double t0 = thread_cpu_s();
    models.push_back(std::make_unique<DexelModel>(
        DexelModel::build(part.mesh, part.triangle_surface, part.metadata.stock, o)));
    std::printf("spacing %g mm: %zu dexels, built in %.1f s CPU\n", s, models.back()->size(),
                thread_cpu_s() - t0);
  }

  // The program on the ideal machine, planned as the soft CNC plans it.
  interp::InterpreterOptions io;
  io.tools = interp::ToolTable::parse(tool_table_text(part.metadata), "tools.tbl");
  const interp::CanonProgram canon =
      interp::Interpreter(io).run_text(keep_operations(part.program, operations), "program.ngc");
  SoftCncJob job;
  const interp::Plan plan =
      interp::plan_program(canon, soft_cnc_planner_options(job, part_machine_ideal(part)));
  std::map<int, CutterShape> shapes;
  for (const auto& t : part.metadata.tools)
    shapes[t.number] = CutterShape{t.radius_mm, t.corner_radius_mm, t.flute_length_mm};

  auto channel = std::make_unique<interp::PlanChannel>();
  interp::Interpolator interpolator;
  std::size_t next = 0;
  bool has_previous = false;
  CutterPose previous;
  long cycles = 0;
  const double period_s = job.period_us * 1e-6;
  for (;;) {
    while (next < plan.segments.size() && channel->try_push(plan.segments[next]))
      ++next;
    const interp::CycleOutput& o = interpolator.step(*channel, period_s);
    ++cycles;
    const auto shape = shapes.find(o.tool);
    const CutterPose pose{{o.tcp_mm[0], o.tcp_mm[1], o.tcp_mm[2]},
                          {o.tool_axis[0], o.tool_axis[1], o.tool_axis[2]}};
    if (shape != shapes.end()) {
      const CutterPose& from = has_previous ? previous : pose;
      reference.cut(shape->second, from, pose, !has_previous);
      for (std::size_t m = 0; m < models.size(); ++m) {
        const double t0 = thread_cpu_s();
        models[m]->cut(shape->second, from, pose, !has_previous);
        cut_cpu_s[m] += thread_cpu_s() - t0;
      }
      previous = pose;
      has_previous = true;
    } else {
      has_previous = false;
    }
    if (cycles % 60000 == 0)
      std::fprintf(stderr, "  %.0f s of machining\n", double(cycles) * period_s);
    if (o.done) break;
  }
  std::printf("%ld servo cycles (%.1f s of machining)\n", cycles, double(cycles) * period_s);

  measure::CmmOptions cmm;
  cmm.sigma_mm = 0;
  for (std::size_t m = 0; m < models.size(); ++m) {
    const auto probed = measure::probe(models[m]->machined_mesh(), points, cmm);
    std::map<int, Stats> by_surface;
    Stats all;
    for (std::size_t i = 0; i < points.size(); ++i) {
      Stats& s = by_surface[points[i].surface];
      if (!probed[i].valid) {
        ++s.invalid;
        ++all.invalid;
        continue;
      }
      const double e_um = (probed[i].deviation_mm - reference.height_mm(ref_dexel[i])) * 1e3;
      s.add(e_um);
      all.add(e_um);
      if (list_over_um >= 0 && std::abs(e_um) > list_over_um) {
        const auto& q = points[i];
        std::printf(
            "    over: (%.4f, %.4f, %.4f) n (%.3f, %.3f, %.3f) surface %d: model %.2f, "
            "reference %.2f um\n",
            q.position_mm.x(), q.position_mm.y(), q.position_mm.z(), q.normal.x(), q.normal.y(),
            q.normal.z(), q.surface, probed[i].deviation_mm * 1e3,
            reference.height_mm(ref_dexel[i]) * 1e3);
      }
    }
    std::printf("spacing %g mm: cutting %.1f s CPU (%.1f us per cycle)\n", spacings[m],
                cut_cpu_s[m], cut_cpu_s[m] / double(cycles) * 1e6);
    std::printf("  surface  points  invalid  mean_um  rms_um  p95_um  max_um  over_5um\n");
    auto row = [](const char* name, Stats& s) {
      const double n = double(std::max<std::size_t>(s.n, 1));
      std::printf("  %-7s %7zu %8zu %8.2f %7.2f %7.2f %7.2f %9zu\n", name, s.n, s.invalid,
                  s.sum / n, std::sqrt(s.sum2 / n), s.p95(), s.max_abs, s.over_5um);
    };
    for (auto& [surface, s] : by_surface)
      row(std::to_string(surface).c_str(), s);
    row("all", all);
  }
  return 0;
}
