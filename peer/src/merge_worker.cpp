#include "merge_worker.h"

#include <utility>

namespace csculpt::peer {

void MergeWorker::start(std::function<MergeOutcome()> merge) {
  ready_.store(false, std::memory_order_relaxed);
  outcome_.reset();
  error_ = nullptr;
  thread_ = std::thread([this, merge = std::move(merge)] {
    try {
      outcome_ = merge();
    } catch (...) {
      error_ = std::current_exception();
    }
    ready_.store(true, std::memory_order_release);
    finished_();
  });
}

std::optional<MergeOutcome> MergeWorker::take() {
  if (!thread_.joinable() || !ready_.load(std::memory_order_acquire)) return std::nullopt;
  thread_.join();
  if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
  return std::exchange(outcome_, std::nullopt);
}

void MergeWorker::drop() {
  if (thread_.joinable()) thread_.join();
  outcome_.reset();
  error_ = nullptr;
}

}  // namespace csculpt::peer
