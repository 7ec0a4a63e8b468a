/* test_rt_violations: a component that does in its servo function what no
 * real-time function may, for the tests that prove the counters of
 * tests/support/alloc_counter.hpp see it inside a loaded library.
 *   loadrt test_rt_violations -> function test_rt_violations.0.update, which
 *   per call allocates and frees (malloc/free, calloc/realloc/free), locks and
 *   unlocks a mutex, a read-write lock (read, then write) and a semaphore. */
#include <errno.h>
#include <pthread.h>
#include <semaphore.h>
#include <stdlib.h>

#include "truecut/rt/hal_abi.h"

static pthread_mutex_t g_mutex = PTHREAD_MUTEX_INITIALIZER;
static pthread_rwlock_t g_rwlock = PTHREAD_RWLOCK_INITIALIZER;
static sem_t g_sem;
static void* volatile g_sink;

static void update(void* arg, long period_ns) {
  void* p;
  (void)arg;
  (void)period_ns;
  p = malloc(16); /* 1 allocation, 1 free */
  g_sink = p;
  free(p);
  p = calloc(2, 8); /* 2 allocations (calloc, realloc), 1 free */
  p = realloc(p, 64);
  g_sink = p;
  free(p);
  pthread_mutex_lock(&g_mutex); /* 4 locks */
  pthread_mutex_unlock(&g_mutex);
  pthread_rwlock_rdlock(&g_rwlock);
  pthread_rwlock_unlock(&g_rwlock);
  pthread_rwlock_wrlock(&g_rwlock);
  pthread_rwlock_unlock(&g_rwlock);
  sem_post(&g_sem);
  sem_wait(&g_sem);
}

TC_COMPONENT_EXPORT int truecut_component_init(const tc_hal_api_t* api, tc_hal_t* hal, int argc,
                                               const char* const* argv, void** state) {
  int id;
  (void)argc;
  (void)argv;
  (void)state;
  if (sem_init(&g_sem, 0, 0) != 0) return -errno;
  id = api->component_new(hal, "test_rt_violations.0");
  if (id < 0) return id;
  if (api->funct_new(hal, id, "test_rt_violations.0.update", update, NULL, 0)) return -EINVAL;
  return api->component_ready(hal, id);
}

TC_COMPONENT_EXPORT void truecut_component_exit(const tc_hal_api_t* api, tc_hal_t* hal,
                                                void* state) {
  (void)api;
  (void)hal;
  (void)state;
  sem_destroy(&g_sem);
}
