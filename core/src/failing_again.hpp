#pragma once
// How often a part's LP has failed in a row, each failure trimming the last fixing
// (RoundingOptions::release_after_trims), kept apart from the rounding loop so that its rule is
// tested on its own.
#include <algorithm>
#include <cstdint>
#include <vector>

namespace shapematch::detail {

class FailingAgain {
public:
  // A round whose LP failed in the parts of `rows` (the whole LP's numbering). Returns how many
  // trims of the last fixing in a row came before it, each after a failure sharing a row with the
  // next (0: a new failure).
  int failed(std::vector<int64_t> rows) {
    std::sort(rows.begin(), rows.end());
    bool again = false;
    for (size_t p = 0, q = 0; p < rows.size() && q < trimmed_.size() && !again;) {
      if (rows[p] == trimmed_[q]) again = true;
      else if (rows[p] < trimmed_[q]) ++p;
      else ++q;
    }
    current_ = again ? trims_ : 0;
    trimmed_.clear();
    trims_ = 0;
    last_ = std::move(rows);
    return current_;
  }
  // The failure just recorded trimmed the last fixing (rather than undoing it whole, going on at
  // a larger cap or releasing).
  void trimmed() {
    trimmed_ = std::move(last_);
    trims_ = current_ + 1;
  }
  // A round whose LP did not fail: what failed before it does not count.
  void solved() {
    trimmed_.clear();
    last_.clear();
    trims_ = current_ = 0;
  }

private:
  std::vector<int64_t> trimmed_, last_;
  int trims_ = 0, current_ = 0;
};

}  // namespace shapematch::detail
