#pragma once
// Positions of keys in a sorted array of distinct non-negative keys, for tens of millions of
// lookups into an array of millions (the constraint builder's product-edge ids).
#include <algorithm>
#include <cstdint>
#include <vector>

namespace shapematch::detail {

// A table over the keys' high bits points into the sorted array, so a lookup searches a bucket
// of about one key: a cache miss or two where a binary search over 100+ MB cost some twenty
// dependent ones. rank(k) is std::lower_bound's position of k. The array must outlive the index
// and hold fewer than 2^32 keys (positions are 32-bit).
class SortedIndex {
public:
  explicit SortedIndex(const std::vector<int64_t>& sorted) : keys_(sorted) {
    const int64_t n = static_cast<int64_t>(sorted.size());
    const uint64_t top = n > 0 ? static_cast<uint64_t>(std::max<int64_t>(sorted.back(), 0)) : 0;
    while ((top >> shift_) > static_cast<uint64_t>(std::max<int64_t>(n, 1))) ++shift_;
    const uint64_t buckets = (top >> shift_) + 1;
    begin_.resize(buckets + 1);
    // begin_[b]: the first position whose key's bucket is b or above.
    int64_t i = 0;
    for (uint64_t b = 0; b <= buckets; ++b) {
      while (i < n && bucket(sorted[i]) < b) ++i;
      begin_[b] = static_cast<uint32_t>(i);
    }
  }
  int64_t rank(int64_t key) const {
    if (key < 0) return 0;
    const uint64_t b = bucket(key);
    if (b + 1 >= begin_.size()) return static_cast<int64_t>(keys_.size());
    const auto first = keys_.begin() + begin_[b], last = keys_.begin() + begin_[b + 1];
    return std::lower_bound(first, last, key) - keys_.begin();
  }

private:
  uint64_t bucket(int64_t key) const { return static_cast<uint64_t>(key) >> shift_; }
  const std::vector<int64_t>& keys_;
  int shift_ = 0;
  std::vector<uint32_t> begin_;
};

}  // namespace shapematch::detail
