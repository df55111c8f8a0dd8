#include "job_worker.h"

#include <exception>
#include <utility>

namespace zeroset::viewer {

JobWorker::JobWorker() : thread_([this](std::stop_token stop) { run(stop); }) {}

JobWorker::~JobWorker() {
  {
    std::lock_guard lock(mutex_);
    waiting_.reset();
    running_stop_.request_stop();
  }
  thread_.request_stop();
  wake_.notify_all();
  // jthread joins here, after the running job returned.
}

void JobWorker::submit(Job job) {
  {
    std::lock_guard lock(mutex_);
    waiting_ = std::move(job);
    running_stop_.request_stop();
  }
  wake_.notify_all();
}

void JobWorker::cancel() {
  std::lock_guard lock(mutex_);
  waiting_.reset();
  running_stop_.request_stop();
}

bool JobWorker::is_idle() const {
  std::lock_guard lock(mutex_);
  return !is_running_ && !waiting_;
}

void JobWorker::post_error(std::string message) {
  std::lock_guard lock(mutex_);
  error_ = std::move(message);
}

std::optional<std::string> JobWorker::take_error() {
  std::lock_guard lock(mutex_);
  return std::exchange(error_, std::nullopt);
}

void JobWorker::run(std::stop_token worker_stop) {
  for (;;) {
    Job job;
    std::stop_token job_stop;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, worker_stop, [&] { return waiting_.has_value(); });
      if (worker_stop.stop_requested()) return;
      job = std::move(*waiting_);
      waiting_.reset();
      running_stop_ = std::stop_source();
      job_stop = running_stop_.get_token();
      is_running_ = true;
    }
    std::string failure;
    try {
      job(job_stop);
    } catch (const std::exception& e) {
      failure = e.what();
    } catch (...) {
      failure = "unknown error in a background job";
    }
    std::lock_guard lock(mutex_);
    is_running_ = false;
    if (!failure.empty()) error_ = std::move(failure);
  }
}

}  // namespace zeroset::viewer
