#include "demo_part.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
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

class Steps {
 public:
  Steps(fs::path dir, std::string part) : dir_(std::move(dir)), part_(std::move(part)) {
    fs::create_directories(dir_);
    script_.open(dir_ / "commands.sh", std::ios::trunc);
    script_ << "#!/bin/sh\n# The steps of `truecut demo` for " << part_
            << ", as run (each one's output is in demo.log).\nset -e\ncd \"$(dirname \"$0\")\"\n";
  }
  // Runs `truecut ARGS` in the part folder (paths relative to it).
  void run(const std::string& what, std::vector<std::string> args) {
    std::fprintf(stderr, "demo %-12s %s\n", part_.c_str(), what.c_str());
    script_ << "\n# " << what << "\ntruecut " << shell_words(args) << "\n";
    script_.flush();
    // This very program, even when a rebuild has replaced the file meanwhile
    // (the kernel keeps the running binary reachable here).
    args.insert(args.begin(), "/proc/self/exe");
    const fs::path log = dir_ / "demo.log";
    const auto start = std::chrono::steady_clock::now();
    const int rc = run_logged(args, log, dir_);
    if (rc != 0)
      throw std::runtime_error(part_ + ": step '" + what + "' failed (exit " + std::to_string(rc) +
                               "); its output is in " + log.string());
    const double wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::fprintf(stderr, "demo %-12s %s: done in %.1f s\n", part_.c_str(), what.c_str(), wall_s);
  }
  const fs::path& dir() const { return dir_; }

 private:
  fs::path dir_;
  std::string part_;
  std::ofstream script_;
};

std::string rewrite_type(const PartInfo::Operation& op, const PartInfo::Tool& tool) {
  if (tool.kind == "ball_end_mill") return "ball";
  if (op.strategy == "face") return "face";
  return "peripheral";
}

}  // namespace

DemoPartResult run_demo_part(const std::string& part, const DemoOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  DemoPartResult r;
  r.part = part;
  r.dir = fs::absolute(o.out_dir / part);
  Steps s(r.dir, part);
  const std::string sigma = rt::format_printf("%g", o.sigma_um),
                    cmm_sigma = rt::format_printf("%g", o.cmm_sigma_um),
                    spacing = rt::format_printf("%g", per_part(o.cmm_spacing_mm, part, 1.0, 2.0));
  uint64_t seed = o.seed * 100;
  auto next_seed = [&] { return std::to_string(++seed); };

  // `truecut part` for this part and these options, into DIR.
  const auto part_command = [&](const std::string& dir) {
    return std::vector<std::string>{
        "part",        part,
        "--out",       dir,
        "--mesh-edge", rt::format_printf("%g", per_part(o.mesh_edge_mm, part, 0.5, 1.0)),
        "--stepover",  rt::format_printf("%g", per_part(o.stepover_mm, part, 0.5, 1.0))};
  };
  s.run("generate the part", part_command("part"));
  const PartInfo info = read_part_info(r.dir / "part" / "part.json");
  r.surfaces = info.surfaces;
  const std::vector<std::string> part_files{"--nominal",      "part/nominal.stl", "--part",
                                            "part/part.json", "--tools",          "part/tools.tbl"};

  auto machine = [&](const std::string& key, const std::string& title, const std::string& program,
                     const std::string& field,
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
    s.run("machine (" + title + ")", args);
    s.run("measure (" + title + ") with the CMM",
          {"cmm", key + "/machined.stl", "--nominal", "part/nominal.stl", "--part",
           "part/part.json", "--spacing", spacing, "--sigma-um", cmm_sigma, "--seed", next_seed(),
           "--out", key + "/cmm.csv"});
    DemoStage st;
    st.key = key;
    st.title = title;
    st.dir = r.dir / key;
    st.cmm = sim::measure::read_cmm_measurements(st.dir / "cmm.csv");
    r.stages.push_back(std::move(st));
  };
  // scan: the scanned mesh (scan_mesh.ply) or the point cloud (scan.ply);
  // paper: truecut field --paper (empty: the project's defaults).
  auto field = [&](const std::string& key, const std::string& field_dir, const std::string& base,
                   const std::string& scan, const std::string& paper) {
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
    const double spacing = o.point_spacing_mm > 0 ? o.point_spacing_mm
                           : part == "implant"    ? 0.1
                                                  : 0.0;
    if (spacing > 0) args.insert(args.end(), {"--spacing", rt::format_printf("%g", spacing)});
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
    if (!base.empty()) args.insert(args.end(), {"--base", base});
    // The error is the machine's: measured against what the program leaves
    // on the error-free machine (scallops, cusps), not against the nominal.
    if (o.ideal_reference) args.insert(args.end(), {"--expected", "ideal/machined.stl"});
    // The sources check no correction's plausibility; their recipes are run
    // as they are (the audit records it when the limit is exceeded).
    if (!paper.empty()) args.insert(args.end(), {"--paper", paper, "--force"});
    s.run("correction field from the scan of " + key + (paper.empty() ? "" : " (" + paper + ")"),
          args);
  };
  auto scan_and_field = [&](const std::string& key, const std::string& field_dir,
                            const std::string& base) {
    s.run("scan " + key + " (sigma " + sigma + " um)",
          {"scan", key + "/machined.stl", "--out", key + "/scan.ply", "--mesh-out",
           key + "/scan_mesh.ply", "--sigma-um", sigma, "--seed", next_seed()});
    field(key, field_dir, base, "scan_mesh.ply", "");
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
  auto regenerate = [&](const std::string& field_dir, const std::string& part_dir) {
    std::vector<std::string> args = part_command(part_dir);
    args.insert(args.end(), {"--adapted", field_dir + "/adapted.stl", "--quiet"});
    s.run("regenerate the program for the adapted geometry of " + field_dir, args);
  };

  if (o.ideal_reference)
    machine("ideal", "error-free machine (reference)", "part/program.ngc", "",
            "part/machine_ideal.json");
  machine("uncompensated", "uncompensated", "part/program.ngc", "");
  scan_and_field("uncompensated", "field_1", "");
  r.first_field_dir = r.dir / "field_1";
  machine("realtime", "real-time compensation", "part/program.ngc", "field_1/field.tcf");

  if (o.rewrite) {
    fs::create_directories(r.dir / "rewrite");
    std::string program = "part/program.ngc";
    int n = 0;
    for (const PartInfo::Operation* judged : judged_operations) {
      const auto& op = *judged;
      const auto& tool = info.tools.at(op.tool);
      const std::string out = "rewrite/program_" + std::to_string(++n) + ".ngc";
      // Densify no finer than the program's own points: a move cut in two
      // is cut slower (the planner's look-ahead), and the slower feed alone
      // changes the part (docs/rewrite.md, "Measured", freeform).
      const double step_mm = std::max(0.5, 1.2 * info.point_spacing_mm);
      s.run("rewrite operation " + op.name,
            {"rewrite", program, "--field", "field_1/field.tcf", "--operation", op.name, "--type",
             rewrite_type(op, tool), "--step", rt::format_printf("%g", step_mm), "--tools",
             "part/tools.tbl", "--out", out});
      program = out;
    }
    machine("rewrite", "G-code rewrite", program, "");
  }
  // The model-adaptation route: the program regenerated by the part's own
  // path generator for the adapted geometry of the first field, run on the
  // machine without any compensation (docs/parts.md).
  if (o.adapted_route && part == "benchmark004") {
    regenerate("field_1", "adapted_part");
    machine("adapted", "program regenerated for the adapted geometry", "adapted_part/program.ngc",
            "");
  }
  // The sources' own recipes on the same scan (docs/results.md, "The
  // sources' methods"): the optical-compensation source's node matrix with
  // tip placement written into the program, and the model-adaptation
  // source's adapted model from the point cloud (its program regenerated
  // where the part's generator can be driven, else its field run in real
  // time).
  if (o.paper_routes) {
    field("uncompensated", "field_denkena", "", "scan_mesh.ply", "denkena");
    fs::create_directories(r.dir / "paper_denkena");
    std::string program = "part/program.ngc";
    int n = 0;
    for (const PartInfo::Operation* op : judged_operations) {
      const std::string out = "paper_denkena/program_" + std::to_string(++n) + ".ngc";
      s.run(
          "rewrite operation " + op->name + " (denkena)",
          {"rewrite", program, "--matrix", "field_denkena/compensation_matrix.csv", "--paper",
           "denkena", "--operation", op->name, "--type", rewrite_type(*op, info.tools.at(op->tool)),
           "--tools", "part/tools.tbl", "--force", "--out", out});
      program = out;
    }
    machine("paper_denkena", "node matrix, tip placement (Denkena et al.)", program, "");
    field("uncompensated", "field_sortino", "", "scan.ply", "sortino");
    if (part == "benchmark004") {
      regenerate("field_sortino", "paper_sortino_part");
      machine("paper_sortino", "adapted model, program regenerated (Sortino et al.)",
              "paper_sortino_part/program.ngc", "");
    } else {
      machine("paper_sortino", "adapted model's field in real time (Sortino et al.)",
              "part/program.ngc", "field_sortino/field.tcf");
    }
  }
  if (o.iterations >= 2) {
    scan_and_field("realtime", "field_2", "field_1/field.tcf");
    machine("realtime_2", "real-time, 2nd iteration", "part/program.ngc", "field_2/field.tcf");
  }
  // The reference goes last in the tables and the report.
  if (o.ideal_reference) std::rotate(r.stages.begin(), r.stages.begin() + 1, r.stages.end());
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace truecut::cli
