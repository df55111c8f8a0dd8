#pragma once
// OpenMP helpers with a serial fallback, and one field evaluator per worker thread.
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "zeroset/expr/field.h"

namespace zeroset::detail {

inline int worker_count(int requested) {
#ifdef _OPENMP
  return requested > 0 ? requested : omp_get_max_threads();
#else
  (void)requested;
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

}  // namespace zeroset::detail
