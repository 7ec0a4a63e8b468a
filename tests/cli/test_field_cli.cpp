// `truecut field` as a user runs it: outputs, audit hashes, the
// max-correction refusal, and malformed inputs.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include "run_process.hpp"
#include "test_paths.hpp"

using namespace truecut::test;
namespace fs = std::filesystem;

namespace {

ProcessResult truecut(std::vector<std::string> args) {
  args.insert(args.begin(), cli_path().string());
  return run_process(args);
}

void write_text(const fs::path& f, const std::string& text) {
  std::ofstream(f, std::ios::binary) << text;
}

std::set<std::string> listing(const fs::path& dir) {
  std::set<std::string> names;
  if (!fs::exists(dir)) return names;
  for (const auto& e : fs::directory_iterator(dir))
    names.insert(e.path().filename().string());
  return names;
}

// The implant benchmark part (coarse) and a scan of it: the nominal binary
// STL with the shaft (z > 0) made oversize_mm thicker on every side.
struct Part {
  fs::path dir, nominal, program, tools, part, scan;
};

Part make_part_and_scan(const fs::path& root, double oversize_mm) {
  Part p;
  p.dir = root / "part";
  const ProcessResult r = truecut({"part", "implant", "--out", p.dir.string(), "--mesh-edge", "0.5",
                                   "--stepover", "0.8", "--step-down", "2"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  p.nominal = p.dir / "nominal.stl";
  p.program = p.dir / "program.ngc";
  p.tools = p.dir / "tools.tbl";
  p.part = p.dir / "part.json";
  p.scan = root / "scan.stl";
  std::string stl = read_file(p.nominal);
  std::uint32_t n = 0;
  std::memcpy(&n, stl.data() + 80, 4);
  EXPECT_EQ(stl.size(), 84u + 50u * n);
  const float k = static_cast<float>((0.8 + oversize_mm) / 0.8);
  for (std::uint32_t f = 0; f < n; ++f) {
    for (int c = 0; c < 3; ++c) {
      float xyz[3];
      char* at = stl.data() + 84 + 50 * f + 12 + 12 * c;
      std::memcpy(xyz, at, 12);
      if (xyz[2] > 1e-4f) {
        xyz[0] *= k;
        xyz[1] *= k;
      }
      std::memcpy(at, xyz, 12);
    }
  }
  write_text(p.scan, stl);
  return p;
}

std::vector<std::string> field_args(const Part& p, const fs::path& out) {
  return {"field",     p.nominal.string(), p.scan.string(), "--program",     p.program.string(),
          "--tools",   p.tools.string(),   "--part",        p.part.string(), "--out",
          out.string()};
}

std::string sha256sum(const fs::path& f) {
  const ProcessResult r = run_process({"/usr/bin/sha256sum", f.string()});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return r.out.substr(0, 64);
}

TEST(FieldCli, WritesOutputsWithAuditHashes) {
  const fs::path root = scratch_dir();
  const Part p = make_part_and_scan(root, 0.05);
  const fs::path out = root / "out";
  std::vector<std::string> args = field_args(p, out);
  args.push_back("--verbose");
  const ProcessResult r = truecut(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("field: registration"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("field: field fit"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("[peak "), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("layer T1"), std::string::npos) << r.out;
  EXPECT_EQ(listing(out), (std::set<std::string>{"adapted.stl", "audit.json",
                                                 "compensation_matrix.csv", "field.tcf"}));
  const nlohmann::json audit = nlohmann::json::parse(read_file(out / "audit.json"));
  EXPECT_EQ(audit["truecut_audit"], 1);
  ASSERT_EQ(audit["outputs"].size(), 3u);
  for (const auto& o : audit["outputs"])
    EXPECT_EQ(o["sha256"].get<std::string>(), sha256sum(o["path"].get<std::string>())) << o;
  std::set<std::string> roles;
  for (const auto& i : audit["inputs"]) {
    roles.insert(i["role"].get<std::string>());
    EXPECT_EQ(i["sha256"].get<std::string>(), sha256sum(i["path"].get<std::string>())) << i;
  }
  EXPECT_EQ(roles, (std::set<std::string>{"nominal", "scan", "program", "tools", "part"}));
  EXPECT_FALSE(audit["max_correction"]["exceeded"].get<bool>());
  EXPECT_FALSE(audit["max_correction"]["forced"].get<bool>());
  EXPECT_LT(audit["registration"]["rms_residual_mm"].get<double>(), 0.05);
  EXPECT_EQ(audit["parameters"]["method"], "ray");
  // The shaft is 0.05 mm oversize: the valid error vectors say so, and the
  // compensation points back by the same amount.
  EXPECT_NEAR(audit["error_vectors"]["mean_normal_mm"].get<double>(), 0.05, 0.005);
  EXPECT_NEAR(audit["compensation_vectors"]["mean_normal_mm"].get<double>(), -0.05, 0.005);
  // A noiseless scan: every shaft face's 0.05 mm is far beyond its noise.
  EXPECT_TRUE(audit["significance"]["tested"].get<bool>());
  ASSERT_FALSE(audit["significance"]["surfaces"].empty());
  for (const auto& s : audit["significance"]["surfaces"])
    if (s["surface"].get<int>() <= 4) {
      EXPECT_TRUE(s["compensated"].get<bool>()) << s;
    }
  EXPECT_NE(r.out.find("surface 1: "), std::string::npos) << r.out;
  // Binary STL of the nominal's size.
  EXPECT_EQ(fs::file_size(out / "adapted.stl"), fs::file_size(p.nominal));
  EXPECT_EQ(read_file(out / "field.tcf").rfind("TRUECUT-FIELD 1\n", 0), 0u);
}

// The controller's parameter file places the program as the machine does:
// with G54 at X+100 no tool of the program touches the part (refused,
// nothing written); with G54 at 0 the field is built and the file is an
// input of the audit.
TEST(FieldCli, ParameterFilePlacesTheToolPath) {
  const fs::path root = scratch_dir();
  const Part p = make_part_and_scan(root, 0.05);
  write_text(root / "away.var", "5220 1\n5221 100\n");
  std::vector<std::string> away = field_args(p, root / "away");
  away.insert(away.end(), {"--var-file", (root / "away.var").string()});
  const ProcessResult r = truecut(away);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("no valid compensation point is cut by any tool of the program"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(root / "away"));
  write_text(root / "zero.var", "5220 1\n5221 0\n");
  std::vector<std::string> zero = field_args(p, root / "zero");
  zero.insert(zero.end(), {"--var-file", (root / "zero.var").string()});
  const ProcessResult z = truecut(zero);
  ASSERT_EQ(z.exit_code, 0) << z.err;
  const nlohmann::json audit = nlohmann::json::parse(read_file(root / "zero" / "audit.json"));
  bool listed = false;
  for (const auto& i : audit["inputs"])
    if (i["role"] == "parameters") {
      listed = true;
      EXPECT_EQ(i["sha256"].get<std::string>(), sha256sum(root / "zero.var")) << i;
    }
  EXPECT_TRUE(listed) << audit["inputs"];
}

// Issue 20: the stage lines come with --verbose; by default one line of
// totals (stderr is not a terminal here, so no progress line), and the
// stages' times and memory are in audit.json either way.
TEST(FieldCli, StageLinesOnlyWithVerboseTotalsAlwaysStagesInAudit) {
  const fs::path root = scratch_dir();
  const Part p = make_part_and_scan(root, 0.05);
  const ProcessResult r = truecut(field_args(p, root / "out"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("field: registration"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find('\r'), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(" stages in "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("peak memory "), std::string::npos) << r.err;
  const nlohmann::json audit = nlohmann::json::parse(read_file(root / "out" / "audit.json"));
  ASSERT_FALSE(audit["stages"].empty());
  for (const auto& s : audit["stages"]) {
    EXPECT_GE(s["wall_s"].get<double>(), 0.0) << s;
    EXPECT_GT(s["peak_rss_mb"].get<double>(), 0.0) << s;
  }

  std::vector<std::string> quiet = field_args(p, root / "quiet");
  quiet.push_back("--quiet");
  const ProcessResult q = truecut(quiet);
  ASSERT_EQ(q.exit_code, 0) << q.err;
  EXPECT_EQ(q.err, "");

  std::vector<std::string> both = field_args(p, root / "both");
  both.push_back("--quiet");
  both.push_back("--verbose");
  const ProcessResult b = truecut(both);
  EXPECT_EQ(b.exit_code, 2) << b.err;
  EXPECT_NE(b.err.find("--verbose and --quiet"), std::string::npos) << b.err;
  EXPECT_FALSE(fs::exists(root / "both"));
}

TEST(FieldCli, RefusesAboveMaxCorrectionUnlessForced) {
  const fs::path root = scratch_dir();
  const Part p = make_part_and_scan(root, 0.05);
  const fs::path out = root / "out";
  fs::create_directories(out);
  write_text(out / "keep.txt", "mine");
  std::vector<std::string> args = field_args(p, out);
  args.insert(args.end(), {"--max-correction", "0.02"});
  ProcessResult r = truecut(args);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("above --max-correction"), std::string::npos) << r.err;
  EXPECT_EQ(listing(out), std::set<std::string>{"keep.txt"});
  args.push_back("--force");
  r = truecut(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(listing(out).size(), 5u);
  const nlohmann::json audit = nlohmann::json::parse(read_file(out / "audit.json"));
  EXPECT_TRUE(audit["max_correction"]["exceeded"].get<bool>());
  EXPECT_TRUE(audit["max_correction"]["forced"].get<bool>());
  EXPECT_GT(audit["max_correction"]["max_mm"].get<double>(), 0.02);
}

// Issue 24: --paper sets every stage's default to the source's recipe, an
// option given explicitly still wins, and the audit records what was used.
TEST(FieldCli, PaperSetsTheSourcesRecipeAndExplicitOptionsWin) {
  const fs::path root = scratch_dir();
  const Part p = make_part_and_scan(root, 0.05);
  const auto parameters = [&](const std::string& name, std::vector<std::string> extra) {
    std::vector<std::string> args = field_args(p, root / name);
    args.insert(args.end(), extra.begin(), extra.end());
    const ProcessResult r = truecut(args);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return nlohmann::json::parse(read_file(root / name / "audit.json"))["parameters"];
  };
  const nlohmann::json sortino = parameters("sortino", {"--paper", "sortino"});
  EXPECT_EQ(sortino["method"], "sphere");
  EXPECT_EQ(sortino["sphere"]["radius_mm"], 1.0);
  EXPECT_EQ(sortino["sphere"]["plane_fit"], "parallel");
  EXPECT_EQ(sortino["sphere"]["max_points_per_sphere"], 0);
  EXPECT_EQ(sortino["sphere"]["max_facets_per_sphere"], 0);
  EXPECT_EQ(sortino["truss"]["stiffness"], "axial_bars");
  EXPECT_EQ(sortino["truss"]["kb_over_kc_used"], 0.2);
  EXPECT_TRUE(sortino["remove_rigid_body_motion"].get<bool>());
  EXPECT_EQ(sortino["significance"]["level"], 0.0);
  EXPECT_EQ(sortino["icp"]["significance_level"], 0.0);

  const nlohmann::json mixed =
      parameters("mixed", {"--paper", "sortino", "--sphere-radius", "1.5", "--truss", "springs"});
  EXPECT_EQ(mixed["sphere"]["radius_mm"], 1.5);
  EXPECT_EQ(mixed["truss"]["stiffness"], "zero_length_springs");
  EXPECT_EQ(mixed["sphere"]["plane_fit"], "parallel");

  const nlohmann::json denkena = parameters("denkena", {"--paper", "denkena"});
  EXPECT_EQ(denkena["method"], "ray");
  EXPECT_EQ(denkena["significance"]["level"], 0.0);
  EXPECT_FALSE(denkena["remove_rigid_body_motion"].get<bool>());

  const nlohmann::json ours = parameters("ours", {});
  EXPECT_EQ(ours["method"], "ray");
  EXPECT_GT(ours["significance"]["level"].get<double>(), 0.0);
  EXPECT_EQ(ours["sphere"]["radius_mm"], 1.5);

  std::vector<std::string> args = field_args(p, root / "bad");
  args.insert(args.end(), {"--paper", "smith"});
  const ProcessResult r = truecut(args);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--paper must be sortino or denkena, not 'smith'"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(root / "bad"));

  // The tool rotation's machine: recorded, and a wrong name refused.
  EXPECT_EQ(ours["tool_rotation"]["kinematics"], "ac-table");
  EXPECT_FALSE(ours["tool_rotation"]["enabled"].get<bool>());
  const nlohmann::json any = parameters("any", {"--tool-rotation", "--rotary-kinematics", "any"});
  EXPECT_EQ(any["tool_rotation"]["kinematics"], "any");
  EXPECT_TRUE(any["tool_rotation"]["enabled"].get<bool>());
  args = field_args(p, root / "bad_kinematics");
  args.insert(args.end(), {"--tool-rotation", "--rotary-kinematics", "head"});
  const ProcessResult rk = truecut(args);
  EXPECT_EQ(rk.exit_code, 2);
  EXPECT_NE(rk.err.find("--rotary-kinematics must be ac-table or any, not 'head'"),
            std::string::npos)
      << rk.err;
  EXPECT_FALSE(fs::exists(root / "bad_kinematics"));
}

// A CAD export with a zero-area facet (two corners the same) in the middle of
// the nominal, and part.json numbering the file's facets: by default the
// facet is dropped, named on stderr and in audit.json, and the result is the
// clean nominal's; --strict-mesh refuses the file and writes nothing.
TEST(FieldCli, DegenerateFacetIsDroppedAndNamedOrRefusedWhenStrict) {
  const fs::path root = scratch_dir();
  const Part p = make_part_and_scan(root, 0.05);
  const ProcessResult clean = truecut(field_args(p, root / "clean"));
  ASSERT_EQ(clean.exit_code, 0) << clean.err;
  EXPECT_EQ(clean.err.find("degenerate"), std::string::npos) << clean.err;

  std::string stl = read_file(p.nominal);
  std::uint32_t n = 0;
  std::memcpy(&n, stl.data() + 80, 4);
  const std::uint32_t k = n / 2;
  std::string sliver = stl.substr(84 + 50 * std::size_t{k}, 50);
  std::memcpy(sliver.data() + 12 + 24, sliver.data() + 12, 12);  // corner 2 := corner 0
  stl.insert(84 + 50 * std::size_t{k}, sliver);
  const std::uint32_t n1 = n + 1;
  std::memcpy(stl.data() + 80, &n1, 4);
  Part q = p;
  q.nominal = root / "with_sliver.stl";
  write_text(q.nominal, stl);
  nlohmann::json part = nlohmann::json::parse(read_file(p.part));
  auto& ids = part["triangle_surface_ids"];
  ids.insert(ids.begin() + k, ids[k]);
  q.part = root / "with_sliver.json";
  write_text(q.part, part.dump());

  const ProcessResult r = truecut(field_args(q, root / "dropped"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("with_sliver.stl: dropped 1 degenerate facet of " + std::to_string(n1) +
                       ": #" + std::to_string(k) + " (area 0 mm²"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(read_file(root / "dropped" / "compensation_matrix.csv"),
            read_file(root / "clean" / "compensation_matrix.csv"));
  const nlohmann::json audit = nlohmann::json::parse(read_file(root / "dropped" / "audit.json"));
  ASSERT_EQ(audit["meshes"].size(), 2u);
  EXPECT_EQ(audit["meshes"][0]["role"], "nominal");
  EXPECT_EQ(audit["meshes"][0]["facets_in_file"], n1);
  ASSERT_EQ(audit["meshes"][0]["degenerate_facets_dropped"].size(), 1u);
  EXPECT_EQ(audit["meshes"][0]["degenerate_facets_dropped"][0]["facet"], k);
  EXPECT_TRUE(audit["meshes"][1]["degenerate_facets_dropped"].empty());

  std::vector<std::string> strict = field_args(q, root / "strict");
  strict.push_back("--strict-mesh");
  const ProcessResult s = truecut(strict);
  EXPECT_EQ(s.exit_code, 2) << s.err;
  for (const std::string& part_of_message :
       {std::string("with_sliver.stl"), "facet " + std::to_string(k) + " is degenerate",
        std::string("zero area"), std::string("without --strict-mesh")})
    EXPECT_NE(s.err.find(part_of_message), std::string::npos) << s.err;
  EXPECT_EQ(s.err.find("DegenerateFaces"), std::string::npos) << s.err;
  EXPECT_FALSE(fs::exists(root / "strict"));
}

// Facets wound against their neighbours, and the whole solid inside out (as
// CAD exports sometimes are): turned round, said on stderr and in
// audit.json, and the result is the clean nominal's; --strict-mesh refuses.
TEST(FieldCli, FacetsWoundWrongAreTurnedRoundOrRefusedWhenStrict) {
  const fs::path root = scratch_dir();
  const Part p = make_part_and_scan(root, 0.05);
  const ProcessResult clean = truecut(field_args(p, root / "clean"));
  ASSERT_EQ(clean.exit_code, 0) << clean.err;
  EXPECT_EQ(clean.err.find("turned round"), std::string::npos) << clean.err;
  const std::string stl = read_file(p.nominal);
  std::uint32_t n = 0;
  std::memcpy(&n, stl.data() + 80, 4);
  auto turned = [&](const std::vector<std::uint32_t>& facets) {
    std::string out = stl;
    for (std::uint32_t f : facets) {
      char* corners = out.data() + 84 + 50 * std::size_t{f} + 24;  // corners 1 and 2
      char tmp[12];
      std::memcpy(tmp, corners, 12);
      std::memcpy(corners, corners + 12, 12);
      std::memcpy(corners + 12, tmp, 12);
    }
    return out;
  };
  std::vector<std::uint32_t> all(n);
  for (std::uint32_t f = 0; f < n; ++f)
    all[f] = f;
  const std::vector<std::pair<std::string, std::vector<std::uint32_t>>> cases{
      {"three facets", {n / 3, n / 2, n - 1}}, {"inside out", all}};
  for (const auto& [name, facets] : cases) {
    Part q = p;
    q.nominal = root / "wound.stl";
    write_text(q.nominal, turned(facets));
    const fs::path out = root / ("out_" + std::to_string(facets.size()));
    const ProcessResult r = truecut(field_args(q, out));
    ASSERT_EQ(r.exit_code, 0) << name << "\n" << r.err;
    EXPECT_NE(r.err.find("wound.stl: 1 shell (0 open"), std::string::npos) << name << r.err;
    EXPECT_NE(r.err.find(std::to_string(facets.size()) + " facets turned round"), std::string::npos)
        << name << r.err;
    EXPECT_EQ(read_file(out / "compensation_matrix.csv"),
              read_file(root / "clean" / "compensation_matrix.csv"))
        << name;
    const nlohmann::json audit = nlohmann::json::parse(read_file(out / "audit.json"));
    EXPECT_EQ(audit["meshes"][0]["topology"]["facets_turned_round"], facets.size()) << name;
    EXPECT_EQ(audit["meshes"][0]["topology"]["inverted_shells"], facets.size() == n ? 1 : 0)
        << name;
    std::vector<std::string> strict = field_args(q, root / "strict");
    strict.push_back("--strict-mesh");
    const ProcessResult s = truecut(strict);
    EXPECT_EQ(s.exit_code, 2) << name << s.err;
    EXPECT_NE(s.err.find("wound.stl: " + std::to_string(facets.size()) + " facets are wound"),
              std::string::npos)
        << name << s.err;
    EXPECT_FALSE(fs::exists(root / "strict")) << name;
  }
}

// The binary STL with every corner moved by f.
std::string moved_stl(std::string stl, const std::function<void(float*)>& f) {
  std::uint32_t n = 0;
  std::memcpy(&n, stl.data() + 80, 4);
  for (std::uint32_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      float xyz[3];
      char* at = stl.data() + 84 + 50 * std::size_t{i} + 12 + 12 * c;
      std::memcpy(xyz, at, 12);
      f(xyz);
      std::memcpy(at, xyz, 12);
    }
  return stl;
}

// Scans that are not of this part or not where they say: refused with exit 2,
// a message that says how far off and which option accepts it, and nothing
// written; the same scans pass when the option says the offset is intended.
// An endless stream given as a mesh is refused by the reader, and never
// hashed (the inputs are hashed only once read): before that order, the
// hash read /dev/zero without end.
TEST(FieldCli, AnEndlessStreamAsAMeshIsRefusedNotHashed) {
  const fs::path root = scratch_dir();
  const Part p = make_part_and_scan(root, 0.05);
  const fs::path out = root / "out";
  for (int which : {1, 2}) {
    std::vector<std::string> args = field_args(p, out);
    args[static_cast<std::size_t>(which)] = "/dev/zero";
    const ProcessResult r = truecut(args);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("/dev/zero"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
  }
}

TEST(FieldCli, WrongScansAreRefused) {
  const fs::path root = scratch_dir();
  const Part p = make_part_and_scan(root, 0.05);
  const fs::path out = root / "out";
  struct Case {
    std::string name;
    std::string stl;
    std::vector<std::string> options;
    std::vector<std::string> message;
  };
  const std::string scan = read_file(p.scan);
  auto shifted_z = [&](float dz) { return moved_stl(scan, [dz](float* v) { v[2] += dz; }); };
  const ProcessResult other =
      truecut({"part", "benchmark004", "--out", (root / "other").string(), "--mesh-edge", "1"});
  ASSERT_EQ(other.exit_code, 0) << other.err;
  std::vector<Case> cases;
  for (float dz : {1.0f, 2.0f, 5.0f}) {
    cases.push_back({"declared in frame, z + " + std::to_string(dz),
                     shifted_z(dz),
                     {"--no-register"},
                     {"--no-register", "--max-scan-offset"}});
    cases.push_back(
        {"registered, z + " + std::to_string(dz), shifted_z(dz), {}, {"--max-scan-offset"}});
  }
  cases.push_back(
      {"another part", read_file(root / "other" / "nominal.stl"), {}, {"--max-scan-offset"}});
  cases.push_back({"scaled 1.5 (points mostly off the nominal)",
                   moved_stl(scan,
                             [](float* v) {
                               for (int i = 0; i < 3; ++i)
                                 v[i] *= 1.5f;
                             }),
                   {"--no-register"},
                   {"--max-scan-outliers"}});
  for (const Case& c : cases) {
    const fs::path file = root / "wrong_scan.stl";
    write_text(file, c.stl);
    Part q = p;
    q.scan = file;
    std::vector<std::string> args = field_args(q, out);
    args.insert(args.end(), c.options.begin(), c.options.end());
    const ProcessResult r = truecut(args);
    EXPECT_EQ(r.exit_code, 2) << c.name << "\n" << r.err;
    EXPECT_NE(r.err.find("wrong_scan.stl: "), std::string::npos) << c.name << "\n" << r.err;
    for (const std::string& m : c.message)
      EXPECT_NE(r.err.find(m), std::string::npos) << c.name << ": " << m << "\n" << r.err;
    EXPECT_NE(r.err.find("nothing written"), std::string::npos) << c.name << "\n" << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.name;
  }
  // A scan 0.4 mm off along the diagonal: registration must move it more
  // than the default allows, and does so when told that is intended.
  write_text(root / "shifted.stl", moved_stl(scan, [](float* v) {
               for (int i = 0; i < 3; ++i)
                 v[i] += 0.4f / std::sqrt(3.0f);
             }));
  Part q = p;
  q.scan = root / "shifted.stl";
  std::vector<std::string> args = field_args(q, out);
  ProcessResult r = truecut(args);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("registration fits the scan to the nominal only by moving it up to 0.4"),
            std::string::npos)
      << r.err;
  args.insert(args.end(), {"--max-scan-offset", "0.5"});
  r = truecut(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json audit = nlohmann::json::parse(read_file(out / "audit.json"));
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(audit["scan_check"]["motion"]["translation_mm"][i].get<double>(),
                -0.4 / std::sqrt(3.0), 0.01);
  EXPECT_LT(audit["scan_check"]["off_percent"].get<double>(), 1.0);
  write_text(root / "nudged.stl", shifted_z(0.1f));
  q.scan = root / "nudged.stl";
  args = field_args(q, root / "nudged");
  args.push_back("--no-register");
  r = truecut(args);
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

// A --spacing or --resolution that would take without bound is refused at
// once (exit 2, the estimate and the option that raises the budget); a
// resolution within the (lowered) budget passes.
TEST(FieldCli, BudgetsRefuseRunawaySpacingAndResolution) {
  const fs::path root = scratch_dir();
  const Part p = make_part_and_scan(root, 0.05);
  const fs::path out = root / "out";
  struct Case {
    std::vector<std::string> options;
    std::vector<std::string> message;
  };
  const std::vector<Case> cases{
      {{"--spacing", "0.0001"}, {"--spacing 0.0001 mm would place about", "--max-points"}},
      {{"--resolution", "0.05", "--max-grid-nodes", "100000"},
       {"--resolution 0.05 mm gives a field grid of about", "--max-grid-nodes 100000"}},
  };
  for (const Case& c : cases) {
    std::vector<std::string> args = field_args(p, out);
    args.insert(args.end(), c.options.begin(), c.options.end());
    const ProcessResult r = truecut(args);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    for (const std::string& m : c.message)
      EXPECT_NE(r.err.find(m), std::string::npos) << m << "\n" << r.err;
    EXPECT_FALSE(fs::exists(out));
  }
  std::vector<std::string> args = field_args(p, out);
  args.insert(args.end(), {"--resolution", "0.5", "--max-grid-nodes", "100000"});
  const ProcessResult r = truecut(args);
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

TEST(FieldCli, MalformedInputsExit2AndWriteNothing) {
  const fs::path root = scratch_dir();
  const Part p = make_part_and_scan(root, 0.05);
  const fs::path out = root / "out";
  fs::create_directories(out);
  write_text(out / "keep.txt", "mine");

  const fs::path truncated = root / "truncated.stl";
  write_text(truncated, read_file(p.nominal).substr(0, 84 + 50 * 10 + 17));
  const fs::path nan_scan = root / "nan.ply";
  write_text(nan_scan,
             "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
             "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
             "end_header\n0 0 0\nnan 0 0\n1 1 1\n3 0 1 2\n");
  const fs::path bad_program = root / "bad.ngc";
  write_text(bad_program, "G21 G90\nT1 M6\nG1 X1 Y2 F100\nG1 X[1+]\nM30\n");
  const fs::path bad_tools = root / "bad.tbl";
  write_text(bad_tools, "T1 P1 D2.000 Zabc\n");
  const fs::path bad_json = root / "bad.json";
  write_text(bad_json, "{ \"triangle_surface_ids\": [1, 2,");
  const fs::path short_json = root / "short.json";
  write_text(short_json, R"({"triangle_surface_ids": [1, 2], "surfaces": [], "tools": []})");
  const fs::path cloud = root / "cloud.xyz";
  write_text(cloud, "0 0 0\n1 0 0\n0 1 0\n");

  struct Case {
    const char* name;
    std::vector<std::string> args;
    fs::path named;
  };
  auto with = [&](int index, const fs::path& f) {
    std::vector<std::string> a = field_args(p, out);
    a[index] = f.string();
    return a;
  };
  std::vector<std::string> ray_on_cloud = with(2, cloud);
  ray_on_cloud.insert(ray_on_cloud.end(), {"--method", "ray"});
  const std::vector<Case> cases{
      {"truncated nominal", with(1, truncated), truncated},
      {"NaN in the scan", with(2, nan_scan), nan_scan},
      {"missing scan", with(2, root / "missing.ply"), root / "missing.ply"},
      {"program error", with(4, bad_program), bad_program},
      {"tool table error", with(6, bad_tools), bad_tools},
      {"part.json not JSON", with(8, bad_json), bad_json},
      {"part.json for another mesh", with(8, short_json), short_json},
      {"ray method on a point cloud", ray_on_cloud, cloud},
  };
  for (const Case& c : cases) {
    const ProcessResult r = truecut(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.name << "\n" << r.err;
    EXPECT_NE(r.err.find(c.named.filename().string()), std::string::npos) << c.name << "\n"
                                                                          << r.err;
    EXPECT_EQ(listing(out), std::set<std::string>{"keep.txt"}) << c.name;
  }
  // Usage errors.
  EXPECT_EQ(truecut({"field", p.nominal.string()}).exit_code, 2);
  std::vector<std::string> no_out = field_args(p, out);
  no_out.resize(no_out.size() - 2);
  EXPECT_EQ(truecut(no_out).exit_code, 2);
  for (const char* bad : {"--significance", "--scan-noise"}) {
    std::vector<std::string> a = field_args(p, out);
    a.insert(a.end(), {bad, "-1"});
    const ProcessResult r = truecut(a);
    EXPECT_EQ(r.exit_code, 2) << bad;
    EXPECT_NE(r.err.find(std::string(bad).substr(2)), std::string::npos) << r.err;
  }
  EXPECT_EQ(listing(out), std::set<std::string>{"keep.txt"});
  EXPECT_FALSE(fs::exists(root / "never"));
}

// Issue 23 (sweep F16): `--base DIR/field.tcf --out DIR`, the natural next
// iteration, replaced the base field it read. Every output is checked
// against every input (by identity: a link too); the input stays.
TEST(FieldCli, AnOutputThatIsAnInputIsRefusedAndTheInputKept) {
  const fs::path root = scratch_dir();
  const Part p = make_part_and_scan(root, 0.05);
  const fs::path it = root / "it";
  ASSERT_EQ(truecut(field_args(p, it)).exit_code, 0);
  const std::string before = read_file(it / "field.tcf");
  fs::create_symlink(it / "field.tcf", root / "base.tcf");
  for (const fs::path& base : {it / "field.tcf", root / "base.tcf"}) {
    std::vector<std::string> args = field_args(p, it);
    args.insert(args.end(), {"--base", base.string()});
    const ProcessResult r = truecut(args);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("--out " + (it / "field.tcf").string() + " is the input " + base.string()),
              std::string::npos)
        << r.err;
  }
  EXPECT_EQ(read_file(it / "field.tcf"), before);
  // The part file as --out's audit.json.
  fs::create_directories(root / "o2");
  write_text(root / "o2" / "audit.json", read_file(p.part));
  std::vector<std::string> args = field_args(p, root / "o2");
  args[8] = (root / "o2" / "audit.json").string();
  const ProcessResult r = truecut(args);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("is the input"), std::string::npos) << r.err;
}

// A .tcf field (docs/formats.md) of one constant vector for `tools` on
// 5 x 5 x 5 nodes of 5 mm from `origin`, with its CRC-64/XZ.
void write_constant_field(const fs::path& file, const std::string& origin, const std::string& tools,
                          int layers) {
  std::string payload;
  const double node[4] = {0.01, 0.0, 0.0, 1.0};
  for (int n = 0; n < 125 * layers; ++n)
    payload.append(reinterpret_cast<const char*>(node), sizeof node);
  const std::string header = "TRUECUT-FIELD 1\nframe: workpiece\nunits: mm\norigin: " + origin +
                             "\nspacing: 5 5 5\ndims: 5 5 5\ntools: " + tools +
                             "\ninterpolation: tricubic-bspline\nchannels: dx dy dz weight\n"
                             "encoding: float64-le\npayload_bytes: " +
                             std::to_string(payload.size()) + "\n";
  std::uint64_t crc = ~std::uint64_t{0};
  for (unsigned char b : header + payload) {
    crc ^= b;
    for (int k = 0; k < 8; ++k)
      crc = (crc >> 1) ^ ((crc & 1) ? 0xC96C5795D7870F42ull : 0);
  }
  char line[40];
  std::snprintf(line, sizeof line, "crc64: %016llx\n", static_cast<unsigned long long>(~crc));
  write_text(file, header + line + "end_header\n" + payload);
}

// Issue 23 (sweep F3, the CLI side; the pipeline's test has the zero
// field): a base field with no layer for the program's tools, or whose grid
// lies off the part, was dropped without a word (the new field byte for byte
// the one made without it).
TEST(FieldCli, ABaseFieldThatAddsNothingIsRefused) {
  const fs::path root = scratch_dir();
  const Part p = make_part_and_scan(root, 0.05);
  write_constant_field(root / "t9.tcf", "-10 -10 -10", "9", 1);
  write_constant_field(root / "far.tcf", "500 500 500", "1 2", 2);
  for (const auto& [base, says] : std::vector<std::pair<std::string, std::string>>{
           {"t9.tcf", " has no layer for any tool the program cuts with (T1"},
           {"far.tcf", " adds nothing at any of the"}}) {
    std::vector<std::string> args = field_args(p, root / "out");
    args.insert(args.end(), {"--base", (root / base).string()});
    const ProcessResult r = truecut(args);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_NE(r.err.find("--base " + (root / base).string() + says), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(root / "out"));
  }
}

// Issue 23 (sweep F28): a scan named in Latin-1 ended the field after all
// its work with nlohmann's type_error.316 (exit 1, no file named); audit.json
// is written with U+FFFD for the byte that is not UTF-8.
TEST(FieldCli, ANameThatIsNotUtf8IsWrittenSafelyInTheAudit) {
  const fs::path root = scratch_dir();
  Part p = make_part_and_scan(root, 0.05);
  const fs::path latin1 = root / "scan\xe9.stl";
  fs::rename(p.scan, latin1);
  p.scan = latin1;
  const ProcessResult r = truecut(field_args(p, root / "out"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json audit = nlohmann::json::parse(read_file(root / "out" / "audit.json"));
  EXPECT_NE(audit.dump().find("scan\xef\xbf\xbd.stl"), std::string::npos);
}

// Issue 23 (sweep, low): values and combinations that mean nothing were
// accepted: a cutting length of 0, a scan noise of 0 (read as "estimate"),
// --register-significance with --no-register; and an --out that cannot be
// written was found only after all the work.
TEST(FieldCli, MeaninglessOptionsAndAnUnwritableOutAreRefusedAtOnce) {
  const fs::path root = scratch_dir();
  const Part p = make_part_and_scan(root, 0.05);
  const fs::path out = root / "out";
  struct Case {
    std::vector<std::string> options;
    std::string says;
  };
  std::vector<Case> cases{
      {{"--cutting-length", "1=0"}, "--cutting-length '1=0': must be greater than 0 mm"},
      {{"--scan-noise", "0"}, "--scan-noise"},
      {{"--no-register", "--register-significance", "0.01"},
       "--register-significance tests a registration, and --no-register makes none"},
  };
  if (fs::is_directory("/proc/self")) cases.push_back({{}, "cannot write in /proc"});
  for (const Case& c : cases) {
    std::vector<std::string> args = field_args(p, c.options.empty() ? "/proc/truecut-field" : out);
    args.insert(args.end(), c.options.begin(), c.options.end());
    const ProcessResult r = truecut(args);
    EXPECT_EQ(r.exit_code, 2) << c.says << ": " << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
    // No stage line ("field: registration ..."): refused before the work.
    EXPECT_NE(r.err.rfind("truecut field: ", 0), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("\nfield: "), std::string::npos) << "work was done: " << r.err;
    EXPECT_FALSE(fs::exists(out));
  }
}

// Issue 23: `field` had no --max-blocks (an endless loop in the program ran
// for the interpreter's default budget), and tool options were read only
// once the meshes had been.
TEST(FieldCli, TheProgramsBlockBudgetAndToolOptionsAreCheckedAsTheUserGaveThem) {
  const fs::path root = scratch_dir();
  const Part p = make_part_and_scan(root, 0.05);
  Part looping = p;
  looping.program = root / "loop.ngc";
  write_text(looping.program, "#1=0\no1 while [1]\n#1=[#1+1]\no1 endwhile\nM2\n");
  std::vector<std::string> args = field_args(looping, root / "out");
  args.insert(args.end(), {"--max-blocks", "1000"});
  const ProcessResult r = truecut(args);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("more than 1000 blocks executed"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(root / "out" / "field.tcf"));
  EXPECT_NE(truecut({"field", "--help"}).out.find("--max-blocks N"), std::string::npos);
  // A tool number beyond an int (once cast to tool 1) is refused before
  // any mesh is read: these meshes do not exist.
  for (const char* option : {"--cutting-length", "--corner-radius"}) {
    const ProcessResult t =
        truecut({"field", "missing.stl", "missing_scan.stl", "--program", "p.ngc", "--tools",
                 "t.tbl", "--out", (root / "o").string(), option, "4294967297=5"});
    EXPECT_EQ(t.exit_code, 2) << t.err;
    EXPECT_NE(
        t.err.find(std::string(option) + " '4294967297=5': expected TOOL=MM (tool 0 to 99999"),
        std::string::npos)
        << t.err;
  }
}

}  // namespace
