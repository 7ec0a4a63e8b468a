// The compensation matrix of the optical-compensation source as the G-code
// rewriter reads it: the CSV that the offline stage writes
// (docs/formats.md, "Compensation matrix"), one row per compensation point
// with the point on the nominal surface and its compensation vector, both in
// the workpiece frame, mm. interp may not use offline/, so it has its own
// reader of the documented format.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace truecut::interp {

// Input that cannot be rewritten with (matrix, field, options, operation).
// The message names the file and, where there is one, the line.
class RewriteError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct CompensationMatrixData {
  std::vector<Eigen::Vector3d> positions_mm;  // nominal points, workpiece frame
  std::vector<Eigen::Vector3d> vectors_mm;    // compensation vectors, mm
  std::vector<std::uint8_t> valid;            // 1, or 0: no measurement (vector 0)
  std::vector<std::int32_t> surface_ids;      // 0 when the file has no surface_id column

  std::size_t size() const { return positions_mm.size(); }
};

// Columns are taken by name from the header line: x y z dx dy dz are
// required, valid and surface_id optional, others ignored. Lines starting
// with '#' and blank lines are skipped; LF, CRLF and CR line ends. Throws
// RewriteError "NAME:LINE: message" on a missing column, a row with the
// wrong number of fields, a value that is not a number, NaN or infinite,
// valid not 0/1, or a file without rows.
// Which vectors to read: dx,dy,dz, or raw_dx,raw_dy,raw_dz (truecut field
// writes the smoothed, significance-tested compensation as dx,dy,dz and the
// mirror of the raw error vectors beside it).
enum class MatrixVectors { kSmoothed, kRaw };
CompensationMatrixData parse_compensation_matrix(std::string_view text, const std::string& name,
                                                 MatrixVectors vectors = MatrixVectors::kSmoothed);
CompensationMatrixData read_compensation_matrix(const std::filesystem::path& file,
                                                MatrixVectors vectors = MatrixVectors::kSmoothed);

}  // namespace truecut::interp
