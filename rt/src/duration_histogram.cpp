#include "truecut/rt/duration_histogram.hpp"

#include <algorithm>
#include <cmath>

namespace truecut::rt {
namespace {
constexpr int64_t kFineEnd = 10'000;         // 1 ns bins
constexpr int64_t kMidEnd = 1'000'000;       // 10 ns bins
constexpr int64_t kCoarseEnd = 100'000'000;  // 1 us bins
constexpr size_t kFineBins = kFineEnd;
constexpr size_t kMidBins = (kMidEnd - kFineEnd) / 10;
constexpr size_t kCoarseBins = (kCoarseEnd - kMidEnd) / 1000;
constexpr size_t kBins = kFineBins + kMidBins + kCoarseBins + 1;

size_t bin_of(int64_t ns) {
  if (ns < 0) ns = 0;
  if (ns < kFineEnd) return static_cast<size_t>(ns);
  if (ns < kMidEnd) return kFineBins + static_cast<size_t>((ns - kFineEnd) / 10);
  if (ns < kCoarseEnd) return kFineBins + kMidBins + static_cast<size_t>((ns - kMidEnd) / 1000);
  return kBins - 1;
}

int64_t upper_edge(size_t bin) {
  if (bin < kFineBins) return static_cast<int64_t>(bin);
  bin -= kFineBins;
  if (bin < kMidBins) return kFineEnd + static_cast<int64_t>(bin) * 10 + 9;
  bin -= kMidBins;
  if (bin < kCoarseBins) return kMidEnd + static_cast<int64_t>(bin) * 1000 + 999;
  return INT64_MAX;
}
}  // namespace

DurationHistogram::DurationHistogram() : bins_(kBins, 0) {}

void DurationHistogram::add(int64_t duration_ns) noexcept {
  bins_[bin_of(duration_ns)]++;
  if (count_ == 0 || duration_ns > max_ns_) max_ns_ = duration_ns;
  if (count_ == 0 || duration_ns < min_ns_) min_ns_ = duration_ns;
  sum_ns_ += static_cast<double>(duration_ns);
  ++count_;
}

void DurationHistogram::clear() noexcept {
  std::fill(bins_.begin(), bins_.end(), 0);
  count_ = 0;
  max_ns_ = min_ns_ = 0;
  sum_ns_ = 0.0;
}

int64_t DurationHistogram::percentile_ns(double q) const noexcept {
  if (count_ == 0) return 0;
  q = std::clamp(q, 0.0, 1.0);
  const auto target = std::max<uint64_t>(1, static_cast<uint64_t>(std::ceil(q * double(count_))));
  uint64_t seen = 0;
  for (size_t i = 0; i < bins_.size(); ++i) {
    seen += bins_[i];
    if (seen >= target) return std::min(upper_edge(i), max_ns_);
  }
  return max_ns_;
}

}  // namespace truecut::rt
