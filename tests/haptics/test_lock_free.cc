// The lock-free hand-overs of the real-time session (haptics/lock_free.h), stressed across threads:
// the triple buffer's reader only ever sees whole values, in order, and the last one published;
// the ring delivers every block pushed, in order, and refuses (never waits) when full.
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <thread>
#include <vector>

#include "haptics/lock_free.h"

namespace fetouch::haptics {
namespace {

struct Stamped {
  long id = -1;
  std::vector<long> copies = std::vector<long>(64, -1);  // every entry equals id in a whole value
};

TEST(TripleBuffer, ReaderSeesWholeValuesInOrderAndTheLastOne) {
  TripleBuffer<Stamped> buffer{Stamped{}};
  constexpr long kValues = 200000;
  std::atomic<bool> done{false};
  long replaced = 0;
  std::thread writer([&] {
    for (long i = 0; i < kValues; ++i) {
      Stamped& s = buffer.back();
      s.id = i;
      for (long& c : s.copies) c = i;
      replaced += !buffer.publish();
    }
    done = true;
  });
  long last = -1, taken = 0, torn = 0, backwards = 0;
  for (;;) {
    const bool finished = done.load();
    if (buffer.take()) {
      const Stamped& s = buffer.front();
      for (long c : s.copies) torn += c != s.id;
      backwards += s.id <= last;
      last = s.id;
      ++taken;
    } else if (finished) {
      break;
    } else {
      std::this_thread::yield();
    }
  }
  writer.join();
  EXPECT_EQ(torn, 0);
  EXPECT_EQ(backwards, 0);
  EXPECT_EQ(last, kValues - 1);  // the newest value always reaches the reader
  EXPECT_GT(taken, 0);
  // Every value was either taken or replaced by a newer one before it could be.
  EXPECT_EQ(taken + replaced, kValues);
}

TEST(SpscRing, DeliversEveryBlockInOrderAndRefusesWhenFull) {
  SpscRing<std::array<long, 2>> ring(96);
  constexpr long kBlocks = 300000;
  std::atomic<bool> done{false};
  long refused = 0;
  std::thread producer([&] {
    std::array<long, 2> block[3];
    for (long i = 0; i < kBlocks;) {
      for (int j = 0; j < 3; ++j) block[j] = {i, 3 * i + j};
      // A real producer drops and counts; this one retries, and lets the consumer run (on a busy
      // machine both threads may share one core).
      if (ring.push(block, 3)) {
        ++i;
      } else {
        ++refused;
        std::this_thread::yield();
      }
    }
    done = true;
  });
  std::vector<std::array<long, 2>> out(64);
  long expected = 0, misplaced = 0;
  for (;;) {
    const bool finished = done.load();
    const std::size_t n = ring.pop(out.data(), out.size());
    for (std::size_t k = 0; k < n; ++k) {
      const long item = expected++;
      misplaced += out[k][1] != item || out[k][0] != item / 3;
    }
    if (finished && n == 0) break;
    if (n == 0) std::this_thread::yield();
  }
  producer.join();
  EXPECT_EQ(expected, 3 * kBlocks);
  EXPECT_EQ(misplaced, 0);

  // Single-threaded: a block that does not fit is refused whole, and the ring is unchanged.
  SpscRing<int> small(5);
  const int items[4] = {1, 2, 3, 4};
  EXPECT_TRUE(small.push(items, 4));
  EXPECT_FALSE(small.push(items, 2));
  EXPECT_TRUE(small.push(items, 1));
  int got[8];
  ASSERT_EQ(small.pop(got, 8), 5u);
  EXPECT_EQ(got[3], 4);
  EXPECT_EQ(got[4], 1);
}

}  // namespace
}  // namespace fetouch::haptics
