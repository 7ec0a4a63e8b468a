// The closed-loop demo of one benchmark part (truecut demo): every step is a
// truecut command run as a child process, written with its command line to
// DIR/<part>/commands.sh, so a user can repeat any step by hand.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "step_graph.hpp"
#include "truecut/sim/measure/cmm.hpp"

namespace truecut::cli {

struct DemoOptions {
  std::filesystem::path out_dir = "out/demo";
  double sigma_um = 20.0;  // scanner noise
  double cmm_sigma_um = 2.0;
  // 0: per part — the implant 1 / 0.5 / 0.5 mm; benchmark004 and freeform,
  // ten times larger, 2 / 1 / 1 mm (docs/results.md).
  double cmm_spacing_mm = 0;
  double mesh_edge_mm = 0;  // part generation
  double stepover_mm = 0;
  double field_resolution_mm = 1.0;
  // Compensation points for the field: even sampling at this spacing
  // (0: 0.1 for the implant, the nominal vertices for the larger parts).
  double point_spacing_mm = -1;  // < 0: each part's default (0.1 implant, else vertices)
  // Error vectors are not taken this close to a sharp nominal edge: about one
  // scan point spacing (25 pt/mm²), where the scanned mesh rounds the edge.
  double edge_exclusion_mm = 0.2;
  double dexel_spacing_mm = 0;  // 0: 0.1 for the implant, 0.3 for the larger parts
  int iterations = 2;           // real-time iterations (1 or 2)
  bool rewrite = true;
  // benchmark004: also machine the program its generator makes for the first
  // field's adapted.stl (the model-adaptation source's route).
  bool adapted_route = true;
  // Also the sources' own recipes on the same scan (truecut field --paper):
  // stages paper_denkena and paper_sortino.
  bool paper_routes = false;
  // Also machine the program on the error-free machine (machine_ideal.json),
  // uncompensated: the deviation the program itself leaves (scallops, the
  // cutting model), which no compensation of the machine can remove.
  bool ideal_reference = true;
  std::uint64_t seed = 1;
  // Threads that cut in each `truecut run` (0: its default, one per CPU);
  // with several parts at once, the CPUs shared among them.
  int cut_threads = 0;
};

struct DemoStage {
  std::string key;    // uncompensated, realtime, rewrite, adapted, realtime_2, ideal
  std::string title;  // for people
  std::filesystem::path dir;
  std::vector<sim::measure::CmmMeasurement> cmm;
};

struct DemoSurface {
  int id = 0;
  std::string name;
  bool compensate = false;
};

struct DemoPartResult {
  std::string part;
  std::filesystem::path dir;
  std::vector<DemoSurface> surfaces;
  std::vector<DemoStage> stages;
  std::filesystem::path first_field_dir;  // field.tcf, audit.json, compensation_matrix.csv
  double wall_s = 0;                      // from the demo's start to this part's last step
};

// One part's steps, added to a StepGraph that runs them with other parts'
// (the order of commands.sh, the seeds and the stages are those of the
// plan, whatever runs at once). Each step's output goes to
// DIR/<part>/logs/NN.log, NN its number in commands.sh.
class DemoPart {
 public:
  DemoPart(std::string part, const DemoOptions& options);
  DemoPart(const DemoPart&) = delete;
  DemoPart& operator=(const DemoPart&) = delete;
  ~DemoPart();

  // The step that generates the part (`truecut part`).
  void plan_generation(StepGraph& graph);
  // The other steps; reads the part.json the generation wrote.
  void plan_stages(StepGraph& graph);
  // Once the graph has run: the stages with their CMM measurements.
  DemoPartResult result() const;

 private:
  struct Plan;
  std::unique_ptr<Plan> plan_;
};

}  // namespace truecut::cli
