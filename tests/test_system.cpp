#include "shapematch/system.hpp"

#include <doctest/doctest.h>

#include <sched.h>

#include <thread>

using namespace shapematch;

TEST_CASE("worker threads: the affinity mask's CPUs, at most the limit asked for") {
  cpu_set_t all;
  CPU_ZERO(&all);
  REQUIRE(sched_getaffinity(0, sizeof(all), &all) == 0);
  const int cpus = CPU_COUNT(&all);
  set_worker_threads(0);
  CHECK(worker_threads() == cpus);
  set_worker_threads(1);
  CHECK(worker_threads() == 1);
  set_worker_threads(cpus + 5);  // never more than the CPUs it may run on
  CHECK(worker_threads() == cpus);
  set_worker_threads(0);

  // `taskset -c 0`: the mask, not the machine's count, sets the default. Run in a thread of its own,
  // whose mask alone changes (sched_setaffinity(0) is per thread on Linux).
  int seen = 0;
  std::thread([&] {
    cpu_set_t one;
    CPU_ZERO(&one);
    for (int c = 0; c < CPU_SETSIZE; ++c)
      if (CPU_ISSET(c, &all)) {
        CPU_SET(c, &one);
        break;
      }
    if (sched_setaffinity(0, sizeof(one), &one) == 0) seen = worker_threads();
  }).join();
  CHECK(seen == 1);
  CHECK(worker_threads() == cpus);  // this thread's mask is untouched
}
