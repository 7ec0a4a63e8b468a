// Real-time evaluation of a CorrectionField: noexcept, no allocation, fixed
// work (64 taps for the B-spline, 8 for trilinear).
#include <algorithm>
#include <cmath>

#include "truecut/rt/core/correction_field.hpp"

namespace truecut::rt {
namespace {

// Where a position falls in the grid: cell index and local coordinate.
struct Cell {
  std::array<int32_t, 3> index;
  Eigen::Vector3d u;  // in [0, 1] per axis
};

// Lets a node on the far face count as inside despite rounding in
// (position - origin) / spacing. In cells.
constexpr double kFaceTolerance = 1e-9;

// False when outside the closed box spanned by the nodes.
bool locate(const FieldGrid& grid, const Eigen::Vector3d& position_mm, Cell& cell) noexcept {
  for (int a = 0; a < 3; ++a) {
    double t = (position_mm[a] - grid.origin_mm[a]) / grid.spacing_mm[a];
    const double last = grid.dims[a] - 1;
    if (!(t >= -kFaceTolerance && t <= last + kFaceTolerance)) return false;
    t = std::clamp(t, 0.0, last);
    const int32_t i = std::min(static_cast<int32_t>(t), grid.dims[a] - 2);
    cell.index[a] = i;
    cell.u[a] = t - i;
  }
  return true;
}

// Uniform cubic B-spline basis on the 4 coefficients around a cell, and its
// derivative with respect to the local coordinate.
void cubic_basis(double u, double b[4], double db[4]) noexcept {
  const double v = 1.0 - u, u2 = u * u, u3 = u2 * u;
  b[0] = v * v * v / 6.0;
  b[1] = (3.0 * u3 - 6.0 * u2 + 4.0) / 6.0;
  b[2] = (-3.0 * u3 + 3.0 * u2 + 3.0 * u + 1.0) / 6.0;
  b[3] = u3 / 6.0;
  db[0] = -0.5 * v * v;
  db[1] = 1.5 * u2 - 2.0 * u;
  db[2] = -1.5 * u2 + u + 0.5;
  db[3] = 0.5 * u2;
}

// From the value (x, y, z = vector, w = weight) and its derivatives along the
// grid axes (per cell, i.e. per spacing) to a sample.
FieldSample finish(const FieldGrid& grid, const Eigen::Vector4d& value,
                   const Eigen::Vector4d (&d_cell)[3]) noexcept {
  FieldSample s;
  Eigen::Matrix<double, 4, 3> d;  // derivative per mm
  for (int a = 0; a < 3; ++a)
    d.col(a) = d_cell[a] / grid.spacing_mm[a];
  if (!value.allFinite() || !d.allFinite()) {
    s.status = FieldStatus::kNonFinite;
    return s;
  }
  s.vector_mm = value.head<3>();
  s.weight = std::clamp(value[3], 0.0, 1.0);  // only rounding can leave [0, 1]
  s.correction_mm = s.weight * s.vector_mm;
  s.jacobian = s.weight * d.topRows<3>() + s.vector_mm * d.row(3);
  return s;
}

// Adds the weighted rotation to an accepted sample (or rejects a non-finite
// one).
void with_rotation(FieldSample& s, const Eigen::Vector3d& rotation_rad) noexcept {
  if (!rotation_rad.allFinite()) {
    s = FieldSample{};
    s.status = FieldStatus::kNonFinite;
    return;
  }
  s.rotation_rad = s.weight * rotation_rad;
}

FieldSample rejected(FieldStatus status) noexcept {
  FieldSample s;
  s.status = status;
  return s;
}

}  // namespace

const CorrectionField::Layer* CorrectionField::find(int32_t tool) const noexcept {
  const auto it = std::lower_bound(tools_.begin(), tools_.end(), tool);
  if (it == tools_.end() || *it != tool) return nullptr;
  return &layers_[static_cast<std::size_t>(it - tools_.begin())];
}

bool CorrectionField::inside(const Eigen::Vector3d& position_mm) const noexcept {
  Cell cell;
  return locate(grid_, position_mm, cell);
}

FieldSample CorrectionField::evaluate(int32_t tool,
                                      const Eigen::Vector3d& position_mm) const noexcept {
  return interpolation_ == FieldInterpolation::kTrilinear ? evaluate_trilinear(tool, position_mm)
                                                          : evaluate_tricubic(tool, position_mm);
}

FieldSample CorrectionField::evaluate_tricubic(int32_t tool,
                                               const Eigen::Vector3d& position_mm) const noexcept {
  if (!position_mm.allFinite()) return rejected(FieldStatus::kNonFinite);
  const Layer* layer = find(tool);
  if (layer == nullptr) return rejected(FieldStatus::kNoLayerForTool);
  Cell cell;
  if (!locate(grid_, position_mm, cell)) return rejected(FieldStatus::kOutsideGrid);

  double bx[4], dbx[4], by[4], dby[4], bz[4], dbz[4];
  cubic_basis(cell.u.x(), bx, dbx);
  cubic_basis(cell.u.y(), by, dby);
  cubic_basis(cell.u.z(), bz, dbz);

  // Coefficient (i-1, j-1, k-1) of cell (i, j, k) sits at padded (i, j, k).
  const int64_t px = grid_.dims[0] + 2, py = grid_.dims[1] + 2;
  const Eigen::Vector4d* base =
      &layer->coefficients[cell.index[0] + px * (cell.index[1] + py * cell.index[2])];
  Eigen::Vector4d value = Eigen::Vector4d::Zero();
  Eigen::Vector4d d[3] = {Eigen::Vector4d::Zero(), Eigen::Vector4d::Zero(),
                          Eigen::Vector4d::Zero()};
  for (int k = 0; k < 4; ++k) {
    for (int j = 0; j < 4; ++j) {
      const Eigen::Vector4d* row = base + px * (j + py * k);
      Eigen::Vector4d s = bx[0] * row[0], ds = dbx[0] * row[0];
      for (int i = 1; i < 4; ++i) {
        s += bx[i] * row[i];
        ds += dbx[i] * row[i];
      }
      value += (by[j] * bz[k]) * s;
      d[0] += (by[j] * bz[k]) * ds;
      d[1] += (dby[j] * bz[k]) * s;
      d[2] += (by[j] * dbz[k]) * s;
    }
  }
  // The weight: the node weights of the cell's 8 corners, blended with the
  // smootherstep of the local coordinates (C2: its first and second
  // derivatives vanish at the nodes). It equals the node weight at every
  // node, so an invalid node (weight 0) gets weight 0, and it reaches no
  // further than the cells around a node: validity fades by distance, within
  // one spacing, and no node's weight is smoothed into its neighbours.
  double s[3][2], ds[3][2];
  for (int a = 0; a < 3; ++a) {
    const double u = cell.u[a], g = u * u * u * (u * (u * 6.0 - 15.0) + 10.0);
    const double dg = 30.0 * u * u * (1.0 - u) * (1.0 - u);
    s[a][0] = 1.0 - g;
    s[a][1] = g;
    ds[a][0] = -dg;
    ds[a][1] = dg;
  }
  double w = 0.0, dw[3] = {0.0, 0.0, 0.0};
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) {
        const double nw = layer
                              ->nodes[static_cast<std::size_t>(grid_.index(
                                  cell.index[0] + i, cell.index[1] + j, cell.index[2] + k))]
                              .weight;
        w += s[0][i] * s[1][j] * s[2][k] * nw;
        dw[0] += ds[0][i] * s[1][j] * s[2][k] * nw;
        dw[1] += s[0][i] * ds[1][j] * s[2][k] * nw;
        dw[2] += s[0][i] * s[1][j] * ds[2][k] * nw;
      }
  value[3] = w;
  for (int a = 0; a < 3; ++a)
    d[a][3] = dw[a];
  FieldSample sample = finish(grid_, value, d);
  if (!layer->rotation_coefficients.empty() && sample.status == FieldStatus::kOk) {
    const Eigen::Vector4d* rbase =
        &layer->rotation_coefficients[cell.index[0] + px * (cell.index[1] + py * cell.index[2])];
    Eigen::Vector4d r = Eigen::Vector4d::Zero();
    for (int k = 0; k < 4; ++k)
      for (int j = 0; j < 4; ++j) {
        const Eigen::Vector4d* row = rbase + px * (j + py * k);
        r += (by[j] * bz[k]) * (bx[0] * row[0] + bx[1] * row[1] + bx[2] * row[2] + bx[3] * row[3]);
      }
    with_rotation(sample, r.head<3>());
  }
  return sample;
}

FieldSample CorrectionField::evaluate_trilinear(int32_t tool,
                                                const Eigen::Vector3d& position_mm) const noexcept {
  if (!position_mm.allFinite()) return rejected(FieldStatus::kNonFinite);
  const Layer* layer = find(tool);
  if (layer == nullptr) return rejected(FieldStatus::kNoLayerForTool);
  Cell cell;
  if (!locate(grid_, position_mm, cell)) return rejected(FieldStatus::kOutsideGrid);

  const double b[3][2] = {{1.0 - cell.u.x(), cell.u.x()},
                          {1.0 - cell.u.y(), cell.u.y()},
                          {1.0 - cell.u.z(), cell.u.z()}};
  constexpr double db[2] = {-1.0, 1.0};
  Eigen::Vector4d value = Eigen::Vector4d::Zero();
  Eigen::Vector4d d[3] = {Eigen::Vector4d::Zero(), Eigen::Vector4d::Zero(),
                          Eigen::Vector4d::Zero()};
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();
  const bool rotates = !layer->rotations.empty();
  for (int k = 0; k < 2; ++k) {
    for (int j = 0; j < 2; ++j) {
      for (int i = 0; i < 2; ++i) {
        const auto at = static_cast<std::size_t>(
            grid_.index(cell.index[0] + i, cell.index[1] + j, cell.index[2] + k));
        const FieldNode& n = layer->nodes[at];
        const Eigen::Vector4d v{n.dx_mm, n.dy_mm, n.dz_mm, n.weight};
        value += (b[0][i] * b[1][j] * b[2][k]) * v;
        d[0] += (db[i] * b[1][j] * b[2][k]) * v;
        d[1] += (b[0][i] * db[j] * b[2][k]) * v;
        d[2] += (b[0][i] * b[1][j] * db[k]) * v;
        if (rotates) rotation += (b[0][i] * b[1][j] * b[2][k]) * layer->rotations[at];
      }
    }
  }
  FieldSample sample = finish(grid_, value, d);
  if (rotates && sample.status == FieldStatus::kOk) with_rotation(sample, rotation);
  return sample;
}

}  // namespace truecut::rt
