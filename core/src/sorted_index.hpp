#pragma once
// Positions of keys in a sorted array of distinct non-negative keys, for tens of millions of
// lookups into an array of millions (the constraint builder's product-edge ids).
#include <algorithm>
#include <bit>
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

// The distinct keys of a list, all in [0, universe), as a bitmap with a count per word: sorted
// and deduplicated in two passes over the list, and ranked in O(1). For a universe not much
// larger than the list (the constraint builder's product edges at the finest level: 6·10^8 ids
// for 3·10^7 touched), where a comparison sort of the list was 6 % of a rebuild. Holds universe/8
// bytes and universe/16 more for the counts; keys must be in range (unchecked).
class KeyBitmap {
public:
  KeyBitmap(const std::vector<int64_t>& keys, int64_t universe)
      : bits_(static_cast<size_t>((universe + 63) / 64), 0) {
    for (const int64_t k : keys) bits_[static_cast<size_t>(k) >> 6] |= uint64_t(1) << (k & 63);
    before_.resize(bits_.size() + 1);
    uint64_t count = 0;
    for (size_t w = 0; w < bits_.size(); ++w) {
      before_[w] = static_cast<uint32_t>(count);
      count += static_cast<uint64_t>(std::popcount(bits_[w]));
    }
    before_.back() = static_cast<uint32_t>(count);
    size_ = static_cast<int64_t>(count);
  }
  // How many distinct keys (exact; ranks are right only below 2^32: the caller checks its bound).
  int64_t size() const { return size_; }
  // The distinct keys, ascending.
  std::vector<int64_t> sorted() const {
    std::vector<int64_t> out;
    out.reserve(static_cast<size_t>(size_));
    for (size_t w = 0; w < bits_.size(); ++w)
      for (uint64_t b = bits_[w]; b != 0; b &= b - 1) out.push_back(int64_t(w << 6) + std::countr_zero(b));
    return out;
  }
  // The position of a key among them (a key in the list).
  int64_t rank(int64_t key) const {
    const size_t w = static_cast<size_t>(key) >> 6;
    return before_[w] + std::popcount(bits_[w] & ((uint64_t(1) << (key & 63)) - 1));
  }

private:
  std::vector<uint64_t> bits_;
  std::vector<uint32_t> before_;
  int64_t size_ = 0;
};

}  // namespace shapematch::detail
