// One cycle of the compensation through the core's single public header,
// built without anything else of truecut (see CMakeLists.txt): a small field,
// comp::step() adopting it, the correction it outputs, the magnitude clamp,
// and the joint mode. Exits 1 naming the first failed check.
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "truecut/rt/comp.hpp"

namespace {

int g_failures = 0;

void check(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "FAILED: %s\n", what);
  ++g_failures;
}

// 3 x 3 x 3 nodes, 10 mm apart around the origin, tool 4: a constant vector
// at weight 1, so the field evaluates to that vector everywhere inside.
truecut::rt::CorrectionField small_field(const Eigen::Vector3d& v) {
  using namespace truecut::rt;
  FieldGrid g;
  g.origin_mm = {-10.0, -10.0, -10.0};
  g.spacing_mm = Eigen::Vector3d::Constant(10.0);
  g.dims = {3, 3, 3};
  FieldLayer layer;
  layer.tool = 4;
  layer.nodes.assign(static_cast<std::size_t>(g.node_count()), FieldNode{v.x(), v.y(), v.z(), 1.0});
  std::vector<FieldLayer> layers;
  layers.push_back(std::move(layer));
  return CorrectionField(g, std::move(layers));
}

}  // namespace

int main() {
  using namespace truecut::rt;
  const Eigen::Vector3d v(0.010, -0.020, 0.030);
  const CorrectionField field = small_field(v);

  // One cycle at 1 kHz: enabled, no fade time, the rate limit wide open.
  comp::CompState state;
  comp::CycleInput in;
  in.enable = true;
  in.tool = 4;
  in.tcp_mm = {1.5, -2.5, 3.5};
  in.candidate = &field;
  const comp::CompLimits limits{comp::kDefaultMaxCorrectionMm, 1e6, 0.0};
  const comp::CycleOutput out = comp::step(state, in, limits, 1e-3);
  check(out.adopted, "the candidate field is adopted");
  check(state.current.field == &field, "the state holds the field");
  check(out.released == nullptr, "nothing to release");
  check(out.fault == comp::Fault::kNone, "no fault");
  check(out.active, "active");
  check(out.fade == 1.0, "fully faded in");
  check(!out.limited, "not limited");
  check((out.correction_mm - v).norm() < 1e-12, "the correction is the field's vector");
  check(state.translation.output == out.correction_mm, "the state keeps the output");

  // The magnitude clamp: the next cycle with a bound of 0.01 mm.
  const comp::CompLimits tight{0.01, 1e6, 0.0};
  in.candidate = nullptr;
  const comp::CycleOutput clamped = comp::step(state, in, tight, 1e-3);
  check(clamped.limited, "the clamp acts");
  check(std::abs(clamped.correction_mm.norm() - 0.01) < 1e-15, "clamped to 0.01 mm");
  check((clamped.correction_mm.normalized() - v.normalized()).norm() < 1e-12,
        "the clamp keeps the direction");

  // Outside the grid: fault outside-grid; the failing source fades out,
  // at once with a fade time of 0.
  in.tcp_mm = {50.0, 0.0, 0.0};
  const comp::CycleOutput outside = comp::step(state, in, tight, 1e-3);
  check(outside.fault == comp::Fault::kOutsideGrid, "outside-grid fault");
  check(state.current.frozen, "the failing source is frozen");
  check(outside.correction_mm.isZero(0.0), "and faded out");

  // Joint mode: the corrected joints put the TCP at tcp + correction.
  AcTrtParams kins;
  kins.z_rot_point_mm = -100.0;
  kins.tool_length_mm = 50.0;
  const AcJoints joints{10.0, 20.0, 30.0, 15.0, 40.0};
  const ToolPose pose = forward_ac(kins, joints);
  const AcJoints moved = comp::correct_joints(kins, joints, pose, v);
  check((forward_ac(kins, moved).tcp_mm - (pose.tcp_mm + v)).norm() < 1e-9,
        "joint mode moves the TCP by the correction");
  check(moved.a_deg == joints.a_deg && moved.c_deg == joints.c_deg, "A and C pass through");

  if (g_failures == 0) std::printf("comp standalone: ok\n");
  return g_failures == 0 ? EXIT_SUCCESS : EXIT_FAILURE;
}
