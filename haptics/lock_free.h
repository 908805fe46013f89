// Lock-free hand-overs between the haptic thread and the others (ARCHITECTURE.md section 5). Neither
// side ever waits for the other, allocates or locks:
//   - SlotExchange: the atomic slot-index swap both slot hand-overs are made of;
//   - TripleBuffer<T>: one writer, one reader, the reader wants only the newest value. The writer
//     fills back(), publish() swaps it with the middle slot; the reader's take() swaps the middle
//     with its front slot when something new is there. A value published twice before a take() is
//     replaced (publish() says so).
//   - SpscRing<T>: one producer, one consumer, every item wanted, in order. push() of a block of
//     items fails (and the caller counts the loss) when the ring has no room; it never waits.
#pragma once

#include <atomic>
#include <cstddef>
#include <vector>

namespace fetouch::haptics {

// The atomic core of the slot hand-overs (TripleBuffer below, and HapticLoop's four slots): one
// slot index in the middle, marked fresh from a publish until a take. The writer swaps its filled
// slot in; the reader swaps a slot it releases for the fresh one. Each side only ever touches the
// slots whose indices it holds.
class SlotExchange {
 public:
  explicit SlotExchange(int middle) : middle_(middle) {}
  // The writer: puts `filled` in the middle and returns the slot it gets back (its next one);
  // `replaced_unread` says whether that slot held a value never taken.
  int publish(int filled, bool& replaced_unread) noexcept {
    const int old = middle_.exchange(filled | kFresh, std::memory_order_acq_rel);
    replaced_unread = (old & kFresh) != 0;
    return old & kIndex;
  }
  // The reader: whether a value was published since its last take().
  bool fresh() const noexcept { return (middle_.load(std::memory_order_acquire) & kFresh) != 0; }
  // The reader, after fresh(): puts `released` in the middle, returns the freshly published slot.
  int take(int released) noexcept { return middle_.exchange(released, std::memory_order_acq_rel) & kIndex; }
  // The slot in the middle now, without taking it (for a caller that owns both sides, as lockstep).
  int peek() const noexcept { return middle_.load(std::memory_order_acquire) & kIndex; }

 private:
  static constexpr int kIndex = 3, kFresh = 4;  // up to four slots
  std::atomic<int> middle_;
};

template <class T>
class TripleBuffer {
 public:
  // Every slot starts as a copy of `initial` (so a writer that assigns same-sized values into its
  // slot never allocates).
  explicit TripleBuffer(const T& initial) : slots_{initial, initial, initial} {}

  T& back() { return slots_[back_]; }  // the writer's slot
  // Makes back() the newest value. Returns false when the value it replaces was never taken.
  bool publish() noexcept {
    bool replaced_unread = false;
    back_ = middle_.publish(back_, replaced_unread);
    return !replaced_unread;
  }

  // The reader: true (and front() is the newest value) when something was published since the
  // last take().
  bool take() noexcept {
    if (!middle_.fresh()) return false;
    front_ = middle_.take(front_);
    return true;
  }
  const T& front() const { return slots_[front_]; }

 private:
  T slots_[3];
  int back_ = 0, front_ = 1;
  SlotExchange middle_{2};
};

template <class T>
class SpscRing {
 public:
  explicit SpscRing(std::size_t capacity) : items_(capacity + 1) {}

  std::size_t capacity() const { return items_.size() - 1; }

  // The producer: copies `count` items in, all or none. False when they do not fit.
  bool push(const T* items, std::size_t count) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    const std::size_t tail = tail_.load(std::memory_order_acquire);
    const std::size_t used = head >= tail ? head - tail : head + items_.size() - tail;
    if (used + count > capacity()) return false;
    std::size_t at = head;
    for (std::size_t i = 0; i < count; ++i) {
      items_[at] = items[i];
      if (++at == items_.size()) at = 0;
    }
    head_.store(at, std::memory_order_release);
    return true;
  }

  // The consumer: moves up to `max` items out, oldest first; returns how many.
  std::size_t pop(T* out, std::size_t max) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    const std::size_t head = head_.load(std::memory_order_acquire);
    std::size_t at = tail, n = 0;
    while (at != head && n < max) {
      out[n++] = items_[at];
      if (++at == items_.size()) at = 0;
    }
    tail_.store(at, std::memory_order_release);
    return n;
  }

 private:
  std::vector<T> items_;
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
};

}  // namespace fetouch::haptics
