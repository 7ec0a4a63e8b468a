// cutting: material removal by the true tool, as a HAL component (normal
// dexels, sim/include/truecut/sim/cutting/dexel_model.hpp; docs/cutting.md).
//
//   loadrt cutting nominal=FILE.stl part=PART.json [out=FOLDER] [spacing=MM]
//                  [surfaces=ID,ID,...] [max-stock=MM] [max-depth=MM] [names=NAME]
//                  [sampling=swept|cycle] [threads=N] [max-dexels=N]
//
// FILE and PART are read at load time (relative to the working folder); a bad
// file fails the load naming the file and key. OUT (default ".") is a folder
// inside the HAL's output folder (relative to it, no '..'; an absolute path
// only at or below it). Pins of instance <i> (default "cutting.0"):
//   in   <i>.tcp-x/-y/-z            true tool tip, workpiece frame (mm)
//   in   <i>.tool-i/-j/-k           true tool axis (tip → spindle), workpiece frame
//   in   <i>.tool-radius, <i>.tool-corner-radius, <i>.tool-flute-length (mm)
//   in   <i>.spindle-rpm
//   in   <i>.enable                 (bit) cut only while true
//   out  <i>.mrr                    material removal rate (mm³/s), filtered
//   out  <i>.spindle-power-kw       kc · mrr
//   out  <i>.force-x/-y/-z          cutting force on the tool (N), workpiece frame
//   out  <i>.contact-x/-y/-z        centroid of the (filtered) removal; the tip when none
//   out  <i>.engaged                (bit) filtered removal above 1e-9 mm³ per cycle
//   out  <i>.removed-mm3            total removed since load (unfiltered)
//   out  <i>.fault                  (bit) tool or pose invalid this cycle (nothing cut)
// Parameters <i>.kc (N/mm², default 1800), <i>.kr (default 0.4), <i>.filter-time
// (s, default 0.01; first-order filter of the removal per cycle, 0 = none).
// Function <i>.update cuts the motion of the tool: with sampling=swept (the
// default) a tool instance is placed only where the swept solid needs one
// (swept_cut.hpp), with sampling=cycle at every cycle's pose. On exit the
// pending motion is cut and the machined surface is written to
// OUT/machined.stl and OUT/machined.ply (nothing when no cycle ran: a dry
// run, a load refused after this one). threads=N (default 0: one per
// hardware thread) cuts each tool instance's grid rows on N threads (the
// servo thread and N − 1 helpers the model starts); the result is the same
// bit for bit for any N. max-dexels (default 10 million, at most 50
// million) bounds the model: a nominal that would need more at this spacing
// (estimated from its triangles before any dexel is made) fails the load.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "truecut/rt/component_support.hpp"
#include "truecut/rt/interrupt_cleanup.hpp"
#include "truecut/sim/cutting/cutting_force.hpp"
#include "truecut/sim/cutting/part_file.hpp"
#include "truecut/sim/cutting/swept_cut.hpp"

namespace {

using namespace truecut::sim::cutting;

struct Params {
  double kc;
  double kr;
  double filter_time_s;
};

struct State {
  std::string name;
  std::filesystem::path out_dir;
  DexelModel model;
  bool per_cycle = false;
  SweptCut swept;
  CycleCut cycle;
  double removed_total_mm3 = 0;
  // A swept sampling cuts every few cycles what those cycles removed; it is
  // fed to the filter spread over as many cycles (Σ ΔV, Σ ΔV·n̂, Σ ΔV·x), so
  // the force a later instance sees does not ripple in step with the
  // instances. (Fed at once, the filtered force would be lowest just before
  // each instance, and the flank cut by it deflect less than it does.)
  struct Removal {
    double mm3 = 0;
    Eigen::Vector3d normal_mm3 = Eigen::Vector3d::Zero();
    Eigen::Vector3d contact_mm4 = Eigen::Vector3d::Zero();
    Removal& operator+=(const Removal& o) {
      mm3 += o.mm3, normal_mm3 += o.normal_mm3, contact_mm4 += o.contact_mm4;
      return *this;
    }
    Removal scaled(double f) const { return {f * mm3, f * normal_mm3, f * contact_mm4}; }
  };
  Removal held;
  int held_cycles = 0;
  // First-order filtered removal per cycle: Σ ΔV, Σ ΔV·n̂, Σ ΔV·x.
  double filtered_mm3 = 0;
  Eigen::Vector3d filtered_normal_mm3 = Eigen::Vector3d::Zero();
  Eigen::Vector3d filtered_contact_mm4 = Eigen::Vector3d::Zero();
  Params* params = nullptr;  // HAL memory: outlives this object
  double* tcp[3];
  double* axis[3];
  double* radius;
  double* corner;
  double* flute;
  double* rpm;
  bool* enable;
  double* mrr;
  double* power_kw;
  double* force[3];
  double* contact[3];
  bool* engaged;
  double* removed;
  bool* fault;
};

void idle(State& s, const CutterPose& pose) {
  *s.mrr = 0;
  *s.power_kw = 0;
  *s.engaged = false;
  for (int i = 0; i < 3; ++i) {
    *s.force[i] = 0;
    *s.contact[i] = pose.tip_mm[i];
  }
}

Engagement finish(State& s) {
  return s.per_cycle ? s.cycle.finish(s.model) : s.swept.finish(s.model);
}

void update(void* arg, long period_ns) {
  auto& s = *static_cast<State*>(arg);
  CutterPose pose;
  for (int i = 0; i < 3; ++i) {
    pose.tip_mm[i] = *s.tcp[i];
    pose.axis[i] = *s.axis[i];
  }
  const CutterShape shape{*s.radius, *s.corner, *s.flute};
  if (!*s.enable) {
    s.removed_total_mm3 += finish(s).removed_mm3;
    *s.removed = s.removed_total_mm3;
    *s.fault = false;
    idle(s, pose);
    return;
  }
  const Engagement e =
      s.per_cycle ? s.cycle.step(s.model, shape, pose) : s.swept.step(s.model, shape, pose);
  s.removed_total_mm3 += e.removed_mm3;
  *s.removed = s.removed_total_mm3;
  *s.fault = e.invalid_input;
  if (e.invalid_input) {
    idle(s, pose);
    return;
  }
  // The removal this cycle for the filter (State::held).
  using Removal = State::Removal;
  if (e.substeps > 0) {
    s.held += {e.removed_mm3, e.removed_mm3 * e.normal, e.removed_mm3 * e.contact_mm};
    s.held_cycles = s.per_cycle ? 1 : s.swept.cycles_covered();
  }
  Removal now;
  if (s.held_cycles > 0) {
    now = s.held.scaled(1.0 / s.held_cycles--);
    s.held += now.scaled(-1);
  }
  // A dexel loses its whole height in the cycle the tool reaches it, so the
  // raw removal per cycle comes in bursts when the feed per cycle is below
  // the dexel spacing; the filter spreads them like a measured power would.
  const double dt_s = double(period_ns) * 1e-9;
  const double tau_s = s.params->filter_time_s;
  const double alpha = tau_s > 0 ? 1 - std::exp(-dt_s / tau_s) : 1.0;
  s.filtered_mm3 += alpha * (now.mm3 - s.filtered_mm3);
  s.filtered_normal_mm3 += alpha * (now.normal_mm3 - s.filtered_normal_mm3);
  s.filtered_contact_mm4 += alpha * (now.contact_mm4 - s.filtered_contact_mm4);
  Engagement f;
  const bool engaged = s.filtered_mm3 > 1e-9;
  if (engaged) {
    f.removed_mm3 = s.filtered_mm3;
    const double len = s.filtered_normal_mm3.norm();
    if (len > 0) f.normal = s.filtered_normal_mm3 / len;
    f.contact_mm = s.filtered_contact_mm4 / s.filtered_mm3;
  }
  const CuttingLoad load =
      cutting_load(f, dt_s, shape.radius_mm, *s.rpm, ForceModel{s.params->kc, s.params->kr});
  *s.mrr = load.mrr_mm3_per_s;
  *s.power_kw = load.power_w * 1e-3;
  *s.engaged = engaged;
  for (int i = 0; i < 3; ++i) {
    *s.force[i] = load.force_n[i];
    *s.contact[i] = engaged ? f.contact_mm[i] : pose.tip_mm[i];
  }
}

std::filesystem::path normal_absolute(const std::filesystem::path& p) {
  std::filesystem::path n = std::filesystem::absolute(p).lexically_normal();
  return n.filename().empty() ? n.parent_path() : n;
}

// OUT inside the HAL's output folder `hal_out` and nowhere else, as the
// recorder's file=: a relative name without '..', or an absolute path at or
// below the folder (run.ini files of earlier versions name it so). An
// absolute OUT_DIR made a repeated run with another --out write its part
// into the first run's folder.
std::filesystem::path output_folder(const std::filesystem::path& hal_out, const std::string& out) {
  using truecut::rt::hal::component::InitError;
  const std::filesystem::path named(out);
  bool up = false;
  for (const auto& part : named)
    up = up || part == "..";
  const std::filesystem::path folder = normal_absolute(hal_out);
  const std::filesystem::path resolved =
      normal_absolute(named.is_absolute() ? named : hal_out / named);
  const auto [f, r] = std::mismatch(folder.begin(), folder.end(), resolved.begin(), resolved.end());
  if (up || f != folder.end())
    throw InitError("out=" + out + ": outside the output folder " + folder.string() +
                    "; the cutting component writes machined.stl and machined.ply inside it "
                    "(a relative name without '..')");
  return resolved;
}

std::vector<int> parse_ids(const std::string& text) {
  std::vector<int> ids;
  std::string cur;
  for (char c : text + ",") {
    if (c != ',') {
      cur += c;
      continue;
    }
    char* end = nullptr;
    const long v = std::strtol(cur.c_str(), &end, 10);
    if (cur.empty() || *end != '\0')
      throw truecut::rt::hal::component::InitError("surfaces='" + text +
                                                   "' must be surface ids separated by commas");
    ids.push_back(static_cast<int>(v));
    cur.clear();
  }
  return ids;
}

}  // namespace

extern "C" TC_COMPONENT_EXPORT int truecut_component_init(const tc_hal_api_t* api, tc_hal_t* hal,
                                                          int argc, const char* const* argv,
                                                          void** module_state) {
  using namespace truecut::rt::hal::component;
  return init_guard(api, hal, [&] {
    Args args(argc, argv);
    auto nominal = args.take("nominal");
    auto part = args.take("part");
    const std::string out = args.take_or("out", ".");
    DexelOptions options;
    options.spacing_mm = args.take_double("spacing", options.spacing_mm);
    options.max_stock_mm = args.take_double("max-stock", options.max_stock_mm);
    options.max_depth_mm = args.take_double("max-depth", options.max_depth_mm);
    options.threads = static_cast<int>(args.take_long("threads", 0, 0, 256));
    options.max_dexels = static_cast<std::size_t>(args.take_long(
        "max-dexels", static_cast<long>(kDefaultMaxDexels), 1, static_cast<long>(kMaxDexels)));
    if (auto ids = args.take("surfaces")) options.surfaces = parse_ids(*ids);
    const std::string sampling = args.take_or("sampling", "swept");
    if (sampling != "swept" && sampling != "cycle")
      throw InitError("sampling='" + sampling + "' must be swept or cycle");
    auto names = instance_names(args, "cutting", 1);
    args.expect_consumed("cutting");
    if (!nominal) throw InitError("cutting needs nominal=FILE.stl (the nominal part)");
    if (!part) throw InitError("cutting needs part=PART.json (stock and surfaces)");
    if (!(options.spacing_mm >= 1e-3)) throw InitError("spacing must be >= 0.001 mm");
    if (!(options.max_stock_mm >= 0)) throw InitError("max-stock must be >= 0");
    if (!(options.max_depth_mm >= 0)) throw InitError("max-depth must be >= 0");

    auto s = std::make_unique<State>();
    s->name = names.at(0);
    s->out_dir = output_folder(api->output_dir(hal), out);
    s->model = load_dexel_model(*nominal, *part, options);
    s->per_cycle = sampling == "cycle";

    const std::string& n = s->name;
    const int id = new_component(api, hal, n);
    Builder b(api, hal, id);
    s->params = b.alloc<Params>();
    s->params->kc = ForceModel{}.kc_n_per_mm2;
    s->params->kr = ForceModel{}.kr;
    s->params->filter_time_s = 0.01;
    for (int i = 0; i < 3; ++i) {
      b.pin(n + ".tcp-" + "xyz"[i], TC_HAL_FLOAT, TC_HAL_IN, &s -> tcp[i]);
      b.pin(n + ".tool-" + "ijk"[i], TC_HAL_FLOAT, TC_HAL_IN, &s -> axis[i]);
    }
    b.pin(n + ".tool-radius", TC_HAL_FLOAT, TC_HAL_IN, &s->radius);
    b.pin(n + ".tool-corner-radius", TC_HAL_FLOAT, TC_HAL_IN, &s->corner);
    b.pin(n + ".tool-flute-length", TC_HAL_FLOAT, TC_HAL_IN, &s->flute);
    b.pin(n + ".spindle-rpm", TC_HAL_FLOAT, TC_HAL_IN, &s->rpm);
    b.pin(n + ".enable", TC_HAL_BIT, TC_HAL_IN, &s->enable);
    b.pin(n + ".mrr", TC_HAL_FLOAT, TC_HAL_OUT, &s->mrr);
    b.pin(n + ".spindle-power-kw", TC_HAL_FLOAT, TC_HAL_OUT, &s->power_kw);
    for (int i = 0; i < 3; ++i) {
      b.pin(n + ".force-" + "xyz"[i], TC_HAL_FLOAT, TC_HAL_OUT, &s -> force[i]);
      b.pin(n + ".contact-" + "xyz"[i], TC_HAL_FLOAT, TC_HAL_OUT, &s -> contact[i]);
    }
    b.pin(n + ".engaged", TC_HAL_BIT, TC_HAL_OUT, &s->engaged);
    b.pin(n + ".removed-mm3", TC_HAL_FLOAT, TC_HAL_OUT, &s->removed);
    b.pin(n + ".fault", TC_HAL_BIT, TC_HAL_OUT, &s->fault);
    b.param(n + ".kc", TC_HAL_FLOAT, TC_HAL_RW, &s->params->kc);
    b.param(n + ".kr", TC_HAL_FLOAT, TC_HAL_RW, &s->params->kr);
    b.param(n + ".filter-time", TC_HAL_FLOAT, TC_HAL_RW, &s->params->filter_time_s);
    *s->axis[2] = 1.0;  // unlinked default: tool along +Z
    b.funct(n + ".update", update, s.get());
    api->component_ready(hal, id);
    api->message(hal, TC_HAL_MSG_INFO,
                 (n + ": " + std::to_string(s->model.size()) + " dexels from " + *nominal).c_str());
    *module_state = s.release();
    return 0;
  });
}

extern "C" TC_COMPONENT_EXPORT void truecut_component_exit(const tc_hal_api_t* api, tc_hal_t* hal,
                                                           void* module_state) {
  std::unique_ptr<State> s(static_cast<State*>(module_state));
  if (!s) return;
  // The surface of a run that never ran (a dry run, a load that another
  // component or the host's checks refused) is the stock: not an output.
  if (TC_HAL_API_HAS(api, cycles_ran) && api->cycles_ran(hal) == 0) {
    api->message(hal, TC_HAL_MSG_INFO,
                 (s->name + ": no cycle ran: machined.stl and machined.ply not written").c_str());
    return;
  }
  try {
    s->removed_total_mm3 += finish(*s).removed_mm3;
    std::filesystem::create_directories(s->out_dir);
    // machined.{stl,ply}.tmp go into the host's table of files to remove on
    // a signal: this library's own copy of it is not the one the host reads.
    const truecut::rt::PendingFilesToHost to_host(api, hal);
    const auto t = s->model.thread_stats();  // of the cut, before the mesh's own job
    s->model.write_machined(s->out_dir);
    api->message(hal, TC_HAL_MSG_INFO,
                 (s->name + ": wrote machined.stl and machined.ply to " + s->out_dir.string() +
                  " (" + std::to_string(s->removed_total_mm3) + " mm³ removed)")
                     .c_str());
    // How the tool instances were shared with the helper threads.
    if (t.jobs > 0) {
      char line[256];
      std::snprintf(
          line, sizeof line,
          "%s: %d threads: %llu instances shared, %.1f chunks each, %.1f %% of the "
          "chunks run by helpers, %llu wake-ups, %.1f polls waiting per instance",
          s->name.c_str(), s->model.threads(), static_cast<unsigned long long>(t.jobs),
          double(t.chunks) / double(t.jobs), 100.0 * double(t.worker_chunks) / double(t.chunks),
          static_cast<unsigned long long>(t.wakes), double(t.wait_spins) / double(t.jobs));
      api->message(hal, TC_HAL_MSG_INFO, line);
    }
  } catch (const std::exception& e) {
    api->message(hal, TC_HAL_MSG_ERR,
                 (s->name + ": writing the machined surface failed: " + e.what()).c_str());
  }
}
