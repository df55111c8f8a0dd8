// The viewer's background worker: newest job wins, the running one is cancelled, errors come
// back instead of escaping.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>

#include "job_worker.h"

namespace zeroset::viewer {
namespace {

bool wait_for(const std::function<bool()>& done) {
  for (int i = 0; i < 2000; ++i) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return false;
}

TEST(JobWorker, SubmittingCancelsTheRunningJobAndRunsTheNewest) {
  JobWorker worker;
  std::atomic<bool> first_started{false}, first_stopped{false};
  std::atomic<int> runs_of_second{0}, runs_of_third{0};
  worker.submit([&](std::stop_token stop) {
    first_started = true;
    while (!stop.stop_requested()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    first_stopped = true;
  });
  ASSERT_TRUE(wait_for([&] { return first_started.load(); }));
  // Two submissions while the first still runs: only the newest of them runs.
  worker.submit([&](std::stop_token) { ++runs_of_second; });
  worker.submit([&](std::stop_token) { ++runs_of_third; });
  ASSERT_TRUE(wait_for([&] { return worker.is_idle(); }));
  EXPECT_TRUE(first_stopped);
  EXPECT_EQ(runs_of_second, 0);
  EXPECT_EQ(runs_of_third, 1);
}

TEST(JobWorker, AnEscapingExceptionBecomesAnErrorMessage) {
  JobWorker worker;
  worker.submit([](std::stop_token) { throw std::runtime_error("the surface is empty"); });
  ASSERT_TRUE(wait_for([&] { return worker.is_idle(); }));
  const auto error = worker.take_error();
  ASSERT_TRUE(error.has_value());
  EXPECT_EQ(*error, "the surface is empty");
  EXPECT_FALSE(worker.take_error().has_value());
  // The worker goes on working.
  std::atomic<bool> ran{false};
  worker.submit([&](std::stop_token) { ran = true; });
  EXPECT_TRUE(wait_for([&] { return ran.load(); }));
}

TEST(JobWorker, DestructionStopsARunningJob) {
  std::atomic<bool> stopped{false};
  {
    JobWorker worker;
    std::atomic<bool> started{false};
    worker.submit([&](std::stop_token stop) {
      started = true;
      while (!stop.stop_requested()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
      stopped = true;
    });
    ASSERT_TRUE(wait_for([&] { return started.load(); }));
  }
  EXPECT_TRUE(stopped);
}

TEST(Mailbox, TakeGivesTheNewestValueOnce) {
  Mailbox<int> box;
  EXPECT_EQ(box.take(), nullptr);
  box.post(std::make_shared<const int>(1));
  box.post(std::make_shared<const int>(2));
  const auto v = box.take();
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(*v, 2);
  EXPECT_EQ(box.take(), nullptr);
}

}  // namespace
}  // namespace zeroset::viewer
