/* test_interrupt: a HAL component that interrupts its own process, as
 * Ctrl-C would, at a given cycle of the thread it runs in.
 *   loadrt test_interrupt at=N
 * Function test_interrupt.update raises SIGINT once, in its N-th cycle
 * (N >= 1), so that a test can stop a run at a known point without a timer. */
#include <errno.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>

#include "truecut/rt/hal_abi.h"

typedef struct {
  long at;
  long cycle;
} interrupt_t;

static void update(void* arg, long period_ns) {
  interrupt_t* s = (interrupt_t*)arg;
  (void)period_ns;
  if (++s->cycle == s->at) raise(SIGINT);
}

TC_COMPONENT_EXPORT int truecut_component_init(const tc_hal_api_t* api, tc_hal_t* hal, int argc,
                                               const char* const* argv, void** state) {
  long at = 0;
  int id;
  interrupt_t* s;
  (void)state;
  if (api->abi_version != TC_HAL_ABI_VERSION) return -EINVAL;
  if (argc != 1 || strncmp(argv[0], "at=", 3) != 0 || (at = atol(argv[0] + 3)) < 1) {
    api->set_error(hal, "test_interrupt needs at=N (N >= 1)");
    return -EINVAL;
  }
  id = api->component_new(hal, "test_interrupt");
  if (id < 0) return id;
  s = (interrupt_t*)api->alloc(hal, sizeof *s);
  if (!s) return -ENOMEM;
  s->at = at;
  s->cycle = 0;
  if (api->funct_new(hal, id, "test_interrupt.update", update, s, 0)) return -EINVAL;
  api->component_ready(hal, id);
  return 0;
}

TC_COMPONENT_EXPORT void truecut_component_exit(const tc_hal_api_t* api, tc_hal_t* hal,
                                                void* state) {
  (void)api;
  (void)hal;
  (void)state;
}
