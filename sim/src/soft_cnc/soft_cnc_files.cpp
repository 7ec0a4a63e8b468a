// The wiring text and the run.ini of a soft-CNC job.
#include <array>
#include <sstream>

#include "truecut/sim/soft_cnc.hpp"

namespace truecut::sim {
namespace {

namespace fs = std::filesystem;

std::string absolute_text(const fs::path& p) {
  return fs::absolute(p).lexically_normal().string();
}

std::string number_text(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

// INI text in the order written, one [SECTION] header per run of keys.
class IniText {
 public:
  void set(const std::string& section, const std::string& key, const std::string& value) {
    if (section != section_) {
      text_ += (text_.empty() ? "[" : "\n[") + section + "]\n";
      section_ = section;
    }
    text_ += key + " = " + value + "\n";
  }
  std::string text() const { return text_; }

 private:
  std::string text_;
  std::string section_;
};

long long servo_period_ns(const SoftCncJob& job) {
  return static_cast<long long>(job.period_us * 1000 + 0.5);
}

// The program starts with the tool at a safe height: 10 mm below the top of
// the Z travel (machine zero may lie inside the part).
std::array<double, 5> start_joints(const MachineDescription& machine) {
  const JointParams& z = machine.machine.joints[2];
  return {0.0, 0.0, z.present ? z.max - 10.0 : 0.0, 0.0, 0.0};
}

}  // namespace

SoftCncJob part_folder_job(const std::filesystem::path& part_dir,
                           const std::filesystem::path& out_dir, const std::string& machine,
                           const std::string& program) {
  SoftCncJob job;
  job.machine = part_dir / machine;
  job.program = part_dir / program;
  job.nominal = part_dir / "nominal.stl";
  job.part = part_dir / "part.json";
  job.tools = part_dir / "tools.tbl";
  job.out_dir = out_dir;
  return job;
}

interp::PlannerOptions soft_cnc_planner_options(const SoftCncJob& job,
                                                const MachineDescription& machine) {
  const KinematicsParams& k = machine.machine.kinematics;
  interp::PlannerOptions o;
  o.servo_period_s = double(servo_period_ns(job)) * 1e-9;
  o.start_joints = start_joints(machine);
  // The description's pivots and directions; its kinematics hold no tool
  // length or A travel (see KinematicsParams), so those keep rt's defaults.
  o.kinematics = k.ac;
  return o;
}

const std::string& soft_cnc_hal_text() {
  static const std::string text =
#include "soft_cnc_hal.inc"
      ;
  return text;
}

std::string soft_cnc_ini_text(const SoftCncJob& job, const MachineDescription& machine,
                              const std::vector<int32_t>& field_tools) {
  const KinematicsParams& k = machine.machine.kinematics;
  IniText ini;
  ini.set("RUN", "MACHINE", absolute_text(job.machine));
  ini.set("RUN", "PROGRAM", absolute_text(job.program));
  ini.set("RUN", "TOOL_TABLE", absolute_text(job.tools));
  ini.set("RUN", "PARAMETER_FILE", job.parameters ? absolute_text(*job.parameters) : "");
  ini.set("RUN", "PARAMETER_UNITS", job.parameters_in_inches ? "inch" : "mm");
  ini.set("RUN", "PART", absolute_text(job.part));
  ini.set("RUN", "NOMINAL", absolute_text(job.nominal));
  ini.set("RUN", "DEXEL_SPACING", number_text(job.dexel_spacing_mm));
  ini.set("RUN", "MAX_DEXELS", std::to_string(job.max_dexels));
  ini.set("RUN", "CUT_THREADS", std::to_string(job.cut_threads));
  ini.set("RUN", "SERVO_PERIOD_NS", std::to_string(servo_period_ns(job)));
  ini.set("RUN", "RECORD_EVERY", std::to_string(job.record_every));
  ini.set("RUN", "MAX_BLOCKS", std::to_string(job.max_blocks));
  ini.set("RUN", "MAX_PROGRAM_TIME", number_text(job.max_program_time_s));
  const std::array<double, 5> start = start_joints(machine);
  std::string start_text;
  for (double v : start)
    start_text += (start_text.empty() ? "" : ",") + number_text(v);
  ini.set("RUN", "START", start_text);
  ini.set("KINS", "X_ROT_POINT", number_text(k.ac.x_rot_point_mm));
  ini.set("KINS", "Y_ROT_POINT", number_text(k.ac.y_rot_point_mm));
  ini.set("KINS", "Z_ROT_POINT", number_text(k.ac.z_rot_point_mm));
  ini.set("KINS", "Y_OFFSET", number_text(k.ac.y_offset_mm));
  ini.set("KINS", "Z_OFFSET", number_text(k.ac.z_offset_mm));
  ini.set("KINS", "CONVENTIONAL_DIRECTIONS", k.ac.conventional_directions ? "1" : "0");
  ini.set("COMP", "FIELD", job.field ? absolute_text(*job.field) : "");
  ini.set("COMP", "ENABLE", job.field ? "1" : "0");
  std::string tools;
  for (const int32_t t : field_tools)
    tools += (tools.empty() ? "" : ",") + std::to_string(t);
  ini.set("COMP", "TOOLS", job.field ? tools : "");
  ini.set("COMP", "MAX_CORRECTION", number_text(job.max_correction_mm));
  ini.set("COMP", "MAX_RATE", number_text(job.max_rate_mm_per_s));
  ini.set("COMP", "FADE_TIME", number_text(job.fade_time_s));
  return "# Written by truecut run for soft_cnc.hal beside it (docs/soft-cnc.md).\n" + ini.text();
}

}  // namespace truecut::sim
