// Fixed-size histogram of durations for per-cycle statistics. All memory is
// allocated by the constructor; add() is real-time safe.
#pragma once

#include <cstdint>
#include <vector>

namespace truecut::rt {

class DurationHistogram {
 public:
  // Resolution: 1 ns below 10 us, 10 ns below 1 ms, 1 us below 100 ms;
  // longer durations go to an overflow bin (max_ns() stays exact).
  DurationHistogram();
  void add(int64_t duration_ns) noexcept;
  void clear() noexcept;
  uint64_t count() const noexcept { return count_; }
  int64_t max_ns() const noexcept { return max_ns_; }
  int64_t min_ns() const noexcept { return count_ ? min_ns_ : 0; }
  double mean_ns() const noexcept { return count_ ? sum_ns_ / double(count_) : 0.0; }
  // Smallest bin upper edge below or at which a fraction q of samples lies
  // (q in [0, 1]); never more than max_ns().
  int64_t percentile_ns(double q) const noexcept;

 private:
  std::vector<uint64_t> bins_;
  uint64_t count_ = 0;
  int64_t max_ns_ = 0;
  int64_t min_ns_ = 0;
  double sum_ns_ = 0.0;
};

}  // namespace truecut::rt
