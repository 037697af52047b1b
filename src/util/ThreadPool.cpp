#include "stereo_fusion/util/ThreadPool.h"

#include <algorithm>

namespace stereo_fusion {

ThreadPool::ThreadPool(int num_threads) {
  int total = num_threads > 0 ? num_threads : static_cast<int>(std::thread::hardware_concurrency());
  total = std::max(total, 1);
  for (int i = 1; i < total; ++i) workers_.emplace_back([this] { workerLoop(); });
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  for (std::thread& t : workers_) t.join();
}

void ThreadPool::runChunks() {
  while (true) {
    const size_t begin = next_index_.fetch_add(job_grain_, std::memory_order_relaxed);
    if (begin >= job_size_) return;
    (*job_)(begin, std::min(begin + job_grain_, job_size_));
  }
}

void ThreadPool::workerLoop() {
  uint64_t seen_generation = 0;
  while (true) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return stopping_ || generation_ != seen_generation; });
      if (stopping_) return;
      seen_generation = generation_;
      ++busy_workers_;
    }
    runChunks();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      --busy_workers_;
    }
    done_.notify_one();
  }
}

void ThreadPool::parallelFor(size_t n, size_t grain,
                             const std::function<void(size_t, size_t)>& fn) {
  if (n == 0) return;
  grain = std::max<size_t>(grain, 1);
  if (workers_.empty() || n <= grain) {
    fn(0, n);
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    job_ = &fn;
    job_size_ = n;
    job_grain_ = grain;
    next_index_.store(0, std::memory_order_relaxed);
    ++generation_;
  }
  wake_.notify_all();
  runChunks();
  // Workers that woke late find no chunk left and leave at once; wait for the ones still busy.
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [&] { return busy_workers_ == 0; });
  job_ = nullptr;
}

}  // namespace stereo_fusion
