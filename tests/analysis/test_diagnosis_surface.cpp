// Surface-mode diagnosis on parts machined by the simulator: the coarse
// implant machined on a "true" machine (the believed ideal machine plus one
// planted effect), probed by the virtual CMM (σ = 1 µm), diagnosed against
// the believed model. The parts and the re-machinings (the same
// description gives the same run) are shared by all cases, also across
// processes (surface_diagnosis_fixture.hpp). Every case checks the effect named, its
// interval covering the truth and the held-out region's residual.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <system_error>

#include "surface_diagnosis_fixture.hpp"
#include "test_paths.hpp"
#include "truecut/analysis/diagnosis/surface.hpp"
#include "truecut/offline/mesh_io.hpp"
#include "truecut/offline/stl_io.hpp"
#include "truecut/sim/benchmark_parts.hpp"
#include "truecut/sim/measure/scanner.hpp"
#include "truecut/sim/soft_cnc.hpp"

namespace truecut::analysis::test {
using namespace truecut::sim;
namespace {

namespace fs = std::filesystem;
namespace dg = diagnosis;
using truecut::test::component_dir;
using truecut::test::scratch_dir;

// Implant surface ids (docs/parts.md).
constexpr int kXPos = 1, kXNeg = 2, kYPos = 3, kYNeg = 4, kTop = 5;

// GCC defines __SANITIZE_ADDRESS__; clang (which builds the sanitizer tree
// when installed, tools/configure.sh) answers __has_feature instead.
#if defined(__SANITIZE_ADDRESS__)
constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif
#else
constexpr bool kSanitized = false;
#endif

class SurfaceDiagnosis : public ::testing::Test {
 protected:
  // Each case re-machines the implant a dozen times through the soft CNC;
  // under AddressSanitizer that is over ten minutes per case on two cores
  // (ctest runs each case in its own process, so nothing is shared). The
  // sanitizer build runs the cheapest case (the short-flute shaft); the
  // others run in the normal build.
  void SetUp() override {
    if (kSanitized && !std::string(::testing::UnitTest::GetInstance()->current_test_info()->name())
                           .starts_with("WorkpieceDeflection"))
      GTEST_SKIP() << "too slow under AddressSanitizer; runs in the normal build";
  }
  static void SetUpTestSuite() {
    // The process's own folder (the truth's machinings, the diagnosis's
    // work folder), removed at the end; the parts and the re-machinings
    // already done by other cases come from the shared fixture.
    dir_ = new fs::path(scratch_dir() / "surface_diagnosis");
    part_ = new BenchmarkPart(make_part(PartId::kImplant, surface_fixture::part_options()));
    parts_ = new fs::path(surface_fixture::parts(*part_));
    const std::vector<int32_t> faces = {kXPos, kXNeg, kYPos, kYNeg, kTop};
    points_ = new std::vector<measure::CmmPoint>(
        measure::cmm_points_on_surfaces(part_->mesh, part_->triangle_surface, 0.25, faces));
    // Away from the corners and ends, shaped by the tool's ends and corners.
    std::erase_if(*points_, [](const measure::CmmPoint& p) {
      const Eigen::Vector3d& x = p.position_mm;
      const bool near_corner =
          std::abs(std::abs(x.x()) - 0.8) < 0.15 && std::abs(std::abs(x.y()) - 0.8) < 0.15;
      const bool near_top_edge = p.surface != kTop && x.z() > 16.7;
      const bool near_base = x.z() < 0.3;
      const bool top_rim = p.surface == kTop && (std::abs(x.x()) > 0.65 || std::abs(x.y()) > 0.65);
      return near_corner || near_top_edge || near_base || top_rim;
    });
  }
  static void TearDownTestSuite() {
    std::error_code ignored;
    fs::remove_all(*dir_, ignored);
    delete points_;
    delete parts_;
    delete part_;
    delete dir_;
  }

  static MachineDescription believed(const std::string& part = "part") {
    return read_machine_description(*parts_ / part / "machine_ideal.json");
  }

  // Machines the part on `truth` and probes it (σ = 1 µm).
  static dg::SurfaceMeasurement measure(const MachineDescription& truth, const std::string& name,
                                        std::uint64_t seed, const std::string& part = "part") {
    const fs::path out = *dir_ / name;
    fs::create_directories(out);
    write_machine_description(out / "machine.json", truth);
    SoftCncJob job = part_folder_job(*parts_ / part, out);
    job.machine = out / "machine.json";  // the truth written above
    job.component_path = {component_dir()};
    job.record_every = 100;
    if (std::getenv("TRUECUT_DIAGNOSIS_VERBOSE"))
      std::printf("machining the part (%s)\n", name.c_str());
    const auto r = run_soft_cnc(job);
    EXPECT_TRUE(r.finished);
    measure::CmmOptions o;
    o.sigma_mm = 0.001;
    o.seed = seed;
    dg::SurfaceMeasurement m;
    m.source = name;
    m.kind = "cmm";
    m.points = measure::probe(offline::read_stl(out / "machined.stl"), *points_, o);
    return m;
  }

  // Against the part's ideal machine, or `model` when given.
  static dg::SurfaceDiagnosisResult diagnose(const dg::SurfaceMeasurement& m,
                                             std::vector<std::string> candidates = {},
                                             const std::string& part = "part",
                                             const MachineDescription* model = nullptr) {
    dg::SurfaceJob job;
    job.program = *parts_ / part / "program.ngc";
    job.nominal = *parts_ / part / "nominal.stl";
    job.part = *parts_ / part / "part.json";
    job.tools = *parts_ / part / "tools.tbl";
    job.component_path = {component_dir()};
    job.work_dir = *dir_ / "work";
    surface_fixture::seed(job.work_dir);
    dg::SurfaceOptions o;
    o.candidates = std::move(candidates);
    if (std::getenv("TRUECUT_DIAGNOSIS_VERBOSE"))
      o.progress = [start = std::chrono::steady_clock::now()](const std::string& line) {
        const std::chrono::duration<double> t = std::chrono::steady_clock::now() - start;
        std::printf("%7.1f s  %s\n", t.count(), line.c_str());
      };
    auto r = dg::diagnose_surface(m, job, model ? *model : believed(part), o);
    surface_fixture::share(job.work_dir);
    if (std::getenv("TRUECUT_DIAGNOSIS_VERBOSE"))
      std::printf("%s\n", dg::surface_diagnosis_summary(r).c_str());
    return r;
  }

  static fs::path* dir_;
  static fs::path* parts_;  // part, part5, part_short_flute (surface_diagnosis_fixture.hpp)
  static BenchmarkPart* part_;
  static std::vector<measure::CmmPoint>* points_;
};

fs::path* SurfaceDiagnosis::dir_ = nullptr;
fs::path* SurfaceDiagnosis::parts_ = nullptr;
BenchmarkPart* SurfaceDiagnosis::part_ = nullptr;
std::vector<measure::CmmPoint>* SurfaceDiagnosis::points_ = nullptr;

const dg::Explanation* find(const dg::SurfaceDiagnosisResult& r, const std::string& effect) {
  for (const auto& e : r.explanations)
    if (e.effect == effect) return &e;
  return nullptr;
}

// Planted near the probe noise (1.5 µm against σ = 1 µm) under an effect
// the believed model already has (the tool bends, 0.054 N/µm).
TEST_F(SurfaceDiagnosis, SmallToolRadiusErrorUnderAKnownToolDeflection) {
  MachineDescription known = believed();
  known.machine.effects.tool_deflection.enabled = true;
  known.machine.effects.tool_deflection.params.stiffness_n_per_um = 0.054;
  MachineDescription truth = known;
  truth.machine.effects.tool_radius_error.enabled = true;
  truth.machine.effects.tool_radius_error.params.radius_mm = -0.0015;
  const auto r = diagnose(measure(truth, "radius", 11), {}, "part", &known);
  const auto s = dg::surface_diagnosis_summary(r);
  ASSERT_EQ(r.explanations.size(), 1u) << s;
  const auto* e = find(r, "tool_radius_error");
  ASSERT_NE(e, nullptr) << s;
  EXPECT_LE(e->parameters[0].ci95_lo, -0.0015) << s;
  EXPECT_GE(e->parameters[0].ci95_hi, -0.0015) << s;
  ASSERT_TRUE(r.has_heldout);
  EXPECT_LT(r.heldout.rms_after_mm, r.heldout.rms_before_mm) << s;
  EXPECT_LT(r.heldout.rms_after_mm, 1.5 * 0.001) << s;
  EXPECT_LT(r.heldout.rms_after_mm, 1.5 * r.noise_floor_mm) << s;
}

// The deflection changes the engagement and so the force: the fit must
// follow it (Gauss–Newton re-machinings at the estimate); one linearisation
// around the believed model put 0.054 at 0.0496 [0.0482, 0.0511].
TEST_F(SurfaceDiagnosis, ToolDeflectionFoundAsACompliance) {
  MachineDescription truth = believed();
  truth.machine.effects.tool_deflection.enabled = true;
  truth.machine.effects.tool_deflection.params.stiffness_n_per_um = 0.054;
  const auto r = diagnose(measure(truth, "deflection", 12));
  const auto s = dg::surface_diagnosis_summary(r);
  const auto* e = find(r, "tool_deflection");
  ASSERT_NE(e, nullptr) << s;
  EXPECT_LE(e->parameters[0].ci95_lo, 0.054) << s;
  EXPECT_GE(e->parameters[0].ci95_hi, 0.054) << s;
  EXPECT_LT(r.train.rms_after_mm, r.train.rms_before_mm) << s;
  if (r.has_heldout) {
    EXPECT_LT(r.heldout.rms_after_mm, r.heldout.rms_before_mm) << s;
  }
}

// Issue 23 (sweep F2): a point cloud of the 1.6 mm shaft was read at the
// nominal points by averaging every cloud point near the normal line, so
// the neighbouring faces' points came in at every edge (the shaft's faces
// read about -120 µm, the top -253 µm) and the base's bottom, which the
// scanner never sees, got the walls' points (-413 µm): the verdict was an
// unexplained mismatch where the mesh and the CMM find the planted tool
// radius error. Now a cloud point counts for a nominal point only on the
// same surface and facing the same way: the reading agrees with the CMM of
// the same machined part, the unseen bottom is reported as not measured,
// and the diagnosis finds the planted -0.02 mm.
TEST_F(SurfaceDiagnosis, APointCloudScanIsReadOnEachFaceAndFindsThePlantedRadiusError) {
  MachineDescription truth = believed();
  truth.machine.effects.tool_radius_error.enabled = true;
  truth.machine.effects.tool_radius_error.params.radius_mm = -0.02;
  measure(truth, "cloud_radius", 14);
  const fs::path dir = *dir_ / "cloud_radius";
  const offline::TriangleMesh machined = offline::read_stl(dir / "machined.stl");
  measure::ScannerOptions so;
  so.sigma0_mm = 0.005;
  so.seed = 3;
  offline::write_point_cloud(dir / "scan.ply", measure::scan(machined, so).cloud);
  const dg::SurfaceMeasurement m =
      dg::read_scan_measurement(dir / "scan.ply", part_->mesh, part_->triangle_surface, 0.5);

  // The machined surface at the same nominal points, probed exactly where
  // the registration put the scan (ICP onto the nominal moves this part's
  // cloud by about 7 µm in z: the diagnosis profiles that out), away from
  // the edges and corners the tool's ends and corners shape (as the cases'
  // CMM points are: there a disc of cloud points and a point probe see
  // different things).
  std::vector<measure::CmmPoint> nominal;
  for (const auto& p : m.points)
    nominal.push_back(p.nominal);
  measure::CmmOptions exact;
  exact.sigma_mm = 0.0;
  ASSERT_TRUE(m.scan_to_nominal);
  offline::TriangleMesh registered = machined;
  for (auto& v : registered.vertices_mm)
    v = *m.scan_to_nominal * v;
  const auto truth_at = measure::probe(registered, nominal, exact);
  std::map<int, std::pair<double, int>> diff, valid;  // per surface: sum, count
  for (std::size_t i = 0; i < m.points.size(); ++i) {
    const int surface = m.points[i].nominal.surface;
    valid[surface].second += 1;
    if (!m.points[i].valid) continue;
    valid[surface].first += 1;
    const Eigen::Vector3d& x = m.points[i].nominal.position_mm;
    const bool edge =
        (std::abs(std::abs(x.x()) - 0.8) < 0.15 && std::abs(std::abs(x.y()) - 0.8) < 0.15) ||
        (surface != kTop && (x.z() > 16.7 || x.z() < 0.3)) ||
        (surface == kTop && (std::abs(x.x()) > 0.65 || std::abs(x.y()) > 0.65));
    if (!truth_at[i].valid || (surface <= kTop && edge)) continue;
    diff[surface].first += m.points[i].deviation_mm - truth_at[i].deviation_mm;
    diff[surface].second += 1;
  }
  for (int face : {kXPos, kXNeg, kYPos, kYNeg, kTop}) {
    ASSERT_GE(diff[face].second, face == kTop ? 1 : 10) << "surface " << face;
    EXPECT_LT(std::abs(diff[face].first / diff[face].second), 0.003) << "surface " << face;
  }
  constexpr int kBaseBottom = 8;
  ASSERT_GT(valid[kBaseBottom].second, 0);
  EXPECT_EQ(valid[kBaseBottom].first, 0.0) << "the scanner has no pose from below";

  const auto r = diagnose(m, {"tool_radius_error", "tool_length_error"});
  const auto s = dg::surface_diagnosis_summary(r);
  EXPECT_NE(s.find("not measured (no valid point): surface 8 (base_bottom)"), std::string::npos)
      << s;
  const auto* e = find(r, "tool_radius_error");
  ASSERT_NE(e, nullptr) << s;
  EXPECT_NEAR(e->parameters[0].value, -0.02, 0.15 * 0.02) << s;
}

TEST_F(SurfaceDiagnosis, CorrectBelievedModelSelectsNothing) {
  const auto r = diagnose(measure(believed(), "control", 13));
  const auto s = dg::surface_diagnosis_summary(r);
  EXPECT_TRUE(r.explanations.empty()) << s;
  EXPECT_EQ(r.fitted, r.believed);
  EXPECT_LT(r.noise_floor_mm, 0.002) << s;
}

TEST_F(SurfaceDiagnosis, WorkpieceDeflectionOfTheShaftIsNotTakenForToolDeflection) {
  // The believed model knows where the shaft is clamped (the effect's
  // geometry, switched off) but not how stiff it is. The short-flute part:
  // each level keeps the deflection of its own cut, growing with the
  // height above the clamp cubed (up to ~35 µm at the top level).
  const std::string part = "part_short_flute";
  MachineDescription known = believed(part);
  auto& wd = known.machine.effects.workpiece_deflection;
  wd.enabled = false;
  wd.params.stiffness_n_per_um = 1.0;
  wd.params.reference_length_mm = 17.0;
  wd.params.clamp_point_mm = {0.0, 0.0, 0.0};
  wd.params.axis = {0.0, 0.0, 1.0};
  MachineDescription truth = known;
  truth.machine.effects.workpiece_deflection.enabled = true;
  truth.machine.effects.workpiece_deflection.params.stiffness_n_per_um = 0.038;
  const auto r =
      diagnose(measure(truth, "workpiece", 15, part),
               {"tool_deflection", "workpiece_deflection", "tool_radius_error"}, part, &known);
  const auto s = dg::surface_diagnosis_summary(r);
  // Something to find: well above the probe noise (σ = 1 µm).
  EXPECT_GT(r.train.rms_before_mm, 0.004) << s;
  const auto* e = find(r, "workpiece_deflection");
  ASSERT_NE(e, nullptr) << s;
  EXPECT_LE(e->parameters[0].ci95_lo, 0.038) << s;
  EXPECT_GE(e->parameters[0].ci95_hi, 0.038) << s;
  EXPECT_EQ(find(r, "tool_deflection"), nullptr) << s;
  ASSERT_TRUE(r.has_heldout);
  EXPECT_LT(r.heldout.rms_after_mm, 0.5 * r.heldout.rms_before_mm) << s;
  EXPECT_LT(r.heldout.rms_after_mm, 3 * r.noise_floor_mm) << s;
}

TEST_F(SurfaceDiagnosis, ToolLengthErrorIsNotTakenForTheAAxisLocation) {
  // On the 5-axis variant a longer tool cuts the +Y face (A = 90°) deeper
  // and the top (A = 0°) lower; the A-axis line's offsets move what is cut
  // at A = 90° differently from what is cut at A = 0°.
  MachineDescription truth = believed("part5");
  truth.machine.effects.tool_length_error.enabled = true;
  truth.machine.effects.tool_length_error.params.length_mm = 0.02;
  const auto r = diagnose(measure(truth, "length5", 14, "part5"),
                          {"tool_length_error", "rotary_location"}, "part5");
  const auto s = dg::surface_diagnosis_summary(r);
  const auto* e = find(r, "tool_length_error");
  ASSERT_NE(e, nullptr) << s;
  EXPECT_LE(e->parameters[0].ci95_lo, 0.02) << s;
  EXPECT_GE(e->parameters[0].ci95_hi, 0.02) << s;
  EXPECT_EQ(find(r, "rotary_location"), nullptr) << s;
  EXPECT_LT(r.train.rms_after_mm, 0.5 * r.train.rms_before_mm) << s;
}

}  // namespace
}  // namespace truecut::analysis::test
