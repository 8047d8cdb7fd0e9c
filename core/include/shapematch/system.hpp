#pragma once
// Process-level measurements shared by the command line, the reports and the benchmarks.
#include <chrono>
#include <cstdint>

namespace shapematch {

// Peak resident set size of this process so far, in MiB.
double peak_rss_mb();

// Memory the system can give without swapping (MemAvailable of /proc/meminfo, and at most what a
// cgroup v2 limit leaves), in bytes; 0 where it cannot be read.
uint64_t available_memory_bytes();

// Threads of this process's parallel loops (assembly, pricing, the native PDHG kernels): the
// CPUs it may run on (its affinity mask, so `taskset` limits it), or fewer where
// set_worker_threads asked for fewer. Sums are split per thread, so results can differ in their
// last digits with the count.
int worker_threads();
// At most `threads` (0: every CPU of the affinity mask). Call it before the first solve: a
// solver keeps the count it started with.
void set_worker_threads(int threads);

// A stop asked for from outside a run (match's SIGINT/SIGTERM handler, where it has a
// checkpoint): PDHG checks it at its residual checks and throws Stopped (errors.hpp) there, after
// its snapshot where it has one, so that a long run leaves off where it can be gone on from.
// Async-signal-safe. `signal`: what asked (reported back by stop_requested; 0: none asked).
void request_stop(int signal) noexcept;
int stop_requested() noexcept;
// Forgets the stop asked for (a test that asked for one; a caller that has handled it).
void clear_stop() noexcept;

class Stopwatch {
public:
  Stopwatch() : start_(std::chrono::steady_clock::now()) {}
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  void reset() { start_ = std::chrono::steady_clock::now(); }

private:
  std::chrono::steady_clock::time_point start_;
};

}  // namespace shapematch
