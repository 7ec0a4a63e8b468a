// The one part.json reader: the inverse of part_json() for every part, and
// errors that name the file and the key.
#include "truecut/sim/part_file.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "test_paths.hpp"
#include "truecut/sim/benchmark_parts.hpp"

namespace truecut::sim {
namespace {

const PartOptions kCoarse{2.0, 0.8, 1.0, 2.0};

void expect_same(const PartMetadata& a, const PartMetadata& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.frame, b.frame);
  EXPECT_EQ(a.material, b.material);
  ASSERT_EQ(a.stock.size(), b.stock.size());
  for (std::size_t i = 0; i < a.stock.size(); ++i) {
    EXPECT_EQ(a.stock[i].min_mm, b.stock[i].min_mm) << i;
    EXPECT_EQ(a.stock[i].max_mm, b.stock[i].max_mm) << i;
  }
  ASSERT_EQ(a.tools.size(), b.tools.size());
  for (std::size_t i = 0; i < a.tools.size(); ++i) {
    const PartTool &x = a.tools[i], &y = b.tools[i];
    EXPECT_EQ(x.number, y.number);
    EXPECT_EQ(x.kind, y.kind);
    EXPECT_EQ(x.radius_mm, y.radius_mm);
    EXPECT_EQ(x.corner_radius_mm, y.corner_radius_mm);
    EXPECT_EQ(x.length_mm, y.length_mm);
    EXPECT_EQ(x.flute_length_mm, y.flute_length_mm);
    EXPECT_EQ(x.flutes, y.flutes);
    EXPECT_EQ(x.comment, y.comment);
  }
  ASSERT_EQ(a.surfaces.size(), b.surfaces.size());
  for (std::size_t i = 0; i < a.surfaces.size(); ++i) {
    EXPECT_EQ(a.surfaces[i].id, b.surfaces[i].id);
    EXPECT_EQ(a.surfaces[i].name, b.surfaces[i].name);
    EXPECT_EQ(a.surfaces[i].kind, b.surfaces[i].kind);
    EXPECT_EQ(a.surfaces[i].compensate, b.surfaces[i].compensate);
  }
  ASSERT_EQ(a.operations.size(), b.operations.size());
  for (std::size_t i = 0; i < a.operations.size(); ++i) {
    EXPECT_EQ(a.operations[i].name, b.operations[i].name);
    EXPECT_EQ(a.operations[i].tool, b.operations[i].tool);
    EXPECT_EQ(a.operations[i].strategy, b.operations[i].strategy);
    EXPECT_EQ(a.operations[i].surface_ids, b.operations[i].surface_ids);
  }
  EXPECT_EQ(a.a_min_deg, b.a_min_deg);
  EXPECT_EQ(a.a_max_deg, b.a_max_deg);
}

TEST(PartFile, ReadsBackEverythingPartJsonHolds) {
  for (const PartId id : kAllParts) {
    SCOPED_TRACE(std::string(part_name(id)));
    const BenchmarkPart part = make_part(id, kCoarse);
    const PartFile p = parse_part_file(part_json(part), "part.json");
    EXPECT_EQ(1, p.version);
    EXPECT_EQ("mm", p.units);
    EXPECT_EQ("tool tip", p.programmed_point);
    ASSERT_TRUE(p.options.has_value());
    EXPECT_EQ(kCoarse.mesh_edge_mm, p.options->mesh_edge_mm);
    EXPECT_EQ(kCoarse.stepover_mm, p.options->stepover_mm);
    EXPECT_EQ(kCoarse.point_spacing_mm, p.options->point_spacing_mm);
    EXPECT_EQ(kCoarse.step_down_mm, p.options->step_down_mm);
    expect_same(part.metadata, p.metadata);
    ASSERT_TRUE(p.mesh.has_value());
    EXPECT_EQ("nominal.stl", p.mesh->file);
    EXPECT_EQ(part.mesh.vertices_mm.size(), p.mesh->vertices);
    EXPECT_EQ(part.mesh.triangles.size(), p.mesh->triangles);
    EXPECT_GT(p.mesh->volume_mm3, 0);
    EXPECT_EQ(part.triangle_surface, p.triangle_surface_ids);
    for (const PartTool& t : part.metadata.tools) {
      ASSERT_NE(nullptr, p.tool(t.number));
      EXPECT_EQ(t.radius_mm, p.tool(t.number)->radius_mm);
    }
    EXPECT_EQ(nullptr, p.tool(99));
    std::vector<int> compensated;
    for (const PartSurface& s : part.metadata.surfaces)
      if (s.compensate) compensated.push_back(s.id);
    EXPECT_EQ(compensated, p.compensated_surface_ids());
  }
}

TEST(PartFile, ReadsTheFileWritePartWrites) {
  const auto dir = truecut::test::scratch_dir();
  const BenchmarkPart part = make_part(PartId::kImplant, kCoarse);
  write_part(part, dir);
  const PartFile p = read_part_file(dir / "part.json");
  expect_same(part.metadata, p.metadata);
  EXPECT_EQ(part.triangle_surface, p.triangle_surface_ids);
}

std::string error_of(const std::string& text, unsigned required = kPartAllKeys) {
  try {
    parse_part_file(text, "p.json", required);
  } catch (const PartFileError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(PartFile, ErrorsNameTheFileAndTheKey) {
  EXPECT_EQ("p.json: not valid JSON (byte 2)", error_of("{,"));
  // fuzz_part_json's finding: a number beyond a double ended the process.
  EXPECT_EQ("p.json: not valid JSON: number overflow parsing '772e680'",
            error_of("[\"772e680\", 772e680]"));
  EXPECT_EQ("p.json: not a JSON object", error_of("[1]"));
  EXPECT_EQ("p.json: key 'truecut_part': missing", error_of("{}"));
  EXPECT_EQ("p.json: key 'stock': missing", error_of("{}", kPartStock));
  EXPECT_EQ("p.json: key 'truecut_part': must be 1", error_of(R"({"truecut_part": 2})", 0));
  EXPECT_EQ("p.json: key 'stock[0].max_mm[1]': must be a finite number",
            error_of(R"({"stock": [{"min_mm": [0, 0, 0], "max_mm": [1, "a", 1]}]})", 0));
  EXPECT_EQ("p.json: key 'stock[0]': max_mm must exceed min_mm on every axis",
            error_of(R"({"stock": [{"min_mm": [0, 0, 0], "max_mm": [1, 0, 1]}]})", 0));
  EXPECT_EQ("p.json: key 'tools[0].radius_mm': missing",
            error_of(R"({"tools": [{"number": 1}]})", 0));
  EXPECT_EQ(
      "p.json: key 'tools[1].number': tool 1 listed twice",
      error_of(R"({"tools": [{"number": 1, "radius_mm": 1}, {"number": 1, "radius_mm": 2}]})", 0));
  EXPECT_EQ("p.json: key 'tools[0].length_mm': must be >= 0",
            error_of(R"({"tools": [{"number": 1, "radius_mm": 1, "length_mm": -3}]})", 0));
  EXPECT_EQ("p.json: key 'tools[0].corner_radius_mm': larger than radius_mm",
            error_of(R"({"tools": [{"number": 1, "radius_mm": 1, "corner_radius_mm": 2}]})", 0));
  EXPECT_EQ("p.json: key 'surfaces[0].compensate': must be true or false",
            error_of(R"({"surfaces": [{"id": 1, "compensate": 1}]})", 0));
  EXPECT_EQ("p.json: key 'operations[0].tool': missing",
            error_of(R"({"operations": [{"name": "A"}]})", 0));
  EXPECT_EQ("p.json: key 'triangle_surface_ids[1]': must be an integer",
            error_of(R"({"triangle_surface_ids": [1, 1.5]})", 0));
  EXPECT_EQ("p.json: key 'triangle_surface_ids[0]': out of range",
            error_of(R"({"triangle_surface_ids": [4294967296]})", 0));
  EXPECT_EQ("p.json: key 'triangle_surface_ids[1]': surface 2 is not in surfaces",
            error_of(R"({"surfaces": [{"id": 1}], "triangle_surface_ids": [1, 2]})", 0));
  EXPECT_EQ("p.json: key 'rotary_travel_deg.a': min must not exceed max",
            error_of(R"({"rotary_travel_deg": {"a": [10, -10]}})", 0));

  const auto missing = truecut::test::scratch_dir() / "missing.json";
  try {
    read_part_file(missing);
    ADD_FAILURE();
  } catch (const PartFileError& e) {
    EXPECT_EQ(missing.string() + ": cannot open the part file: No such file or directory",
              std::string(e.what()));
    EXPECT_EQ("", e.key());
  }
}

TEST(PartFile, KeysACallerDoesNotNeedMayBeAbsent) {
  const PartFile p = parse_part_file(R"({"surfaces": [{"id": 5, "compensate": true}, {"id": 6}],
                                         "triangle_surface_ids": [5, 6, 5]})",
                                     "p.json", kPartSurfaces | kPartTriangleSurfaceIds);
  EXPECT_EQ(0, p.version);
  EXPECT_TRUE(p.metadata.stock.empty());
  EXPECT_TRUE(p.metadata.tools.empty());
  EXPECT_FALSE(p.options.has_value());
  EXPECT_FALSE(p.mesh.has_value());
  EXPECT_EQ((std::vector<int>{5, 6, 5}), p.triangle_surface_ids);
  EXPECT_EQ(std::vector<int>{5}, p.compensated_surface_ids());
  EXPECT_EQ("", p.surface(6)->name);
  EXPECT_FALSE(p.surface(6)->compensate);
  // Optional tool fields default to 0.
  const PartFile t =
      parse_part_file(R"({"tools": [{"number": 3, "radius_mm": 1.5}]})", "t.json", kPartTools);
  ASSERT_NE(nullptr, t.tool(3));
  EXPECT_EQ(1.5, t.tool(3)->radius_mm);
  EXPECT_EQ(0, t.tool(3)->flute_length_mm);
}

// The one error type in both wordings: the reader's, and the cutting
// model's checks ("FILE: KEY: DETAIL", truecut/sim/cutting/part_file.hpp).
TEST(PartFile, OneErrorTypeTwoWordings) {
  const PartFileError quoted("p.json", "stock", "missing");
  EXPECT_EQ("p.json: key 'stock': missing", std::string(quoted.what()));
  const PartFileError plain("p.json", "stock", "missing", PartFileError::Wording::kPlain);
  EXPECT_EQ("p.json: stock: missing", std::string(plain.what()));
  EXPECT_EQ("stock", plain.key());
  EXPECT_EQ("missing", plain.detail());
  EXPECT_EQ("p.json: cannot open",
            std::string(
                PartFileError("p.json", "", "cannot open", PartFileError::Wording::kPlain).what()));
}

}  // namespace
}  // namespace truecut::sim
