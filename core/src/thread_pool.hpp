#pragma once
// A persistent pool for the native PDHG kernels: one iteration is two short parallel loops, so
// threads are kept alive and woken per loop instead of being created each time.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <exception>
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
  // Runs job(c) once for each chunk c = 0 … chunks−1 and waits for all. Chunks go to whichever
  // thread asks first, the caller included, which starts at once: on a shared machine a worker
  // that is not scheduled delays the loop by at most the chunk it holds, not by its whole share.
  // If chunks throw, the others still run, and the first exception is rethrown here.
  void run(int chunks, const std::function<void(int)>& job);

private:
  void work();
  // Claims and runs chunks of the current loop until none is left; `lock` holds mutex_.
  void drain(std::unique_lock<std::mutex>& lock);

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable start_, done_;
  // Under mutex_; generation_ and finished_ are atomic so that waiting threads can spin on them.
  const std::function<void(int)>* job_ = nullptr;
  int chunks_ = 0, next_ = 0;
  std::atomic<int> finished_{0};
  std::atomic<uint64_t> generation_{0};
  std::exception_ptr error_;  // the first exception of the current loop
  int sleeping_ = 0;
  bool stop_ = false;
};

}  // namespace shapematch::detail
