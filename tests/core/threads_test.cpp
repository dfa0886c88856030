// Compute-thread budget: bounds, default, and that OpenMP follows it.
#include "engine/core/threads.h"

#include <gtest/gtest.h>
#include <omp.h>

#include "engine/core/error.h"

namespace dynscope {
namespace {

TEST(ThreadsTest, SetBudgetReachesOpenMp) {
  set_compute_threads(1);
  EXPECT_EQ(compute_threads(), 1);
  EXPECT_EQ(omp_get_max_threads(), 1);
  set_compute_threads(3);
  EXPECT_EQ(compute_threads(), 3);
  EXPECT_EQ(omp_get_max_threads(), 3);
  set_compute_threads(0);
  EXPECT_EQ(compute_threads(), kDefaultComputeThreads);
  EXPECT_EQ(omp_get_max_threads(), kDefaultComputeThreads);
  EXPECT_GE(available_cores(), 1);
}

TEST(ThreadsTest, RejectsCountsOutOfRange) {
  EXPECT_THROW(set_compute_threads(-1), ValueError);
  EXPECT_THROW(set_compute_threads(kMaxComputeThreads + 1), ValueError);
  set_compute_threads(2);
  EXPECT_THROW(set_compute_threads(100000), ValueError);
  EXPECT_EQ(compute_threads(), 2) << "a rejected count must leave the budget unchanged";
}

}  // namespace
}  // namespace dynscope
