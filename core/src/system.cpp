#include "shapematch/system.hpp"

#include <sys/resource.h>

namespace shapematch {

double peak_rss_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux reports KiB
}

}  // namespace shapematch
