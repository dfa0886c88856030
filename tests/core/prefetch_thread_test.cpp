// PrefetchThread: jobs run on their own thread beside the caller, results and errors come back in
// take(), and destruction waits for a running job.
#include "engine/core/prefetch_thread.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>

namespace dynscope {
namespace {

using namespace std::chrono_literals;

// Waits up to 10 s for `flag`; true when it was set in time.
bool wait_for(const std::atomic<bool>& flag) {
  const auto until = std::chrono::steady_clock::now() + 10s;
  while (!flag && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(1ms);
  return flag;
}

TEST(PrefetchThread, AJobRunsBesideTheCallerAndItsResultIsTaken) {
  PrefetchThread<std::string> prefetch;
  std::atomic<bool> go{false};
  std::thread::id worker;
  // The job waits for the caller, who lets it go only after start() returned: a job run inside
  // start() would time out and say so.
  prefetch.start([&] {
    worker = std::this_thread::get_id();
    return wait_for(go) ? std::string("ran beside") : std::string("timed out");
  });
  go = true;
  EXPECT_EQ(prefetch.take(), "ran beside");
  EXPECT_NE(worker, std::this_thread::get_id());
  // The same thread takes the next job.
  std::thread::id second;
  prefetch.start([&] {
    second = std::this_thread::get_id();
    return std::string("next");
  });
  EXPECT_EQ(prefetch.take(), "next");
  EXPECT_EQ(second, worker);
}

TEST(PrefetchThread, AJobsErrorComesBackInTakeAndTheThreadGoesOn) {
  PrefetchThread<int> prefetch;
  prefetch.start([]() -> int { throw std::runtime_error("scene 7 is broken"); });
  try {
    prefetch.take();
    ADD_FAILURE() << "take() should rethrow the job's error";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "scene 7 is broken");
  }
  prefetch.start([] { return 42; });
  EXPECT_EQ(prefetch.take(), 42);
}

TEST(PrefetchThread, DestructionWaitsForARunningJob) {
  std::atomic<bool> started{false}, finished{false};
  {
    PrefetchThread<int> prefetch;
    prefetch.start([&] {
      started = true;
      std::this_thread::sleep_for(50ms);
      finished = true;
      return 1;
    });
    ASSERT_TRUE(wait_for(started));
  }  // the result is never taken
  EXPECT_TRUE(finished);
}

}  // namespace
}  // namespace dynscope
