// One helper thread that runs a task beside the caller's own work, joined before the caller
// goes on: a dab lists its triangles' corners there while it recomputes their normals, and a
// merged version's boxes are refitted there while its normals are recomputed.
// The helper sleeps between tasks (a futex wait), so it costs the renderer nothing between
// them. On a loaded machine it may not be scheduled in time: if the caller finishes its own
// part before the helper has taken the task, the caller runs the task itself, so a helper
// that never wakes costs nothing (one that is preempted while running the task still does).
#pragma once

#include <atomic>
#include <functional>
#include <thread>

class SideTask {
 public:
  SideTask() : thread_([this] { loop(); }) {}
  ~SideTask() {
    wait();  // a task still pending or running (an exception between start and wait) ends first
    state_.store(kQuit);
    state_.notify_all();
    thread_.join();
  }
  SideTask(const SideTask&) = delete;
  SideTask& operator=(const SideTask&) = delete;

  /** Offers `task` to the helper. Until wait() returns, the caller must not touch what the
   *  task writes, nor write what it reads. One task at a time. */
  void start(std::function<void()> task) {
    task_ = std::move(task);
    state_.store(kPending);  // publishes task_ and everything the caller wrote before
    state_.notify_all();
  }
  /** Runs the task here if the helper has not taken it; else returns once the helper is done.
   *  Everything the task wrote is then visible to the caller. */
  void wait() {
    int s = kPending;
    if (state_.compare_exchange_strong(s, kCallerRunning)) {
      task_();
      state_.store(kIdle);
      state_.notify_all();
      return;
    }
    for (int spin = 0; spin < 4000 && state_.load() == kHelperRunning; ++spin) {
    }
    for (s = state_.load(); s == kHelperRunning; s = state_.load()) state_.wait(s);
  }

 private:
  enum : int { kIdle, kPending, kHelperRunning, kCallerRunning, kQuit };
  void loop() {
    for (;;) {
      int s = state_.load();
      if (s == kQuit) return;
      if (s == kPending && state_.compare_exchange_strong(s, kHelperRunning)) {
        task_();
        state_.store(kIdle);
        state_.notify_all();
        continue;
      }
      state_.wait(s);  // until the state moves on from what was seen
    }
  }
  std::function<void()> task_;
  std::atomic<int> state_{kIdle};
  std::thread thread_;
};
