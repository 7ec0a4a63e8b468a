// Normal-dexel material removal. Dexels sit on the nominal part surface (an
// even sampling of its triangles); each holds the material height h along its
// outward surface normal. A cutter swept between two poses lowers h where its
// solid meets the dexel line. See docs/cutting.md for the model and its
// limits.
//
//   auto model = DexelModel::build(mesh, triangle_surface_ids, stock, options);
//   Engagement e = model.cut(shape, pose_from, pose_to);   // no allocation
//   model.write_machined(dir);                             // machined.stl/.ply
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <vector>

#include "truecut/offline/mesh.hpp"
#include "truecut/sim/benchmark_parts.hpp"
#include "truecut/sim/cutting/cutter.hpp"

namespace truecut::sim::cutting {

// The dexel model's size: by default at most this many dexels, and never
// more than kMaxDexels (the index shares a word with flags). A run takes
// about kBytesPerDexel each (measured: the implant at 0.05 and 0.025 mm,
// 0.55 and 2.1 million dexels, 211 and 741 MB peak); benchmark004 at the
// default 0.1 mm has 5.4 million.
inline constexpr std::size_t kDefaultMaxDexels = 10'000'000;
inline constexpr std::size_t kMaxDexels = 50'000'000;
inline constexpr std::size_t kBytesPerDexel = 350;

struct DexelOptions {
  double spacing_mm = 0.1;     // longest distance between neighbouring dexels of a triangle
  double max_stock_mm = 3.0;   // initial h is capped here (material beyond it is ignored)
  double max_depth_mm = 0.5;   // how far below the nominal surface a dexel can be cut (gouge)
  double tolerance_mm = 1e-3;  // sweep sampling error (between sub-step instances)
  int max_substeps = 4096;     // per cut() call; a longer move is sampled more coarsely
  double cell_mm = 0;          // spatial grid cell; 0 = automatic
  std::vector<int> surfaces;   // surface ids to model; empty = all
  // The dexels the model may have, estimated from the modelled triangles and
  // the spacing before any is made (a nominal in µm instead of mm asked for
  // 2.8 GB and more); at most kMaxDexels.
  std::size_t max_dexels = kDefaultMaxDexels;
  // Threads that cut (the caller and threads − 1 helper threads the model
  // starts); 0 = one per hardware thread. The result is the same bit for bit
  // whatever the number.
  int threads = 1;
};

namespace detail {
class WorkerPool;
// The model's helper threads; a copy of the model starts its own.
class CutThreads {
 public:
  CutThreads() noexcept;
  explicit CutThreads(int threads);
  CutThreads(const CutThreads& other);
  CutThreads& operator=(const CutThreads& other);
  CutThreads(CutThreads&&) noexcept;
  CutThreads& operator=(CutThreads&&) noexcept;
  ~CutThreads();
  WorkerPool* get() const noexcept { return pool_.get(); }
  int threads() const noexcept;

 private:
  std::unique_ptr<WorkerPool> pool_;
};
}  // namespace detail

// What one cut() removed. Weights are removed volumes (Δh × dexel area).
struct Engagement {
  double removed_mm3 = 0;
  // Mean outward surface normal of the removed material (unit; zero when
  // nothing was removed). It points from the part towards the tool.
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  Eigen::Vector3d contact_mm = Eigen::Vector3d::Zero();  // centroid of the removed material
  // Engaged height along the tool axis, from the tip of the instance that cut
  // (mm); both 0 when nothing was removed.
  double axial_min_mm = 0;
  double axial_max_mm = 0;
  std::uint32_t dexels_touched = 0;  // distinct dexels lowered
  std::uint32_t substeps = 0;        // tool instances tested
  bool substeps_capped = false;      // the move needed more than max_substeps
  bool invalid_input = false;        // shape or pose not valid(): nothing was cut
};

class DexelModel {
 public:
  DexelModel() = default;
  // `triangle_surface` gives the surface id of each triangle of `nominal`
  // (outward normals, mm). Throws std::invalid_argument on bad options or a
  // size mismatch, std::length_error beyond 50 million dexels.
  static DexelModel build(const offline::TriangleMesh& nominal,
                          std::span<const int> triangle_surface, std::span<const StockBox> stock,
                          const DexelOptions& options = {});

  // Sweeps the cutter from `from` to `to` (tip moves linearly, the axis turns
  // at constant rate in the plane of the two axes), sub-stepped so the swept
  // surface is sampled to options.tolerance_mm. With include_start = false the
  // instance at `from` is skipped (it was the previous call's end). Allocates
  // nothing, throws nothing; work is bounded by max_substeps × the dexels in
  // the grid cells under one tool instance.
  Engagement cut(const CutterShape& shape, const CutterPose& from, const CutterPose& to,
                 bool include_start = true) noexcept;

  // How many tool instances cut() places between `from` and `to` to sample
  // the swept solid to options.tolerance_mm (before rounding up; ≤ 1 means
  // the instance at `to` alone is within the tolerance of the sweep).
  double substeps_needed(const CutterShape& shape, const CutterPose& from,
                         const CutterPose& to) const noexcept;

  // Nominal topology subdivided at the dexels, vertices at p + h·n; triangles
  // of surfaces that are not modelled are copied unchanged. A dexel on a
  // sharp edge whose line holds no surface point (cut through to its floor,
  // or material up to the stock cap) takes the vertex of a partner on the
  // other face that has one: the corner where the machined faces meet.
  offline::TriangleMesh machined_mesh() const;
  // machined.stl (binary) and machined.ply (binary) into `dir`, each atomic.
  void write_machined(const std::filesystem::path& dir, const std::string& comment = {}) const;

  std::size_t size() const { return line_.size(); }
  const Eigen::Vector3d& position(std::size_t i) const { return position_[i]; }
  const Eigen::Vector3d& normal(std::size_t i) const { return normal_[i]; }
  double height_mm(std::size_t i) const { return line_[i].height; }
  double initial_height_mm(std::size_t i) const { return initial_height_[i]; }
  double area_mm2(std::size_t i) const { return area_[i]; }
  int surface(std::size_t i) const { return surface_[i]; }
  // Σ (initial h − h) × area.
  double removed_total_mm3() const;
  // Threads that cut (DexelOptions::threads, resolved).
  int threads() const noexcept { return threads_.threads(); }
  // Jobs shared with the helper threads so far, and how the hand-over went
  // (worker_pool.hpp): for the benchmark.
  struct ThreadStats {
    std::uint64_t jobs = 0, chunks = 0, worker_chunks = 0, wakes = 0, wait_spins = 0;
  };
  ThreadStats thread_stats() const noexcept;

 private:
  // `centre_motion`: unit direction in which the ball centre moves during
  // this sweep (zero when it stands still), for the dexels' swept surfaces.
  void apply_instance(const CutterShape& shape, const Eigen::Vector3d& tip,
                      const Eigen::Vector3d& axis, const Eigen::Vector3d& centre_motion,
                      Engagement& e, Eigen::Vector3d& normal_sum,
                      Eigen::Vector3d& contact_sum) noexcept;
  struct Instance;
  // Tests and lowers the dexels of one chunk of grid rows (any thread).
  void cut_chunk(const Instance& in, std::uint32_t chunk, int thread) noexcept;
  // Whether no line tested in grid cell (x, y, z) can meet the instance's
  // tool (cell_reach_, detail::box_misses_tool): the cell is skipped.
  bool cell_misses_tool(const Instance& in, std::size_t cell, int x, int y, int z) const noexcept;
  // Keeps the surface the instance swept at dexel d, just lowered to new_h
  // (to_floor: cut through, no surface), for machined_mesh()'s cusps.
  void record_swept(const Instance& in, std::uint32_t d, const Eigen::Vector3d& p,
                    const Eigen::Vector3d& n, double new_h, bool to_floor) noexcept;

  // Per dexel (structure of arrays).
  std::vector<Eigen::Vector3d> position_;     // on the nominal surface (output mesh)
  std::vector<Eigen::Vector3d> line_origin_;  // where the line is tested (inset on sharp edges)
  std::vector<Eigen::Vector3d> normal_;
  std::vector<double> initial_height_;
  std::vector<double> floor_;  // −max_depth_mm
  std::vector<double> area_;
  std::vector<int> surface_;
  // Next dexel at the same position with another normal (a cycle through the
  // dexels of a sharp edge or corner); its own index when there is none.
  std::vector<std::uint32_t> partner_;
  // The local swept surface at each dexel, from the tool instance that last
  // lowered it (sweep_kind_): kSweptBall, the tube of radius sweep_radius_
  // swept by the ball centre position_ + sweep_point_ moving along unit
  // sweep_vector_ (zero: the ball itself); kSweptPlane, the plane through
  // position_ + sweep_point_ with unit normal sweep_vector_ out of the
  // material (a flank or a flat bottom); kSweptNone: not cut, cut to the
  // floor, or by a bull-nose corner. machined_mesh() intersects the swept
  // surfaces of neighbouring dexels to put the cusp between two passes
  // where it is (dexel_mesh.cpp).
  static constexpr std::uint8_t kSweptNone = 0, kSweptBall = 1, kSweptPlane = 2;
  std::vector<std::uint8_t> sweep_kind_;
  std::vector<Eigen::Vector3f> sweep_point_;
  std::vector<Eigen::Vector3f> sweep_vector_;
  std::vector<float> sweep_radius_;
  // What a tool instance reads of each dexel it tests, on one cache line:
  // line_origin_, normal_ and floor_ (copies, made at build) and the
  // material height h (the only copy: cut() lowers it here).
  struct alignas(64) Line {
    Eigen::Vector3d origin;
    Eigen::Vector3d normal;
    double floor;
    double height;
  };
  std::vector<Line> line_;
  std::vector<std::uint32_t> stamp_;  // last cut() that lowered the dexel
  std::uint32_t epoch_ = 0;
  // One tool instance's work: grid rows in chunks, each chunk lowering
  // dexels on one thread and listing them (their index in lowered_[thread],
  // their height before in old_height_); the sums are then taken over the
  // chunks in order, so they do not depend on which thread ran which chunk.
  struct ChunkResult {
    std::uint32_t thread = 0, begin = 0, count = 0, touched = 0;
  };
  // At most this many chunks of consecutive rows per instance: enough to share
  // between a few threads, few enough that empty rows cost little.
  static constexpr std::uint32_t kMaxChunks = 32;
  std::vector<ChunkResult> chunks_;
  std::vector<std::vector<std::uint32_t>> lowered_;
  struct alignas(64) Cursor {  // per thread, on its own cache line
    std::uint32_t value = 0;
  };
  std::vector<Cursor> cursor_;
  std::vector<double> old_height_;
  detail::CutThreads threads_;
  // Output topology: triangles over dexels, plus the unmodelled triangles.
  std::vector<offline::Triangle> triangles_;
  std::vector<Eigen::Vector3d> fixed_vertices_;
  std::vector<offline::Triangle> fixed_triangles_;
  // Uniform grid: dexel indices per cell (CSR); a dexel is listed in every
  // cell of the box of cells its line [p + floor·n, p + h0·n] touches. The
  // top bits of an entry say whether the cell is the first of that box along
  // x, y, z (kFirstX…): a tool instance tests a dexel in the first cell of
  // its box that lies in the instance's box of cells, so exactly once; the
  // dexels it lowers are summed in the order of (that cell, dexel index).
  Eigen::Vector3d grid_origin_mm_ = Eigen::Vector3d::Zero();
  double cell_mm_ = 1;
  Eigen::Vector3i grid_dims_ = Eigen::Vector3i::Zero();
  std::vector<std::uint32_t> cell_start_;
  std::vector<std::uint32_t> cell_items_;
  // Per cell, the end of its leading entries that start their box there
  // (all three kFirst flags); the others follow, each part in index order.
  std::vector<std::uint32_t> cell_home_end_;
  // Per cell, how far up x, y and z (bits 0-7, 8-15, 16-23, in eighths of a
  // cell from its low corner, rounded up; kReachUnbounded beyond 254) the lines of
  // its entries reach: every part of a line tested in the cell that an
  // instance can touch lies in [corner, corner + reach], so a cell whose box
  // misses the tool is skipped (detail::box_misses_tool).
  std::vector<std::uint32_t> cell_reach_;
  static constexpr std::uint32_t kReachUnbounded = 255;
  static constexpr std::uint32_t kFirstX = 1u << 31, kFirstY = 1u << 30, kFirstZ = 1u << 29,
                                 kIndexMask = kFirstZ - 1;
  DexelOptions options_;
};

}  // namespace truecut::sim::cutting
