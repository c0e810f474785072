// The merger's merges, one at a time on a thread of their own. A merge can take seconds (a
// healed partition's whole branch, a loaded machine's long runs of strokes); on the network
// thread it delayed the merger's heartbeats past the others' expiry, they took the busy merger
// for dead, elected another and partitioned the session while it still worked. Here the
// network thread goes on answering and sending heartbeats and picks up the result when the
// worker wakes it.
#pragma once

#include <atomic>
#include <exception>
#include <functional>
#include <optional>
#include <thread>

#include "merger_role.h"

namespace csculpt::peer {

class MergeWorker {
 public:
  /// `finished` runs on the worker's thread once a merge's outcome is ready (the network
  /// thread's wake-up).
  explicit MergeWorker(std::function<void()> finished) : finished_(std::move(finished)) {}
  ~MergeWorker() { drop(); }
  MergeWorker(const MergeWorker&) = delete;
  MergeWorker& operator=(const MergeWorker&) = delete;

  /// Whether a merge is running or its outcome has not been taken.
  bool busy() const { return thread_.joinable(); }
  /// Runs `merge` on the worker's thread. Needs !busy().
  void start(std::function<MergeOutcome()> merge);
  /// The outcome of the merge started last, once it finished (rethrowing what it threw), and
  /// then the worker is free; nullopt while it runs or when none was started.
  std::optional<MergeOutcome> take();
  /// Waits for the merge in flight and forgets its outcome.
  void drop();

 private:
  std::function<void()> finished_;
  std::thread thread_;
  std::atomic<bool> ready_{false};  // the outcome (or error) below is written
  std::optional<MergeOutcome> outcome_;
  std::exception_ptr error_;
};

}  // namespace csculpt::peer
