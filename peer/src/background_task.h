// Work the network thread hands to a thread of its own, one task at a time: the merger's
// merges, and a joiner's loading of its first snapshot (decoding it and building the mesh's
// hierarchy). Either can take seconds (a healed partition's whole branch, a mesh of millions
// of faces); on the network thread they silenced the peer's heartbeats past the others'
// expiry, and the others took it for dead (a busy merger was replaced and the session
// partitioned while it still worked; a joiner was dropped mid-join). Here the network thread
// goes on answering and sending heartbeats and picks up the result when the task wakes it.
#pragma once

#include <atomic>
#include <exception>
#include <functional>
#include <optional>
#include <thread>
#include <utility>

namespace csculpt::peer {

template <class Result>
class BackgroundTask {
 public:
  /// `finished` runs on the task's thread once its result is ready (the network thread's
  /// wake-up).
  explicit BackgroundTask(std::function<void()> finished) : finished_(std::move(finished)) {}
  ~BackgroundTask() { drop(); }
  BackgroundTask(const BackgroundTask&) = delete;
  BackgroundTask& operator=(const BackgroundTask&) = delete;

  /// Whether a task is running or its result has not been taken.
  bool busy() const { return thread_.joinable(); }

  /// Runs `work` on the task's thread. Needs !busy().
  void start(std::function<Result()> work) {
    ready_.store(false, std::memory_order_relaxed);
    result_.reset();
    error_ = nullptr;
    thread_ = std::thread([this, work = std::move(work)] {
      try {
        result_ = work();
      } catch (...) {
        error_ = std::current_exception();
      }
      ready_.store(true, std::memory_order_release);
      finished_();
    });
  }

  /// The result of the task started last, once it finished (rethrowing what it threw), and
  /// then the task is free; nullopt while it runs or when none was started.
  std::optional<Result> take() {
    if (!thread_.joinable() || !ready_.load(std::memory_order_acquire)) return std::nullopt;
    thread_.join();
    if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
    return std::exchange(result_, std::nullopt);
  }

  /// Waits for the task in flight and forgets its result.
  void drop() {
    if (thread_.joinable()) thread_.join();
    result_.reset();
    error_ = nullptr;
  }

 private:
  std::function<void()> finished_;
  std::thread thread_;
  std::atomic<bool> ready_{false};  // the result (or error) below is written
  std::optional<Result> result_;
  std::exception_ptr error_;
};

}  // namespace csculpt::peer
