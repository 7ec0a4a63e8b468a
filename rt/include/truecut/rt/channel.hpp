// Lock-free channels between the non-real-time side and the servo thread.
//
// SpscChannel: one producer thread, one consumer thread, fixed capacity,
// wait-free push/pop that never allocate (Boost.Lockfree spsc_queue with
// compile-time capacity). Use it for motion segments (non-RT -> RT) and
// recorded samples (RT -> non-RT).
//
// Handover: publishes immutable objects (a correction field, a parameter
// set) to the servo thread by pointer. The servo thread takes the newest,
// keeps using it, and hands the one it replaces back through a second
// channel, so that it is destroyed outside the servo thread.
#pragma once

#include <boost/lockfree/spsc_queue.hpp>
#include <cstddef>
#include <memory>
#include <type_traits>

namespace truecut::rt {

template <class T, std::size_t Capacity>
class SpscChannel {
  static_assert(std::is_trivially_copyable_v<T> || std::is_nothrow_move_assignable_v<T>,
                "channel items must move without throwing");

 public:
  // Producer side. False when full; the item is not taken.
  [[nodiscard]] bool try_push(const T& item) noexcept { return queue_.push(item); }
  // Consumer side. False when empty.
  [[nodiscard]] bool try_pop(T& item) noexcept { return queue_.pop(item); }
  // Consumer side: items waiting. Producer side: may be stale.
  std::size_t size() const noexcept { return queue_.read_available(); }
  std::size_t free_slots() const noexcept { return queue_.write_available(); }
  static constexpr std::size_t capacity() noexcept { return Capacity; }

 private:
  boost::lockfree::spsc_queue<T, boost::lockfree::capacity<Capacity>> queue_;
};

template <class T, std::size_t Depth = 4>
class Handover {
 public:
  Handover() = default;
  Handover(const Handover&) = delete;
  Handover& operator=(const Handover&) = delete;
  ~Handover() {
    T* p = nullptr;
    while (incoming_.try_pop(p))
      delete p;
    while (retired_.try_pop(p))
      delete p;
  }

  // Non-RT: offers a new object. Returns false (and keeps ownership with the
  // caller, in `object`) when Depth objects are already waiting.
  [[nodiscard]] bool publish(std::unique_ptr<const T>& object) noexcept {
    if (!object) return false;
    if (!incoming_.try_push(const_cast<T*>(object.get()))) return false;
    object.release();
    return true;
  }

  // RT: if newer objects were published, makes the newest current and
  // retires the ones it replaces (returns true). Never allocates or frees;
  // bounded by Depth. If the retire channel is full the swap waits for a
  // later cycle.
  bool take_latest(const T*& current) noexcept {
    bool swapped = false;
    T* next = nullptr;
    while (retired_.free_slots() > 0 && incoming_.try_pop(next)) {
      if (current) (void)retired_.try_push(const_cast<T*>(current));  // a slot was free
      current = next;
      swapped = true;
    }
    return swapped;
  }

  // RT: retires `current` without replacing it (e.g. on shutdown of a stage).
  bool retire(const T*& current) noexcept {
    if (!current) return true;
    if (!retired_.try_push(const_cast<T*>(current))) return false;
    current = nullptr;
    return true;
  }

  // Non-RT: destroys what the servo thread gave back. Returns how many.
  std::size_t collect_retired() {
    std::size_t n = 0;
    T* p = nullptr;
    while (retired_.try_pop(p)) {
      delete p;
      ++n;
    }
    return n;
  }

 private:
  SpscChannel<T*, Depth> incoming_;
  SpscChannel<T*, Depth> retired_;
};

}  // namespace truecut::rt
