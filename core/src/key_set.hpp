#pragma once
// A set of 64-bit keys for membership tests over millions of product triangles.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace shapematch::detail {

// Keys that are hashes already (CarriedIterate::key), so their low bits pick the slot: open
// addressing, linear probing, the table at most half full. A lookup costs a cache miss or two
// where a binary search over millions of sorted keys cost some twenty dependent ones.
class KeySet {
public:
  explicit KeySet(const std::vector<uint64_t>& keys) {
    size_t capacity = 16;
    while (capacity < 2 * keys.size()) capacity *= 2;
    mask_ = capacity - 1;
    slots_.assign(capacity, kEmpty);
    for (uint64_t k : keys) {
      if (k == kEmpty) {
        has_empty_ = true;
        continue;
      }
      size_t i = k & mask_;
      while (slots_[i] != kEmpty && slots_[i] != k) i = (i + 1) & mask_;
      slots_[i] = k;
    }
  }
  bool contains(uint64_t k) const {
    if (k == kEmpty) return has_empty_;
    for (size_t i = k & mask_;; i = (i + 1) & mask_) {
      if (slots_[i] == k) return true;
      if (slots_[i] == kEmpty) return false;
    }
  }

private:
  static constexpr uint64_t kEmpty = 0;
  std::vector<uint64_t> slots_;
  size_t mask_ = 0;
  bool has_empty_ = false;
};

}  // namespace shapematch::detail
