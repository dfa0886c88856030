// parallel_chunks, on_compute_threads and TaskErrors: every chunk once, work really shared by the
// region's threads, the work on the calling thread, errors carried out of tasks and regions.
#include "engine/core/parallel.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "engine/core/threads.h"

namespace dynscope {
namespace {

class ParallelTest : public ::testing::Test {
 protected:
  void SetUp() override { saved_ = compute_threads(); }
  void TearDown() override { set_compute_threads(saved_); }

 private:
  int saved_ = 1;
};

// Runs parallel_chunks over n items and checks that every item was visited exactly once, by a
// chunk that starts on a multiple of `chunk` and is at most `chunk` long.
void expect_each_item_once(int64_t n, int64_t chunk) {
  std::vector<std::atomic<int>> visits(static_cast<size_t>(n));
  std::atomic<bool> bad_chunk{false};
  parallel_chunks(n, chunk, true, [&](int64_t begin, int64_t end) {
    if (begin % chunk != 0 || end - begin > chunk || end <= begin || end > n) bad_chunk = true;
    for (int64_t i = begin; i < end; ++i) ++visits[static_cast<size_t>(i)];
  });
  EXPECT_FALSE(bad_chunk) << "n " << n << " chunk " << chunk;
  for (int64_t i = 0; i < n; ++i) {
    ASSERT_EQ(visits[static_cast<size_t>(i)], 1) << "item " << i << " of " << n;
  }
}

TEST_F(ParallelTest, EveryItemOnceOnAnyThreadCountInsideOrOutsideARegion) {
  for (const int threads : {1, 2, 3}) {
    set_compute_threads(threads);
    for (const int64_t n : {0, 1, 7, 64, 65, 1000}) {
      expect_each_item_once(n, 8);
      on_compute_threads([&] { expect_each_item_once(n, 8); });
    }
  }
}

TEST_F(ParallelTest, SerialWhenNotAskedToBeParallel) {
  set_compute_threads(2);
  std::set<int> threads;
  std::vector<int64_t> order;
  parallel_chunks(100, 3, false, [&](int64_t begin, int64_t) {
    threads.insert(omp_get_thread_num());
    order.push_back(begin);
  });
  EXPECT_EQ(threads.size(), 1u);
  ASSERT_EQ(order.size(), 34u);
  for (size_t c = 0; c < order.size(); ++c) EXPECT_EQ(order[c], 3 * static_cast<int64_t>(c));
}

// Inside on_compute_threads the chunks are tasks: while one thread sleeps in a chunk, the region's
// other thread takes the next ones.
TEST_F(ParallelTest, ChunksInsideARegionRunOnItsThreads) {
  set_compute_threads(2);
  std::mutex mutex;
  std::set<int> threads;
  on_compute_threads([&] {
    parallel_chunks(16, 1, true, [&](int64_t, int64_t) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      const std::lock_guard<std::mutex> lock(mutex);
      threads.insert(omp_get_thread_num());
    });
  });
  EXPECT_EQ(threads.size(), 2u);
}

// A task started in on_compute_threads runs at the same time as the work that started it: each
// waits for a flag only the other sets (with a time limit, so a failure cannot hang).
TEST_F(ParallelTest, TaskRunsBesideTheWorkThatStartedIt) {
  set_compute_threads(2);
  std::atomic<bool> task_started{false}, work_saw_task{false}, task_saw_work{false};
  const auto wait_for = [](const std::atomic<bool>& flag) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (!flag && std::chrono::steady_clock::now() < until) std::this_thread::yield();
    return flag.load();
  };
  on_compute_threads([&] {
#pragma omp task shared(task_started, work_saw_task, task_saw_work, wait_for)
    {
      task_started = true;
      task_saw_work = wait_for(work_saw_task);
    }
    work_saw_task = wait_for(task_started);
#pragma omp taskwait
  });
  EXPECT_TRUE(work_saw_task);
  EXPECT_TRUE(task_saw_work);
}

// `work` runs on the thread that called on_compute_threads, so what that thread holds in
// thread-local state (LibTorch's grad mode, for one) holds inside: the other threads of the
// region only take tasks. Many regions, so that any other thread would have had its chance.
TEST_F(ParallelTest, WorkRunsOnTheCallingThread) {
  thread_local int mark = 0;
  mark = 7;
  for (const int threads : {1, 2, 3}) {
    set_compute_threads(threads);
    for (int i = 0; i < 50; ++i) {
      std::thread::id inside;
      int seen = 0;
      on_compute_threads([&] {
        inside = std::this_thread::get_id();
        seen = mark;
      });
      ASSERT_EQ(inside, std::this_thread::get_id()) << threads << " threads, region " << i;
      ASSERT_EQ(seen, 7);
    }
  }
}

TEST_F(ParallelTest, WorkErrorIsRethrownAfterTheRegion) {
  for (const int threads : {1, 2}) {
    set_compute_threads(threads);
    EXPECT_THROW(on_compute_threads([] { throw std::runtime_error("work failed"); }),
                 std::runtime_error);
  }
}

TEST_F(ParallelTest, TaskErrorsKeepsTheFirstOfSeveral) {
  set_compute_threads(2);
  TaskErrors errors;
  std::atomic<int> ran{0};
  on_compute_threads([&] {
    for (int t = 0; t < 8; ++t) {
#pragma omp task shared(errors, ran) firstprivate(t)
      errors.run([&] {
        ++ran;
        if (t % 2 == 1) throw std::runtime_error("task " + std::to_string(t));
      });
    }
#pragma omp taskwait
  });
  EXPECT_EQ(ran, 8) << "one failing task must not stop the others";
  try {
    errors.rethrow();
    FAIL() << "no error kept";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("task ", 0), 0u) << e.what();
  }
  TaskErrors none;
  EXPECT_NO_THROW(none.rethrow());
}

}  // namespace
}  // namespace dynscope
