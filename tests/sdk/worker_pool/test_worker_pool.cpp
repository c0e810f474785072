// The merge's internal pool (sdk/src/worker_pool.h): run(count, task) calls task(i) exactly once
// for every i in [0, count) and returns only when all are done, for any count (0 included) and
// any pool size (1 = the calling thread alone); one task and a one-thread pool run inline on the
// calling thread in index order; for_chunks partitions [0, n) into the same chunks whatever the
// pool size; a pool runs region after region (after a pause, when its workers sleep, too) and
// shuts down cleanly.
//
// A task that throws, on any thread, does not end the process: the region's other tasks still
// run, run() rethrows the first exception once all are done, and the pool runs the next region.
// Callers that need every task's error catch inside the task (the merge's validation keeps an
// exception_ptr per index); that pattern is tested here too.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <exception>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "worker_pool.h"

namespace csculpt {
namespace {

using detail::WorkerPool;

const unsigned kThreadCounts[] = {1, 2, 3, 8};
const std::size_t kCounts[] = {0, 1, 2, 3, 7, 64, 1000, 100000};

/// Runs pool.run(count) and checks every index was processed exactly once, by the time run
/// returned.
void expect_each_once(WorkerPool& pool, std::size_t count) {
  std::vector<std::atomic<int>> hits(count);
  pool.run(count, [&](std::size_t i) { hits[i].fetch_add(1, std::memory_order_relaxed); });
  std::size_t wrong = 0, first = count;
  for (std::size_t i = 0; i < count; ++i) {
    if (hits[i].load() != 1) {
      ++wrong;
      if (first == count) first = i;
    }
  }
  EXPECT_EQ(wrong, 0u) << "count " << count << " on " << pool.size() << " threads: index " << first
                       << " processed " << (first < count ? hits[first].load() : 0) << " times";
}

TEST(WorkerPool, ATaskThatThrowsReachesTheCallerOnceTheRegionIsDone) {
  for (const unsigned threads : kThreadCounts) {
    WorkerPool pool(threads);
    for (const std::size_t count :
         {std::size_t{1}, std::size_t{2}, std::size_t{64}, std::size_t{1000}}) {
      std::vector<std::atomic<int>> hits(count);
      const std::size_t first = count / 2, last = count - 1;
      std::string caught;
      try {
        pool.run(count, [&](std::size_t i) {
          hits[i].fetch_add(1, std::memory_order_relaxed);
          if (i == first || i == last) throw std::runtime_error("task " + std::to_string(i));
        });
      } catch (const std::runtime_error& e) {
        caught = e.what();
      }
      EXPECT_TRUE(caught == "task " + std::to_string(first) ||
                  caught == "task " + std::to_string(last))
          << "count " << count << " on " << threads << " threads: caught '" << caught << "'";
      std::size_t missed = 0;
      for (const auto& h : hits) missed += h.load() != 1;
      EXPECT_EQ(missed, 0u) << "every task runs once, the throwing ones' neighbours too";
      expect_each_once(pool, 100);  // and the pool goes on
    }
  }
}

TEST(WorkerPool, SizeCountsTheCallingThread) {
  EXPECT_EQ(WorkerPool(1).size(), 1u);
  EXPECT_EQ(WorkerPool(2).size(), 2u);
  EXPECT_EQ(WorkerPool(8).size(), 8u);
  const unsigned hw = std::thread::hardware_concurrency();
  const unsigned expected = hw == 0 ? 1 : (hw > 8 ? 8 : hw);
  EXPECT_EQ(WorkerPool(0).size(), expected) << "0 = the hardware threads, at most 8";
}

TEST(WorkerPool, EveryIndexIsProcessedExactlyOnce) {
  for (unsigned threads : kThreadCounts) {
    WorkerPool pool(threads);
    for (std::size_t count : kCounts) expect_each_once(pool, count);
  }
}

TEST(WorkerPool, ZeroItemsCallsNothing) {
  for (unsigned threads : kThreadCounts) {
    WorkerPool pool(threads);
    std::atomic<int> calls{0};
    pool.run(0, [&](std::size_t) { ++calls; });
    pool.for_chunks(0, 16, [&](std::size_t, std::size_t) { ++calls; });
    EXPECT_EQ(calls.load(), 0) << threads;
  }
}

TEST(WorkerPool, OneTaskAndAOneThreadPoolRunInlineInIndexOrder) {
  const std::thread::id caller = std::this_thread::get_id();
  {
    WorkerPool pool(4);
    std::thread::id ran_on;
    pool.run(1, [&](std::size_t i) {
      EXPECT_EQ(i, 0u);
      ran_on = std::this_thread::get_id();
    });
    EXPECT_EQ(ran_on, caller) << "one task runs inline";
  }
  WorkerPool pool(1);
  std::vector<std::size_t> order;
  pool.run(100, [&](std::size_t i) {
    EXPECT_EQ(std::this_thread::get_id(), caller);
    order.push_back(i);  // no lock: all on the calling thread
  });
  ASSERT_EQ(order.size(), 100u);
  for (std::size_t i = 0; i < order.size(); ++i) ASSERT_EQ(order[i], i);
}

TEST(WorkerPool, SpreadsWorkOverMoreThanOneThread) {
  WorkerPool pool(4);
  std::mutex m;
  std::set<std::thread::id> ids;
  pool.run(64, [&](std::size_t) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    std::lock_guard<std::mutex> lock(m);
    ids.insert(std::this_thread::get_id());
  });
  EXPECT_GT(ids.size(), 1u) << "64 tasks of 2 ms each all ran on one thread";
  EXPECT_LE(ids.size(), 4u);
}

TEST(WorkerPool, ForChunksGivesTheSamePartitionWhateverThePoolSize) {
  for (std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{5}, std::size_t{100},
                        std::size_t{1001}, std::size_t{65536}}) {
    for (std::size_t grain : {std::size_t{1}, std::size_t{3}, std::size_t{64}, std::size_t{2000}}) {
      std::set<std::pair<std::size_t, std::size_t>> expected;
      for (std::size_t b = 0; b < n; b += grain) expected.insert({b, std::min(n, b + grain)});
      for (unsigned threads : kThreadCounts) {
        SCOPED_TRACE("n " + std::to_string(n) + " grain " + std::to_string(grain) + " threads " +
                     std::to_string(threads));
        WorkerPool pool(threads);
        std::mutex m;
        std::vector<std::pair<std::size_t, std::size_t>> chunks;
        std::vector<std::atomic<int>> covered(n);
        pool.for_chunks(n, grain, [&](std::size_t b, std::size_t e) {
          for (std::size_t i = b; i < e; ++i) covered[i].fetch_add(1, std::memory_order_relaxed);
          std::lock_guard<std::mutex> lock(m);
          chunks.emplace_back(b, e);
        });
        EXPECT_EQ(chunks.size(), expected.size()) << "no chunk twice";
        const std::set<std::pair<std::size_t, std::size_t>> got(chunks.begin(), chunks.end());
        EXPECT_EQ(got, expected);
        for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(covered[i].load(), 1) << i;
      }
    }
  }
}

TEST(WorkerPool, RunsRegionAfterRegionIncludingAfterItsWorkersSleep) {
  WorkerPool pool(3);
  for (int region = 0; region < 2000; ++region) expect_each_once(pool, 1 + region % 17);
  for (int pause = 0; pause < 5; ++pause) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));  // past the 200 us spin
    expect_each_once(pool, 5000);
  }
}

TEST(WorkerPool, ResultsDoNotDependOnThePoolSize) {
  // disjoint outputs per index: the same result from every pool size
  auto compute = [](unsigned threads) {
    WorkerPool pool(threads);
    std::vector<double> out(4099);
    pool.for_chunks(out.size(), 37, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i)
        out[i] = static_cast<double>(i) * 0.5 + 1.0 / (1.0 + static_cast<double>(i));
    });
    return out;
  };
  const std::vector<double> one = compute(1);
  for (unsigned threads : kThreadCounts) EXPECT_EQ(compute(threads), one) << threads;
}

TEST(WorkerPool, TasksThatCatchTheirOwnExceptionsReportExactlyTheFailingIndices) {
  // the merge's pattern: each index keeps its exception, the caller rethrows the first
  for (unsigned threads : kThreadCounts) {
    WorkerPool pool(threads);
    std::vector<std::exception_ptr> errors(50);
    pool.run(errors.size(), [&](std::size_t i) {
      try {
        if (i % 7 == 3) throw std::runtime_error("index " + std::to_string(i));
      } catch (...) {
        errors[i] = std::current_exception();
      }
    });
    for (std::size_t i = 0; i < errors.size(); ++i) EXPECT_EQ(errors[i] != nullptr, i % 7 == 3);
    try {
      for (const auto& e : errors)
        if (e) std::rethrow_exception(e);
      ADD_FAILURE() << "nothing rethrown";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "index 3") << "the first in index order";
    }
    expect_each_once(pool, 100);  // and the pool works on
  }
}

TEST(WorkerPool, ManyPoolsStartAndStopCleanly) {
  for (int i = 0; i < 50; ++i) {
    WorkerPool pool(1 + i % 5);
    if (i % 2) expect_each_once(pool, static_cast<std::size_t>(i));
  }
}

}  // namespace
}  // namespace csculpt
