// truecut demo [--part NAME|all] [--out DIR]: the closed loop end to end.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "args.hpp"
#include "commands.hpp"
#include "demo_part.hpp"
#include "quiet_option.hpp"
#include "truecut/analysis/report/closed_loop_report.hpp"
#include "truecut/rt/atomic_write.hpp"
#include "truecut/sim/part_file.hpp"
#include "truecut/sim/soft_cnc_outputs.hpp"

namespace truecut::cli {
namespace {

namespace fs = std::filesystem;

const char* kHelp =
    "usage: truecut demo [--part implant|benchmark004|freeform|all] [--out DIR] [options]\n"
    "\n"
    "The closed loop, per part: machine part 1 on a machine with hidden physics\n"
    "(tool and workpiece deflection, a tool radius error, servo lag, rotary location\n"
    "errors on the 5-axis part), scan it, build the correction field, machine part 2\n"
    "with the real-time compensation and part 3 with the G-code rewritten from the\n"
    "same field (truecut rewrite --field), measure\n"
    "every part with the virtual CMM, then scan part 2 and machine a 2nd iteration.\n"
    "A last part machined on the error-free machine shows the deviation the program\n"
    "itself leaves (scallops), the floor of what compensation can reach.\n"
    "Every step is a truecut command; DIR/<part>/commands.sh lists them, logs/\n"
    "holds their output. Writes DIR/report.html and DIR/results.json.\n"
    "\n"
    "options:\n"
    "  --part NAME        implant, benchmark004, freeform or all (default implant)\n"
    "  --out DIR          output folder (default out/demo)\n"
    "  --sigma-um S       scanner noise, 5..50 (default 20)\n"
    "  --tolerance-um T   tolerance drawn in the report (default 20)\n"
    "  --iterations N     real-time iterations, 1 or 2 (default 2)\n"
    "  --no-rewrite       skip the G-code rewrite stage\n"
    "  --no-adapted       benchmark004: skip the part machined with the program its\n"
    "                     generator makes for the first field's adapted.stl\n"
    "  --paper            also the sources' own recipes on the same scan: the node\n"
    "                     matrix with tip placement rewritten into the program\n"
    "                     (Denkena et al.) and the adapted model from the point\n"
    "                     cloud (Sortino et al.; benchmark004: program regenerated,\n"
    "                     other parts: its field in real time); docs/results.md\n"
    "  --no-ideal         skip the reference part machined on the error-free\n"
    "                     machine (machine_ideal.json, no compensation); the\n"
    "                     fields then measure errors against the nominal instead\n"
    "                     of that part's surface (scallops taken for errors)\n"
    "  --mesh-edge MM     nominal mesh edge (default 0.5 implant, 1 others)\n"
    "  --stepover MM      tool path stepover (default 0.5 implant, 1 others)\n"
    "  --cmm-spacing MM   CMM point spacing (default 1 implant, 2 others)\n"
    "  --resolution MM    correction field grid (default 1)\n"
    "  --point-spacing MM compensation points every MM on the surface (default\n"
    "                     0.1 implant; 0 = nominal vertices, default for others)\n"
    "  --edge-exclusion MM no error vector this close to a sharp edge (default 0.2)\n"
    "  --dexel-spacing MM cutting model sampling (default 0.1 implant, 0.3 others)\n"
    "  --seed N           noise seed (default 1)\n"
    "  --jobs N           steps run at once (default: the number of CPUs): other\n"
    "                     parts' and the same part's independent stages; the\n"
    "                     results do not depend on it\n"
    "  --quiet            no progress on stderr (shown only on a terminal)\n"
    "  --help             this text\n";

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

nlohmann::ordered_json stats_json(const sim::measure::SurfaceDeviationStats& s) {
  return {{"points", s.valid},      {"rms_um", s.rms_um}, {"max_um", s.max_abs_um},
          {"p95_um", s.p95_abs_um}, {"std_um", s.std_um}, {"mean_um", s.mean_um}};
}

}  // namespace

int cmd_demo(const std::vector<std::string>& argv) {
  ParsedArgs a(argv, {{"part", true},          {"out", true},           {"sigma-um", true},
                      {"tolerance-um", true},  {"iterations", true},    {"no-rewrite", false},
                      {"no-adapted", false},   {"paper", false},        {"no-ideal", false},
                      {"mesh-edge", true},     {"stepover", true},      {"cmm-spacing", true},
                      {"resolution", true},    {"point-spacing", true}, {"edge-exclusion", true},
                      {"dexel-spacing", true}, {"seed", true},          {"jobs", true},
                      {"quiet", false},        {"help", false}});
  if (a.flag("help")) {
    std::fputs(kHelp, stdout);
    return kExitOk;
  }
  if (!a.positionals().empty())
    throw UsageError("unexpected argument '" + a.positionals()[0] + "'");
  DemoOptions o;
  o.out_dir = a.value("out").value_or("out/demo");
  o.sigma_um = a.number("sigma-um", 20.0, 5.0, 50.0);
  o.iterations = static_cast<int>(a.integer("iterations", 2, 1, 2));
  o.rewrite = !a.flag("no-rewrite");
  o.adapted_route = !a.flag("no-adapted");
  o.paper_routes = a.flag("paper");
  o.ideal_reference = !a.flag("no-ideal");
  // 0 stands for "each part's default" inside; a spacing given must be > 0
  // (--mesh-edge 0 silently meant the default).
  const auto spacing = [&](const char* name, double max_mm) {
    return a.value(name) ? a.number(name, 0.0, 1e-3, max_mm) : 0.0;
  };
  o.mesh_edge_mm = spacing("mesh-edge", 10.0);
  o.stepover_mm = spacing("stepover", 10.0);
  o.cmm_spacing_mm = spacing("cmm-spacing", 20.0);
  o.field_resolution_mm = a.number("resolution", 1.0, 0.1, 20.0);
  o.dexel_spacing_mm = spacing("dexel-spacing", 5.0);
  // 0 is a spacing of its own here: the nominal's vertices.
  o.point_spacing_mm = a.value("point-spacing") ? a.number("point-spacing", 0.0, 0.0, 10.0) : -1.0;
  o.edge_exclusion_mm = a.number("edge-exclusion", o.edge_exclusion_mm, 0.0, 10.0);
  o.seed = static_cast<std::uint64_t>(a.integer("seed", 1, 0, 1'000'000'000));
  const double tolerance_um = a.number("tolerance-um", 20.0, 0.1, 10000.0);
  const std::string which = a.value("part").value_or("implant");
  std::vector<std::string> parts;
  if (which == "all")
    parts = {"implant", "benchmark004", "freeform"};
  else if (which == "implant" || which == "benchmark004" || which == "freeform")
    parts = {which};
  else
    throw UsageError("--part must be implant, benchmark004, freeform or all, not '" + which + "'");

  // The steps of all parts form one graph; independent ones run at once,
  // each machine run cutting with its share of the CPUs (the results do
  // not depend on the number of cutting threads, nor on what runs at once).
  const unsigned cpus = std::max(1u, std::thread::hardware_concurrency());
  const auto jobs = static_cast<std::size_t>(a.integer("jobs", cpus, 1, 64));
  if (jobs > 1) o.cut_threads = static_cast<int>(std::max<std::size_t>(1, cpus / jobs));

  fs::create_directories(o.out_dir);
  std::vector<std::unique_ptr<DemoPart>> plans;
  StepGraph graph;
  const bool progress = progress_shown(a);
  graph.show_progress(progress);
  for (const auto& part : parts) {
    plans.push_back(std::make_unique<DemoPart>(part, o));
    plans.back()->plan_generation(graph);
  }
  graph.run(jobs);
  for (auto& plan : plans)
    plan->plan_stages(graph);
  graph.run(jobs);
  std::vector<DemoPartResult> results;
  for (const auto& plan : plans)
    results.push_back(plan->result());

  std::vector<analysis::report::ReportPart> report_parts;
  nlohmann::ordered_json json;
  json["truecut_demo"] = 1;
  json["scanner_sigma_um"] = o.sigma_um;
  json["tolerance_um"] = tolerance_um;
  int title_width = 28;
  for (const auto& r : results)
    for (const auto& st : r.stages)
      title_width = std::max(title_width, static_cast<int>(st.title.size()));
  std::printf("%-13s %-*s %9s %9s %9s %9s %10s\n", "part", title_width, "stage", "RMS um", "max um",
              "P95 um", "std um", "RMS cut");
  for (const auto& r : results) {
    analysis::report::ReportPart rp;
    rp.name = r.part;
    rp.nominal_stl = r.dir / "part" / "nominal.stl";
    rp.triangle_surface_ids =
        sim::read_part_file(r.dir / "part" / "part.json", sim::kPartTriangleSurfaceIds)
            .triangle_surface_ids;
    for (const auto& s : r.surfaces)
      rp.surfaces.push_back({s.id, s.name, s.compensate});
    rp.field_tcf = r.first_field_dir / "field.tcf";
    rp.audit_json = read_text(r.first_field_dir / "audit.json");
    rp.commands = read_text(r.dir / "commands.sh");
    nlohmann::ordered_json pj;
    pj["part"] = r.part;
    pj["wall_s"] = r.wall_s;
    double reference_rms = 0;
    for (const auto& st : r.stages) {
      rp.stages.push_back({st.key, st.title, st.dir / sim::kMachinedStl, st.cmm});
      const auto stats = analysis::report::judged_statistics(st.cmm, rp.surfaces);
      const auto& all = stats.back();
      if (st.key == "uncompensated") reference_rms = all.rms_um;
      nlohmann::ordered_json sj;
      sj["title"] = st.title;
      sj["all_judged"] = stats_json(all);
      for (std::size_t i = 0; i + 1 < stats.size(); ++i) {
        std::string name = std::to_string(stats[i].surface);
        for (const auto& s : r.surfaces)
          if (s.id == stats[i].surface) name = s.name;
        sj["surfaces"][name] = stats_json(stats[i]);
      }
      const bool is_floor = st.key == "ideal";
      if (is_floor)
        sj["reference"] = "the program on the error-free machine: what no compensation removes";
      else if (st.key != "uncompensated" && reference_rms > 0)
        sj["rms_reduction_percent"] = 100.0 * (1.0 - all.rms_um / reference_rms);
      pj["stages"][st.key] = sj;
      std::printf("%-13s %-*s %9.1f %9.1f %9.1f %9.1f %9s\n", r.part.c_str(), title_width,
                  st.title.c_str(), all.rms_um, all.max_abs_um, all.p95_abs_um, all.std_um,
                  st.key == "uncompensated" ? "-"
                  : is_floor                ? "floor"
                                            : (std::to_string(static_cast<int>(
                                    std::lround(100.0 * (1.0 - all.rms_um / reference_rms)))) +
                                " %")
                                   .c_str());
    }
    json["parts"].push_back(pj);
    report_parts.push_back(std::move(rp));
  }
  analysis::report::ReportOptions ro;
  ro.tolerance_um = tolerance_um;
  ro.scanner_sigma_um = o.sigma_um;
  if (progress) std::fprintf(stderr, "demo: writing the report\n");
  rt::write_file_atomically(o.out_dir / "report.html",
                            analysis::report::closed_loop_html(report_parts, ro));
  rt::write_file_atomically(
      o.out_dir / "results.json",
      json.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n");
  std::printf("report: %s\nresults: %s\n", (o.out_dir / "report.html").string().c_str(),
              (o.out_dir / "results.json").string().c_str());
  return kExitOk;
}

namespace {
const CommandRegistration kRegistration{
    "demo", "the closed loop end to end: machine, scan, compensate, measure", cmd_demo, 1};
}  // namespace

}  // namespace truecut::cli
