// The dab's helper thread (reference-app/side_task.h): what a task writes is visible once
// wait() returns, what the caller wrote before start() is visible to the task, a slow task
// is waited for, and a helper that never ran one shuts down cleanly. Also run under TSan.
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

TEST(AppSideTask, WaitReturnsOnlyAfterASlowTaskEnds) {
  SideTask side;
  bool done = false;
  side.start([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(30));
    done = true;
  });
  side.wait();
  EXPECT_TRUE(done);
}

TEST(AppSideTask, AHelperThatNeverRanATaskShutsDown) {
  for (int i = 0; i < 50; ++i) SideTask side;
}

}  // namespace
