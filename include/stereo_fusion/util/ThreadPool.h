#pragma once
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace stereo_fusion {

/// Persistent worker pool for the parallel stages (regions in lookup, blocks in fusion and
/// meshing). Idle workers sleep on a condition variable instead of spinning, so a busy
/// neighbour process (a SLAM stack) is not starved and does not starve us.
class ThreadPool {
 public:
  /// `num_threads` counts the calling thread too; 0 means std::thread::hardware_concurrency().
  explicit ThreadPool(int num_threads = 0);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int size() const { return static_cast<int>(workers_.size()) + 1; }

  /// Calls fn(begin, end) over [0, n) in chunks of `grain` items, on all threads, and returns
  /// when every chunk is done. Chunks are claimed dynamically (balanced), so `fn` must only
  /// write to per-item state for the result to be independent of the thread count. The first
  /// exception thrown by `fn` on any thread is rethrown here after all chunks have stopped.
  /// Not re-entrant: do not call parallelFor from inside `fn`; one caller at a time.
  void parallelFor(size_t n, size_t grain, const std::function<void(size_t, size_t)>& fn);

 private:
  struct Job {
    const std::function<void(size_t, size_t)>* fn = nullptr;
    size_t size = 0;
    size_t grain = 1;
  };
  void workerLoop();
  void runChunks(const Job& job);

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable done_;
  Job current_;                        // guarded by mutex_; fn == nullptr when no job runs
  std::atomic<size_t> next_index_{0};  // next unclaimed item of the current job
  std::exception_ptr error_;           // guarded by mutex_
  uint64_t generation_ = 0;
  int busy_workers_ = 0;
  bool stopping_ = false;
};

/// pool->parallelFor(n, grain, fn) when a pool is given; otherwise fn(0, n) on this thread.
inline void parallelForOrHere(ThreadPool* pool, size_t n, size_t grain,
                              const std::function<void(size_t, size_t)>& fn) {
  if (pool != nullptr)
    pool->parallelFor(n, grain, fn);
  else
    fn(0, n);
}

}  // namespace stereo_fusion
