#pragma once
// A persistent pool for the native PDHG kernels: one iteration is two short parallel loops, so
// threads are kept alive and woken per loop instead of being created each time.
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace shapematch::detail {

class ThreadPool {
public:
  explicit ThreadPool(int threads);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int size() const { return static_cast<int>(workers_.size()) + 1; }
  // Runs job(t) for t = 0 … size()−1 (t = 0 on the calling thread) and waits for all.
  void run(const std::function<void(int)>& job);

private:
  void work(int t);
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable start_, done_;
  const std::function<void(int)>* job_ = nullptr;
  uint64_t generation_ = 0;
  int pending_ = 0;
  bool stop_ = false;
};

}  // namespace shapematch::detail
