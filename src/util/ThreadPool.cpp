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

void ThreadPool::runChunks(const Job& job) {
  while (true) {
    const size_t begin = next_index_.fetch_add(job.grain, std::memory_order_relaxed);
    if (begin >= job.size) return;
    try {
      (*job.fn)(begin, std::min(begin + job.grain, job.size));
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!error_) error_ = std::current_exception();
    }
  }
}

void ThreadPool::workerLoop() {
  uint64_t seen_generation = 0;
  while (true) {
    Job job;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return stopping_ || generation_ != seen_generation; });
      if (stopping_) return;
      seen_generation = generation_;
      // A worker that wakes after its job has finished must not touch the next one's state:
      // the job is copied, and joined, only while the caller still waits for it.
      if (current_.fn == nullptr) continue;
      job = current_;
      ++busy_workers_;
    }
    runChunks(job);
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
  Job job{&fn, n, grain};
  {
    std::lock_guard<std::mutex> lock(mutex_);
    current_ = job;
    error_ = nullptr;
    next_index_.store(0, std::memory_order_relaxed);
    ++generation_;
  }
  wake_.notify_all();
  runChunks(job);
  std::exception_ptr error;
  {
    // Wait for the workers that joined this job; the job is withdrawn before the lock is
    // released, so workers waking later skip it.
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [&] { return busy_workers_ == 0; });
    current_ = Job{};
    error = error_;
    error_ = nullptr;
  }
  if (error) std::rethrow_exception(error);
}

}  // namespace stereo_fusion
