// Lock-free channels: order, capacity, and hand-over of immutable objects.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "truecut/rt/channel.hpp"

using truecut::rt::Handover;
using truecut::rt::SpscChannel;

TEST(SpscChannel, FifoOrderAndFullEmpty) {
  SpscChannel<int, 4> ch;
  int v = 0;
  EXPECT_FALSE(ch.try_pop(v));
  for (int i = 0; i < 4; ++i)
    EXPECT_TRUE(ch.try_push(i));
  EXPECT_FALSE(ch.try_push(99)) << "capacity is 4";
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(ch.try_pop(v));
    EXPECT_EQ(i, v);
  }
  EXPECT_FALSE(ch.try_pop(v));
}

TEST(SpscChannel, TwoThreadsLoseNothingAndKeepOrder) {
  SpscChannel<uint64_t, 64> ch;
  constexpr uint64_t kN = 200'000;
  // Each side yields when the other is behind: with more runnable threads
  // than cores (ctest -j2 beside other tests) a spinning side would burn
  // its time slice waiting for one that is not running.
  std::thread producer([&] {
    for (uint64_t i = 0; i < kN;)
      if (ch.try_push(i))
        ++i;
      else
        std::this_thread::yield();
  });
  uint64_t expected = 0, v = 0;
  while (expected < kN) {
    if (ch.try_pop(v)) {
      ASSERT_EQ(expected++, v);
    } else {
      std::this_thread::yield();
    }
  }
  producer.join();
}

namespace {
struct Tracked {
  static inline std::atomic<int> alive{0};
  int id;
  explicit Tracked(int i) : id(i) { ++alive; }
  ~Tracked() { --alive; }
};
}  // namespace

TEST(Handover, NewestWinsAndReplacedOnesComeBackForFreeing) {
  Tracked::alive = 0;
  {
    Handover<Tracked, 4> h;
    const Tracked* current = nullptr;
    EXPECT_FALSE(h.take_latest(current));
    for (int i = 1; i <= 3; ++i) {
      std::unique_ptr<const Tracked> p = std::make_unique<Tracked>(i);
      ASSERT_TRUE(h.publish(p));
      EXPECT_EQ(nullptr, p);
    }
    EXPECT_TRUE(h.take_latest(current));
    ASSERT_NE(nullptr, current);
    EXPECT_EQ(3, current->id);
    EXPECT_EQ(3, Tracked::alive.load()) << "nothing is freed on the servo side";
    EXPECT_EQ(2u, h.collect_retired());
    EXPECT_EQ(1, Tracked::alive.load());
    EXPECT_TRUE(h.retire(current));
    EXPECT_EQ(nullptr, current);
    EXPECT_EQ(1u, h.collect_retired());
    EXPECT_EQ(0, Tracked::alive.load());
  }
}

TEST(Handover, FullChannelKeepsOwnershipWithTheCaller) {
  Handover<Tracked, 2> h;
  std::unique_ptr<const Tracked> a = std::make_unique<Tracked>(1), b = std::make_unique<Tracked>(2),
                                 c = std::make_unique<Tracked>(3);
  EXPECT_TRUE(h.publish(a));
  EXPECT_TRUE(h.publish(b));
  EXPECT_FALSE(h.publish(c));
  ASSERT_NE(nullptr, c);
  EXPECT_EQ(3, c->id);
}

TEST(Handover, SwapsUnderConcurrentPublishingNeverTearOrLeak) {
  Tracked::alive = 0;
  {
    Handover<Tracked, 4> h;
    std::atomic<bool> stop{false};
    std::atomic<bool> rt_done{false};
    std::thread rt([&] {
      const Tracked* current = nullptr;
      int last = 0;
      while (!stop.load()) {
        h.take_latest(current);
        if (current) {
          EXPECT_GE(current->id, last) << "objects arrive in publication order";
          last = current->id;
        }
      }
      while (!h.retire(current)) {
      }
      rt_done = true;
    });
    for (int i = 1; i <= 5000; ++i) {
      std::unique_ptr<const Tracked> p = std::make_unique<Tracked>(i);
      while (!h.publish(p))
        h.collect_retired();
      h.collect_retired();
    }
    stop = true;
    // The servo side may still swap in what was waiting and fill the retire
    // channel; its last retire needs the collector to keep going until then.
    while (!rt_done.load())
      h.collect_retired();
    rt.join();
    h.collect_retired();
  }
  EXPECT_EQ(0, Tracked::alive.load());
}
