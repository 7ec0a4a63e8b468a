#include "alloc_counter.hpp"

#include <dlfcn.h>
#include <pthread.h>
#include <semaphore.h>

#include <atomic>
#include <cstdlib>
#include <new>

extern "C" {
void* __libc_malloc(size_t);
void* __libc_calloc(size_t, size_t);
void* __libc_realloc(void*, size_t);
void* __libc_memalign(size_t, size_t);
void __libc_free(void*);
}

namespace {
std::atomic<uint64_t> g_count{0};
std::atomic<uint64_t> g_frees{0};
std::atomic<uint64_t> g_locks{0};
thread_local bool t_armed = false;
inline void note() noexcept {
  if (t_armed) g_count.fetch_add(1, std::memory_order_relaxed);
}
inline void note_lock() noexcept {
  if (t_armed) g_locks.fetch_add(1, std::memory_order_relaxed);
}

// The C library's own lock functions, behind the counting ones below.
template <typename F>
F next_symbol(F& cache, const char* name) noexcept {
  if (cache == nullptr) cache = reinterpret_cast<F>(::dlsym(RTLD_NEXT, name));
  return cache;
}
using MutexFn = int (*)(pthread_mutex_t*);
using MutexTimedFn = int (*)(pthread_mutex_t*, const timespec*);
using RwlockFn = int (*)(pthread_rwlock_t*);
using RwlockTimedFn = int (*)(pthread_rwlock_t*, const timespec*);
using SemFn = int (*)(sem_t*);
using SemTimedFn = int (*)(sem_t*, const timespec*);
MutexFn g_mutex_lock, g_mutex_trylock;
MutexTimedFn g_mutex_timedlock;
RwlockFn g_rdlock, g_wrlock, g_tryrdlock, g_trywrlock;
RwlockTimedFn g_timedrdlock, g_timedwrlock;
SemFn g_sem_wait, g_sem_trywait;
SemTimedFn g_sem_timedwait;
// Resolved before main(), while one thread runs.
[[gnu::constructor]] void resolve_lock_functions() noexcept {
  next_symbol(g_mutex_lock, "pthread_mutex_lock");
  next_symbol(g_mutex_trylock, "pthread_mutex_trylock");
  next_symbol(g_mutex_timedlock, "pthread_mutex_timedlock");
  next_symbol(g_rdlock, "pthread_rwlock_rdlock");
  next_symbol(g_wrlock, "pthread_rwlock_wrlock");
  next_symbol(g_tryrdlock, "pthread_rwlock_tryrdlock");
  next_symbol(g_trywrlock, "pthread_rwlock_trywrlock");
  next_symbol(g_timedrdlock, "pthread_rwlock_timedrdlock");
  next_symbol(g_timedwrlock, "pthread_rwlock_timedwrlock");
  next_symbol(g_sem_wait, "sem_wait");
  next_symbol(g_sem_trywait, "sem_trywait");
  next_symbol(g_sem_timedwait, "sem_timedwait");
}
}  // namespace

extern "C" {
void* malloc(size_t n) {
  note();
  return __libc_malloc(n);
}
void* calloc(size_t n, size_t m) {
  note();
  return __libc_calloc(n, m);
}
void* realloc(void* p, size_t n) {
  note();
  return __libc_realloc(p, n);
}
void* memalign(size_t a, size_t n) {
  note();
  return __libc_memalign(a, n);
}
void* aligned_alloc(size_t a, size_t n) {
  note();
  return __libc_memalign(a, n);
}
int posix_memalign(void** out, size_t a, size_t n) {
  note();
  void* p = __libc_memalign(a, n);
  if (!p) return 12;  // ENOMEM
  *out = p;
  return 0;
}
void free(void* p) {
  if (p != nullptr && t_armed) g_frees.fetch_add(1, std::memory_order_relaxed);
  __libc_free(p);
}

// Every way to block on a mutex, a read-write lock or a semaphore (also
// the try- variants: a real-time function may not take a lock at all).
int pthread_mutex_lock(pthread_mutex_t* m) {
  note_lock();
  return next_symbol(g_mutex_lock, "pthread_mutex_lock")(m);
}
int pthread_mutex_trylock(pthread_mutex_t* m) {
  note_lock();
  return next_symbol(g_mutex_trylock, "pthread_mutex_trylock")(m);
}
int pthread_mutex_timedlock(pthread_mutex_t* m, const timespec* t) {
  note_lock();
  return next_symbol(g_mutex_timedlock, "pthread_mutex_timedlock")(m, t);
}
int pthread_rwlock_rdlock(pthread_rwlock_t* l) {
  note_lock();
  return next_symbol(g_rdlock, "pthread_rwlock_rdlock")(l);
}
int pthread_rwlock_wrlock(pthread_rwlock_t* l) {
  note_lock();
  return next_symbol(g_wrlock, "pthread_rwlock_wrlock")(l);
}
int pthread_rwlock_tryrdlock(pthread_rwlock_t* l) {
  note_lock();
  return next_symbol(g_tryrdlock, "pthread_rwlock_tryrdlock")(l);
}
int pthread_rwlock_trywrlock(pthread_rwlock_t* l) {
  note_lock();
  return next_symbol(g_trywrlock, "pthread_rwlock_trywrlock")(l);
}
int pthread_rwlock_timedrdlock(pthread_rwlock_t* l, const timespec* t) {
  note_lock();
  return next_symbol(g_timedrdlock, "pthread_rwlock_timedrdlock")(l, t);
}
int pthread_rwlock_timedwrlock(pthread_rwlock_t* l, const timespec* t) {
  note_lock();
  return next_symbol(g_timedwrlock, "pthread_rwlock_timedwrlock")(l, t);
}
int sem_wait(sem_t* s) {
  note_lock();
  return next_symbol(g_sem_wait, "sem_wait")(s);
}
int sem_trywait(sem_t* s) {
  note_lock();
  return next_symbol(g_sem_trywait, "sem_trywait")(s);
}
int sem_timedwait(sem_t* s, const timespec* t) {
  note_lock();
  return next_symbol(g_sem_timedwait, "sem_timedwait")(s, t);
}
}

// operator new goes through the counted malloc above.
void* operator new(size_t n) {
  void* p = malloc(n ? n : 1);
  if (!p) throw std::bad_alloc();
  return p;
}
void* operator new[](size_t n) {
  return operator new(n);
}
void* operator new(size_t n, const std::nothrow_t&) noexcept {
  return malloc(n ? n : 1);
}
void* operator new[](size_t n, const std::nothrow_t&) noexcept {
  return malloc(n ? n : 1);
}
void* operator new(size_t n, std::align_val_t a) {
  void* p = memalign(static_cast<size_t>(a), n ? n : 1);
  if (!p) throw std::bad_alloc();
  return p;
}
void* operator new[](size_t n, std::align_val_t a) {
  return operator new(n, a);
}
void operator delete(void* p) noexcept {
  free(p);
}
void operator delete[](void* p) noexcept {
  free(p);
}
void operator delete(void* p, size_t) noexcept {
  free(p);
}
void operator delete[](void* p, size_t) noexcept {
  free(p);
}
void operator delete(void* p, std::align_val_t) noexcept {
  free(p);
}
void operator delete[](void* p, std::align_val_t) noexcept {
  free(p);
}
void operator delete(void* p, size_t, std::align_val_t) noexcept {
  free(p);
}
void operator delete[](void* p, size_t, std::align_val_t) noexcept {
  free(p);
}

namespace truecut::test {

void arm_alloc_counter() noexcept {
  t_armed = true;
}
void disarm_alloc_counter() noexcept {
  t_armed = false;
}
uint64_t armed_allocations() noexcept {
  return g_count.load();
}
uint64_t armed_frees() noexcept {
  return g_frees.load();
}
uint64_t armed_locks() noexcept {
  return g_locks.load();
}
RtViolations armed_violations() noexcept {
  return {g_count.load(), g_frees.load(), g_locks.load()};
}
void reset_alloc_counter() noexcept {
  g_count.store(0);
  g_frees.store(0);
  g_locks.store(0);
}

uint64_t alloc_counter_self_test() {
  reset_alloc_counter();
  arm_alloc_counter();
  auto* volatile p = new int(42);
  void* volatile q = std::malloc(16);
  disarm_alloc_counter();
  delete p;
  std::free(q);
  uint64_t seen = armed_allocations();
  reset_alloc_counter();
  return seen;
}

void alloc_counting_probe(void*, int phase) {
  if (phase == 0)
    arm_alloc_counter();
  else
    disarm_alloc_counter();
}

}  // namespace truecut::test
