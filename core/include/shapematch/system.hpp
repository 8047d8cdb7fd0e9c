#pragma once
// Process-level measurements shared by the command line, the reports and the benchmarks.
#include <chrono>

namespace shapematch {

// Peak resident set size of this process so far, in MiB.
double peak_rss_mb();

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
