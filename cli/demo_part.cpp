#include "demo_part.hpp"

#include <algorithm>
#include <chrono>
#include <fstream>
#include <map>
#include <mutex>
#include <stdexcept>

#include "subprocess.hpp"
#include "truecut/rt/number_format.hpp"
#include "truecut/sim/part_file.hpp"

namespace truecut::cli {
namespace {

namespace fs = std::filesystem;

struct PartInfo {
  std::vector<DemoSurface> surfaces;
  struct Operation {
    std::string name, strategy;
    int tool = 0;
    std::vector<int> surfaces;
  };
  std::vector<Operation> operations;
  struct Tool {
    std::string kind;
    double radius_mm = 0;
  };
  std::map<int, Tool> tools;
  double point_spacing_mm = 0.5;  // of the program's curved passes
};

PartInfo read_part_info(const fs::path& file) {
  const sim::PartFile part = sim::read_part_file(file);
  PartInfo p;
  for (const sim::PartSurface& s : part.metadata.surfaces)
    p.surfaces.push_back({s.id, s.name, s.compensate});
  for (const sim::PartOperation& o : part.metadata.operations)
    p.operations.push_back({o.name, o.strategy, o.tool, o.surface_ids});
  for (const sim::PartTool& t : part.metadata.tools)
    p.tools[t.number] = {t.kind, t.radius_mm};
  if (part.options) p.point_spacing_mm = part.options->point_spacing_mm;
  return p;
}

// The option's value, or when it is 0 the default for the implant or for
// the larger parts.
double per_part(double value, const std::string& part, double implant, double larger) {
  return value > 0 ? value : part == "implant" ? implant : larger;
}

std::string rewrite_type(const PartInfo::Operation& op, const PartInfo::Tool& tool) {
  if (tool.kind == "ball_end_mill") return "ball";
  if (op.strategy == "face") return "face";
  return "peripheral";
}

}  // namespace

struct DemoPart::Plan {
  std::string part;
  DemoOptions o;
  fs::path dir;
  std::ofstream script;
  int steps = 0;
  std::uint64_t seed = 0;
  std::size_t generated = 0;                                // the generation step
  std::vector<std::pair<std::string, std::string>> stages;  // key, title, in plan order
  std::vector<DemoSurface> surfaces;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  mutable std::mutex end_mutex;
  std::chrono::steady_clock::time_point last_end = start;

  // Relative cost of a step, for the graph's order: the larger parts' steps
  // take about ten times the implant's.
  double scale() const { return part == "implant" ? 0.1 : part == "freeform" ? 0.3 : 1.0; }
  std::string next_seed() { return std::to_string(++seed); }

  // `truecut ARGS` in the part folder (paths relative to it), after NEEDS.
  std::size_t step(StepGraph& graph, const std::string& what, std::vector<std::string> args,
                   std::vector<std::size_t> needs, double cost) {
    const int number = ++steps;
    const std::string log = rt::format_printf("logs/%02d.log", number);
    script << "\n# " << what << " (output: " << log << ")\ntruecut " << shell_words(args) << "\n";
    script.flush();
    // This very program, even when a rebuild has replaced the file meanwhile
    // (the kernel keeps the running binary reachable here).
    args.insert(args.begin(), "/proc/self/exe");
    GraphStep g;
    g.label = part + " " + what;
    g.needs = std::move(needs);
    g.cost = cost;
    g.run = [this, what, args = std::move(args), log] {
      const int rc = run_logged(args, dir / log, dir);
      if (rc != 0)
        throw std::runtime_error(part + ": step '" + what + "' failed (exit " + std::to_string(rc) +
                                 "); its output is in " + (dir / log).string());
      std::lock_guard<std::mutex> lock(end_mutex);
      last_end = std::max(last_end, std::chrono::steady_clock::now());
    };
    return graph.add(std::move(g));
  }
};

DemoPart::DemoPart(std::string part, const DemoOptions& options) : plan_(std::make_unique<Plan>()) {
  Plan& p = *plan_;
  p.part = std::move(part);
  p.o = options;
  p.dir = fs::absolute(options.out_dir / p.part);
  p.seed = options.seed * 100;
  fs::create_directories(p.dir / "logs");
  p.script.open(p.dir / "commands.sh", std::ios::trunc);
  if (!p.script) throw std::runtime_error((p.dir / "commands.sh").string() + ": cannot write");
  p.script << "#!/bin/sh\n# The steps of `truecut demo` for " << p.part
           << ",\n# in an order that runs them one after another (the demo runs independent\n"
              "# ones at once); each one's output is in logs/.\nset -e\ncd \"$(dirname \"$0\")\"\n";
}

DemoPart::~DemoPart() = default;

namespace {

// `truecut part` for this part and these options, into DIR.
std::vector<std::string> part_command(const std::string& part, const DemoOptions& o,
                                      const std::string& dir) {
  return {"part",        part,
          "--out",       dir,
          "--mesh-edge", rt::format_printf("%g", per_part(o.mesh_edge_mm, part, 0.5, 1.0)),
          "--stepover",  rt::format_printf("%g", per_part(o.stepover_mm, part, 0.5, 1.0))};
}

}  // namespace

void DemoPart::plan_generation(StepGraph& graph) {
  Plan& p = *plan_;
  p.generated = p.step(graph, "generate the part", part_command(p.part, p.o, "part"), {}, 0.5);
}

void DemoPart::plan_stages(StepGraph& graph) {
  Plan& p = *plan_;
  const DemoOptions& o = p.o;
  const std::string& part = p.part;
  const double scale = p.scale();
  const std::string sigma = rt::format_printf("%g", o.sigma_um),
                    cmm_sigma = rt::format_printf("%g", o.cmm_sigma_um),
                    spacing = rt::format_printf("%g", per_part(o.cmm_spacing_mm, part, 1.0, 2.0));
  const PartInfo info = read_part_info(p.dir / "part" / "part.json");
  p.surfaces = info.surfaces;
  const std::vector<std::string> part_files{"--nominal",      "part/nominal.stl", "--part",
                                            "part/part.json", "--tools",          "part/tools.tbl"};
  // The step that machined each stage, and the scan of each.
  std::map<std::string, std::size_t> machined, scanned;

  auto machine = [&](const std::string& key, const std::string& title, const std::string& program,
                     const std::string& field, std::vector<std::size_t> needs,
                     const std::string& machine_file = "part/machine.json") {
    const double dexel = o.dexel_spacing_mm > 0 ? o.dexel_spacing_mm
                         : part == "implant"    ? 0.1
                                                : 0.3;
    std::vector<std::string> args{"run",
                                  machine_file,
                                  program,
                                  "--out",
                                  key,
                                  "--dexel-spacing",
                                  rt::format_printf("%g", dexel)};
    args.insert(args.end(), part_files.begin(), part_files.end());
    if (!field.empty()) args.insert(args.end(), {"--field", field});
    if (o.cut_threads > 0)
      args.insert(args.end(), {"--cut-threads", std::to_string(o.cut_threads)});
    machined[key] = p.step(graph, "machine (" + title + ")", args, std::move(needs), 10 * scale);
    p.step(graph, "measure (" + title + ") with the CMM",
           {"cmm", key + "/machined.stl", "--nominal", "part/nominal.stl", "--part",
            "part/part.json", "--spacing", spacing, "--sigma-um", cmm_sigma, "--seed",
            p.next_seed(), "--out", key + "/cmm.csv"},
           {machined[key]}, scale);
    p.stages.emplace_back(key, title);
  };
  // scan: the scanned mesh (scan_mesh.ply) or the point cloud (scan.ply);
  // paper: truecut field --paper (empty: the project's defaults). Returns
  // the step.
  auto field = [&](const std::string& key, const std::string& field_dir, const std::string& base,
                   std::size_t base_step, const std::string& scan,
                   const std::string& paper) -> std::size_t {
    std::vector<std::string> args{"field",
                                  "part/nominal.stl",
                                  key + "/" + scan,
                                  "--program",
                                  "part/program.ngc",
                                  "--tools",
                                  "part/tools.tbl",
                                  "--part",
                                  "part/part.json",
                                  "--resolution",
                                  rt::format_printf("%g", o.field_resolution_mm),
                                  "--out",
                                  field_dir};
    const double point_spacing = o.point_spacing_mm >= 0 ? o.point_spacing_mm
                                 : part == "implant"     ? 0.1
                                                         : 0.0;
    if (point_spacing > 0)
      args.insert(args.end(), {"--spacing", rt::format_printf("%g", point_spacing)});
    // Register on the surfaces the compensation does not touch, as a shop
    // registers on datums: on all surfaces, ICP takes part of the real error
    // for a motion of the scan (the implant shaft's oversize, larger at its
    // foot, for a 0.04° tilt; the freeform top's for a 26 µm drop, which
    // turned the correction's sign). Not the bottom the part stands on: the
    // scanner hardly sees it, and its few points tilt the fit. Directions
    // the datums leave open (freeform: its sides fix all but Z) stay as
    // scanned; without any datum (benchmark004) all surfaces are used.
    std::string datum;
    for (const auto& sf : info.surfaces) {
      const bool bottom = sf.name.size() >= 6 && sf.name.ends_with("bottom");
      if (sf.compensate || bottom) continue;
      datum += (datum.empty() ? "" : ",") + std::to_string(sf.id);
    }
    if (!datum.empty()) args.insert(args.end(), {"--datum", datum});
    args.insert(args.end(), {"--edge-exclusion", rt::format_printf("%g", o.edge_exclusion_mm)});
    std::vector<std::size_t> needs{scanned.at(key)};
    if (!base.empty()) {
      args.insert(args.end(), {"--base", base});
      needs.push_back(base_step);
    }
    // The error is the machine's: measured against what the program leaves
    // on the error-free machine (scallops, cusps), not against the nominal.
    if (o.ideal_reference) {
      args.insert(args.end(), {"--expected", "ideal/machined.stl"});
      needs.push_back(machined.at("ideal"));
    }
    // The sources check no correction's plausibility; their recipes are run
    // as they are (the audit records it when the limit is exceeded).
    if (!paper.empty()) args.insert(args.end(), {"--paper", paper, "--force"});
    return p.step(
        graph,
        "correction field from the scan of " + key + (paper.empty() ? "" : " (" + paper + ")"),
        args, std::move(needs), 3 * scale);
  };
  auto scan_and_field = [&](const std::string& key, const std::string& field_dir,
                            const std::string& base, std::size_t base_step) {
    scanned[key] = p.step(graph, "scan " + key + " (sigma " + sigma + " um)",
                          {"scan", key + "/machined.stl", "--out", key + "/scan.ply", "--mesh-out",
                           key + "/scan_mesh.ply", "--sigma-um", sigma, "--seed", p.next_seed()},
                          {machined.at(key)}, 2 * scale);
    return field(key, field_dir, base, base_step, "scan_mesh.ply", "");
  };
  // The operations a compensation rewrites: those that cut a judged surface.
  std::vector<const PartInfo::Operation*> judged_operations;
  for (const auto& op : info.operations) {
    bool judged = false;
    for (int sid : op.surfaces)
      for (const auto& sf : info.surfaces)
        judged = judged || (sf.id == sid && sf.compensate);
    if (judged) judged_operations.push_back(&op);
  }
  // Regenerates the program for FIELD_DIR/adapted.stl into PART_DIR.
  auto regenerate = [&](const std::string& field_dir, std::size_t field_step,
                        const std::string& part_dir) {
    std::vector<std::string> args = part_command(part, o, part_dir);
    args.insert(args.end(), {"--adapted", field_dir + "/adapted.stl", "--quiet"});
    return p.step(graph, "regenerate the program for the adapted geometry of " + field_dir, args,
                  {field_step}, 0.5);
  };

  if (o.ideal_reference)
    machine("ideal", "error-free machine (reference)", "part/program.ngc", "", {p.generated},
            "part/machine_ideal.json");
  machine("uncompensated", "uncompensated", "part/program.ngc", "", {p.generated});
  const std::size_t field_1 = scan_and_field("uncompensated", "field_1", "", 0);
  machine("realtime", "real-time compensation", "part/program.ngc", "field_1/field.tcf", {field_1});

  if (o.rewrite) {
    fs::create_directories(p.dir / "rewrite");
    std::string program = "part/program.ngc";
    std::size_t last = field_1;
    int n = 0;
    for (const PartInfo::Operation* judged : judged_operations) {
      const auto& op = *judged;
      const auto& tool = info.tools.at(op.tool);
      const std::string out = "rewrite/program_" + std::to_string(++n) + ".ngc";
      // Densify no finer than the program's own points: a move cut in two
      // is cut slower (the planner's look-ahead), and the slower feed alone
      // changes the part (docs/rewrite.md, "Measured", freeform).
      const double step_mm = std::max(0.5, 1.2 * info.point_spacing_mm);
      last = p.step(graph, "rewrite operation " + op.name,
                    {"rewrite", program, "--field", "field_1/field.tcf", "--operation", op.name,
                     "--type", rewrite_type(op, tool), "--step", rt::format_printf("%g", step_mm),
                     "--tools", "part/tools.tbl", "--out", out},
                    {last}, 0.5);
      program = out;
    }
    machine("rewrite", "G-code rewrite", program, "", {last});
  }
  // The model-adaptation route: the program regenerated by the part's own
  // path generator for the adapted geometry of the first field, run on the
  // machine without any compensation (docs/parts.md).
  if (o.adapted_route && part == "benchmark004") {
    const std::size_t regenerated = regenerate("field_1", field_1, "adapted_part");
    machine("adapted", "program regenerated for the adapted geometry", "adapted_part/program.ngc",
            "", {regenerated});
  }
  // The sources' own recipes on the same scan (docs/results.md, "The
  // sources' methods"): the optical-compensation source's node matrix with
  // tip placement written into the program, and the model-adaptation
  // source's adapted model from the point cloud (its program regenerated
  // where the part's generator can be driven, else its field run in real
  // time).
  if (o.paper_routes) {
    const std::size_t denkena =
        field("uncompensated", "field_denkena", "", 0, "scan_mesh.ply", "denkena");
    fs::create_directories(p.dir / "paper_denkena");
    std::string program = "part/program.ngc";
    std::size_t last = denkena;
    int n = 0;
    for (const PartInfo::Operation* op : judged_operations) {
      const std::string out = "paper_denkena/program_" + std::to_string(++n) + ".ngc";
      last = p.step(
          graph, "rewrite operation " + op->name + " (denkena)",
          {"rewrite", program, "--matrix", "field_denkena/compensation_matrix.csv", "--paper",
           "denkena", "--operation", op->name, "--type", rewrite_type(*op, info.tools.at(op->tool)),
           "--tools", "part/tools.tbl", "--force", "--out", out},
          {last}, 0.5);
      program = out;
    }
    machine("paper_denkena", "node matrix, tip placement (Denkena et al.)", program, "", {last});
    const std::size_t sortino =
        field("uncompensated", "field_sortino", "", 0, "scan.ply", "sortino");
    if (part == "benchmark004") {
      const std::size_t regenerated = regenerate("field_sortino", sortino, "paper_sortino_part");
      machine("paper_sortino", "adapted model, program regenerated (Sortino et al.)",
              "paper_sortino_part/program.ngc", "", {regenerated});
    } else {
      machine("paper_sortino", "adapted model's field in real time (Sortino et al.)",
              "part/program.ngc", "field_sortino/field.tcf", {sortino});
    }
  }
  if (o.iterations >= 2) {
    const std::size_t field_2 = scan_and_field("realtime", "field_2", "field_1/field.tcf", field_1);
    machine("realtime_2", "real-time, 2nd iteration", "part/program.ngc", "field_2/field.tcf",
            {field_2});
  }
  // The reference goes last in the tables and the report.
  if (o.ideal_reference) std::rotate(p.stages.begin(), p.stages.begin() + 1, p.stages.end());
}

DemoPartResult DemoPart::result() const {
  const Plan& p = *plan_;
  DemoPartResult r;
  r.part = p.part;
  r.dir = p.dir;
  r.surfaces = p.surfaces;
  r.first_field_dir = p.dir / "field_1";
  for (const auto& [key, title] : p.stages) {
    DemoStage st;
    st.key = key;
    st.title = title;
    st.dir = p.dir / key;
    st.cmm = sim::measure::read_cmm_measurements(st.dir / "cmm.csv");
    r.stages.push_back(std::move(st));
  }
  std::lock_guard<std::mutex> lock(p.end_mutex);
  r.wall_s = std::chrono::duration<double>(p.last_end - p.start).count();
  return r;
}

}  // namespace truecut::cli
