// Internal: a small persistent pool for the merge's data-parallel loops. Tasks write
// disjoint outputs, so results do not depend on which thread runs which chunk.
//
// A task that throws does not end the process: the region's other tasks still run, and the
// first exception (in the order they were thrown) is rethrown by run() once all are done.
//
// A merge runs a dozen short parallel regions back to back (one per hierarchy level), so
// threads spin briefly on atomics before sleeping on the condition variable: waking a
// sleeping thread costs a system call per region, which profiling showed at ~10% of a merge.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <utility>
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
      stop_.store(true);
    }
    wake_.notify_all();
    for (auto& t : workers_) t.join();
  }
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  unsigned size() const { return static_cast<unsigned>(workers_.size()) + 1; }

  /// Runs task(i) for i in [0, count), spread over the pool and the calling thread; returns
  /// when all are done, rethrowing the first exception a task threw. One task runs inline.
  void run(std::size_t count, const std::function<void(std::size_t)>& task) {
    if (count == 0) return;
    if (count == 1 || workers_.empty()) {
      std::exception_ptr error;
      for (std::size_t i = 0; i < count; ++i) {
        try {
          task(i);
        } catch (...) {
          if (!error) error = std::current_exception();
        }
      }
      if (error) std::rethrow_exception(error);
      return;
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      task_ = &task;
      error_ = nullptr;
      count_ = count;
      next_.store(0);
      active_.store(static_cast<unsigned>(workers_.size()));
      generation_.fetch_add(1);
    }
    wake_.notify_all();
    drain();
    // wait for the workers: spin first, sleep if it takes long
    const auto until = std::chrono::steady_clock::now() + std::chrono::microseconds(200);
    while (active_.load() != 0 && std::chrono::steady_clock::now() < until)
      std::this_thread::yield();
    if (active_.load() != 0) {
      std::unique_lock<std::mutex> lock(mutex_);
      done_.wait(lock, [this] { return active_.load() == 0; });
    }
    std::exception_ptr error;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      error = std::exchange(error_, nullptr);
    }
    if (error) std::rethrow_exception(error);
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
      try {
        (*task_)(i);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!error_) error_ = std::current_exception();
      }
    }
  }
  void work() {
    std::uint64_t seen = 0;
    for (;;) {
      // spin a little for the next region, then sleep
      const auto until = std::chrono::steady_clock::now() + std::chrono::microseconds(200);
      while (generation_.load() == seen && !stop_.load() &&
             std::chrono::steady_clock::now() < until)
        std::this_thread::yield();
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [&] { return stop_.load() || generation_.load() != seen; });
        if (stop_.load()) return;
        seen = generation_.load();
      }
      drain();
      if (active_.fetch_sub(1) == 1) {
        std::lock_guard<std::mutex> lock(mutex_);  // pairs with the caller's wait
        done_.notify_one();
      }
    }
  }

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  const std::function<void(std::size_t)>* task_ = nullptr;
  std::exception_ptr error_;  ///< the region's first exception, under mutex_
  std::size_t count_ = 0;
  std::atomic<std::size_t> next_{0};
  std::atomic<unsigned> active_{0};
  std::atomic<std::uint64_t> generation_{0};
  std::atomic<bool> stop_{false};
};

}  // namespace csculpt::detail
