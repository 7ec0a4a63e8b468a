// The virtual CMM: accurate probing of nominal points along their nominal
// normals on a machined mesh (workpiece frame, mm). The judge of every
// accuracy figure. Model, statistics and file formats: docs/measurement.md.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "truecut/offline/mesh.hpp"

namespace truecut::sim::measure {

// A nominal point to probe: position on the nominal surface, unit outward
// normal, surface id (−1 when unknown).
struct CmmPoint {
  Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  int surface = -1;
};

struct CmmOptions {
  double sigma_mm = 0.002;  // probing noise along the normal; 0 … 0.020 mm
  std::uint64_t seed = 1;
  // The machined surface is searched this far along ±normal from the point.
  double search_distance_mm = 1.0;
  // A surface whose normal is farther than this from the nominal normal is
  // not the one probed (the far side of a thin wall, say).
  double max_normal_angle_deg = 60.0;
};

struct CmmMeasurement {
  CmmPoint nominal;
  bool valid = false;  // false: no matching surface within the search distance
  // Along the nominal normal, measured − nominal: positive = material
  // outside the nominal surface (oversize). NaN when not valid.
  double deviation_mm = 0;
  Eigen::Vector3d measured_mm = Eigen::Vector3d::Zero();  // nominal + deviation·normal
};

// Throws std::invalid_argument for out-of-range options or a point with a
// non-finite coordinate, one beyond kMaxCmmCoordinateMm or a zero normal
// (normals are normalised).
// Deterministic: the noise of point i depends only on (seed, i).
std::vector<CmmMeasurement> probe(const offline::TriangleMesh& machined,
                                  std::span<const CmmPoint> points, const CmmOptions& options = {});

// Points on the nominal mesh: an even sampling (about one point per
// spacing_mm) of the triangles of `surfaces` (empty: all), with the face
// normals (offline::sample_compensation_points).
std::vector<CmmPoint> cmm_points_on_surfaces(const offline::TriangleMesh& nominal,
                                             std::span<const std::int32_t> triangle_surface_ids,
                                             double spacing_mm,
                                             std::span<const std::int32_t> surfaces = {});

// Deviation statistics of one surface (or of all points: surface = −1),
// from the valid points, in µm. P95 is the 95th percentile of |deviation|
// (linear interpolation between order statistics); std is the sample
// standard deviation (n − 1). Zero when fewer than one (two for std) valid points.
struct SurfaceDeviationStats {
  int surface = -1;
  std::size_t points = 0;
  std::size_t valid = 0;
  double mean_um = 0;
  double std_um = 0;
  double rms_um = 0;
  double max_abs_um = 0;
  double p95_abs_um = 0;
};

// One entry per surface id present, ascending.
std::vector<SurfaceDeviationStats> surface_statistics(std::span<const CmmMeasurement> measurements);
// Over all points (surface = −1).
SurfaceDeviationStats overall_statistics(std::span<const CmmMeasurement> measurements);

// Thrown by the CSV reader: what() is "FILE:LINE: message".
class CmmInputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A probed point lies within ±1e5 mm of the workpiece origin, the range of
// the recording and machine readers (no machine is larger than 100 m).
constexpr double kMaxCmmCoordinateMm = 1e5;
// "" when every coordinate is within kMaxCmmCoordinateMm, else what is wrong
// ("x 1e+20 mm is outside ±1e+05 mm (no machine is larger than 100 m; ...)").
std::string cmm_coordinate_error(const Eigen::Vector3d& position_mm);

// "x y z nx ny nz [surface]" per line; blanks, ',' or ';' separate; '#'
// starts a comment; an optional first line of column names (any order,
// other columns ignored: a cmm.csv reads back). The file must be a regular
// file within the input budget (truecut/rt/input_file.hpp) and every
// coordinate within kMaxCmmCoordinateMm.
std::vector<CmmPoint> read_cmm_points(const std::filesystem::path& file);

// CSV with the header x,y,z,nx,ny,nz,surface,deviation_mm,valid (nominal
// point and normal; deviation "nan" when not valid). Written to FILE.tmp
// and renamed; refuses to replace anything but a regular file.
void write_cmm_csv(const std::filesystem::path& file, std::span<const CmmMeasurement> measurements);
// Reads a cmm.csv back (the header must name deviation_mm and valid).
std::vector<CmmMeasurement> read_cmm_measurements(const std::filesystem::path& file);

}  // namespace truecut::sim::measure
