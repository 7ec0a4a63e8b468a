/* test_busy: takes a given amount of wall time per cycle, to provoke overruns.
 *   loadrt test_busy  -> in s32 pin test_busy.0.busy-ns, function test_busy.0.spin */
#include <errno.h>
#include <time.h>

#include "truecut/rt/hal_abi.h"

typedef struct {
  tc_hal_s32_t* busy_ns;
} busy_t;

static long long now_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (long long)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static void spin(void* arg, long period_ns) {
  busy_t* b = (busy_t*)arg;
  long long end = now_ns() + *b->busy_ns;
  (void)period_ns;
  while (now_ns() < end) {
  }
}

TC_COMPONENT_EXPORT int truecut_component_init(const tc_hal_api_t* api, tc_hal_t* hal, int argc,
                                               const char* const* argv, void** state) {
  int id;
  busy_t* b;
  (void)argc;
  (void)argv;
  (void)state;
  id = api->component_new(hal, "test_busy.0");
  if (id < 0) return id;
  b = (busy_t*)api->alloc(hal, sizeof *b);
  if (!b) return -ENOMEM;
  if (api->pin_new(hal, id, "test_busy.0.busy-ns", TC_HAL_S32, TC_HAL_IN, (void**)&b->busy_ns))
    return -EINVAL;
  if (api->funct_new(hal, id, "test_busy.0.spin", spin, b, 0)) return -EINVAL;
  return api->component_ready(hal, id);
}

TC_COMPONENT_EXPORT void truecut_component_exit(const tc_hal_api_t* api, tc_hal_t* hal,
                                                void* state) {
  (void)api;
  (void)hal;
  (void)state;
}
