// DexelModel::cut: the swept cutter lowers the dexels it meets. Runs in the
// servo cycle: no allocation, no exception, bounded loops.
#include <algorithm>
#include <cmath>

#include "tool_solid.hpp"
#include "truecut/sim/cutting/dexel_model.hpp"
#include "worker_pool.hpp"

namespace truecut::sim::cutting {

namespace {

bool finite(const Eigen::Vector3d& v) {
  return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
}

// Sub-steps so the union of tool instances is within `tol` of the swept
// solid: a smooth profile of radius r moved by δ between instances leaves a
// cusp of δ²/(8r); a sharp edge (the flat bottom moving along the axis, or
// tilting) leaves a step of δ. Smooth steps are halved (cusp ≤ tol/4 at
// radius r) because away from the path the tool's section is smaller than r
// (a ball at lateral offset d: √(r² − d²)).
double substeps_needed(const CutterShape& s, const Eigen::Vector3d& d, const Eigen::Vector3d& a,
                       double angle_rad, double tol) {
  const double da = std::abs(d.dot(a));
  const double dp = (d - d.dot(a) * a).norm();
  const double rc = s.corner_radius_mm;
  const double lateral = 0.5 * std::sqrt(8 * s.radius_mm * tol);
  double n = dp / lateral;
  if (rc > 0)
    n = std::max(n, da / (0.5 * std::sqrt(8 * rc * tol)));
  else if (dp > 0)
    n = std::max(n, da / tol);
  else
    n = std::max(n, da / (0.5 * s.flute_length_mm));  // a plunge: instances must overlap
  const double reach = std::hypot(s.flute_length_mm, s.radius_mm);
  n = std::max(n, angle_rad * reach / (0.5 * std::sqrt(8 * (rc > 0 ? rc : s.radius_mm) * tol)));
  if (rc < s.radius_mm) n = std::max(n, angle_rad * (s.radius_mm - rc) / tol);
  return n;
}

}  // namespace

bool valid(const CutterShape& s) noexcept {
  return std::isfinite(s.radius_mm) && std::isfinite(s.corner_radius_mm) &&
         std::isfinite(s.flute_length_mm) && s.radius_mm > 0 && s.corner_radius_mm >= 0 &&
         s.corner_radius_mm <= s.radius_mm && s.flute_length_mm > 0 &&
         s.flute_length_mm >= s.corner_radius_mm;
}

bool valid(const CutterPose& p) noexcept {
  if (!finite(p.tip_mm) || !finite(p.axis)) return false;
  const double len = p.axis.norm();
  return len >= 0.5 && len <= 2.0;
}

double DexelModel::substeps_needed(const CutterShape& shape, const CutterPose& from,
                                   const CutterPose& to) const noexcept {
  const Eigen::Vector3d a0 = from.axis.normalized(), a1 = to.axis.normalized();
  const double angle = std::atan2(a0.cross(a1).norm(), a0.dot(a1));
  Eigen::Vector3d mean_axis = a0 + a1;
  mean_axis = mean_axis.norm() > 1e-6 ? mean_axis.normalized() : a0;
  return cutting::substeps_needed(shape, to.tip_mm - from.tip_mm, mean_axis, angle,
                                  options_.tolerance_mm);
}

Engagement DexelModel::cut(const CutterShape& shape, const CutterPose& from, const CutterPose& to,
                           bool include_start) noexcept {
  Engagement e;
  if (!valid(shape) || !valid(from) || !valid(to)) {
    e.invalid_input = true;
    return e;
  }
  if (++epoch_ == 0) {  // wrapped: forget old stamps
    std::fill(stamp_.begin(), stamp_.end(), 0u);
    epoch_ = 1;
  }
  const Eigen::Vector3d a0 = from.axis.normalized(), a1 = to.axis.normalized();
  const double angle = std::atan2(a0.cross(a1).norm(), a0.dot(a1));
  const double sin_angle = std::sin(angle);
  const Eigen::Vector3d d = to.tip_mm - from.tip_mm;

  const double need = substeps_needed(shape, from, to);
  int steps = 1;
  if (need > options_.max_substeps) {
    steps = options_.max_substeps;
    e.substeps_capped = true;
  } else {
    steps = std::max(1, static_cast<int>(std::ceil(need)));
  }

  // The ball centre's motion over the sweep (its tube, for the output mesh).
  const double rc = shape.corner_radius_mm;
  Eigen::Vector3d centre_motion = (to.tip_mm + rc * a1) - (from.tip_mm + rc * a0);
  const double centre_travel = centre_motion.norm();
  centre_motion = centre_travel > 1e-9 ? Eigen::Vector3d(centre_motion / centre_travel)
                                       : Eigen::Vector3d::Zero();
  Eigen::Vector3d normal_sum = Eigen::Vector3d::Zero(), contact_sum = Eigen::Vector3d::Zero();
  e.axial_min_mm = detail::kInf;
  e.axial_max_mm = -detail::kInf;
  for (int k = include_start ? 0 : 1; k <= steps; ++k) {
    const double s = double(k) / double(steps);
    const Eigen::Vector3d tip = k == steps ? to.tip_mm : from.tip_mm + s * d;
    Eigen::Vector3d axis;
    if (k == steps)
      axis = a1;
    else if (sin_angle > 1e-9)
      axis = ((std::sin((1 - s) * angle) * a0 + std::sin(s * angle) * a1) / sin_angle).normalized();
    else
      axis = angle < 1.0 ? ((1 - s) * a0 + s * a1).normalized() : (s < 0.5 ? a0 : a1);
    apply_instance(shape, tip, axis, centre_motion, e, normal_sum, contact_sum);
    ++e.substeps;
  }
  if (e.removed_mm3 > 0) {
    const double len = normal_sum.norm();
    if (len > 0) e.normal = normal_sum / len;
    e.contact_mm = contact_sum / e.removed_mm3;
  } else {
    e.axial_min_mm = e.axial_max_mm = 0;
  }
  return e;
}

struct DexelModel::Instance {
  DexelModel* model;
  detail::ToolGeometry g;
  Eigen::Vector3d tip, axis, centre_motion;
  Eigen::Vector3d lo_box, hi_box;  // the tool's bounding box
  int c0[3], c1[3];
  std::uint32_t ny;              // grid rows per z layer of the box
  std::uint32_t rows;            // grid rows (y, z) in the box
  std::uint32_t rows_per_chunk;  // consecutive rows per chunk
};

namespace {

// Below this many grid entries under an instance the helper threads cost
// more than they save.
constexpr std::uint32_t kMinParallelEntries = 256;

}  // namespace

void DexelModel::apply_instance(const CutterShape& shape, const Eigen::Vector3d& tip,
                                const Eigen::Vector3d& axis, const Eigen::Vector3d& centre_motion,
                                Engagement& e, Eigen::Vector3d& normal_sum,
                                Eigen::Vector3d& contact_sum) noexcept {
  if (cell_start_.empty()) return;
  Instance in{this,
              {shape.radius_mm, shape.corner_radius_mm, shape.radius_mm - shape.corner_radius_mm,
               shape.flute_length_mm},
              tip,
              axis,
              centre_motion,
              {},
              {},
              {},
              {},
              0,
              0,
              1};
  // Bounding box of the tool: its axis segment widened by the rim disk.
  const Eigen::Vector3d top = tip + shape.flute_length_mm * axis;
  Eigen::Vector3d lo_box = tip.cwiseMin(top), hi_box = tip.cwiseMax(top);
  for (int i = 0; i < 3; ++i) {
    const double r = shape.radius_mm * std::sqrt(std::max(0.0, 1 - axis[i] * axis[i])) + 1e-9;
    lo_box[i] -= r;
    hi_box[i] += r;
  }
  in.lo_box = lo_box;
  in.hi_box = hi_box;
  for (int i = 0; i < 3; ++i) {
    const double a = std::floor((lo_box[i] - grid_origin_mm_[i]) / cell_mm_);
    const double b = std::floor((hi_box[i] - grid_origin_mm_[i]) / cell_mm_);
    if (b < 0 || a >= grid_dims_[i]) return;
    in.c0[i] = static_cast<int>(std::max(a, 0.0));
    in.c1[i] = static_cast<int>(std::min(b, double(grid_dims_[i] - 1)));
  }
  in.ny = static_cast<std::uint32_t>(in.c1[1] - in.c0[1] + 1);
  in.rows = in.ny * static_cast<std::uint32_t>(in.c1[2] - in.c0[2] + 1);
  in.rows_per_chunk = (in.rows + kMaxChunks - 1) / kMaxChunks;
  const std::uint32_t chunks = (in.rows + in.rows_per_chunk - 1) / in.rows_per_chunk;
  for (auto& c : cursor_)
    c.value = 0;
  detail::WorkerPool* pool = threads_.get();
  bool parallel = false;
  if (pool != nullptr && pool->threads() > 1 && chunks > 1) {
    std::uint32_t entries = 0;
    for (int z = in.c0[2]; z <= in.c1[2] && entries < kMinParallelEntries; ++z)
      for (int y = in.c0[1]; y <= in.c1[1]; ++y) {
        const std::size_t row = (std::size_t(z) * grid_dims_[1] + y) * grid_dims_[0];
        entries += cell_start_[row + in.c1[0] + 1] - cell_start_[row + in.c0[0]];
      }
    parallel = entries >= kMinParallelEntries;
  }
  if (parallel) {
    pool->run(
        chunks,
        [](void* context, std::uint32_t chunk, int thread) {
          const auto& instance = *static_cast<const Instance*>(context);
          instance.model->cut_chunk(instance, chunk, thread);
        },
        &in);
  } else {
    for (std::uint32_t c = 0; c < chunks; ++c)
      cut_chunk(in, c, 0);
  }
  // The sums over the lowered dexels, chunk by chunk in row order: the order
  // one thread lowers them in, whichever thread did.
  for (std::uint32_t c = 0; c < chunks; ++c) {
    const ChunkResult& r = chunks_[c];
    e.dexels_touched += r.touched;
    const std::uint32_t* list = lowered_[r.thread].data() + r.begin;
    for (std::uint32_t k = 0; k < r.count; ++k) {
      const std::uint32_t d = list[k];
      const double h = old_height_[d], new_h = line_[d].height;
      const Eigen::Vector3d& p = line_origin_[d];
      const Eigen::Vector3d& n = normal_[d];
      const double removed = (h - new_h) * area_[d];
      e.removed_mm3 += removed;
      normal_sum += removed * n;
      contact_sum += removed * (p + (0.5 * (h + new_h)) * n);
      const double w = (p + new_h * n - tip).dot(axis);
      e.axial_min_mm = std::min(e.axial_min_mm, w);
      e.axial_max_mm = std::max(e.axial_max_mm, w);
    }
  }
}

void DexelModel::record_swept(const Instance& in, std::uint32_t d, const Eigen::Vector3d& p,
                              const Eigen::Vector3d& n, double new_h, bool to_floor) noexcept {
  // The surface this instance leaves at the dexel, for the output mesh's
  // cusps: the ball's tube, the flank's or the flat bottom's tangent plane
  // (g: out of the material, into the tool).
  const detail::ToolGeometry& g = in.g;
  const Eigen::Vector3d& tip = in.tip;
  const Eigen::Vector3d& axis = in.axis;
  const double w = (p + new_h * n - tip).dot(axis);
  const Eigen::Vector3d x = p + new_h * n;
  const Eigen::Vector3d radial = x - tip - w * axis;
  const double r = radial.norm();
  constexpr double kOn = 1e-7;  // mm: which face of the cutter the entry lies on
  std::uint8_t kind = kSweptNone;
  if (to_floor) {
    // cut to the floor: no surface of the tool here
  } else if (g.core_mm <= 0 && g.corner_mm > 0 && w < g.corner_mm) {
    kind = kSweptBall;
    sweep_point_[d] = (tip + g.corner_mm * axis - position_[d]).cast<float>();
    sweep_vector_[d] = in.centre_motion.cast<float>();
    sweep_radius_[d] = static_cast<float>(g.corner_mm);
  } else if (w <= kOn && r <= g.core_mm + kOn) {
    kind = kSweptPlane;  // flat bottom
    sweep_point_[d] = (x - position_[d]).cast<float>();
    sweep_vector_[d] = axis.cast<float>();
  } else if (w >= g.corner_mm - kOn && w <= g.flute_mm - kOn && r > 0.5 * g.radius_mm &&
             std::abs(r - g.radius_mm) <= 1e-6) {
    kind = kSweptPlane;  // flank
    sweep_point_[d] = (x - position_[d]).cast<float>();
    sweep_vector_[d] = (-radial / r).cast<float>();
  }
  sweep_kind_[d] = kind;
}

bool DexelModel::cell_misses_tool(const Instance& in, std::size_t cell, int x, int y,
                                  int z) const noexcept {
  const std::uint32_t reach = cell_reach_[cell];
  const int index[3] = {x, y, z};
  Eigen::Vector3d lo, hi;
  for (int k = 0; k < 3; ++k) {
    const std::uint32_t r = (reach >> (8 * k)) & 0xFFu;
    const double corner = grid_origin_mm_[k] + index[k] * cell_mm_;
    lo[k] = std::max(corner, in.lo_box[k]);
    hi[k] = r == kReachUnbounded ? in.hi_box[k]
                                 : std::min(corner + double(r) * (cell_mm_ / 8), in.hi_box[k]);
    if (hi[k] < lo[k] - 1e-6) return true;  // the lines end before the tool's box
  }
  return detail::box_misses_tool(lo - in.tip, hi - in.tip, in.axis, in.g);
}

void DexelModel::cut_chunk(const Instance& in, std::uint32_t chunk, int thread) noexcept {
  const detail::ToolGeometry& g = in.g;
  const Eigen::Vector3d& tip = in.tip;
  const Eigen::Vector3d& axis = in.axis;
  std::uint32_t* const lowered = lowered_[std::size_t(thread)].data();
  std::uint32_t cursor = cursor_[std::size_t(thread)].value;
  ChunkResult result{static_cast<std::uint32_t>(thread), cursor, 0, 0};
  // The arrays as local pointers: the stores below (heights, swept surfaces)
  // cannot then make the compiler reload them for every dexel.
  const std::uint32_t* const items = cell_items_.data();
  Line* const lines = line_.data();
  double* const old_height = old_height_.data();
  std::uint32_t* const stamp = stamp_.data();
  const std::uint32_t epoch = epoch_;
  // Lowers the dexels of grid entries [first, last) whose flags include `need`
  // (the dexel's box of cells starts in this cell along those axes).
  auto cut_entries = [&](std::uint32_t first, std::uint32_t last, std::uint32_t need) {
    const std::uint32_t cell_begin = cursor;
    for (std::uint32_t it = first; it < last; ++it) {
      const std::uint32_t entry = items[it];
      if ((entry & need) != need) continue;
      const std::uint32_t d = entry & kIndexMask;
      Line& line = lines[d];
      const double h = line.height, floor = line.floor;
      if (h <= floor) continue;
      const Eigen::Vector3d& p = line.origin;
      const Eigen::Vector3d& n = line.normal;
      const Eigen::Vector3d q = p - tip;
      if (detail::starts_above(q, n, axis, g, h)) continue;
      const detail::Span span = detail::tool_span(q, n, axis, g, floor, h);
      if (span.empty() || !(span.t0 < h) || !(span.t1 > floor)) continue;
      const double new_h = std::max(span.t0, floor);
      line.height = new_h;
      old_height[d] = h;
      lowered[cursor++] = d;
      record_swept(in, d, p, n, new_h, span.t0 <= floor);
      if (stamp[d] != epoch) {
        stamp[d] = epoch;
        ++result.touched;
      }
    }
    // The cell's home dexels were tested before the others: lowered ones in
    // index order, as the cell lists them (insertion sort: a handful).
    for (std::uint32_t i = cell_begin + 1; i < cursor; ++i) {
      const std::uint32_t d = lowered[i];
      std::uint32_t j = i;
      for (; j > cell_begin && lowered[j - 1] > d; --j)
        lowered[j] = lowered[j - 1];
      lowered[j] = d;
    }
  };
  // One cell: all its entries with the flags `need`; inside the instance's
  // box (need = all three flags) those are its leading home entries.
  constexpr std::uint32_t kHome = kFirstX | kFirstY | kFirstZ;
  auto cut_cell = [&](std::size_t cell, std::uint32_t need) {
    if (need == kHome)
      cut_entries(cell_start_[cell], cell_home_end_[cell], need);
    else
      cut_entries(cell_start_[cell], cell_start_[cell + 1], need);
  };
  const std::uint32_t row_end = std::min(in.rows, (chunk + 1) * in.rows_per_chunk);
  for (std::uint32_t r = chunk * in.rows_per_chunk; r < row_end; ++r) {
    const int z = in.c0[2] + static_cast<int>(r / in.ny);
    const int y = in.c0[1] + static_cast<int>(r % in.ny);
    // In the instance's first row (column) of cells every dexel listed there
    // starts its box at or before it; further in, only those that start there.
    const std::uint32_t need = (y != in.c0[1] ? kFirstY : 0u) | (z != in.c0[2] ? kFirstZ : 0u);
    const std::size_t row = (std::size_t(z) * grid_dims_[1] + y) * grid_dims_[0];
    if (cell_start_[row + in.c0[0]] == cell_start_[row + in.c1[0] + 1]) continue;  // empty
    for (int x = in.c0[0]; x <= in.c1[0]; ++x) {
      const std::size_t cell = row + x;
      if (cell_start_[cell] == cell_start_[cell + 1]) continue;
      if (cell_misses_tool(in, cell, x, y, z)) continue;
      cut_cell(cell, x == in.c0[0] ? need : need | kFirstX);
    }
  }
  cursor_[std::size_t(thread)].value = cursor;
  ChunkResult& out = chunks_[chunk];
  out.thread = result.thread;
  out.begin = result.begin;
  out.count = cursor - result.begin;
  out.touched = result.touched;
}

DexelModel::ThreadStats DexelModel::thread_stats() const noexcept {
  ThreadStats t;
  if (const detail::WorkerPool* pool = threads_.get()) {
    const auto s = pool->stats();
    t = {s.jobs, s.chunks, s.worker_chunks, s.wakes, s.wait_spins};
  }
  return t;
}

namespace detail {

CutThreads::CutThreads() noexcept = default;
CutThreads::CutThreads(int threads) {
  if (threads > 1) pool_ = std::make_unique<WorkerPool>(threads);
}
CutThreads::CutThreads(const CutThreads& other) : CutThreads(other.threads()) {}
CutThreads& CutThreads::operator=(const CutThreads& other) {
  if (this != &other && threads() != other.threads()) *this = CutThreads(other.threads());
  return *this;
}
CutThreads::CutThreads(CutThreads&&) noexcept = default;
CutThreads& CutThreads::operator=(CutThreads&&) noexcept = default;
CutThreads::~CutThreads() = default;
int CutThreads::threads() const noexcept {
  return pool_ ? pool_->threads() : 1;
}

}  // namespace detail

}  // namespace truecut::sim::cutting
