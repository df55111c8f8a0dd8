#pragma once
// Exceptions out of parallel work (OpenMP regions and loops, std::thread functions), for the
// modules with OpenMP (through zeroset/detail/parallel.h) and the renderer's own threads alike.
#include <atomic>
#include <exception>

namespace zeroset::detail {

// An exception must not leave an OpenMP region or work-sharing loop, nor a std::thread's
// function: either calls std::terminate (std::bad_alloc would abort instead of exiting with a
// message). Each piece of parallel work runs through `run`, which keeps the first exception
// and makes later pieces return at once; after the region, `rethrow` throws it on the calling
// thread. `run` is a template, so the body is inlined: no call through a pointer per piece.
class ExceptionTrap {
 public:
  template <class Body>
  void run(Body&& body) noexcept {
    if (failed_.load(std::memory_order_relaxed)) return;
    try {
      body();
    } catch (...) {
      if (!failed_.exchange(true)) error_ = std::current_exception();
    }
  }
  bool failed() const { return failed_.load(std::memory_order_relaxed); }
  /// After the region (its closing barrier or the threads' join orders the writes).
  void rethrow() const {
    if (error_) std::rethrow_exception(error_);
  }

 private:
  std::atomic<bool> failed_{false};
  std::exception_ptr error_;
};

}  // namespace zeroset::detail
