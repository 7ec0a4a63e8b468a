// The closed loop with a fixed synthetic field: the coarse implant machined
// on its ideal machine through the shipped soft-CNC wiring (interpreter and
// planner -> truecut_comp in joint mode -> machine -> cutting), once without
// a field and once with one, measured by the virtual CMM. A correction moves
// the tool, so a pure translation c moves every machined face by c·n along
// its outward normal n (positive = oversize): the ±X shaft faces by ±c_x,
// the ±Y faces and the top by nothing when c is along X.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>

#include "e2e_support.hpp"
#include "truecut/offline/stl_io.hpp"
#include "truecut/sim/measure/cmm.hpp"

using namespace truecut;
using namespace truecut::test;
using namespace truecut::test::e2e;
using sim::measure::CmmMeasurement;

namespace {

namespace fs = std::filesystem;

// Implant surface ids (docs/parts.md).
constexpr int kXPos = 1, kXNeg = 2, kYPos = 3, kYNeg = 4, kTop = 5;

struct Machined {
  sim::SoftCncResult result;
  std::vector<CmmMeasurement> cmm;
};

class ClosedLoopField : public ::testing::Test {
 protected:
  // The part and the baseline run (no field) are made once per process, in
  // the scratch folder of the first test that runs (ctest runs every test
  // in its own process, so parallel runs never share a folder).
  void SetUp() override {
    if (dir_) return;
    dir_ = new fs::path(scratch_dir());
    part_ = new sim::BenchmarkPart(sim::make_part(sim::PartId::kImplant, coarse_options()));
    sim::write_part(*part_, *dir_ / "part");
    const std::vector<int32_t> faces = {kXPos, kXNeg, kYPos, kYNeg, kTop};
    points_ = new std::vector<sim::measure::CmmPoint>(
        sim::measure::cmm_points_on_surfaces(part_->mesh, part_->triangle_surface, 0.2, faces));
    // Away from the face edges: the corners of the shaft, the base and the
    // top are shaped by the tool's ends and corners, not by a face pass.
    std::erase_if(*points_, [](const sim::measure::CmmPoint& p) {
      const Eigen::Vector3d& x = p.position_mm;
      const bool near_corner =
          std::abs(std::abs(x.x()) - 0.8) < 0.15 && std::abs(std::abs(x.y()) - 0.8) < 0.15;
      const bool near_top_edge = p.surface != kTop && x.z() > 16.7;
      const bool top_rim = p.surface == kTop && (std::abs(x.x()) > 0.65 || std::abs(x.y()) > 0.65);
      return near_corner || near_top_edge || top_rim;
    });
    baseline_ = new Machined(machine("baseline", std::nullopt, 11));
  }
  static void TearDownTestSuite() {
    delete baseline_;
    delete points_;
    delete part_;
    delete dir_;
    dir_ = nullptr;
  }

  // Machines the part with `field` (none: the component passes the joints
  // bit for bit) and probes the machined surface (σ = 1 µm, seeded).
  static Machined machine(const std::string& name, std::optional<fs::path> field,
                          std::uint64_t seed, std::vector<sim::SoftCncFieldSwap> swaps = {},
                          double fade_time_s = 0.2) {
    sim::SoftCncJob job = ideal_job(*dir_ / "part", *dir_ / name);
    job.field = field;
    job.field_swaps = std::move(swaps);
    job.fade_time_s = fade_time_s;
    Machined m;
    m.result = sim::run_soft_cnc(job);
    EXPECT_TRUE(m.result.finished) << name;
    EXPECT_FALSE(m.result.limit_fault) << name;
    const auto mesh = offline::read_stl(*dir_ / name / "machined.stl");
    sim::measure::CmmOptions o;
    o.sigma_mm = 0.001;
    o.seed = seed;
    m.cmm = sim::measure::probe(mesh, *points_, o);
    return m;
  }

  static fs::path field_file(const std::string& name, const CorrectionFn& fn) {
    const fs::path f = *dir_ / (name + ".tcf");
    write_synthetic_field(f, *part_, fn);
    return f;
  }

  static fs::path* dir_;
  static sim::BenchmarkPart* part_;
  static std::vector<sim::measure::CmmPoint>* points_;
  static Machined* baseline_;
};

fs::path* ClosedLoopField::dir_ = nullptr;
sim::BenchmarkPart* ClosedLoopField::part_ = nullptr;
std::vector<sim::measure::CmmPoint>* ClosedLoopField::points_ = nullptr;
Machined* ClosedLoopField::baseline_ = nullptr;

// Per face: the deviation change of each point (with field − without).
struct FaceShift {
  std::vector<double> shift_mm;
  std::vector<Eigen::Vector3d> position_mm;
  double mean() const {
    double s = 0;
    for (double v : shift_mm)
      s += v;
    return shift_mm.empty() ? 0.0 : s / double(shift_mm.size());
  }
};

std::map<int, FaceShift> face_shifts(const Machined& base, const Machined& with) {
  std::map<int, FaceShift> faces;
  EXPECT_EQ(base.cmm.size(), with.cmm.size());
  for (std::size_t i = 0; i < base.cmm.size() && i < with.cmm.size(); ++i) {
    const auto& a = base.cmm[i];
    const auto& b = with.cmm[i];
    EXPECT_TRUE(a.valid && b.valid) << "point " << i << " at " << a.nominal.position_mm.transpose();
    if (!a.valid || !b.valid) continue;
    auto& f = faces[a.nominal.surface];
    f.shift_mm.push_back(b.deviation_mm - a.deviation_mm);
    f.position_mm.push_back(a.nominal.position_mm);
  }
  return faces;
}

void print_faces(const char* what, const std::map<int, FaceShift>& faces) {
  for (const auto& [id, f] : faces) {
    double lo = 1e9, hi = -1e9;
    for (double v : f.shift_mm)
      lo = std::min(lo, v), hi = std::max(hi, v);
    std::printf("  %s: surface %d, %zu points, shift mean %+.4f mm, min %+.4f, max %+.4f\n", what,
                id, f.shift_mm.size(), f.mean(), lo, hi);
  }
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

// Every point and the face's median, on every face: gouged faces (c·n < 0,
// the tool driven into the nominal surface) as well as oversize ones.
void expect_face_shift(int id, const FaceShift& f, const std::function<double(std::size_t)>& want) {
  SCOPED_TRACE("surface " + std::to_string(id));
  EXPECT_GE(f.shift_mm.size(), 20u);
  std::vector<double> error(f.shift_mm.size());
  for (std::size_t i = 0; i < f.shift_mm.size(); ++i)
    error[i] = f.shift_mm[i] - want(i);
  EXPECT_NEAR(0.0, median(error), 0.003);
  for (std::size_t i = 0; i < error.size(); ++i)
    EXPECT_NEAR(0.0, error[i], 0.008) << "at " << f.position_mm[i].transpose();
}

// Tolerances: the probe noise (σ = 1 µm, two runs: σ√2 per point) plus the
// cutting model's discretisation of the surface, which a 30 µm shift of the
// tool can move by a few µm: 8 µm per point, 3 µm on a face's median.
constexpr double kMeanTolMm = 0.003;

TEST_F(ClosedLoopField, ConstantCorrectionAlongXMovesOnlyTheXFacesByItsAmount) {
  const double c = 0.03;
  const Machined with = machine(
      "constant",
      field_file("constant", [&](const Eigen::Vector3d&) { return Eigen::Vector3d(c, 0, 0); }), 12);
  EXPECT_EQ(1, with.result.field_generation);
  const auto faces = face_shifts(*baseline_, with);
  print_faces("constant +X", faces);
  ASSERT_EQ(5u, faces.size());
  const std::map<int, double> expected = {
      {kXPos, +c}, {kXNeg, -c}, {kYPos, 0.0}, {kYNeg, 0.0}, {kTop, 0.0}};
  for (const auto& [id, f] : faces) {
    const double shift = expected.at(id);
    expect_face_shift(id, f, [&](std::size_t) { return shift; });
  }
}

// c = (0.03 + 0.04·y, 0, 0): on the X faces the shift follows y (the tool
// centre passes there at the same y as the face point); on the Y faces and
// the top the correction is tangential and moves nothing.
TEST_F(ClosedLoopField, GradientCorrectionFollowsThePositionAlongTheFace) {
  auto fn = [](const Eigen::Vector3d& p) { return Eigen::Vector3d(0.03 + 0.04 * p.y(), 0, 0); };
  const Machined with = machine("gradient", field_file("gradient", fn), 13);
  const auto faces = face_shifts(*baseline_, with);
  print_faces("gradient", faces);
  ASSERT_EQ(5u, faces.size());
  // (The face by name, not by structured binding: clang 14, which builds the
  // sanitizer tree, cannot capture a structured binding in a lambda.)
  for (const auto& entry : faces) {
    const int id = entry.first;
    const auto& f = entry.second;
    expect_face_shift(id, f, [&](std::size_t i) {
      const double cx = fn(f.position_mm[i]).x();
      return id == kXPos ? cx : id == kXNeg ? -cx : 0.0;
    });
  }
  // The gradient is visible, not averaged away: across the +X face the
  // shift spans 0.04 mm/mm × 1.3 mm.
  const auto& xpos = faces.at(kXPos);
  double lo = 1e9, hi = -1e9;
  for (double v : xpos.shift_mm)
    lo = std::min(lo, v), hi = std::max(hi, v);
  EXPECT_GT(hi - lo, 0.04);
}

namespace {

// The time at which the baseline run's tool 1 (peripheral milling) is on
// the +X face of the shaft, heading −Y at y ≈ +0.25, on the level z = 9
// (the swap then lands 10 to 20 ms later, near the middle of the face).
double time_on_x_face(const fs::path& trace_csv) {
  std::ifstream in(trace_csv);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> names;
  for (std::size_t a = 0, b; a <= line.size(); a = b + 1) {
    b = line.find(',', a);
    if (b == std::string::npos) b = line.size();
    names.push_back(line.substr(a, b - a));
  }
  auto column = [&](const std::string& n) {
    for (std::size_t i = 0; i < names.size(); ++i)
      if (names[i] == n) return i;
    ADD_FAILURE() << "no column " << n << " in " << trace_csv;
    return std::size_t{0};
  };
  const std::size_t ct = column("t"), ctool = column("tool"), cx = column("tcp_true_x"),
                    cy = column("tcp_true_y"), cz = column("tcp_true_z");
  while (std::getline(in, line)) {
    std::vector<double> v;
    for (std::size_t a = 0, b; a <= line.size(); a = b + 1) {
      b = line.find(',', a);
      if (b == std::string::npos) b = line.size();
      v.push_back(std::strtod(line.substr(a, b - a).c_str(), nullptr));
    }
    if (v.size() < names.size()) continue;
    if (v[ctool] == 1 && std::abs(v[cz] - 9.0) < 0.01 && std::abs(v[cx] - 1.8) < 0.01 &&
        v[cy] < 0.3 && v[cy] > 0.2)
      return v[ct];
  }
  ADD_FAILURE() << "the tool never passes the +X face at z = 9 in " << trace_csv;
  return 0.0;
}

// Largest deviation difference between horizontal neighbours (0.05 mm apart
// in y, |y| <= 0.2) on the +X face, in
// the middle of each 2 mm peripheral level, and the per-level mean deviation change.
struct FaceProfile {
  double max_neighbour_step_mm = 0;
  std::vector<double> level_mean_shift_mm;  // z = 2, 4, ..., 16
};

FaceProfile x_face_profile(const fs::path& baseline_stl, const fs::path& machined_stl) {
  std::vector<sim::measure::CmmPoint> pts;
  for (int level = 1; level <= 8; ++level)
    for (int i = -4; i <= 4; ++i)
      pts.push_back({Eigen::Vector3d(0.8, 0.05 * i, 2.0 * level), Eigen::Vector3d::UnitX(), kXPos});
  sim::measure::CmmOptions o;
  o.sigma_mm = 0.0005;
  o.seed = 21;
  const auto base = sim::measure::probe(offline::read_stl(baseline_stl), pts, o);
  o.seed = 22;
  const auto with = sim::measure::probe(offline::read_stl(machined_stl), pts, o);
  FaceProfile p;
  for (int level = 0; level < 8; ++level) {
    double sum = 0;
    for (int i = 0; i < 9; ++i) {
      const std::size_t k = std::size_t(level * 9 + i);
      EXPECT_TRUE(base[k].valid && with[k].valid) << pts[k].position_mm.transpose();
      const double shift = with[k].deviation_mm - base[k].deviation_mm;
      sum += shift;
      if (i > 0) {
        const double prev = with[k - 1].deviation_mm - base[k - 1].deviation_mm;
        p.max_neighbour_step_mm = std::max(p.max_neighbour_step_mm, std::abs(shift - prev));
      }
    }
    p.level_mean_shift_mm.push_back(sum / 9.0);
  }
  return p;
}

}  // namespace

// Field A (+0.01 mm along X) is replaced by field B (+0.07 mm: the tool
// farther from the +X face; both leave the face oversize) while the tool mills the +X face at z = 9
// (the swap protocol of docs/compensation.md: file replaced, reload pulsed). The flank of later,
// deeper passes stays clear of what A cut, so the face keeps the history: levels above show A,
// levels below show B. With a 1 s cross-fade the surface along the pass shows no step; the same
// swap with no fade (only the 5 mm/s rate limit) leaves a step in the same place — the check can
// see one.
TEST_F(ClosedLoopField, FieldSwappedMidProgramLeavesNoStepAlongThePass) {
  const fs::path a =
      field_file("swap_a", [](const Eigen::Vector3d&) { return Eigen::Vector3d(0.01, 0, 0); });
  const fs::path b =
      field_file("swap_b", [](const Eigen::Vector3d&) { return Eigen::Vector3d(0.07, 0, 0); });
  const double t_swap = time_on_x_face(*dir_ / "baseline" / "trace.csv");
  ASSERT_GT(t_swap, 0.0);
  const Machined faded = machine("swap_faded", a, 14, {{t_swap, b}}, 1.0);
  const Machined abrupt = machine("swap_abrupt", a, 15, {{t_swap, b}}, 0.0);
  EXPECT_EQ(2, faded.result.field_generation);
  EXPECT_EQ(0, faded.result.field_load_errors);
  EXPECT_EQ(2, abrupt.result.field_generation);

  const fs::path base_stl = *dir_ / "baseline" / "machined.stl";
  const FaceProfile pf = x_face_profile(base_stl, *dir_ / "swap_faded" / "machined.stl");
  const FaceProfile pa = x_face_profile(base_stl, *dir_ / "swap_abrupt" / "machined.stl");
  std::printf("  swap at t = %.3f s; largest step along the pass: faded %.4f mm, abrupt %.4f mm\n",
              t_swap, pf.max_neighbour_step_mm, pa.max_neighbour_step_mm);
  for (std::size_t l = 0; l < pf.level_mean_shift_mm.size(); ++l)
    std::printf("  z = %2zu: mean shift faded %+.4f mm, abrupt %+.4f mm\n", 2 * (l + 1),
                pf.level_mean_shift_mm[l], pa.level_mean_shift_mm[l]);
  // Both fields acted: A above the swap level, B below it.
  EXPECT_NEAR(0.01, pf.level_mean_shift_mm.back(), kMeanTolMm);   // z = 16
  EXPECT_NEAR(0.07, pf.level_mean_shift_mm.front(), kMeanTolMm);  // z = 2
  // The abrupt swap lands in the z = 10 band, between the two.
  EXPECT_GT(pa.level_mean_shift_mm[4], 0.01 + 0.005);
  EXPECT_LT(pa.level_mean_shift_mm[4], 0.07 - 0.005);
  // A 60 µm swap over a 1 s fade at 500 mm/min changes the surface by at
  // most 0.06 × 15/8 / 8.3 ≈ 0.014 mm per mm of path, 0.7 µm per 0.05 mm;
  // 6 µm leaves room for the probe noise (σ = 0.5 µm on four probings)
  // and the dexel discretisation. The abrupt swap moves 60 µm within about
  // 0.1 mm of path (the rate limit), which the 0.057 mm dexel grid spreads
  // over two or three neighbours: more than 12 µm each.
  EXPECT_LT(pf.max_neighbour_step_mm, 0.006);
  EXPECT_GT(pa.max_neighbour_step_mm, 0.012);
}
