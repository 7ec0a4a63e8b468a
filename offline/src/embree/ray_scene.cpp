// The Embree adapter: the only translation unit that includes rtcore.h.
#include "truecut/offline/ray_scene.hpp"

#include "truecut/offline/mesh_geometry.hpp"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <mutex>

namespace truecut::offline {

namespace {

constexpr unsigned kAllMask = 0xffffffffu;  // one geometry, every ray sees it
constexpr std::size_t kRaysPerTask = 1024;
// Embree asserts (and ends the process) on a ray it cannot hold in float: a
// NaN, or a coordinate beyond 1.8e18. Queries farther than this from the
// scene's centre, or not finite, are refused before any reaches it; no
// query of a real part comes near (a CMM point at x = 1e20 mm did).
constexpr double kMaxQueryOffsetMm = 1e9;

std::string format_vector(const Eigen::Vector3d& v) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%g, %g, %g)", v.x(), v.y(), v.z());
  return buf;
}

bool usable_offset(const Eigen::Vector3d& offset_mm) {
  return offset_mm.allFinite() && offset_mm.cwiseAbs().maxCoeff() <= kMaxQueryOffsetMm;
}

const char* error_name(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE:
      return "RTC_ERROR_NONE";
    case RTC_ERROR_UNKNOWN:
      return "RTC_ERROR_UNKNOWN";
    case RTC_ERROR_INVALID_ARGUMENT:
      return "RTC_ERROR_INVALID_ARGUMENT";
    case RTC_ERROR_INVALID_OPERATION:
      return "RTC_ERROR_INVALID_OPERATION";
    case RTC_ERROR_OUT_OF_MEMORY:
      return "RTC_ERROR_OUT_OF_MEMORY";
    case RTC_ERROR_UNSUPPORTED_CPU:
      return "RTC_ERROR_UNSUPPORTED_CPU";
    case RTC_ERROR_CANCELLED:
      return "RTC_ERROR_CANCELLED";
  }
  return "RTC_ERROR_?";
}

// Embree calls back from its own threads and must not see an exception, so
// the callback only records; check() turns the record into an exception on
// the caller's side of the API.
struct ErrorSink {
  std::mutex mutex;
  std::atomic<bool> any{false};
  std::string first;

  static void callback(void* user, RTCError code, const char* text) {
    auto* sink = static_cast<ErrorSink*>(user);
    std::lock_guard lock(sink->mutex);
    if (!sink->any.load()) {
      sink->first = std::string("Embree ") + error_name(code) + ": " + (text ? text : "");
      sink->any.store(true);
    }
  }

  void check(const char* during) {
    if (!any.load()) return;
    std::lock_guard lock(mutex);
    throw RayEngineError(first + " (during " + during + ")");
  }
};

}  // namespace

struct RayScene::Impl {
  std::vector<Eigen::Vector3d> vertices_mm;  // world frame, double
  std::vector<Triangle> triangles;
  Eigen::Vector3d origin_mm = Eigen::Vector3d::Zero();
  double half_diagonal_mm = 0.0;
  ErrorSink errors;
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  bool masks_supported = false;
  bool posed = false;  // world_from_mesh is not the identity
  Eigen::Isometry3d world_from_mesh = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d mesh_from_world = Eigen::Isometry3d::Identity();

  // A world ray in the mesh frame (distances along it are the same).
  Ray to_mesh(const Ray& ray) const {
    if (!posed) return ray;
    Ray r = ray;
    r.origin_mm = mesh_from_world * ray.origin_mm;
    r.direction = mesh_from_world.linear() * ray.direction;
    return r;
  }
  // Throws RayEngineError for a ray Embree cannot take (kMaxQueryOffsetMm).
  void check_ray(const Ray& world, std::size_t i, std::size_t n) const {
    const Ray r = to_mesh(world);
    const double d = r.direction.norm();
    const bool ok = usable_offset(r.origin_mm - origin_mm) && r.direction.allFinite() && d > 0.0 &&
                    d <= kMaxQueryOffsetMm && !std::isnan(r.t_min_mm) && !std::isnan(r.t_max_mm);
    if (ok) return;
    throw RayEngineError("ray " + std::to_string(i + 1) + " of " + std::to_string(n) + ": origin " +
                         format_vector(world.origin_mm) + " mm, direction " +
                         format_vector(world.direction) +
                         ": not finite, zero or farther than 1e9 mm from the mesh; the ray "
                         "engine cannot take it");
  }
  // Throws RayEngineError for a query point Embree cannot take.
  void check_point(const Eigen::Vector3d& p_mesh) const {
    if (usable_offset(p_mesh - origin_mm)) return;
    throw RayEngineError("query point " + format_vector(p_mesh) +
                         " mm: not finite or farther than 1e9 mm from the mesh; the ray engine "
                         "cannot take it");
  }

  // A hit found with to_mesh(ray): its normal back in the world frame.
  void to_world(RayHit& hit) const {
    if (posed && hit.hit()) hit.normal = world_from_mesh.linear() * hit.normal;
  }

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }

  void fill_ray(RTCRay& r, const Ray& ray) const {
    const Eigen::Vector3d o = ray.origin_mm - origin_mm;
    r.org_x = static_cast<float>(o.x());
    r.org_y = static_cast<float>(o.y());
    r.org_z = static_cast<float>(o.z());
    r.dir_x = static_cast<float>(ray.direction.x());
    r.dir_y = static_cast<float>(ray.direction.y());
    r.dir_z = static_cast<float>(ray.direction.z());
    r.tnear = static_cast<float>(ray.t_min_mm);
    r.tfar = static_cast<float>(std::min(ray.t_max_mm, 3.0e38));
    r.time = 0.0f;
    r.mask = kAllMask;
    r.id = 0;
    r.flags = 0;
  }

  // Recomputes the hit on triangle t in double: intersection with the
  // triangle's plane, barycentrics of that point, unit normal.
  void finish(const Ray& ray, std::uint32_t t, float t_embree, float u, float v,
              const Eigen::Vector3d& ng_embree, bool refine, RayHit& hit) const {
    hit.triangle = t;
    if (!refine) {
      hit.distance_mm = t_embree;
      hit.u = u;
      hit.v = v;
      hit.normal = ng_embree.normalized();
      return;
    }
    const auto& [ia, ib, ic] = triangles[t];
    const Eigen::Vector3d& a = vertices_mm[ia];
    const Eigen::Vector3d e1 = vertices_mm[ib] - a, e2 = vertices_mm[ic] - a;
    const Eigen::Vector3d n = e1.cross(e2);
    const double denom = n.dot(ray.direction);
    hit.distance_mm = denom != 0.0 ? n.dot(a - ray.origin_mm) / denom : double(t_embree);
    const Eigen::Vector3d w = ray.origin_mm + hit.distance_mm * ray.direction - a;
    const double d11 = e1.dot(e1), d12 = e1.dot(e2), d22 = e2.dot(e2);
    const double dw1 = w.dot(e1), dw2 = w.dot(e2);
    const double det = d11 * d22 - d12 * d12;
    hit.u = det != 0.0 ? (d22 * dw1 - d12 * dw2) / det : double(u);
    hit.v = det != 0.0 ? (d11 * dw2 - d12 * dw1) / det : double(v);
    hit.normal = n.normalized();
  }
};

RayScene::RayScene(const TriangleMesh& mesh) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.vertices_mm = mesh.vertices_mm;
  m.triangles = mesh.triangles;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (std::size_t i = 0; i < m.vertices_mm.size(); ++i) {
    const Eigen::Vector3d& p = m.vertices_mm[i];
    if (!p.allFinite()) throw RayEngineError("vertex " + std::to_string(i) + " is not finite");
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    for (std::uint32_t v : m.triangles[t]) {
      if (v >= m.vertices_mm.size()) {
        throw RayEngineError("triangle " + std::to_string(t) + " refers to vertex " +
                             std::to_string(v) + ", but the mesh has " +
                             std::to_string(m.vertices_mm.size()) + " vertices");
      }
    }
  }
  if (!m.vertices_mm.empty()) {
    m.origin_mm = 0.5 * (lo + hi);
    m.half_diagonal_mm = 0.5 * (hi - lo).norm();
  }

  m.device = rtcNewDevice(nullptr);
  if (!m.device) {
    throw RayEngineError(std::string("Embree device creation failed: ") +
                         error_name(rtcGetDeviceError(nullptr)));
  }
  rtcSetDeviceErrorFunction(m.device, &ErrorSink::callback, &m.errors);
  m.masks_supported = rtcGetDeviceProperty(m.device, RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED) != 0;

  m.scene = rtcNewScene(m.device);
  // ROBUST: no arithmetic shortcuts that let rays slip between neighbours.
  rtcSetSceneFlags(m.scene, RTC_SCENE_FLAG_ROBUST);
  // LOW: Embree's Morton-code BVH builder. The scene is built once for a
  // few 10^5 rays, so build time dominates (offline_stages_bench); the hits
  // do not depend on the BVH.
  rtcSetSceneBuildQuality(m.scene, RTC_BUILD_QUALITY_LOW);
  RTCGeometry geom = rtcNewGeometry(m.device, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetGeometryBuildQuality(geom, RTC_BUILD_QUALITY_LOW);
  // rtcSetNewGeometryBuffer pads the buffer for Embree's 16-byte loads.
  auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), m.vertices_mm.size()));
  auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), m.triangles.size()));
  m.errors.check("buffer allocation");
  if ((!vb && !m.vertices_mm.empty()) || (!ib && !m.triangles.empty())) {
    rtcReleaseGeometry(geom);
    throw RayEngineError("Embree returned no geometry buffer");
  }
  for (std::size_t i = 0; i < m.vertices_mm.size(); ++i) {
    const Eigen::Vector3d p = m.vertices_mm[i] - m.origin_mm;
    for (int k = 0; k < 3; ++k)
      vb[3 * i + k] = static_cast<float>(p[k]);
  }
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k)
      ib[3 * t + k] = m.triangles[t][k];
  }
  rtcSetGeometryMask(geom, kAllMask);
  rtcCommitGeometry(geom);
  rtcAttachGeometryByID(m.scene, geom, 0);
  rtcReleaseGeometry(geom);
  rtcCommitScene(m.scene);
  m.errors.check("scene build");
}

RayScene::~RayScene() = default;
RayScene::RayScene(RayScene&&) noexcept = default;
RayScene& RayScene::operator=(RayScene&&) noexcept = default;

const Eigen::Vector3d& RayScene::local_origin_mm() const {
  return impl_->origin_mm;
}
std::size_t RayScene::triangle_count() const {
  return impl_->triangles.size();
}
const Triangle& RayScene::triangle(std::uint32_t t) const {
  return impl_->triangles.at(t);
}
bool RayScene::ray_masks_supported() const {
  return impl_->masks_supported;
}

void RayScene::intersect(std::span<const Ray> rays, std::span<RayHit> hits,
                         const RayQueryOptions& options) const {
  if (hits.size() != rays.size()) {
    throw RayEngineError(std::to_string(rays.size()) + " rays but room for " +
                         std::to_string(hits.size()) + " hits");
  }
  const Impl& m = *impl_;
  for (std::size_t i = 0; i < rays.size(); ++i)
    m.check_ray(rays[i], i, rays.size());
  const bool refine = options.refine_in_double;
  auto miss = [](RayHit& h) { h = RayHit{}; };

  switch (options.batch) {
    case RayBatch::kSingle:
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), kRaysPerTask),
                        [&](const tbb::blocked_range<std::size_t>& r) {
                          RTCIntersectContext ctx;
                          rtcInitIntersectContext(&ctx);
                          for (std::size_t i = r.begin(); i != r.end(); ++i) {
                            const Ray local = m.to_mesh(rays[i]);
                            RTCRayHit rh;
                            m.fill_ray(rh.ray, local);
                            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                            rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
                            rtcIntersect1(m.scene, &ctx, &rh);
                            if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
                              miss(hits[i]);
                              continue;
                            }
                            m.finish(local, rh.hit.primID, rh.ray.tfar, rh.hit.u, rh.hit.v,
                                     {rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z}, refine, hits[i]);
                            m.to_world(hits[i]);
                          }
                        });
      break;
    case RayBatch::kPacket16: {
      const std::size_t packets = (rays.size() + 15) / 16;
      tbb::parallel_for(
          tbb::blocked_range<std::size_t>(0, packets, kRaysPerTask / 16),
          [&](const tbb::blocked_range<std::size_t>& r) {
            RTCIntersectContext ctx;
            rtcInitIntersectContext(&ctx);
            std::array<Ray, 16> local;
            for (std::size_t p = r.begin(); p != r.end(); ++p) {
              RTCRayHit16 rh;
              alignas(64) int valid[16];
              const std::size_t base = 16 * p;
              for (std::size_t k = 0; k < 16; ++k) {
                const std::size_t i = base + k;
                valid[k] = i < rays.size() ? -1 : 0;
                local[k] = m.to_mesh(rays[std::min(i, rays.size() - 1)]);
                RTCRay one;
                m.fill_ray(one, local[k]);
                rh.ray.org_x[k] = one.org_x;
                rh.ray.org_y[k] = one.org_y;
                rh.ray.org_z[k] = one.org_z;
                rh.ray.dir_x[k] = one.dir_x;
                rh.ray.dir_y[k] = one.dir_y;
                rh.ray.dir_z[k] = one.dir_z;
                rh.ray.tnear[k] = one.tnear;
                rh.ray.tfar[k] = one.tfar;
                rh.ray.time[k] = one.time;
                rh.ray.mask[k] = one.mask;
                rh.ray.id[k] = static_cast<unsigned>(k);
                rh.ray.flags[k] = 0;
                rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
                rh.hit.primID[k] = RTC_INVALID_GEOMETRY_ID;
              }
              rtcIntersect16(valid, m.scene, &ctx, &rh);
              for (std::size_t k = 0; k < 16 && base + k < rays.size(); ++k) {
                const std::size_t i = base + k;
                if (rh.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID) {
                  miss(hits[i]);
                  continue;
                }
                m.finish(local[k], rh.hit.primID[k], rh.ray.tfar[k], rh.hit.u[k], rh.hit.v[k],
                         {rh.hit.Ng_x[k], rh.hit.Ng_y[k], rh.hit.Ng_z[k]}, refine, hits[i]);
                m.to_world(hits[i]);
              }
            }
          });
      break;
    }
    case RayBatch::kStream:
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), kRaysPerTask),
                        [&](const tbb::blocked_range<std::size_t>& r) {
                          RTCIntersectContext ctx;
                          rtcInitIntersectContext(&ctx);
                          std::vector<RTCRayHit> block(r.size());
                          std::vector<Ray> local(r.size());
                          for (std::size_t i = r.begin(); i != r.end(); ++i) {
                            RTCRayHit& rh = block[i - r.begin()];
                            local[i - r.begin()] = m.to_mesh(rays[i]);
                            m.fill_ray(rh.ray, local[i - r.begin()]);
                            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                            rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
                          }
                          rtcIntersect1M(m.scene, &ctx, block.data(),
                                         static_cast<unsigned>(block.size()), sizeof(RTCRayHit));
                          for (std::size_t i = r.begin(); i != r.end(); ++i) {
                            const RTCRayHit& rh = block[i - r.begin()];
                            if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
                              miss(hits[i]);
                              continue;
                            }
                            m.finish(local[i - r.begin()], rh.hit.primID, rh.ray.tfar, rh.hit.u,
                                     rh.hit.v, {rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z}, refine,
                                     hits[i]);
                            m.to_world(hits[i]);
                          }
                        });
      break;
  }
  impl_->errors.check("ray intersection");
}

namespace {

template <class Found>
struct ProximityQuery {
  const std::vector<Eigen::Vector3d>* vertices;
  const std::vector<Triangle>* triangles;
  Eigen::Vector3d p;
  double r2;
  std::vector<Found>* out;
};

void keep(std::vector<std::uint32_t>& out, std::uint32_t triangle, const Eigen::Vector3d&) {
  out.push_back(triangle);
}
void keep(std::vector<RayScene::NearTriangle>& out, std::uint32_t triangle,
          const Eigen::Vector3d& closest_mm) {
  out.push_back({triangle, closest_mm});
}

template <class Found>
bool collect_triangle(RTCPointQueryFunctionArguments* args) {
  auto* q = static_cast<ProximityQuery<Found>*>(args->userPtr);
  const auto& [a, b, c] = (*q->triangles)[args->primID];
  const auto& v = *q->vertices;
  const Eigen::Vector3d x = closest_point_on_triangle(q->p, v[a], v[b], v[c]);
  if ((x - q->p).squaredNorm() <= q->r2) keep(*q->out, args->primID, x);
  return false;  // the query radius is left as it is
}

std::uint32_t triangle_of(std::uint32_t t) {
  return t;
}
std::uint32_t triangle_of(const RayScene::NearTriangle& t) {
  return t.triangle;
}

}  // namespace

template <class Found>
void RayScene::collect_within(const Eigen::Vector3d& p, double radius_mm,
                              std::vector<Found>& out) const {
  const Impl& m = *impl_;
  m.check_point(p);
  const std::size_t first = out.size();
  ProximityQuery<Found> q{&m.vertices_mm, &m.triangles, p, radius_mm * radius_mm, &out};
  const Eigen::Vector3d local = p - m.origin_mm;
  RTCPointQuery query;
  query.x = static_cast<float>(local.x());
  query.y = static_cast<float>(local.y());
  query.z = static_cast<float>(local.z());
  query.time = 0.0f;
  // Padded by far more than the float rounding of the query point and the
  // vertices, so Embree cannot cut off a triangle the exact test keeps.
  query.radius =
      static_cast<float>(radius_mm * (1.0 + 1e-5) + 1e-6 * (m.half_diagonal_mm + local.norm()));
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  rtcPointQuery(m.scene, &query, &context, &collect_triangle<Found>, &q);
  const auto by_triangle = [](const Found& x, const Found& y) {
    return triangle_of(x) < triangle_of(y);
  };
  std::sort(out.begin() + first, out.end(), by_triangle);
  out.erase(
      std::unique(out.begin() + first, out.end(),
                  [](const Found& x, const Found& y) { return triangle_of(x) == triangle_of(y); }),
      out.end());
  impl_->errors.check("point query");
}

void RayScene::set_world_from_mesh(const Eigen::Isometry3d& world_from_mesh) {
  if (!world_from_mesh.matrix().allFinite())
    throw RayEngineError("the scene's placement is not finite");
  Impl& m = *impl_;
  m.world_from_mesh = world_from_mesh;
  m.mesh_from_world = world_from_mesh.inverse();
  m.posed = world_from_mesh.matrix() != Eigen::Matrix4d::Identity();
}

void RayScene::triangles_within(const Eigen::Vector3d& p_world, double radius_mm,
                                std::vector<std::uint32_t>& out) const {
  const Impl& m = *impl_;
  collect_within(m.posed ? Eigen::Vector3d(m.mesh_from_world * p_world) : p_world, radius_mm, out);
}

void RayScene::triangles_within(const Eigen::Vector3d& p_world, double radius_mm,
                                std::vector<NearTriangle>& out) const {
  const Impl& m = *impl_;
  const std::size_t first = out.size();
  collect_within(m.posed ? Eigen::Vector3d(m.mesh_from_world * p_world) : p_world, radius_mm, out);
  if (m.posed)
    for (std::size_t i = first; i < out.size(); ++i)
      out[i].closest_mm = m.world_from_mesh * out[i].closest_mm;
}

}  // namespace truecut::offline
