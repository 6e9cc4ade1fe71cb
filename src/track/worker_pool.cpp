#include "track/worker_pool.h"

#include <algorithm>

namespace dynahand::track {

WorkerPool::WorkerPool(int threads) {
  for (int t = 1; t < std::max(threads, 1); ++t) workers_.emplace_back([this] { workerLoop(); });
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  for (std::thread& t : workers_) t.join();
}

void WorkerPool::drain() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (next_ < count_) {
    const int i = next_++;
    lock.unlock();
    (*work_)(i);
    lock.lock();
    if (++finished_ == count_) done_.notify_all();
  }
}

void WorkerPool::workerLoop() {
  unsigned seen = 0;
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
    }
    drain();
  }
}

void WorkerPool::run(int count, const std::function<void(int)>& work) {
  if (workers_.empty() || count <= 1) {
    for (int i = 0; i < count; ++i) work(i);
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    work_ = &work;
    count_ = count;
    next_ = 0;
    finished_ = 0;
    ++generation_;
  }
  wake_.notify_all();
  drain();
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [&] { return finished_ == count_; });
  work_ = nullptr;
}

}  // namespace dynahand::track
