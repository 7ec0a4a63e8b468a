/* test_counter: a HAL component in plain C, loaded as a shared library.
 *   loadrt test_counter [count=N] [fail=1]
 * Per instance <n> = test_counter.<i>: out s32 <n>.count (+= <n>.step per
 * cycle), in s32 <n>.step (default 1), in float <n>.in, out float <n>.sum
 * (running sum of in), ro s32 param <n>.period-ns (last period seen);
 * function <n>.update. fail=1 makes init fail after creating a pin. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "truecut/rt/hal_abi.h"

typedef struct {
  tc_hal_s32_t* count;
  tc_hal_s32_t* step;
  tc_hal_float_t* in;
  tc_hal_float_t* sum;
  tc_hal_s32_t period_ns;
} counter_t;

/* Read by the tests through dlsym to prove exit ran. */
TC_COMPONENT_EXPORT int test_counter_exit_calls = 0;

static void update(void* arg, long period_ns) {
  counter_t* c = (counter_t*)arg;
  *c->count += *c->step;
  *c->sum += *c->in;
  c->period_ns = (tc_hal_s32_t)period_ns;
}

TC_COMPONENT_EXPORT int truecut_component_init(const tc_hal_api_t* api, tc_hal_t* hal, int argc,
                                               const char* const* argv, void** state) {
  int count = 1, fail = 0, i;
  (void)state;
  if (api->abi_version != TC_HAL_ABI_VERSION) return -EINVAL;
  for (i = 0; i < argc; ++i) {
    if (strncmp(argv[i], "count=", 6) == 0)
      count = atoi(argv[i] + 6);
    else if (strcmp(argv[i], "fail=1") == 0)
      fail = 1;
    else {
      api->set_error(hal, "unknown argument");
      return -EINVAL;
    }
  }
  if (count < 1 || count > 8) {
    api->set_error(hal, "count must be 1..8");
    return -EINVAL;
  }
  for (i = 0; i < count; ++i) {
    char name[64], pin[96];
    int id;
    counter_t* c;
    snprintf(name, sizeof name, "test_counter.%d", i);
    id = api->component_new(hal, name);
    if (id < 0) return id;
    c = (counter_t*)api->alloc(hal, sizeof *c);
    if (!c) return -ENOMEM;
    snprintf(pin, sizeof pin, "%s.count", name);
    if (api->pin_new(hal, id, pin, TC_HAL_S32, TC_HAL_OUT, (void**)&c->count)) return -EINVAL;
    if (fail) {
      api->set_error(hal, "asked to fail (fail=1)");
      return -EIO;
    }
    snprintf(pin, sizeof pin, "%s.step", name);
    if (api->pin_new(hal, id, pin, TC_HAL_S32, TC_HAL_IN, (void**)&c->step)) return -EINVAL;
    *c->step = 1;
    snprintf(pin, sizeof pin, "%s.in", name);
    if (api->pin_new(hal, id, pin, TC_HAL_FLOAT, TC_HAL_IN, (void**)&c->in)) return -EINVAL;
    snprintf(pin, sizeof pin, "%s.sum", name);
    if (api->pin_new(hal, id, pin, TC_HAL_FLOAT, TC_HAL_OUT, (void**)&c->sum)) return -EINVAL;
    snprintf(pin, sizeof pin, "%s.period-ns", name);
    if (api->param_new(hal, id, pin, TC_HAL_S32, TC_HAL_RO, &c->period_ns)) return -EINVAL;
    snprintf(pin, sizeof pin, "%s.update", name);
    if (api->funct_new(hal, id, pin, update, c, 1)) return -EINVAL;
    api->component_ready(hal, id);
  }
  return 0;
}

TC_COMPONENT_EXPORT void truecut_component_exit(const tc_hal_api_t* api, tc_hal_t* hal,
                                                void* state) {
  (void)api;
  (void)hal;
  (void)state;
  ++test_counter_exit_calls;
}
