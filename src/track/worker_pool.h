// A fixed set of worker threads that run the indices of a loop in parallel, for the
// tracker's simulations. run() returns when every index is done; with one thread (the
// default) it is a plain loop on the caller. Which thread runs which index is not fixed,
// so the work for an index must depend on nothing but the index.
#pragma once

#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace dynahand::track {

class WorkerPool {
 public:
  // threads: threads that work in run(), the caller included (1 = no extra threads).
  explicit WorkerPool(int threads = 1);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int threads() const { return static_cast<int>(workers_.size()) + 1; }
  // Calls work(i) for every i in [0, count), on the caller and the workers.
  void run(int count, const std::function<void(int)>& work);

 private:
  void workerLoop();
  void drain();  // takes indices until none is left

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  const std::function<void(int)>* work_ = nullptr;
  int count_ = 0, next_ = 0, finished_ = 0;
  unsigned generation_ = 0;
  bool stop_ = false;
};

}  // namespace dynahand::track
