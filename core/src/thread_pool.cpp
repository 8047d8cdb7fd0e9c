#include "thread_pool.hpp"

#include "parallel.hpp"

#include <chrono>
#include <exception>
#include <utility>

namespace shapematch::detail {
namespace {

// Waits a little before sleeping: the next loop usually starts within microseconds (the two
// loops of an iteration follow each other), and a futex wake-up costs tens of microseconds.
constexpr auto kSpin = std::chrono::microseconds(50);

template <class Ready>
bool spin_until(Ready ready) {
  const auto until = std::chrono::steady_clock::now() + kSpin;
  do {
    for (int k = 0; k < 64; ++k)
      if (ready()) return true;
  } while (std::chrono::steady_clock::now() < until);
  return ready();
}

}  // namespace

ThreadPool::ThreadPool(int threads) {
  if (threads <= 0) threads = worker_threads();
  for (int t = 1; t < threads; ++t) workers_.emplace_back([this] { work(); });
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
    generation_.fetch_add(1);
  }
  start_.notify_all();
  for (auto& w : workers_) w.join();
}

void ThreadPool::drain(std::unique_lock<std::mutex>& lock) {
  while (next_ < chunks_) {
    const int c = next_++;
    const std::function<void(int)>* job = job_;
    lock.unlock();
    std::exception_ptr failure;
    try {
      (*job)(c);
    } catch (...) {
      failure = std::current_exception();
    }
    lock.lock();
    if (failure && !error_) error_ = failure;
    // A failed chunk still counts as finished, so that run() returns (and rethrows) only once no
    // thread holds the job any more.
    if (finished_.fetch_add(1) + 1 == chunks_) done_.notify_one();
  }
}

void ThreadPool::run(int chunks, const std::function<void(int)>& job) {
  if (chunks <= 0) return;
  if (workers_.empty()) {
    std::exception_ptr first;
    for (int c = 0; c < chunks; ++c) {
      try {
        job(c);
      } catch (...) {
        if (!first) first = std::current_exception();
      }
    }
    if (first) std::rethrow_exception(first);
    return;
  }
  std::unique_lock lock(mutex_);
  job_ = &job;
  chunks_ = chunks;
  next_ = 0;
  finished_.store(0);
  generation_.fetch_add(1);
  if (sleeping_ > 0) start_.notify_all();
  drain(lock);
  if (finished_.load() != chunks_) {
    lock.unlock();
    if (!spin_until([&] { return finished_.load(std::memory_order_acquire) == chunks; })) {
      lock.lock();
      done_.wait(lock, [&] { return finished_.load() == chunks_; });
    } else {
      lock.lock();
    }
  }
  job_ = nullptr;  // a worker that wakes late finds next_ == chunks_ and goes back to waiting
  if (error_) {
    const std::exception_ptr e = std::exchange(error_, nullptr);
    lock.unlock();
    std::rethrow_exception(e);
  }
}

void ThreadPool::work() {
  uint64_t seen = 0;
  std::unique_lock lock(mutex_);
  for (;;) {
    if (generation_.load() == seen) {
      lock.unlock();
      const bool woke = spin_until([&] { return generation_.load(std::memory_order_acquire) != seen; });
      lock.lock();
      if (!woke) {
        ++sleeping_;
        start_.wait(lock, [&] { return generation_.load() != seen; });
        --sleeping_;
      }
    }
    if (stop_) return;
    seen = generation_.load();
    drain(lock);
  }
}

}  // namespace shapematch::detail
