// Counts heap allocations, frees and lock operations made by the calling
// thread between arm() and disarm(). Linking this library replaces malloc,
// calloc, realloc, the aligned allocators, free, every operator new and
// delete, and the blocking and try- functions of pthread mutexes, read-write
// locks and semaphores (pthread_mutex_lock/trylock/timedlock,
// pthread_rwlock_*rdlock/*wrlock, sem_wait/trywait/timedwait) in the test
// executable and, for the components it loads, in the process (the test
// executables export these symbols: tests/CMakeLists.txt).
#pragma once

#include <cstdint>
#include <ostream>

namespace truecut::test {

void arm_alloc_counter() noexcept;      // start counting on this thread
void disarm_alloc_counter() noexcept;   // stop counting on this thread
uint64_t armed_allocations() noexcept;  // allocations seen while armed, all threads
uint64_t armed_frees() noexcept;        // frees (of non-null pointers) seen while armed
uint64_t armed_locks() noexcept;        // lock, try-lock and semaphore waits seen while armed

// All three at once, comparable and printable, for EXPECT_EQ(RtViolations{}, ...).
struct RtViolations {
  uint64_t allocations = 0;
  uint64_t frees = 0;
  uint64_t locks = 0;
  bool operator==(const RtViolations&) const = default;
};
inline std::ostream& operator<<(std::ostream& os, const RtViolations& v) {
  return os << v.allocations << " allocations, " << v.frees << " frees, " << v.locks << " locks";
}
RtViolations armed_violations() noexcept;
void reset_alloc_counter() noexcept;
// Proves the counter works: allocates while armed and reports what it saw.
uint64_t alloc_counter_self_test();

// RunLimits::cycle_probe that arms the counter for the duration of a cycle.
void alloc_counting_probe(void* user, int phase);

}  // namespace truecut::test
