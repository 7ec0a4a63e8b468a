#include "truecut/offline/tool_centre_placement.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <stdexcept>
#include <string>

#include "spatial/kd_tree.hpp"

namespace truecut::offline {

namespace {

void check_shape(const ToolShape& s) {
  const std::string t = "tool " + std::to_string(s.tool) + ": ";
  if (!(s.radius_mm > 0.0) || !std::isfinite(s.radius_mm))
    throw std::invalid_argument(t + "radius must be positive");
  if (!(s.corner_radius_mm >= 0.0) || s.corner_radius_mm > s.radius_mm)
    throw std::invalid_argument(t + "corner radius must be in [0, radius]");
  if (!(s.cutting_length_mm >= s.corner_radius_mm) || !std::isfinite(s.cutting_length_mm) ||
      !(s.cutting_length_mm > 0.0))
    throw std::invalid_argument(t +
                                "cutting length must be positive and at least the corner radius");
}

// Probe points along the core axis of the first sample of every chunk of
// consecutive samples of one tool. A chunk holds samples whose probes lie
// within `spread` of the first one's (tip shift + cutting length × axis
// change); a point within R + tol of a member's core axis segment is then
// within query_radius of a probe of its chunk. Path samples are dense along
// the path (the tool path step), so chunks keep the tree small; probes every
// R/2 along the axis keep the query radius close to R + tol, so few samples
// that cannot reach the point are tested.
struct ToolIndex {
  std::vector<Eigen::Vector3d> probes;
  std::vector<std::uint32_t> probe_chunk;
  std::vector<std::uint32_t> chunk_begin;  // into the tool's samples; one past the last at the end
  std::vector<double> chunk_spread;        // of each chunk's members from its first sample
  spatial::KdTree tree;
  double query_radius = 0.0;
};

ToolIndex build_index(const ToolShape& shape, const ToolPath& path,
                      std::span<const std::uint32_t> samples, double tol) {
  const double r = shape.corner_radius_mm, len = shape.cutting_length_mm - r;
  const int k = std::max(1, static_cast<int>(std::ceil(2.0 * len / shape.radius_mm)));
  const double step = len / k;
  const double max_spread = 0.3 * shape.radius_mm;
  constexpr std::size_t kMaxChunk = 32;
  ToolIndex ix;
  double spread = 0.0;
  for (std::size_t c = 0; c < samples.size();) {
    const ToolPathSample& lead = path.samples[samples[c]];
    std::size_t e = c + 1;
    double chunk_spread = 0.0;
    for (; e < samples.size() && e - c < kMaxChunk; ++e) {
      const ToolPathSample& m = path.samples[samples[e]];
      const double d =
          (m.tip_mm - lead.tip_mm).norm() + shape.cutting_length_mm * (m.axis - lead.axis).norm();
      if (d > max_spread) break;
      chunk_spread = std::max(chunk_spread, d);
    }
    spread = std::max(spread, chunk_spread);
    const auto chunk = static_cast<std::uint32_t>(ix.chunk_begin.size());
    ix.chunk_begin.push_back(static_cast<std::uint32_t>(c));
    ix.chunk_spread.push_back(chunk_spread);
    for (int i = 0; i <= k; ++i) {
      ix.probes.push_back(lead.tip_mm + (r + i * step) * lead.axis);
      ix.probe_chunk.push_back(chunk);
    }
    c = e;
  }
  ix.chunk_begin.push_back(static_cast<std::uint32_t>(samples.size()));
  ix.tree = spatial::KdTree(ix.probes);
  ix.query_radius = std::hypot(shape.radius_mm + tol, 0.5 * step) + spread;
  return ix;
}

// Points in blocks of neighbours, so that one query of the index serves a
// block: in Morton order of a grid of `extent` cells, cut where a block
// would hold more than kMaxBlock points or grow beyond `extent` across.
struct PointBlocks {
  std::vector<std::uint32_t> order;  // point indices, block after block
  std::vector<std::uint32_t> begin;  // into order; one past the last at the end
  std::vector<Eigen::Vector3d> centre;
  std::vector<double> half_diagonal;
};

std::uint64_t spread_bits(std::uint64_t v) {  // 21 bits to every third of 63
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffull;
  v = (v | v << 16) & 0x1f0000ff0000ffull;
  v = (v | v << 8) & 0x100f00f00f00f00full;
  v = (v | v << 4) & 0x10c30c30c30c30c3ull;
  v = (v | v << 2) & 0x1249249249249249ull;
  return v;
}

PointBlocks point_blocks(std::span<const Eigen::Vector3d> positions_mm, double extent_mm) {
  constexpr std::size_t kMaxBlock = 32;
  const std::size_t n = positions_mm.size();
  PointBlocks b;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  for (const Eigen::Vector3d& p : positions_mm)
    lo = lo.cwiseMin(p);
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d g = (positions_mm[i] - lo) / extent_mm;
    std::uint64_t key = 0;
    for (int a = 0; a < 3; ++a) {
      const double c = std::clamp(g[a], 0.0, double{0x1fffff});
      key |= spread_bits(static_cast<std::uint64_t>(c)) << a;
    }
    keyed[i] = {key, static_cast<std::uint32_t>(i)};
  }
  std::sort(keyed.begin(), keyed.end());
  Eigen::AlignedBox3d box;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d& p = positions_mm[keyed[i].second];
    Eigen::AlignedBox3d grown = box;
    grown.extend(p);
    const bool full = !b.begin.empty() && i - b.begin.back() >= kMaxBlock;
    if (b.begin.empty() || full || grown.diagonal().norm() > extent_mm) {
      if (!b.begin.empty()) {
        b.centre.push_back(box.center());
        b.half_diagonal.push_back(0.5 * box.diagonal().norm());
      }
      b.begin.push_back(static_cast<std::uint32_t>(i));
      box = Eigen::AlignedBox3d(p, p);
    } else {
      box = grown;
    }
    b.order.push_back(keyed[i].second);
  }
  if (!b.begin.empty()) {
    b.centre.push_back(box.center());
    b.half_diagonal.push_back(0.5 * box.diagonal().norm());
  }
  b.begin.push_back(static_cast<std::uint32_t>(n));
  return b;
}

}  // namespace

namespace {

// hypot(x, y) for x, y >= 0: hypot(x, ±0) is x exactly (C Annex F), so the
// call (the costly part of a distance) is skipped where the point faces the
// flank or the bottom of the core.
double hypot_non_negative(double x, double y) {
  if (y == 0.0) return x;
  if (x == 0.0) return y;
  return std::hypot(x, y);
}

// The core in the (ρ, h) half-plane: |ρ| ≤ R − r, r ≤ h ≤ L. (qx, qy): how
// far P lies beyond it radially and axially.
struct CorePosition {
  double qx = 0.0, qy = 0.0, side = 0.0;
};

CorePosition core_position(const ToolShape& shape, double rho, double h) {
  const double r = shape.corner_radius_mm;
  const double hc = 0.5 * (r + shape.cutting_length_mm);
  const double hh = 0.5 * (shape.cutting_length_mm - r);
  return {rho - (shape.radius_mm - r), std::abs(h - hc) - hh, h >= hc ? 1.0 : -1.0};
}

double distance_from_core(const ToolShape& shape, const CorePosition& c) {
  if (c.qx > 0.0 || c.qy > 0.0)
    return hypot_non_negative(std::max(c.qx, 0.0), std::max(c.qy, 0.0)) - shape.corner_radius_mm;
  return std::max(c.qx, c.qy) - shape.corner_radius_mm;
}

// cutter_distance(...).distance_mm, without the normal.
double cutter_signed_distance(const ToolShape& shape, const Eigen::Vector3d& tip_mm,
                              const Eigen::Vector3d& axis, const Eigen::Vector3d& p_mm) {
  const Eigen::Vector3d d = p_mm - tip_mm;
  const double h = d.dot(axis);
  const Eigen::Vector3d w = d - h * axis;
  return distance_from_core(shape, core_position(shape, w.norm(), h));
}

}  // namespace

CutterDistance cutter_distance(const ToolShape& shape, const Eigen::Vector3d& tip_mm,
                               const Eigen::Vector3d& axis, const Eigen::Vector3d& p_mm) {
  const Eigen::Vector3d d = p_mm - tip_mm;
  const double h = d.dot(axis);
  const Eigen::Vector3d w = d - h * axis;
  const double rho = w.norm();
  const CorePosition c = core_position(shape, rho, h);
  const double dist = distance_from_core(shape, c);
  double nx = 0.0, ny = 0.0;
  if (c.qx > 0.0 || c.qy > 0.0) {
    const double ox = std::max(c.qx, 0.0), oy = std::max(c.qy, 0.0);
    const double len = hypot_non_negative(ox, oy);
    nx = ox / len;
    ny = c.side * oy / len;
  } else if (c.qx > c.qy) {
    nx = 1.0;
  } else {
    ny = c.side;
  }
  Eigen::Vector3d radial;
  if (rho > 1e-12) {
    radial = w / rho;
  } else {
    radial = axis.unitOrthogonal();
  }
  return {dist, (nx * radial + ny * axis).normalized()};
}

namespace {

// A sample within the contact tolerance of P, and its signed distance.
struct NearSample {
  std::uint32_t sample = 0;
  double distance_mm = 0.0;
};

// Of the samples within tolerance (`near`, any order) whose cutter normal
// faces P's normal (`faces`), those within tie of the closest: the earliest
// in the program, or per pass (run of consecutive samples) the one whose tip
// is nearest to p. The normal is tested only where it can change the choice:
// on the closest until one faces, then on those within tie of it.
template <class Faces>
void choose_samples(std::vector<NearSample>& near, const Faces& faces, const Eigen::Vector3d& p,
                    const ToolPath& path, const PlacementOptions& options,
                    std::vector<std::pair<std::uint32_t, double>>& chosen) {
  constexpr double kRejected = std::numeric_limits<double>::infinity();
  double best = kRejected;
  std::size_t found = near.size();  // the closest that faces
  while (found == near.size()) {
    std::size_t closest = near.size();
    for (std::size_t k = 0; k < near.size(); ++k) {
      if (std::abs(near[k].distance_mm) <
          (closest < near.size() ? std::abs(near[closest].distance_mm) : kRejected))
        closest = k;
    }
    if (closest == near.size()) return;
    if (faces(near[closest].sample)) {
      found = closest;
      best = std::abs(near[closest].distance_mm);
    } else {
      near[closest].distance_mm = kRejected;
    }
  }
  std::size_t kept = 0;
  for (std::size_t k = 0; k < near.size(); ++k) {
    const NearSample s = near[k];
    if (std::abs(s.distance_mm) > best + options.tie_mm) continue;
    if (k != found && !faces(s.sample)) continue;
    near[kept++] = s;
  }
  near.resize(kept);
  std::sort(near.begin(), near.end(),
            [](const NearSample& a, const NearSample& b) { return a.sample < b.sample; });
  if (!options.every_generating_pass) {
    chosen.push_back({near.front().sample, near.front().distance_mm});
    return;
  }
  std::uint32_t previous = 0;
  double nearest = 0.0;
  for (const NearSample& s : near) {
    const double tip_distance = (path.samples[s.sample].tip_mm - p).squaredNorm();
    if (chosen.empty() || s.sample != previous + 1) {
      chosen.push_back({s.sample, s.distance_mm});
      nearest = tip_distance;
    } else if (tip_distance < nearest) {
      chosen.back() = {s.sample, s.distance_mm};
      nearest = tip_distance;
    }
    previous = s.sample;
  }
}

}  // namespace

PlacementResult place_at_tool_centre(std::span<const Eigen::Vector3d> positions_mm,
                                     std::span<const Eigen::Vector3d> normals, const ToolPath& path,
                                     std::span<const ToolShape> shapes,
                                     const PlacementOptions& options) {
  if (positions_mm.size() != normals.size())
    throw std::invalid_argument("placement: one normal per point is needed");
  if (!(options.contact_tolerance_mm > 0.0) || !(options.tie_mm >= 0.0) ||
      !(options.max_normal_angle_deg > 0.0 && options.max_normal_angle_deg <= 90.0))
    throw std::invalid_argument("placement: bad options");
  std::map<std::int32_t, const ToolShape*> shape_of;
  for (const ToolShape& s : shapes) {
    check_shape(s);
    shape_of[s.tool] = &s;
  }
  std::map<std::int32_t, std::vector<std::uint32_t>> samples_of;
  for (std::size_t i = 0; i < path.samples.size(); ++i) {
    const ToolPathSample& s = path.samples[i];
    if (!shape_of.count(s.tool))
      throw std::invalid_argument("tool " + std::to_string(s.tool) + " cuts at program line " +
                                  std::to_string(s.line) + " but has no tool shape");
    samples_of[s.tool].push_back(static_cast<std::uint32_t>(i));
  }

  const std::size_t n = positions_mm.size();
  const double tol = options.contact_tolerance_mm;
  const double min_cos = std::cos(options.max_normal_angle_deg * std::numbers::pi / 180.0);
  PlacementResult out;
  out.cut.assign(n, 0);
  for (const auto& entry : samples_of) {
    // Named, not a structured binding: the lambdas below capture it (clang
    // before 16 cannot capture a binding; the fuzz build uses clang).
    const auto& tool = entry.first;
    const auto& samples = entry.second;
    const ToolShape& shape = *shape_of.at(tool);
    const ToolIndex ix = build_index(shape, path, samples, tol);
    // Per point, the chosen samples (one, or one per generating pass).
    std::vector<std::vector<std::pair<std::uint32_t, double>>> chosen(n);
    const double reach = shape.radius_mm + tol;
    // Per thread: the last block each chunk came up for.
    const std::size_t chunks = ix.chunk_begin.size() - 1;
    tbb::enumerable_thread_specific<std::vector<std::uint32_t>> last_block([&] {
      return std::vector<std::uint32_t>(chunks, std::numeric_limits<std::uint32_t>::max());
    });
    const PointBlocks blocks = point_blocks(positions_mm, shape.radius_mm);
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, blocks.centre.size(), 16),
        [&](const tbb::blocked_range<std::size_t>& range) {
          std::vector<std::uint32_t> near;
          std::vector<NearSample> within;
          std::vector<std::uint32_t>& seen = last_block.local();
          for (std::size_t block = range.begin(); block != range.end(); ++block) {
            near.clear();
            ix.tree.within(blocks.centre[block], ix.query_radius + blocks.half_diagonal[block],
                           near);
            // A chunk comes up once per probe near the block: keep it once.
            std::size_t kept = 0;
            for (const std::uint32_t q : near) {
              const std::uint32_t chunk = ix.probe_chunk[q];
              if (seen[chunk] == static_cast<std::uint32_t>(block)) continue;
              seen[chunk] = static_cast<std::uint32_t>(block);
              near[kept++] = chunk;
            }
            near.resize(kept);
            for (std::uint32_t b = blocks.begin[block]; b < blocks.begin[block + 1]; ++b) {
              const std::uint32_t p = blocks.order[b];
              within.clear();
              for (std::uint32_t chunk : near) {
                // Necessary for a member within reach: P within R + tol +
                // the chunk's spread of its first sample's core axis segment.
                const ToolPathSample& lead = path.samples[samples[ix.chunk_begin[chunk]]];
                const Eigen::Vector3d dl = positions_mm[p] - lead.tip_mm;
                const double hl =
                    std::clamp(dl.dot(lead.axis), shape.corner_radius_mm, shape.cutting_length_mm);
                const double reach_chunk = reach + ix.chunk_spread[chunk];
                if ((dl - hl * lead.axis).squaredNorm() > reach_chunk * reach_chunk) continue;
                for (std::uint32_t m = ix.chunk_begin[chunk]; m < ix.chunk_begin[chunk + 1]; ++m) {
                  const std::uint32_t sample = samples[m];
                  const ToolPathSample& s = path.samples[sample];
                  // Necessary for |distance| <= tol: P within R + tol of the
                  // core's axis segment. Cheaper than the exact distance.
                  const Eigen::Vector3d d = positions_mm[p] - s.tip_mm;
                  const double h =
                      std::clamp(d.dot(s.axis), shape.corner_radius_mm, shape.cutting_length_mm);
                  if ((d - h * s.axis).squaredNorm() > reach * reach) continue;
                  const double distance =
                      cutter_signed_distance(shape, s.tip_mm, s.axis, positions_mm[p]);
                  if (std::abs(distance) <= tol) within.push_back({sample, distance});
                }
              }
              // The cutter normal just inside the material: unambiguous where P lies
              // on the rim of a flat end mill, where its bottom meets its flank.
              const Eigen::Vector3d inside = positions_mm[p] - 0.5 * tol * normals[p];
              const auto faces = [&](std::uint32_t sample) {
                const ToolPathSample& s = path.samples[sample];
                return -cutter_distance(shape, s.tip_mm, s.axis, inside).normal.dot(normals[p]) >=
                       min_cos;
              };
              choose_samples(within, faces, positions_mm[p], path, options, chosen[p]);
            }
          }
        });
    ToolPlacement tp;
    tp.tool = tool;
    for (std::size_t p = 0; p < n; ++p) {
      for (const auto& [sample, distance] : chosen[p]) {
        const ToolPathSample& s = path.samples[sample];
        tp.points.push_back({static_cast<std::uint32_t>(p), sample, s.tip_mm, s.axis, distance});
        out.cut[p] = 1;
      }
    }
    out.tools.push_back(std::move(tp));
  }
  out.uncut_points = std::count(out.cut.begin(), out.cut.end(), std::uint8_t{0});
  return out;
}

}  // namespace truecut::offline
