// Internal: a small persistent pool for the merge's data-parallel loops. Tasks write
// disjoint outputs, so results do not depend on which thread runs which chunk.
#pragma once

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace csculpt::detail {

class WorkerPool {
 public:
  /// `threads` includes the calling thread; 0 = the machine's hardware threads (at most 8).
  explicit WorkerPool(unsigned threads = 0) {
    if (threads == 0) threads = std::clamp(std::thread::hardware_concurrency(), 1u, 8u);
    for (unsigned i = 1; i < threads; ++i) workers_.emplace_back([this] { work(); });
  }
  ~WorkerPool() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    for (auto& t : workers_) t.join();
  }
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  unsigned size() const { return static_cast<unsigned>(workers_.size()) + 1; }

  /// Runs task(i) for i in [0, count), spread over the pool and the calling thread; returns
  /// when all are done. Small counts run inline.
  void run(std::size_t count, const std::function<void(std::size_t)>& task) {
    if (count == 0) return;
    if (count == 1 || workers_.empty()) {
      for (std::size_t i = 0; i < count; ++i) task(i);
      return;
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      task_ = &task;
      count_ = count;
      next_.store(0);
      active_ = static_cast<unsigned>(workers_.size());
      ++generation_;
    }
    wake_.notify_all();
    drain();
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [this] { return active_ == 0; });
    task_ = nullptr;
  }

  /// Runs body(begin, end) over [0, n) in chunks of `grain`.
  void for_chunks(std::size_t n, std::size_t grain,
                  const std::function<void(std::size_t, std::size_t)>& body) {
    const std::size_t chunks = (n + grain - 1) / grain;
    run(chunks, [&](std::size_t c) { body(c * grain, std::min(n, (c + 1) * grain)); });
  }

 private:
  void drain() {
    for (;;) {
      const std::size_t i = next_.fetch_add(1);
      if (i >= count_) return;
      (*task_)(i);
    }
  }
  void work() {
    std::uint64_t seen = 0;
    for (;;) {
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
        if (stop_) return;
        seen = generation_;
      }
      drain();
      {
        std::lock_guard<std::mutex> lock(mutex_);
        --active_;
      }
      done_.notify_one();
    }
  }

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  const std::function<void(std::size_t)>* task_ = nullptr;
  std::size_t count_ = 0;
  std::atomic<std::size_t> next_{0};
  unsigned active_ = 0;
  std::uint64_t generation_ = 0;
  bool stop_ = false;
};

}  // namespace csculpt::detail
