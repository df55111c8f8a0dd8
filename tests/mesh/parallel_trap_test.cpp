// Exceptions in OpenMP regions: ExceptionTrap (zeroset/detail/parallel.h) keeps the first one
// and rethrows it after the region, where an escaping exception would call std::terminate.
#include <gtest/gtest.h>

#include <atomic>
#include <new>
#include <stdexcept>
#include <thread>

#include "zeroset/detail/parallel.h"

namespace zeroset::detail {
namespace {

// std::bad_alloc thrown by a worker inside a parallel loop reaches the caller; the pieces
// after the failure are skipped instead of run. The failing piece waits for the 100 before it,
// and the pieces after it wait inside their body until the trap has recorded the failure, so
// the count does not depend on how the threads are scheduled: the 100 pieces before, the
// failing one, and at most one waiting piece per other thread.
TEST(ExceptionTrap, BadAllocInAWorkerReachesTheCaller) {
  constexpr long long kPieces = 20000;
  constexpr int kThreads = 4;
  std::atomic<long long> ran{0};
  auto loop = [&] {
    ExceptionTrap trap;
#pragma omp parallel for num_threads(kThreads) schedule(dynamic, 1)
    for (long long i = 0; i < kPieces; ++i)
      trap.run([&] {
        while (i == 100 && ran.load() < 100) std::this_thread::yield();
        while (i > 100 && !trap.failed()) std::this_thread::yield();
        ++ran;
        if (i == 100) throw std::bad_alloc();
      });
    trap.rethrow();
  };
  EXPECT_THROW(loop(), std::bad_alloc);
  EXPECT_GE(ran.load(), 101);
  EXPECT_LE(ran.load(), 101 + (kThreads - 1));
}

// Every worker throwing: one exception comes out, the first kept.
TEST(ExceptionTrap, OneOfManyFailuresComesOut) {
  ExceptionTrap trap;
#pragma omp parallel num_threads(4)
  trap.run([] { throw std::runtime_error("worker failed"); });
  try {
    trap.rethrow();
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "worker failed");
  }
}

// A region with barriers between its phases (as the spatial hash has): after a failure in
// one phase every thread still meets every barrier, and the later phases do not run.
TEST(ExceptionTrap, PhasesBetweenBarriersStopAfterAFailure) {
  std::atomic<int> second_phase{0};
  ExceptionTrap trap;
#pragma omp parallel num_threads(3)
  {
    trap.run([] {
      if (worker_index() == team_size() - 1) throw std::bad_alloc();
    });
#pragma omp barrier
    trap.run([&] { ++second_phase; });
#pragma omp barrier
  }
  EXPECT_THROW(trap.rethrow(), std::bad_alloc);
  EXPECT_EQ(second_phase.load(), 0);
}

TEST(ExceptionTrap, NothingThrownNothingRethrown) {
  long long sum = 0;
  ExceptionTrap trap;
#pragma omp parallel for num_threads(4) reduction(+ : sum)
  for (long long i = 0; i < 1000; ++i) trap.run([&] { sum += i; });
  EXPECT_NO_THROW(trap.rethrow());
  EXPECT_EQ(sum, 999 * 1000 / 2);
  EXPECT_FALSE(trap.failed());
}

}  // namespace
}  // namespace zeroset::detail
