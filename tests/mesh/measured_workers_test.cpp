// MeasuredWorkers (zeroset/detail/parallel.h): relaxation's choice between one worker and all
// cores, from step times. Here the times are made up, so each test knows which count is faster.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "zeroset/detail/parallel.h"

namespace zeroset::detail {
namespace {

// The worker counts the steps ran on, each step taking seconds(its workers).
template <class Seconds>
std::vector<int> run_steps(MeasuredWorkers& m, int steps, Seconds seconds) {
  std::vector<int> used;
  for (int k = 0; k < steps; ++k) {
    const int w = m.next();
    used.push_back(w);
    m.took(seconds(w));
  }
  return used;
}

long long count(const std::vector<int>& used, int workers, size_t from = 0) {
  return std::count(used.begin() + static_cast<long long>(from), used.end(), workers);
}

// Idle machine: all cores twice as fast. The choice stays on them, and the probes on one
// worker thin out (4, 8, 16, then 32 steps apart).
TEST(MeasuredWorkers, AnIdleMachineKeepsAllCores) {
  MeasuredWorkers m(2);
  const auto used = run_steps(m, 200, [](int w) { return w == 2 ? 0.005 : 0.010; });
  EXPECT_EQ(m.current(), 2);
  EXPECT_GE(count(used, 1), 3);   // it keeps checking
  EXPECT_LE(count(used, 1), 10);  // but seldom
}

// Busy machine: one worker faster. The first probe switches to it, and it stays; only the
// first steps and the probes run on two.
TEST(MeasuredWorkers, ABusyMachineSwitchesToOneWorker) {
  MeasuredWorkers m(2);
  const auto used = run_steps(m, 100, [](int w) { return w == 2 ? 0.020 : 0.014; });
  EXPECT_EQ(m.current(), 1);
  EXPECT_LE(count(used, 2, 10), 5);
  EXPECT_LE(count(used, 2), 10);
}

// The load comes and goes: the choice follows it.
TEST(MeasuredWorkers, TheChoiceFollowsTheLoad) {
  MeasuredWorkers m(2);
  bool busy = true;
  auto seconds = [&](int w) { return busy ? (w == 2 ? 0.020 : 0.014) : (w == 2 ? 0.005 : 0.010); };
  run_steps(m, 60, seconds);
  EXPECT_EQ(m.current(), 1);
  busy = false;
  run_steps(m, 80, seconds);
  EXPECT_EQ(m.current(), 2);
  busy = true;
  run_steps(m, 80, seconds);
  EXPECT_EQ(m.current(), 1);
}

// A probe faster by less than the margin (15%) does not switch: step times are noisy.
TEST(MeasuredWorkers, NoSwitchWithinTheMargin) {
  MeasuredWorkers m(2);
  run_steps(m, 100, [](int w) { return w == 2 ? 0.010 : 0.0095; });
  EXPECT_EQ(m.current(), 2);
}

// One core: nothing to choose and nothing probed.
TEST(MeasuredWorkers, OneCoreNeverProbes) {
  MeasuredWorkers m(1);
  const auto used = run_steps(m, 50, [](int) { return 0.01; });
  EXPECT_EQ(count(used, 1), 50);
}

}  // namespace
}  // namespace zeroset::detail
