#pragma once
// OpenMP helpers with a serial fallback, and one field evaluator per worker thread: the one
// place where the modules ask OpenMP how many workers there are and which one is running.
#include <algorithm>
#include <atomic>
#include <latch>
#include <span>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "zeroset/detail/exception_trap.h"
#include "zeroset/error.h"
#include "zeroset/expr/field.h"
#include "zeroset/types.h"

namespace zeroset::detail {

/// Throws Error when `n` threads cannot run at once (a process limit such as `ulimit -u`, or
/// no memory for their stacks). libgomp ends the whole process when it cannot create a worker
/// ("Thread creation failed"), which no caller could catch, so a count is first tried with
/// std::threads that all wait until the last one started; the largest count that ran is
/// remembered and not tried again.
inline void ensure_threads_can_start(int n) {
  static std::atomic<int> proven{1};
  if (n <= proven.load(std::memory_order_relaxed)) return;
  std::latch all_started(1);
  std::string failure;
  {
    std::vector<std::jthread> probe;
    probe.reserve(static_cast<size_t>(n - 1));
    try {
      for (int i = 1; i < n; ++i) probe.emplace_back([&all_started] { all_started.wait(); });
    } catch (const std::system_error& e) {
      failure = e.what();
    }
    all_started.count_down();
  }  // joined
  if (!failure.empty())
    throw Error("cannot start " + std::to_string(n) + " worker threads (" + failure +
                "): ask for fewer (--threads, threads=)");
  for (int p = proven.load(); p < n && !proven.compare_exchange_weak(p, n);) {
  }
}

/// The workers for `requested` threads (0: OpenMP's default, one per core). Throws
/// InvalidArgument above kMaxThreads and Error when that many threads cannot start.
inline int worker_count(int requested) {
  if (requested < 0 || requested > kMaxThreads)
    throw InvalidArgument("threads", std::to_string(requested),
                          "must lie in [0, " + std::to_string(kMaxThreads) + "] (0: all cores)");
#ifdef _OPENMP
  const int n = requested > 0 ? requested : omp_get_max_threads();
  ensure_threads_can_start(n);
  return n;
#else
  return 1;
#endif
}

inline int worker_index() {
#ifdef _OPENMP
  return omp_get_thread_num();
#else
  return 0;
#endif
}

// The number of workers in the enclosing parallel region (1 outside one).
inline int team_size() {
#ifdef _OPENMP
  return omp_get_num_threads();
#else
  return 1;
#endif
}

// The number of workers for a loop of similar parallel steps, chosen by timing them: one
// worker, or `most`. On an idle machine the steps run faster on all cores; on a busy one a
// preempted worker holds up the others at every barrier, where they spin and take the CPU
// from it, and one worker is faster (docs/meshing.md). So now and then a step is a probe,
// run with the count not in use; the choice switches when the probe beat the fastest of the
// last kRecent steps by kMargin. The probes come every kFirstGap steps at first and after a
// switch, twice as far apart after each probe that confirmed the choice, at most kLastGap.
// Only for steps whose results do not depend on the number of workers.
class MeasuredWorkers {
 public:
  // most ≤ 1: always one worker, nothing measured.
  explicit MeasuredWorkers(int most) : most_(std::max(1, most)), current_(most_) {}

  // The workers for the coming step.
  int next() {
    probing_ = most_ > 1 && ++step_ == probe_at_;
    return probing_ ? other() : current_;
  }
  // The seconds the step from next() took.
  void took(double seconds) {
    if (!probing_) {
      recent_[count_++ % kRecent] = seconds;
      return;
    }
    const int n = std::min(count_, kRecent);
    const double best = n > 0 ? *std::min_element(recent_, recent_ + n) : 0.0;
    if (n > 0 && seconds < kMargin * best) {
      current_ = other(), count_ = 0, gap_ = kFirstGap;
    } else {
      gap_ = std::min(2 * gap_, kLastGap);
    }
    probe_at_ = step_ + gap_;
  }
  int current() const { return current_; }

 private:
  static constexpr int kFirstGap = 4, kLastGap = 32, kRecent = 3;
  static constexpr double kMargin = 0.85;
  int other() const { return current_ == 1 ? most_ : 1; }
  int most_, current_;
  int step_ = 0, probe_at_ = kFirstGap, gap_ = kFirstGap, count_ = 0;
  bool probing_ = false;
  double recent_[kRecent] = {};
};

// Evaluators own scratch memory and must not be shared, so each worker gets its own.
class EvaluatorPool {
 public:
  EvaluatorPool(const Field& field, int workers) {
    pool_.reserve(static_cast<size_t>(workers));
    for (int i = 0; i < workers; ++i) pool_.emplace_back(field);
  }
  Evaluator& local() { return pool_[static_cast<size_t>(worker_index())]; }
  Evaluator& at(int i) { return pool_[static_cast<size_t>(i)]; }

 private:
  std::vector<Evaluator> pool_;
};

// One worker's scratch for F and ∇F at a batch of points through one evaluator, in
// structure-of-arrays form (much cheaper per point than one point at a time).
struct GradientBatch {
  std::vector<double> x, y, z, f, gx, gy, gz;

  // F and ∇F at point(0), ..., point(m - 1) into f and gradient(k).
  template <class Point>
  void evaluate(Evaluator& ev, size_t m, Point point) {
    x.resize(m), y.resize(m), z.resize(m), f.resize(m), gx.resize(m), gy.resize(m), gz.resize(m);
    for (size_t k = 0; k < m; ++k) {
      const Vec3& p = point(k);
      x[k] = p.x(), y[k] = p.y(), z[k] = p.z();
    }
    ev.values_gradients(x, y, z, f, gx, gy, gz);
  }
  Vec3 gradient(size_t k) const { return Vec3(gx[k], gy[k], gz[k]); }
};

// F and ∇F at many points, in structure-of-arrays batches of 1,024 split over the workers
// (one evaluator each from `pool`, which must have at least `workers` of them).
inline void values_gradients(EvaluatorPool& pool, int workers, std::span<const Vec3> pts,
                             std::vector<double>& f, std::vector<Vec3>& g) {
  const long long n = static_cast<long long>(pts.size());
  f.resize(pts.size());
  g.resize(pts.size());
  constexpr long long kChunk = 1024;
  const long long chunks = (n + kChunk - 1) / kChunk;
  ExceptionTrap trap;
#pragma omp parallel num_threads(workers)
  {
    GradientBatch batch;
#pragma omp for schedule(static)
    for (long long c = 0; c < chunks; ++c)
      trap.run([&] {
        const size_t b = static_cast<size_t>(c * kChunk);
        const size_t m = static_cast<size_t>(std::min(n, (c + 1) * kChunk)) - b;
        batch.evaluate(pool.local(), m, [&](size_t q) -> const Vec3& { return pts[b + q]; });
        for (size_t q = 0; q < m; ++q) f[b + q] = batch.f[q], g[b + q] = batch.gradient(q);
      });
  }
  trap.rethrow();
}

}  // namespace zeroset::detail
