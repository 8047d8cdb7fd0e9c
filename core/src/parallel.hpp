#pragma once
// A minimal static-partition parallel loop over index ranges (the hot loops of assembly and the
// native PDHG kernels are uniform, so static chunks balance well and need no scheduler).
#include "shapematch/system.hpp"

#include <algorithm>
#include <cstdint>
#include <exception>
#include <thread>
#include <vector>

namespace shapematch::detail {

// Calls body(begin, end, chunk) for `threads` contiguous chunks of [0, n), each of about `grain`
// items at least (a thread costs a spawn). If bodies throw, every chunk still runs to its end and
// the first chunk's exception is rethrown here (an exception escaping a std::thread would
// terminate the process).
template <class Body>
void parallel_chunks(int64_t n, int threads, Body&& body, int64_t grain = 4096) {
  if (threads <= 0) threads = worker_threads();
  threads = static_cast<int>(std::max<int64_t>(1, std::min<int64_t>(threads, n / std::max<int64_t>(1, grain) + 1)));
  if (threads == 1) {
    body(int64_t{0}, n, 0);
    return;
  }
  std::vector<std::exception_ptr> errors(threads);
  auto guarded = [&body, &errors](int64_t b, int64_t e, int t) {
    try {
      body(b, e, t);
    } catch (...) {
      errors[t] = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(threads - 1);
  const int64_t step = (n + threads - 1) / threads;
  for (int t = 1; t < threads; ++t) {
    const int64_t b = std::min(n, t * step), e = std::min(n, (t + 1) * step);
    pool.emplace_back(guarded, b, e, t);
  }
  guarded(int64_t{0}, std::min(n, step), 0);
  for (auto& th : pool) th.join();
  for (const auto& error : errors)
    if (error) std::rethrow_exception(error);
}

template <class Body>
void parallel_for(int64_t n, int threads, Body&& body, int64_t grain = 4096) {
  parallel_chunks(
      n, threads,
      [&](int64_t b, int64_t e, int) {
        for (int64_t i = b; i < e; ++i) body(i);
      },
      grain);
}

// body(i) for every row i of a CSR matrix (row_ptr: its rows + 1 offsets), in chunks of about
// equal entries plus rows: a matching LP's face rows, all at the end of A, hold as many entries
// as its closedness rows, so equal row counts gave one thread twice the other's work.
template <class Body>
void parallel_rows(const std::vector<uint32_t>& row_ptr, int threads, Body&& body) {
  const int64_t n = static_cast<int64_t>(row_ptr.size()) - 1;
  if (n <= 0) return;
  if (threads <= 0) threads = worker_threads();
  const int64_t total = int64_t(row_ptr[n]) + n;
  threads = static_cast<int>(std::max<int64_t>(1, std::min<int64_t>(threads, total / 16384 + 1)));
  std::vector<int64_t> cut(threads + 1, n);
  cut[0] = 0;
  for (int t = 1; t < threads; ++t) {  // the first row whose offset reaches t/threads of the total
    const int64_t target = total * t / threads;
    int64_t lo = cut[t - 1], hi = n;
    while (lo < hi) {
      const int64_t mid = lo + (hi - lo) / 2;
      if (int64_t(row_ptr[mid]) + mid < target) lo = mid + 1; else hi = mid;
    }
    cut[t] = lo;
  }
  parallel_chunks(
      threads, threads,
      [&](int64_t b, int64_t e, int) {
        for (int64_t c = b; c < e; ++c)
          for (int64_t i = cut[c]; i < cut[c + 1]; ++i) body(i);
      },
      1);
}

// Sorts [first, first + n) like std::sort (for a total order: the same result): chunks sorted in
// parallel, then merged pairwise, the merges of each round in parallel too.
template <class T>
void parallel_sort(T* first, int64_t n, int threads = 0) {
  if (threads <= 0) threads = worker_threads();
  const int64_t chunks = std::max<int64_t>(1, std::min<int64_t>(threads, n / 65536));
  std::vector<int64_t> cut(chunks + 1);
  for (int64_t c = 0; c <= chunks; ++c) cut[c] = n * c / chunks;
  // grain 2: a second thread only where there is a second chunk (or merge).
  parallel_for(chunks, threads, [&](int64_t c) { std::sort(first + cut[c], first + cut[c + 1]); }, 2);
  for (int64_t width = 1; width < chunks; width *= 2) {
    const int64_t merges = (chunks + 2 * width - 1) / (2 * width);
    parallel_for(merges, threads, [&](int64_t k) {
      const int64_t lo = 2 * width * k, mid = std::min(chunks, lo + width), hi = std::min(chunks, lo + 2 * width);
      if (mid < hi) std::inplace_merge(first + cut[lo], first + cut[mid], first + cut[hi]);
    }, 2);
  }
}

}  // namespace shapematch::detail
