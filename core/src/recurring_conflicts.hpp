#pragma once
// Which of propagation's contradictions came back (CoarseToFineOptions::recurring_margin), kept
// apart from the level loop so that its counting is tested on its own.
#include <algorithm>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace shapematch::detail {

// Counts, per π row (by its face: X faces first, then Y faces, as in the LP's row order), the
// passes of one level in which propagation failed there. The row index itself changes with
// every rebuild of the space; the face does not.
class RecurringConflicts {
public:
  // One propagation pass that failed in the π rows of `faces` (duplicates count once). Returns
  // how often the most frequent of them had failed before (0: none came back), and puts those
  // that had into `back`.
  int record(std::vector<int64_t> faces, std::vector<int64_t>& back) {
    std::sort(faces.begin(), faces.end());
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    back.clear();
    int most = 0;
    for (int64_t f : faces)
      if (const int before = seen_[f]++; before > 0) {
        back.push_back(f);
        most = std::max(most, before);
      }
    return most;
  }

private:
  std::unordered_map<int64_t, int> seen_;
};

// Whether a recurring widening of `faces` (fine X faces, each at ring + extra[f] now) to ring `cap`
// is too wide for it (CoarseToFineOptions::recurring_max_share): it would grow more than `share`
// of the level's `num_faces`. Faces already at the cap do not grow and do not count. `share` 0:
// never too wide.
inline bool recurring_too_wide(const std::vector<int>& faces, const std::vector<int>& extra, int ring, int cap,
                               double share, int64_t num_faces, int64_t* growing_out = nullptr) {
  const auto growing = std::count_if(faces.begin(), faces.end(), [&](int f) {
    return ring + (size_t(f) < extra.size() ? extra[size_t(f)] : 0) < cap;
  });
  if (growing_out) *growing_out = growing;
  return share > 0.0 && double(growing) > share * double(num_faces);
}

}  // namespace shapematch::detail
