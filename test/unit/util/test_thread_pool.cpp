#include <gtest/gtest.h>

#include <atomic>
#include <numeric>

#include "QuickMode.h"
#include "stereo_fusion/util/ThreadPool.h"

using stereo_fusion::ThreadPool;

TEST(ThreadPool, EveryItemExactlyOnce) {
  for (int threads : {1, 2, 4}) {
    ThreadPool pool(threads);
    EXPECT_EQ(pool.size(), threads);
    for (size_t n : {0ul, 1ul, 7ul, 1000ul, 12345ul}) {
      std::vector<std::atomic<int>> hits(n);
      for (auto& h : hits) h = 0;
      pool.parallelFor(n, 13, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) ++hits[i];
      });
      for (size_t i = 0; i < n; ++i) ASSERT_EQ(hits[i].load(), 1) << threads << " " << n;
    }
  }
}

TEST(ThreadPool, ManyConsecutiveJobs) {
  ThreadPool pool(3);
  std::atomic<long> sum{0};
  for (int job = 0; job < 2000; ++job)
    pool.parallelFor(64, 1, [&](size_t b, size_t e) {
      for (size_t i = b; i < e; ++i) sum += static_cast<long>(i);
    });
  EXPECT_EQ(sum.load(), 2000L * (63 * 64 / 2));
}

TEST(ThreadPool, AlternatingJobShapesNeverSkipOrRepeatItems) {
  // Mapper alternates lookup (grain 4) and fusion (grain 8) jobs. A worker waking late for one
  // job must never run chunks of the next with the old size or grain.
  for (int threads : {3, 8}) {
    ThreadPool pool(threads);
    std::vector<int> hits(64);
    int bad = 0;
    const int jobs = stereo_fusion::test::quickMode() ? 20000 : 300000;
    for (int job = 0; job < jobs; ++job) {
      const size_t n = 17 + (job % 5) * 11;
      const size_t grain = job % 2 ? 8 : 1;
      std::fill(hits.begin(), hits.end(), 0);
      pool.parallelFor(n, grain, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) __atomic_add_fetch(&hits[i], 1, __ATOMIC_RELAXED);
      });
      for (size_t i = 0; i < hits.size(); ++i) bad += hits[i] != (i < n ? 1 : 0);
    }
    EXPECT_EQ(bad, 0) << threads << " threads";
  }
}

TEST(ThreadPool, ExceptionsReachTheCallerAfterAllChunksStop) {
  ThreadPool pool(3);
  std::atomic<int> running{0};
  EXPECT_THROW(pool.parallelFor(1000, 1,
                                [&](size_t b, size_t) {
                                  ++running;
                                  if (b == 500) throw std::runtime_error("boom");
                                  --running;
                                }),
               std::runtime_error);
  EXPECT_EQ(running.load(), 1);  // only the throwing chunk never finished
  // The pool still works.
  std::atomic<int> sum{0};
  pool.parallelFor(100, 3, [&](size_t b, size_t e) { sum += static_cast<int>(e - b); });
  EXPECT_EQ(sum.load(), 100);
}
