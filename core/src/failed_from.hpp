#pragma once
// The fixings to 1 an infeasibility proof blamed, remembered per state of the rounding they were
// made from, so that a rounding back at that state after undoing earlier fixings does not make
// them again (RoundingOptions::remember_refuted). Kept apart from the rounding loop so that its
// rule is tested on its own.
#include <cstdint>
#include <cstring>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace shapematch::detail {

// A hash of a rounding's state: one value per variable (−1 free, 0, 1). Equal states hash equal;
// others rarely collide, and a collision costs candidates left out, not a wrong result.
inline uint64_t state_hash(const std::vector<int8_t>& value) {
  uint64_t h = 0x9e3779b97f4a7c15ull ^ value.size();
  const auto mix = [&](uint64_t w) {
    h ^= w + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    h *= 0xff51afd7ed558ccdull;
    h ^= h >> 33;
  };
  size_t k = 0;
  for (; k + 8 <= value.size(); k += 8) {
    uint64_t w;
    std::memcpy(&w, value.data() + k, 8);
    mix(w);
  }
  uint64_t tail = 0;
  if (k < value.size()) std::memcpy(&tail, value.data() + k, value.size() - k);
  mix(tail);
  return h;
}

class FailedFrom {
public:
  // Fixings to 1 made from the state `from` that a proof blamed.
  void blamed(uint64_t from, const std::vector<int64_t>& ones) {
    if (!ones.empty()) failed_[from].insert(ones.begin(), ones.end());
  }
  // Those blamed from `state` so far (empty where none were, or it was not seen).
  std::vector<int64_t> recall(uint64_t state) const {
    const auto it = failed_.find(state);
    if (it == failed_.end()) return {};
    return {it->second.begin(), it->second.end()};
  }
  bool empty() const { return failed_.empty(); }

private:
  std::unordered_map<uint64_t, std::unordered_set<int64_t>> failed_;
};

}  // namespace shapematch::detail
