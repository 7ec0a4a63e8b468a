// The files `truecut field` writes into its output folder, and the audit
// record (docs/offline.md, "Outputs" and "audit.json"):
//   field.tcf               the correction field (rt/field_file.hpp)
//   compensation_matrix.csv the mirror of the raw error vectors
//   adapted.stl             the nominal mesh moved by the smoothed compensation (binary)
//   audit.json              SHA-256 of every input and of the three files above,
//                           parameters, registration, statistics, max-correction check
// All four are written as NAME.new first and renamed to NAME only when every
// one of them has been written; on failure the .new files are removed and
// nothing in the folder has changed.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "truecut/offline/field_pipeline.hpp"
#include "truecut/offline/mesh_io_options.hpp"
#include "truecut/offline/mesh_topology.hpp"
#include "truecut/rt/comp.hpp"

namespace truecut::offline {

// `truecut field` refuses (exits 1, writes nothing) a field whose correction
// exceeds this, unless --max-correction says otherwise. It overrides the
// compensation's bound (rt::comp::kDefaultMaxCorrectionMm) on purpose: it is
// a plausibility check of the measurement, not a limit of the machine. A
// correction this large on a finished part is taken as a sign of a failed
// registration or a wrong input rather than an error to compensate, and a
// field that passes is never clipped by a truecut_comp left at its default.
inline constexpr double kFieldMaxCorrectionMm = 0.2;
static_assert(kFieldMaxCorrectionMm <= rt::comp::kDefaultMaxCorrectionMm);

struct FileDigest {
  std::string role;  // "nominal", "scan", "program", "tools", "part", "field", ...
  std::filesystem::path path;
  std::uintmax_t bytes = 0;
  std::string sha256;
};
// The file's size and SHA-256 (truecut/interp/sha256.hpp). Throws
// std::runtime_error naming the file when it cannot be read.
FileDigest digest_file(const std::string& role, const std::filesystem::path& file);

// A mesh input as read: its facets and the degenerate ones dropped.
struct MeshInputAudit {
  std::string role;  // "nominal", "scan", "expected"
  std::filesystem::path file;
  std::size_t facets_in_file = 0;
  std::vector<DroppedTriangle> dropped;
  std::optional<MeshTopology> topology;  // as read, before the winding was repaired
};

struct AuditContext {
  std::vector<FileDigest> inputs;
  std::vector<MeshInputAudit> meshes;
  std::vector<std::string> command_line;  // argv as given
  std::string created_utc;                // ISO 8601; empty: now
  std::vector<ToolShape> tools;           // the tool shapes the placement used
  double max_correction_limit_mm = kFieldMaxCorrectionMm;
  bool forced = false;  // --force: written although max_correction_mm exceeds the limit
};

// The files write_field_outputs writes into its folder, in this order.
inline constexpr std::array<const char*, 4> kFieldOutputFiles{
    "field.tcf", "compensation_matrix.csv", "adapted.stl", "audit.json"};

// The audit record as JSON text (schema: docs/offline.md, "audit.json").
std::string audit_json(const FieldPipelineResult& result, const FieldPipelineOptions& options,
                       const AuditContext& context, std::span<const FileDigest> outputs);

// Writes the four files into `dir` (created if missing). Refuses (throws
// std::runtime_error, nothing written) when a target exists and is not a
// regular file. Returns the digests of the written files, audit.json last.
std::vector<FileDigest> write_field_outputs(const std::filesystem::path& dir,
                                            const FieldPipelineResult& result,
                                            const FieldPipelineOptions& options,
                                            const AuditContext& context);

}  // namespace truecut::offline
