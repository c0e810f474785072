// The dab's helper thread (reference-app/side_task.h): what a task writes is visible once
// wait() returns, what the caller wrote before start() is visible to the task, a slow task
// on the helper is waited for, a task still pending at destruction runs, and a helper that
// never ran one shuts down cleanly. Also run under TSan.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <thread>
#include <vector>

#include "side_task.h"

namespace {

TEST(AppSideTask, EachTaskSeesTheCallersWritesAndTheCallerSeesTheTasks) {
  SideTask side;
  std::vector<uint32_t> input(4096), output(4096);
  for (uint32_t round = 0; round < 2000; ++round) {
    for (uint32_t i = 0; i < input.size(); ++i) input[i] = round * 7 + i;
    side.start([&] {  // the upper half on the helper
      for (size_t i = input.size() / 2; i < input.size(); ++i) output[i] = input[i] * 3;
    });
    for (size_t i = 0; i < input.size() / 2; ++i) output[i] = input[i] * 3;
    side.wait();
    for (uint32_t i = 0; i < output.size(); ++i)
      ASSERT_EQ(output[i], (round * 7 + i) * 3) << "round " << round << " item " << i;
  }
}

TEST(AppSideTask, WaitReturnsOnlyAfterASlowTaskEndsOnTheHelper) {
  SideTask side;
  const std::thread::id caller = std::this_thread::get_id();
  int on_helper = 0;
  for (int round = 0; round < 20; ++round) {
    bool done = false;
    std::thread::id ran_on;
    side.start([&] {
      ran_on = std::this_thread::get_id();
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      done = true;
    });
    // The caller is slow: the helper has time to take the task (the caller runs it only if
    // the helper has not).
    std::this_thread::sleep_for(std::chrono::milliseconds(3));
    side.wait();
    ASSERT_TRUE(done) << "round " << round;
    on_helper += ran_on != caller;
  }
  EXPECT_GT(on_helper, 0);  // the helper does run tasks, and wait() waits for it
}

TEST(AppSideTask, DestroyedWithATaskPendingRunsItFirst) {
  bool done = false;
  {
    SideTask side;
    side.start([&] { done = true; });
  }  // as when an exception unwinds between start() and wait()
  EXPECT_TRUE(done);
}

TEST(AppSideTask, AHelperThatNeverRanATaskShutsDown) {
  for (int i = 0; i < 50; ++i) SideTask side;
}

}  // namespace
