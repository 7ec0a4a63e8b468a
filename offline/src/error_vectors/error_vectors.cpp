#include "truecut/offline/error_vectors.hpp"

#include <algorithm>
#include <cmath>

namespace truecut::offline {

std::string_view to_string(ErrorStatus status) {
  switch (status) {
    case ErrorStatus::kValid:
      return "valid";
    case ErrorStatus::kNoHit:
      return "no_hit";
    case ErrorStatus::kGrazing:
      return "grazing";
    case ErrorStatus::kBackFace:
      return "back_face";
    case ErrorStatus::kNominalEdge:
      return "nominal_edge";
    case ErrorStatus::kTooFewPoints:
      return "too_few_points";
    case ErrorStatus::kIllConditioned:
      return "ill_conditioned";
    case ErrorStatus::kBeyondSphereReach:
      return "beyond_sphere_reach";
    case ErrorStatus::kPlaneTilted:
      return "plane_tilted";
  }
  return "?";
}

std::string_view to_string(SphereCase c) {
  switch (c) {
    case SphereCase::kNone:
      return "none";
    case SphereCase::kSurface:
      return "surface";
    case SphereCase::kEdge:
      return "edge";
    case SphereCase::kCorner:
      return "corner";
    case SphereCase::kMulti:
      return "multi";
  }
  return "?";
}

std::vector<std::uint8_t> ErrorVectors::valid_mask() const {
  std::vector<std::uint8_t> mask(size());
  for (std::size_t i = 0; i < size(); ++i)
    mask[i] = valid(i) ? 1 : 0;
  return mask;
}

ErrorVectorSummary summarize(const ErrorVectors& e, double radius_mm) {
  ErrorVectorSummary s;
  s.points = e.size();
  double sum = 0.0, sum2 = 0.0, len2 = 0.0;
  for (std::size_t i = 0; i < e.size(); ++i) {
    ++s.by_status[static_cast<int>(e.status[i])];
    if (!e.sphere_case.empty()) ++s.by_case[static_cast<int>(e.sphere_case[i])];
    if (!e.valid(i)) continue;
    ++s.valid;
    sum += e.normal_mm[i];
    sum2 += e.normal_mm[i] * e.normal_mm[i];
    len2 += e.vectors_mm[i].squaredNorm();
    s.max_length_mm = std::max(s.max_length_mm, e.vectors_mm[i].norm());
  }
  if (s.valid > 0) {
    const double n = static_cast<double>(s.valid);
    s.mean_normal_mm = sum / n;
    s.rms_normal_mm = std::sqrt(sum2 / n);
    s.rms_length_mm = std::sqrt(len2 / n);
  }
  if (!e.points_in_sphere.empty() && radius_mm > 0.0) {
    const double area = M_PI * radius_mm * radius_mm;
    std::vector<double> density(e.points_in_sphere.size());
    for (std::size_t i = 0; i < density.size(); ++i) {
      density[i] = e.points_in_sphere[i] / e.scan_fraction / area;
      if (density[i] < kRecommendedDensityPerMm2) ++s.below_recommended_density;
    }
    auto mid = density.begin() + static_cast<std::ptrdiff_t>(density.size() / 2);
    std::nth_element(density.begin(), mid, density.end());
    s.median_density_per_mm2 = *mid;
  }
  return s;
}

}  // namespace truecut::offline
