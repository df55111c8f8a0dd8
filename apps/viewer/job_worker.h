#pragma once
// Background work for the viewer: one long-lived thread that runs one job at a time, and a
// mailbox through which jobs hand their results to the UI thread. Nothing here ever blocks the
// UI thread for longer than a mutex hand-over.
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <stop_token>
#include <string>
#include <thread>

namespace zeroset::viewer {

/// Runs jobs on one background thread, newest first: submit() asks the running job to stop
/// (through its std::stop_token) and queues the new one in place of any job still waiting, so
/// a burst of edits costs one cancelled job and one run. The UI thread never waits for a job.
/// A job reports its own errors with its result; an exception that still escapes a job is
/// caught here and kept for take_error(). Thread safety: all members may be called from any
/// thread; the destructor stops and joins the thread (it waits for the running job to notice
/// its stop request).
class JobWorker {
 public:
  using Job = std::function<void(std::stop_token)>;

  JobWorker();
  ~JobWorker();
  JobWorker(const JobWorker&) = delete;
  JobWorker& operator=(const JobWorker&) = delete;

  /// Cancels the running job and replaces the waiting one (if any) with `job`.
  void submit(Job job);
  /// Cancels the running job and drops the waiting one.
  void cancel();
  /// True when no job is running or waiting.
  bool is_idle() const;
  /// Reports an error from inside a job (a job that recovers from it and goes on).
  void post_error(std::string message);
  /// The last error a job reported or let escape since the previous call, if any.
  std::optional<std::string> take_error();

 private:
  void run(std::stop_token worker_stop);

  mutable std::mutex mutex_;
  std::condition_variable_any wake_;
  std::optional<Job> waiting_;
  std::stop_source running_stop_;
  bool is_running_ = false;
  std::optional<std::string> error_;
  std::jthread thread_;  // last: starts once everything above exists
};

/// The latest value a producer thread posted, for a consumer thread to take. Posting replaces
/// an untaken value (the consumer only wants the newest). Thread-safe.
template <class T>
class Mailbox {
 public:
  void post(std::shared_ptr<const T> value) {
    std::lock_guard lock(mutex_);
    value_ = std::move(value);
  }
  /// The posted value, or nullptr when nothing new arrived since the last take().
  std::shared_ptr<const T> take() {
    std::lock_guard lock(mutex_);
    return std::move(value_);
  }
  /// The posted value, left for take(); nullptr when there is none.
  std::shared_ptr<const T> peek() {
    std::lock_guard lock(mutex_);
    return value_;
  }
  void clear() { post(nullptr); }

 private:
  std::mutex mutex_;
  std::shared_ptr<const T> value_;
};

}  // namespace zeroset::viewer
