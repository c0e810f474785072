// One helper thread that runs a task beside the caller's own work, joined before the caller
// goes on: a dab lists its triangles' corners there while it recomputes their normals itself.
// The helper sleeps between tasks (a futex wait), so it costs the renderer nothing between
// dabs; wait() spins briefly first, as the task usually ends within microseconds of the
// caller's own part.
#pragma once

#include <atomic>
#include <functional>
#include <thread>

class SideTask {
 public:
  SideTask() : thread_([this] { loop(); }) {}
  ~SideTask() {
    state_.store(kQuit);
    state_.notify_all();
    thread_.join();
  }
  SideTask(const SideTask&) = delete;
  SideTask& operator=(const SideTask&) = delete;

  /** Starts `task` on the helper. Until wait() returns, the caller must not touch what the
   *  task writes, nor write what it reads. One task at a time. */
  void start(std::function<void()> task) {
    task_ = std::move(task);
    state_.store(kRunning);  // publishes task_ and everything the caller wrote before
    state_.notify_all();
  }
  /** Returns once the task has ended; everything it wrote is then visible to the caller. */
  void wait() {
    for (int spin = 0; spin < 4000 && state_.load() == kRunning; ++spin) {
    }
    for (int s = state_.load(); s == kRunning; s = state_.load()) state_.wait(s);
  }

 private:
  enum : int { kIdle, kRunning, kQuit };
  void loop() {
    for (;;) {
      state_.wait(kIdle);
      const int s = state_.load();
      if (s == kQuit) return;
      if (s != kRunning) continue;
      task_();
      state_.store(kIdle);
      state_.notify_all();
    }
  }
  std::function<void()> task_;
  std::atomic<int> state_{kIdle};
  std::thread thread_;
};
