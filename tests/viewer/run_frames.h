#pragma once
// Frames of the viewer state without a window, for the tests that drive it like a user.
#include <chrono>
#include <thread>

#include "viewer_state.h"

namespace zeroset::viewer::test {

inline double seconds_now() {
  using clock = std::chrono::steady_clock;
  return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
}

/// Runs frames (without drawing) until `done` or the timeout; returns whether `done` held.
template <class Done>
bool run_until(ViewerState& state, Done done, double timeout_s = 20) {
  const double end = seconds_now() + timeout_s;
  while (seconds_now() < end) {
    state.update(seconds_now());
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

}  // namespace zeroset::viewer::test
