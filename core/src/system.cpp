#include "shapematch/system.hpp"

#include <sched.h>
#include <sys/resource.h>

#include <algorithm>
#include <atomic>
#include <fstream>
#include <limits>
#include <string>
#include <thread>

namespace shapematch {

double peak_rss_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux reports KiB
}

uint64_t available_memory_bytes() {
  uint64_t available = 0;
  std::ifstream in("/proc/meminfo");
  for (std::string key; in >> key;) {
    uint64_t kib = 0;
    if (key == "MemAvailable:" && in >> kib) {
      available = kib * 1024;
      break;
    }
    in.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
  }
  // In a container the cgroup's limit binds first (v2: memory.max, "max" where there is none).
  uint64_t limit = 0, used = 0;
  if (std::ifstream max("/sys/fs/cgroup/memory.max"); max >> limit) {
    std::ifstream("/sys/fs/cgroup/memory.current") >> used;
    const uint64_t left = limit > used ? limit - used : 1;  // (1: none left, yet "known")
    available = available == 0 ? left : std::min(available, left);
  }
  return available;
}

namespace {
std::atomic<int> g_thread_limit{0};

int affinity_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) == 0) {
    const int n = CPU_COUNT(&set);
    if (n > 0) return n;
  }
  const unsigned n = std::thread::hardware_concurrency();
  return n == 0 ? 1 : static_cast<int>(n);
}
}  // namespace

int worker_threads() {
  const int cpus = affinity_cpus();  // a system call of a microsecond; a parallel loop costs far more
  const int limit = g_thread_limit.load(std::memory_order_relaxed);
  return limit > 0 ? std::min(limit, cpus) : cpus;
}

namespace {
std::atomic<int> g_stop{0};
static_assert(std::atomic<int>::is_always_lock_free, "request_stop is called from signal handlers");
}  // namespace

void request_stop(int signal) noexcept {
  int none = 0;  // (the first request is the one reported)
  g_stop.compare_exchange_strong(none, signal == 0 ? -1 : signal, std::memory_order_relaxed);
}
int stop_requested() noexcept { return g_stop.load(std::memory_order_relaxed); }
void clear_stop() noexcept { g_stop.store(0, std::memory_order_relaxed); }

void set_worker_threads(int threads) { g_thread_limit.store(std::max(0, threads), std::memory_order_relaxed); }

}  // namespace shapematch
