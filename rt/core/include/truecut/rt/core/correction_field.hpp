// The correction field: on a regular 3-D grid in the workpiece frame, one
// layer per tool of correction vectors (mm) and a validity weight in [0, 1].
//
// Evaluation (real-time safe: noexcept, no allocation, fixed work):
// - vector: interpolating tricubic B-spline. Grid values are node values, not
//   control points; construction prefilters them into B-spline coefficients
//   (natural end conditions), so the vector at a valid node equals the stored
//   one. C2 inside the grid. A node of weight 0 is invalid: its stored vector
//   is not used (construction replaces it, in order of distance from the
//   valid nodes, by the mean of its neighbours one face step nearer), so it
//   never enters its neighbours' interpolation.
// - weight: the node weights of the cell's 8 corners blended with the
//   smootherstep of the local coordinates. C2 (its first and second
//   derivatives vanish at the nodes), within [0, 1], equal to the node
//   weight at every node (0 at an invalid node), and reaching only the cells
//   around a node: validity fades by distance within one spacing. When the
//   two outermost node layers have weight 0, weight and its gradient vanish
//   on the grid boundary, so the correction joins the zero outside the grid
//   C2-smoothly.
// - correction = weight * vector.
// - rotation (optional, a field either has it in every layer or in none): a
//   small rotation of the tool about its tip, rad, per node (the rotation
//   vector, workpiece frame: the corrected tool axis is k + r x k; the part of
//   r along k does nothing). Interpolated like the vector, weighted by the
//   same weight.
// A trilinear evaluation of the node values (C0, as in FANUC-style pitch and
// 3-D error compensation tables) is available as a baseline.
#pragma once

// Part of the real-time core: include "truecut/rt/comp.hpp" (std and Eigen only).

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace truecut::rt {

struct FieldGrid {
  Eigen::Vector3d origin_mm = Eigen::Vector3d::Zero();   // position of node (0, 0, 0)
  Eigen::Vector3d spacing_mm = Eigen::Vector3d::Ones();  // > 0 along each axis
  std::array<int32_t, 3> dims{2, 2, 2};                  // nodes along x, y, z; each >= 2

  int64_t node_count() const noexcept { return int64_t{dims[0]} * dims[1] * dims[2]; }
  // Nodes are stored x fastest, then y, then z.
  int64_t index(int32_t i, int32_t j, int32_t k) const noexcept {
    return i + int64_t{dims[0]} * (j + int64_t{dims[1]} * k);
  }
  Eigen::Vector3d node_position_mm(int32_t i, int32_t j, int32_t k) const noexcept {
    return origin_mm + spacing_mm.cwiseProduct(Eigen::Vector3d(i, j, k));
  }
};

struct FieldNode {
  double dx_mm = 0.0;
  double dy_mm = 0.0;
  double dz_mm = 0.0;
  double weight = 0.0;  // in [0, 1]
};

struct FieldLayer {
  int32_t tool = 0;              // tool number, >= 0
  std::vector<FieldNode> nodes;  // grid.node_count() entries, x fastest
  // Empty (no orientation correction) or one rotation vector per node, rad,
  // in the order of `nodes`.
  std::vector<Eigen::Vector3d> rotation_rad = {};
};

enum class FieldInterpolation { kTricubicBspline, kTrilinear };

enum class FieldStatus {
  kOk,
  kOutsideGrid,     // zero correction, weight 0
  kNoLayerForTool,  // zero correction, weight 0
  kNonFinite,       // the position (or, never expected, the result) was not finite
};

const char* to_string(FieldStatus status) noexcept;
const char* to_string(FieldInterpolation interpolation) noexcept;

struct FieldSample {
  FieldStatus status = FieldStatus::kOk;
  Eigen::Vector3d correction_mm = Eigen::Vector3d::Zero();  // weight * vector_mm
  Eigen::Vector3d vector_mm = Eigen::Vector3d::Zero();      // unweighted interpolant
  double weight = 0.0;
  // d correction_mm(i) / d position(j), mm per mm.
  Eigen::Matrix3d jacobian = Eigen::Matrix3d::Zero();
  // weight * the interpolated rotation vector, rad (zero when the field has
  // no rotation).
  Eigen::Vector3d rotation_rad = Eigen::Vector3d::Zero();
};

// What a field was built for, as the real-time side sees it: the CRC-64 of
// its file and 32-bit ids of the machine, the part and the tool set it names
// (0: not named). Set by the loader (field_file.hpp: field_identity_id()).
struct FieldIdentity {
  uint64_t crc64 = 0;
  uint32_t machine = 0;
  uint32_t part = 0;
  uint32_t tool_set = 0;
};

// Immutable once built. Build it outside the real-time thread; publish it by
// pointer.
class CorrectionField {
 public:
  // Validates the grid (finite origin, positive finite spacing, dims >= 2, at
  // most kMaxNodes nodes), the layers (distinct tools >= 0, right node count,
  // finite vectors, weights in [0, 1], a finite rotation per node in every
  // layer or in none) and prefilters. Throws
  // std::invalid_argument saying what is wrong. Layers are kept sorted by tool.
  CorrectionField(const FieldGrid& grid, std::vector<FieldLayer> layers,
                  FieldInterpolation interpolation = FieldInterpolation::kTricubicBspline);

  static constexpr int64_t kMaxNodes = int64_t{1} << 26;  // per layer
  static constexpr std::size_t kMaxLayers = 1024;

  // Uses interpolation().
  FieldSample evaluate(int32_t tool, const Eigen::Vector3d& position_mm) const noexcept;
  FieldSample evaluate_tricubic(int32_t tool, const Eigen::Vector3d& position_mm) const noexcept;
  FieldSample evaluate_trilinear(int32_t tool, const Eigen::Vector3d& position_mm) const noexcept;

  const FieldGrid& grid() const noexcept { return grid_; }
  FieldInterpolation interpolation() const noexcept { return interpolation_; }
  std::span<const int32_t> tools() const noexcept { return tools_; }  // ascending
  // Node values of the layer for `tool`; empty when there is none.
  std::span<const FieldNode> nodes(int32_t tool) const noexcept;
  // Whether the field corrects the tool's orientation too.
  bool has_rotation() const noexcept { return has_rotation_; }
  // Node rotations of the layer for `tool`, rad; empty when there is none
  // or the field has no rotation.
  std::span<const Eigen::Vector3d> rotations(int32_t tool) const noexcept;
  bool inside(const Eigen::Vector3d& position_mm) const noexcept;
  const FieldIdentity& identity() const noexcept { return identity_; }
  // Before publishing only (the field is immutable once shared).
  void set_identity(const FieldIdentity& identity) noexcept { identity_ = identity; }

 private:
  struct Layer {
    std::vector<FieldNode> nodes;
    // (dims + 2)^3 padded coefficients: x, y, z = vector B-spline
    // coefficients, w = node weight (edges repeated; not used by the
    // evaluation, which blends the node weights themselves).
    std::vector<Eigen::Vector4d> coefficients;
    std::vector<Eigen::Vector3d> rotations;  // empty: no rotation
    // Padded like `coefficients`: x, y, z = the rotation's B-spline
    // coefficients (w unused).
    std::vector<Eigen::Vector4d> rotation_coefficients;
  };
  const Layer* find(int32_t tool) const noexcept;

  FieldGrid grid_;
  FieldInterpolation interpolation_;
  bool has_rotation_ = false;
  std::vector<int32_t> tools_;
  std::vector<Layer> layers_;  // same order as tools_
  FieldIdentity identity_;
};

}  // namespace truecut::rt
