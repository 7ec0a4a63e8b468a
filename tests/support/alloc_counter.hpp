// Counts heap allocations made by the calling thread between arm() and
// disarm(). Linking this library replaces malloc, calloc, realloc, the
// aligned allocators and every operator new in the test executable.
#pragma once

#include <cstdint>

namespace truecut::test {

void arm_alloc_counter() noexcept;      // start counting on this thread
void disarm_alloc_counter() noexcept;   // stop counting on this thread
uint64_t armed_allocations() noexcept;  // allocations seen while armed, all threads
void reset_alloc_counter() noexcept;
// Proves the counter works: allocates while armed and reports what it saw.
uint64_t alloc_counter_self_test();

// RunLimits::cycle_probe that arms the counter for the duration of a cycle.
void alloc_counting_probe(void* user, int phase);

}  // namespace truecut::test
