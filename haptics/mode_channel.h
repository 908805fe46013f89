// A change of local model and hold asked while a haptic loop runs (the trainer's controls), and the
// loop's answer. The asking thread calls ask() and reads verdict(); the loop's producer (the solver
// thread: HapticLoop::fill_answer) takes the newest request, runs the stability analysis for it on
// that frame's stiffness and answers. The tick never touches the channel: an accepted mode reaches
// it inside the frame slot, like the gains.
#pragma once

#include <atomic>
#include <mutex>
#include <string>

#include "haptics/hold.h"
#include "haptics/local_model.h"

namespace fetouch::haptics {

struct ModeVerdict {
  long request = 0;  // the request answered (ask()'s number); 0: none answered yet
  bool accepted = false;
  LocalModelKind local_model = LocalModelKind::pi;  // the mode asked
  HoldKind hold = HoldKind::zoh;
  LocalModelGains gains;       // accepted: the gains it starts with; refused: the best found
  double spectral_radius = 0;  // robust (gain_selection.h): under 1 is stable
  std::string text;            // one line for the screen: what was applied, or why not
};

class ModeChannel {
 public:
  // Any thread: asks for a mode; returns the request's number (1, 2, ...). A newer request before
  // the producer took the older one replaces it.
  long ask(LocalModelKind local_model, HoldKind hold) {
    const long number = ++asked_count_;
    asked_.store(number * 8 + static_cast<long>(local_model) * 2 + static_cast<long>(hold), std::memory_order_release);
    return number;
  }
  // Any thread: the newest answer.
  ModeVerdict verdict() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return verdict_;
  }

  // The producer: a request not yet taken (false: none).
  bool take(long& request, LocalModelKind& local_model, HoldKind& hold) {
    const long asked = asked_.load(std::memory_order_acquire);
    if (asked / 8 <= taken_) return false;
    taken_ = asked / 8;
    request = taken_;
    local_model = static_cast<LocalModelKind>((asked % 8) / 2);
    hold = static_cast<HoldKind>(asked % 2);
    return true;
  }
  void answer(const ModeVerdict& verdict) {
    std::lock_guard<std::mutex> lock(mutex_);
    verdict_ = verdict;
  }

 private:
  std::atomic<long> asked_count_{0};
  std::atomic<long> asked_{0};  // number * 8 + model * 2 + hold
  long taken_ = 0;              // the producer's
  mutable std::mutex mutex_;
  ModeVerdict verdict_;
};

}  // namespace fetouch::haptics
