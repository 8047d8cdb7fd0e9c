#pragma once
// How far a release of fixings reaches around a part without a binary solution
// (RoundingOptions::max_releases), kept apart from the rounding loop so that its rule is tested
// on its own. A release starts 2 LP steps around the part and reaches twice as far as the last
// one only where the part fails again: where its rows share a column with the rows the last
// release was made around. A failure elsewhere starts at 2 again. (Until the sixty-fifth
// session the reach doubled with every release of the rounding, wherever it was. Measured,
// TOSCA_r victoria0-victoria4 without WKS at full resolution: releases 2 to 5 started at 4, 8,
// 16 and 32 steps and freed 5 099, 1 330, 7 247 and 5 204 fixings, nearly all there were, each
// followed by an LP over almost the whole 22.8 M-variable space of 12-13 minutes. With this
// rule the same rounding, resumed, released 61 to 2 232 fixings six times, within 2 to 8 steps,
// and finished in 38 minutes; docs/results-log.md.)
#include <algorithm>
#include <cstdint>
#include <vector>

namespace shapematch::detail {

class ReleaseReach {
public:
  static constexpr int kFirst = 2;
  static constexpr int kLargestFirst = 64;  // (the old rule's: 2 << 5)

  // The depth a release around rows holding the columns `cols` starts from.
  int first_depth(const std::vector<int64_t>& cols) const {
    return same_part(cols) ? std::max(kFirst, std::min(2 * depth_, kLargestFirst)) : kFirst;
  }
  // Whether rows holding the columns `cols` share one with the last release's (the same part
  // failing again).
  bool same_part(const std::vector<int64_t>& cols) const {
    if (depth_ == 0) return false;
    for (int64_t j : cols)
      if (std::binary_search(last_cols_.begin(), last_cols_.end(), j)) return true;
    return false;
  }
  // A release was made around rows holding the columns `cols`, reaching `depth` steps (1: the
  // fixings a search's proofs rest on, before any release within 2 steps).
  void released(std::vector<int64_t> cols, int depth) {
    std::sort(cols.begin(), cols.end());
    cols.erase(std::unique(cols.begin(), cols.end()), cols.end());
    last_cols_ = std::move(cols);
    depth_ = depth;
  }

private:
  std::vector<int64_t> last_cols_;
  int depth_ = 0;
};

}  // namespace shapematch::detail
