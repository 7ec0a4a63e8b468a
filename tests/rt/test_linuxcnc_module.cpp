// truecut_comp built as a LinuxCNC module (rt/linuxcnc/) and run in
// LinuxCNC's own HAL: halrun loads it, halstreamer feeds every input pin
// one sample per servo cycle from a trajectory the test writes, halsampler
// records every output pin in the same thread, and each sample must equal,
// to the last bit, what the truecut shim's truecut_comp gives for the same
// input sample. Floats go through truecut_f64bits (tests/support/linuxcnc/)
// because halsampler prints floats with six decimals.
//
// Needs LinuxCNC 2.9 (linuxcnc-uspace, linuxcnc-uspace-dev when configuring)
// and root: halrun runs in a private mount namespace where LinuxCNC's module
// folder holds the modules built here (tests/support/linuxcnc/halrun_private.sh);
// nothing is installed into the system. Skipped otherwise, failed under
// TRUECUT_REQUIRE_ORACLES=1.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "linuxcnc_support.hpp"
#include "oracle.hpp"
#include "run_process.hpp"
#include "test_truecut_comp_support.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal_file.hpp"

using namespace truecut;
using namespace truecut::test;
using namespace truecut::test::comp;
using rt::hal::Hal;
using rt::hal::PinDir;
using rt::hal::Type;

namespace {

constexpr int kSamples = 2500;
// The servo period on both sides: the component's time step. LinuxCNC runs
// it in wall-clock time (uspace, not real time: a late cycle still takes one
// sample), so the shorter it is, the faster the test.
constexpr long kPeriodNs = 500000;
constexpr double kPeriodS = kPeriodNs * 1e-9;
const std::string kThreads =
    "loadrt threads name1=servo-thread period1=" + std::to_string(kPeriodNs) + "\n";

struct PinSpec {
  std::string name;  // without the instance prefix "c."
  Type type;
};

// A value of one input pin at sample i, as text (halstreamer's format).
using InputFn = std::function<double(const std::string& pin, int i, double fallback)>;

std::string text_of(Type type, double v) {
  char buf[48];
  switch (type) {
    case Type::kBit:
      return v != 0.0 ? "1" : "0";
    case Type::kS32:
      std::snprintf(buf, sizeof buf, "%d", static_cast<int32_t>(v));
      return buf;
    case Type::kU32:
      std::snprintf(buf, sizeof buf, "%u", static_cast<uint32_t>(v));
      return buf;
    case Type::kFloat:
      if (std::isnan(v)) return "nan";
      std::snprintf(buf, sizeof buf, "%.17g", v);
      return buf;
  }
  return {};
}

char cfg_char(Type type) {
  switch (type) {
    case Type::kBit:
      return 'b';
    case Type::kS32:
      return 's';
    case Type::kU32:
      return 'u';
    case Type::kFloat:
      return 'f';
  }
  return '?';
}

// One recorded output sample as halsampler prints it: floats as the u32
// high and low halves of their bits, then the other pins.
void append_tokens(const rt::hal::Value& v, std::vector<std::string>& row) {
  char buf[32];
  switch (v.type) {
    case Type::kFloat: {
      uint64_t bits;
      std::memcpy(&bits, &v.f, sizeof bits);
      std::snprintf(buf, sizeof buf, "%u", static_cast<uint32_t>(bits >> 32));
      row.push_back(buf);
      std::snprintf(buf, sizeof buf, "%u", static_cast<uint32_t>(bits));
      row.push_back(buf);
      return;
    }
    case Type::kBit:
      row.push_back(v.b ? "1" : "0");
      return;
    case Type::kS32:
      std::snprintf(buf, sizeof buf, "%d", v.s);
      row.push_back(buf);
      return;
    case Type::kU32:
      std::snprintf(buf, sizeof buf, "%u", v.u);
      row.push_back(buf);
      return;
  }
}

// The shim side: a component `feed` with one out pin per input of `c`,
// written directly (setp refuses NaN).
struct Feed {
  std::vector<PinSpec> specs;
  std::vector<void*> pins;
};
Feed*& feed_slot() {
  static Feed* slot = nullptr;
  return slot;
}
int feed_init(const tc_hal_api_t* api, tc_hal_t* hal, int, const char* const*, void**) {
  Feed& f = *feed_slot();
  const int id = api->component_new(hal, "feed");
  f.pins.assign(f.specs.size(), nullptr);
  for (std::size_t k = 0; k < f.specs.size(); ++k)
    if (api->pin_new(hal, id, ("feed." + std::to_string(k)).c_str(),
                     static_cast<tc_hal_type_t>(f.specs[k].type), TC_HAL_OUT, &f.pins[k]) != 0)
      return -22;
  return api->component_ready(hal, id);
}
void feed_write(const PinSpec& spec, void* pin, double v) {
  switch (spec.type) {
    case Type::kBit:
      *static_cast<bool*>(pin) = v != 0.0;
      break;
    case Type::kS32:
      *static_cast<int32_t*>(pin) = static_cast<int32_t>(v);
      break;
    case Type::kU32:
      *static_cast<uint32_t*>(pin) = static_cast<uint32_t>(v);
      break;
    case Type::kFloat:
      *static_cast<double*>(pin) = v;
      break;
  }
}

// The component's own pins (not its function's `c.update.*`), by direction.
struct PinLists {
  std::vector<PinSpec> inputs, outputs;
  std::map<std::string, double> defaults;  // inputs' values after load
};

PinLists pin_lists(const Hal& hal) {
  PinLists l;
  for (const auto& p : hal.pins()) {
    if (p.name.rfind("c.", 0) != 0 || p.name.rfind("c.update.", 0) == 0) continue;
    const PinSpec s{p.name.substr(2), p.type};
    if (p.dir == PinDir::kIn) {
      l.inputs.push_back(s);
      l.defaults[s.name] = hal.get_pin_or_param(p.name).as_double();
    } else {
      l.outputs.push_back(s);
    }
  }
  return l;
}

std::string load_args(const std::string& field, const std::string& mode) {
  return "names=c field=" + field + " mode=" + mode;
}

struct Scenario {
  std::string mode;  // tcp or joint
  std::string field;
  InputFn input;
  // Field swaps: when set, `field` is a copy of `initial` when the component
  // loads, and is replaced by a copy of `after_load` right after (before the
  // first cycle), so a reload reads the second field.
  std::filesystem::path initial = {}, after_load = {};
};

void copy_over(const std::filesystem::path& from, const std::string& to) {
  std::filesystem::copy_file(from, to, std::filesystem::copy_options::overwrite_existing);
  ::chmod(to.c_str(), 0666);  // halrun's `cp` runs as nobody
}

// The component's pins as the shim makes them.
PinLists shim_pin_lists(const Scenario& sc) {
  if (!sc.initial.empty()) copy_over(sc.initial, sc.field);
  Hal hal(hal_options());
  load_hal_text(hal, "loadrt truecut_comp " + load_args(sc.field, sc.mode) + "\n", "pins.hal");
  return pin_lists(hal);
}

// The shim's rows, one per sample. The component's service (which loads a
// field after a reload request) runs before the cycles in `services_before`
// only: in LinuxCNC it runs in its own thread, at times no test can choose,
// so the cycles where a load took effect there are taken from LinuxCNC's
// recording and reproduced here.
std::vector<std::vector<std::string>> run_shim(const Scenario& sc, PinLists& lists,
                                               const std::set<int>& services_before) {
  if (!sc.initial.empty()) copy_over(sc.initial, sc.field);
  Hal hal(hal_options());
  load_hal_text(hal, kThreads + "loadrt truecut_comp " + load_args(sc.field, sc.mode) + "\n",
                "shim.hal");
  if (!sc.after_load.empty()) copy_over(sc.after_load, sc.field);
  lists = pin_lists(hal);
  Feed feed;
  feed.specs = lists.inputs;
  feed_slot() = &feed;
  hal.load("feed", feed_init, nullptr);
  std::string nets;
  for (std::size_t k = 0; k < lists.inputs.size(); ++k)
    nets += "net in" + std::to_string(k) + " feed." + std::to_string(k) + " => c." +
            lists.inputs[k].name + "\n";
  load_hal_text(hal, nets + "addf c.update servo-thread\n", "nets.hal");
  rt::hal::Executor ex(hal);
  std::vector<std::vector<std::string>> rows;
  for (int i = 0; i < kSamples; ++i) {
    for (std::size_t k = 0; k < lists.inputs.size(); ++k) {
      const PinSpec& s = lists.inputs[k];
      feed_write(s, feed.pins[k], sc.input(s.name, i, lists.defaults.at(s.name)));
    }
    if (services_before.count(i) != 0) hal.run_services();
    ex.step();
    std::vector<std::string> row;
    for (const PinSpec& s : lists.outputs)
      append_tokens(hal.get_pin_or_param("c." + s.name), row);
    rows.push_back(std::move(row));
  }
  return rows;
}

struct LinuxcncRun {
  bool ok = false;
  std::string log;
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> pin_listing;  // "type dir name" of c.*, from halcmd's show pin
};

std::vector<std::string> split(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> out;
  std::string t;
  while (in >> t)
    out.push_back(t);
  return out;
}

// halstreamer and halsampler channels carry at most 20 pins each.
constexpr std::size_t kMaxChannelPins = 20;

LinuxcncRun run_linuxcnc(const Scenario& sc, const PinLists& lists,
                         const std::filesystem::path& work) {
  // halrun runs as nobody: its folder must be writable, its files readable.
  std::filesystem::create_directories(work);
  ::chmod(work.c_str(), 0777);

  // Inputs: streamer channel 0 starts with a bit `record`, 1 for the
  // kSamples samples and 0 in one sample after them, which enables the
  // samplers: once the streamer runs dry it holds that last sample, so the
  // samplers' FIFOs hold exactly kSamples samples however late halsampler
  // reads them.
  struct Slot {
    std::size_t channel, pin;
  };
  std::vector<std::string> stream_cfg(1, "b");
  std::vector<Slot> in_slots;
  for (const PinSpec& s : lists.inputs) {
    if (stream_cfg.back().size() == kMaxChannelPins) stream_cfg.emplace_back();
    in_slots.push_back({stream_cfg.size() - 1, stream_cfg.back().size()});
    stream_cfg.back() += cfg_char(s.type);
  }
  std::string nets = "net record streamer.0.pin.0\n";
  for (std::size_t k = 0; k < lists.inputs.size(); ++k)
    nets += "net in" + std::to_string(k) + " streamer." + std::to_string(in_slots[k].channel) +
            ".pin." + std::to_string(in_slots[k].pin) + " => c." + lists.inputs[k].name + "\n";
  std::vector<std::filesystem::path> stream_files;
  for (std::size_t ch = 0; ch < stream_cfg.size(); ++ch) {
    stream_files.push_back(work / ("stream" + std::to_string(ch) + ".txt"));
    std::ofstream out(stream_files.back());
    for (int i = 0; i <= kSamples; ++i) {
      if (ch == 0) out << (i < kSamples ? "1 " : "0 ");
      for (std::size_t k = 0; k < lists.inputs.size(); ++k) {
        if (in_slots[k].channel != ch) continue;
        const PinSpec& s = lists.inputs[k];
        out << text_of(s.type,
                       sc.input(s.name, std::min(i, kSamples - 1), lists.defaults.at(s.name)))
            << ' ';
      }
      out << '\n';
    }
  }

  // Outputs: floats as two u32 (truecut_f64bits), in sampler channels of up
  // to 20 pins, read back in order.
  std::vector<std::string> sample_cfg(1);
  int floats = 0;
  auto sampler_pin = [&](char type) {
    if (sample_cfg.back().size() == kMaxChannelPins) sample_cfg.emplace_back();
    const std::string pin = "sampler." + std::to_string(sample_cfg.size() - 1) + ".pin." +
                            std::to_string(sample_cfg.back().size());
    sample_cfg.back() += type;
    return pin;
  };
  for (std::size_t k = 0; k < lists.outputs.size(); ++k) {
    const PinSpec& s = lists.outputs[k];
    const std::string sig = "out" + std::to_string(k);
    if (s.type == Type::kFloat) {
      const std::string b = "truecut_f64bits." + std::to_string(floats++);
      nets += "net " + sig + " c." + s.name + " => " + b + ".in\n";
      nets += "net " + sig + "hi " + b + ".hi => " + sampler_pin('u') + "\n";
      nets += "net " + sig + "lo " + b + ".lo => " + sampler_pin('u') + "\n";
    } else {
      nets += "net " + sig + " c." + s.name + " => " + sampler_pin(cfg_char(s.type)) + "\n";
    }
  }
  for (std::size_t ch = 0; ch < sample_cfg.size(); ++ch)
    nets += "net record => sampler." + std::to_string(ch) + ".enable\n";

  auto joined = [](const std::vector<std::string>& cfgs) {
    std::string out;
    for (const auto& c : cfgs)
      out += (out.empty() ? "" : ",") + c;
    return out;
  };
  // One depth per FIFO.
  auto depths = [](std::size_t n) {
    std::string out;
    for (std::size_t k = 0; k < n; ++k)
      out += (k == 0 ? "" : ",") + std::to_string(kSamples + 16);
    return out;
  };
  const auto hal_file = work / "run.hal";
  std::vector<std::filesystem::path> sample_files;
  {
    std::ofstream out(hal_file);
    out << kThreads << "loadrt streamer depth=" << depths(stream_cfg.size())
        << " cfg=" << joined(stream_cfg) << "\n"
        << "loadrt truecut_comp " << load_args(sc.field, sc.mode) << "\n"
        << "loadrt truecut_f64bits count=" << floats << "\n"
        << "loadrt sampler depth=" << depths(sample_cfg.size()) << " cfg=" << joined(sample_cfg)
        << "\n"
        << nets;
    if (!sc.after_load.empty())
      out << "loadusr -w cp " << sc.after_load.string() << " " << sc.field << "\n";
    // One thread, in this order: each cycle the streamers set the inputs of
    // one sample, the component runs, the samplers record its outputs.
    for (std::size_t ch = 0; ch < stream_cfg.size(); ++ch)
      out << "addf streamer." << ch << " servo-thread\n";
    out << "addf c.update servo-thread\n"
        << "addf truecut_f64bits.update servo-thread\n";
    for (std::size_t ch = 0; ch < sample_cfg.size(); ++ch)
      out << "addf sampler." << ch << " servo-thread\n";
    out << "show pin c.\n";
    // The whole trajectory is in the streamers' FIFOs before the thread
    // starts, so no cycle runs without a sample.
    for (std::size_t ch = 0; ch < stream_cfg.size(); ++ch)
      out << "loadusr -w halstreamer -c " << ch << " " << stream_files[ch].string() << "\n";
    out << "start\n";
    for (std::size_t ch = 0; ch < sample_cfg.size(); ++ch) {
      sample_files.push_back(work / ("samples" + std::to_string(ch) + ".txt"));
      std::filesystem::remove(sample_files.back());
      out << "loadusr -w halsampler -c " << ch << " -n " << kSamples << " "
          << sample_files.back().string() << "\n";
    }
    out << "stop\n";
  }
  const ProcessResult r = run_linuxcnc_private(work, {"halrun", "-f", hal_file.string()});
  LinuxcncRun run;
  run.log =
      "halrun exit " + std::to_string(r.exit_code) + "\nstdout:\n" + r.out + "\nstderr:\n" + r.err;
  run.ok = r.exit_code == 0;
  std::istringstream listing(r.out);
  for (std::string line; std::getline(listing, line);) {
    const auto t = split(line);
    if (t.size() >= 5 && t[4].rfind("c.", 0) == 0 && t[4].rfind("c.update.", 0) != 0)
      run.pin_listing.push_back(t[1] + " " + t[2] + " " + t[4]);
  }
  run.rows.assign(kSamples, {});
  for (const auto& file : sample_files) {
    std::ifstream in(file);
    std::size_t i = 0;
    for (std::string line; std::getline(in, line) && i < run.rows.size(); ++i)
      for (auto& t : split(line))
        run.rows[i].push_back(std::move(t));
    if (i != run.rows.size()) {
      run.ok = false;
      run.log += "\n" + file.string() + ": " + std::to_string(i) + " samples";
    }
  }
  return run;
}

std::string names_of(const std::vector<PinSpec>& outputs, std::size_t token) {
  std::size_t t = 0;
  for (const PinSpec& s : outputs) {
    const std::size_t n = s.type == Type::kFloat ? 2 : 1;
    if (token < t + n) return "c." + s.name + (n == 2 ? (token == t ? " (hi)" : " (lo)") : "");
    t += n;
  }
  return "?";
}

double as_double(const std::string& hi, const std::string& lo) {
  const uint64_t bits = (std::stoull(hi) << 32) | std::stoull(lo);
  double v;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

// Runs the scenario on both sides; expects the same pins and every sample
// bit-identical.
// Where output `pin` sits in a recorded row.
std::size_t token_of(const std::vector<PinSpec>& outputs, const std::string& pin) {
  std::size_t t = 0;
  for (const PinSpec& s : outputs) {
    if (s.name == pin) return t;
    t += s.type == Type::kFloat ? 2 : 1;
  }
  throw std::runtime_error("no output pin " + pin);
}

// The samples where a field load took effect in LinuxCNC (field-generation
// or load-errors changed), in order.
std::vector<int> load_cycles(const std::vector<std::vector<std::string>>& rows,
                             const std::vector<PinSpec>& outputs) {
  const std::size_t gen = token_of(outputs, "field-generation");
  const std::size_t err = token_of(outputs, "load-errors");
  std::vector<int> out;
  for (std::size_t i = 1; i < rows.size(); ++i)
    if (rows[i].size() > std::max(gen, err) && rows[i - 1].size() > std::max(gen, err) &&
        (rows[i][gen] != rows[i - 1][gen] || rows[i][err] != rows[i - 1][err]))
      out.push_back(static_cast<int>(i));
  return out;
}

// Runs the scenario in LinuxCNC, then in the shim; expects the same pins
// and every sample bit-identical. Returns the samples where a field load
// took effect.
std::vector<int> compare(const Scenario& sc) {
  PinLists lists = shim_pin_lists(sc);
  const LinuxcncRun lc = run_linuxcnc(sc, lists, scratch_dir() / "linuxcnc");
  EXPECT_TRUE(lc.ok) << lc.log;
  if (!lc.ok) return {};
  const std::vector<int> loads = load_cycles(lc.rows, lists.outputs);
  const auto shim_rows = run_shim(sc, lists, std::set<int>(loads.begin(), loads.end()));

  std::vector<std::string> shim_listing;
  auto dir_text = [](bool in) { return in ? "IN" : "OUT"; };
  for (const PinSpec& s : lists.inputs)
    shim_listing.push_back(std::string(rt::hal::to_string(s.type)) + " " + dir_text(true) + " c." +
                           s.name);
  for (const PinSpec& s : lists.outputs)
    shim_listing.push_back(std::string(rt::hal::to_string(s.type)) + " " + dir_text(false) + " c." +
                           s.name);
  std::sort(shim_listing.begin(), shim_listing.end(),
            [](const std::string& a, const std::string& b) {
              return a.substr(a.rfind(' ')) < b.substr(b.rfind(' '));
            });
  EXPECT_EQ(shim_listing, lc.pin_listing) << "pins (type, direction, name)\n" << lc.log;

  EXPECT_EQ(shim_rows.size(), lc.rows.size()) << lc.log;
  if (shim_rows.size() != lc.rows.size()) return loads;
  int mismatches = 0;
  for (std::size_t i = 0; i < shim_rows.size() && mismatches < 5; ++i) {
    if (shim_rows[i] == lc.rows[i]) continue;
    ++mismatches;
    EXPECT_EQ(shim_rows[i].size(), lc.rows[i].size()) << "sample " << i << "\n" << lc.log;
    if (shim_rows[i].size() != lc.rows[i].size()) break;
    for (std::size_t t = 0; t < shim_rows[i].size(); ++t)
      if (shim_rows[i][t] != lc.rows[i][t]) {
        std::string detail;
        const std::string name = names_of(lists.outputs, t);
        if (name.find(" (") != std::string::npos) {
          const std::size_t hi = name.find("(hi)") != std::string::npos ? t : t - 1;
          char buf[96];
          std::snprintf(buf, sizeof buf, " (shim %.17g, LinuxCNC %.17g)",
                        as_double(shim_rows[i][hi], shim_rows[i][hi + 1]),
                        as_double(lc.rows[i][hi], lc.rows[i][hi + 1]));
          detail = buf;
        }
        ADD_FAILURE() << "sample " << i << ": " << name << " shim " << shim_rows[i][t]
                      << ", LinuxCNC " << lc.rows[i][t] << detail;
        break;
      }
  }
  EXPECT_EQ(0, mismatches);
  return loads;
}

double smooth(double t, double f) {
  return std::sin(2.0 * M_PI * f * t);
}

}  // namespace

// TCP mode: fade in, a path through the field, tool change to a tool
// without a layer (fault, fade out, fade back), enable off and on, a
// position outside the grid, non-finite input, a reset.
TEST(LinuxcncModule, TcpModeIsBitIdenticalToTheShim) {
  if (const std::string missing = linuxcnc_missing(); !missing.empty())
    TRUECUT_ORACLE_MISSING(missing);
  const auto field = write_field(scratch_dir() / "field.tcf", {});
  ::chmod(scratch_dir().c_str(), 0755);
  Scenario sc{"tcp", field.string(), [](const std::string& pin, int i, double fallback) {
                const double t = i * kPeriodS;
                if (pin == "enable") return (i >= 100 && i < 1400) || i >= 1700 ? 1.0 : 0.0;
                if (pin == "tool") return i >= 700 && i < 800 ? 7.0 : 1.0;
                if (pin == "fade-time") return 0.2;
                if (pin == "max-rate") return 5.0;
                if (pin == "tcp-x")
                  return 15.0 * std::cos(M_PI * t) + (i >= 1900 && i < 2000 ? 40.0 : 0.0);
                if (pin == "tcp-y")
                  return i >= 2100 && i < 2105 ? std::numeric_limits<double>::quiet_NaN()
                                               : 15.0 * std::sin(M_PI * t);
                if (pin == "tcp-z") return 4.0 * smooth(t, 0.3);
                if (pin == "axis-i") return 0.2 * smooth(t, 0.7);
                if (pin == "reset") return i >= 2300 && i < 2302 ? 1.0 : 0.0;
                return fallback;
              }};
  EXPECT_EQ(std::vector<int>{}, compare(sc)) << "no field loads";
}

// Joint mode (xyzac-trt kinematics): the A/C table turning under a moving
// tool, fade in, a soft limit that clips X, a per-joint limit on Y, A
// outside its travel (kinematics fault), non-finite input.
TEST(LinuxcncModule, JointModeIsBitIdenticalToTheShim) {
  if (const std::string missing = linuxcnc_missing(); !missing.empty())
    TRUECUT_ORACLE_MISSING(missing);
  FieldSpec spec;
  spec.origin_mm = {-40.0, -40.0, -30.0};
  spec.dims = {17, 17, 13};
  spec.scale = 4.0;
  const auto field = write_field(scratch_dir() / "field.tcf", spec);
  Scenario sc{"joint", field.string(), [](const std::string& pin, int i, double fallback) {
                const double t = i * kPeriodS;
                if (pin == "enable") return i >= 100 ? 1.0 : 0.0;
                if (pin == "tool") return 1.0;
                if (pin == "fade-time") return 0.2;
                if (pin == "x-rot-point") return 5.0;
                if (pin == "y-rot-point") return -3.0;
                if (pin == "z-rot-point") return 20.0;
                if (pin == "z-offset") return -12.0;
                if (pin == "tool-offset") return 50.0;
                if (pin == "joint-x") return 3.0 + 5.0 * smooth(t, 0.5);
                if (pin == "joint-y") return -7.0 + 5.0 * std::cos(M_PI * t);
                if (pin == "joint-z") return 60.0 + 3.0 * smooth(t, 0.3);
                if (pin == "joint-a") return 25.0 + 10.0 * smooth(t, 0.4);
                if (pin == "joint-c")
                  return i >= 2200 && i < 2204 ? std::numeric_limits<double>::infinity()
                                               : 40.0 + 90.0 * t;
                if (pin == "joint-x-max-limit" && i >= 300 && i < 700) return 6.0;
                if (pin == "joint-y-max-correction" && i >= 1700 && i < 1900) return 0.05;
                if (pin == "a-max" && i >= 2000 && i < 2100) return 10.0;
                return fallback;
              }};
  EXPECT_EQ(std::vector<int>{}, compare(sc)) << "no field loads";
}

// Field swaps under a running path: the component loads field A, the file
// is then replaced by field B; a reload swaps to B with a cross-fade, a
// second reload (held back by swap-inhibit for a while) swaps to B again.
// When the loads take effect depends on LinuxCNC's service thread: those
// samples come from LinuxCNC's recording, everything else must match.
TEST(LinuxcncModule, FieldSwapsAreBitIdenticalToTheShim) {
  if (const std::string missing = linuxcnc_missing(); !missing.empty())
    TRUECUT_ORACLE_MISSING(missing);
  const auto work = scratch_dir() / "linuxcnc";
  std::filesystem::create_directories(work);
  ::chmod(work.c_str(), 0777);
  FieldSpec b_spec;
  b_spec.scale = -2.0;
  Scenario sc{"tcp", (work / "field.tcf").string(),
              [](const std::string& pin, int i, double fallback) {
                const double t = i * kPeriodS;
                if (pin == "enable") return i >= 50 ? 1.0 : 0.0;
                if (pin == "tool") return 1.0;
                if (pin == "fade-time") return 0.3;
                if (pin == "max-rate") return 5.0;
                if (pin == "tcp-x") return 15.0 * std::cos(M_PI * t);
                if (pin == "tcp-y") return 15.0 * std::sin(M_PI * t);
                if (pin == "tcp-z") return 4.0 * smooth(t, 0.3);
                if (pin == "reload")
                  return (i >= 600 && i < 610) || (i >= 1500 && i < 1510) ? 1.0 : 0.0;
                if (pin == "swap-inhibit") return i >= 1400 && i < 1900 ? 1.0 : 0.0;
                return fallback;
              },
              write_field(scratch_dir() / "a.tcf", {}),
              write_field(scratch_dir() / "b.tcf", b_spec)};
  const std::vector<int> loads = compare(sc);
  ASSERT_EQ(2u, loads.size()) << "two swaps";
  EXPECT_GT(loads[0], 600);
  EXPECT_GE(loads[1], 1900) << "held back by swap-inhibit";
}

// A reload without a field file fails in the service: load-errors counts it
// (no field: the component stays in its fault).
TEST(LinuxcncModule, AFailedReloadIsBitIdenticalToTheShim) {
  if (const std::string missing = linuxcnc_missing(); !missing.empty())
    TRUECUT_ORACLE_MISSING(missing);
  Scenario sc{"tcp", "", [](const std::string& pin, int i, double fallback) {
                if (pin == "enable") return i >= 50 ? 1.0 : 0.0;
                if (pin == "tcp-x") return 0.01 * i;
                if (pin == "reload") return i >= 300 && i < 310 ? 1.0 : 0.0;
                return fallback;
              }};
  const std::vector<int> loads = compare(sc);
  ASSERT_EQ(1u, loads.size()) << "one failed load";
  EXPECT_GT(loads[0], 300);
}
