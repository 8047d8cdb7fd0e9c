#pragma once
// What an infeasibility certificate of a rounding's LP says about the fixings behind it
// (RoundingOptions::certificate_release), kept apart from the rounding loop so that its rules are
// tested on their own.
//
// The LP a fixing state leaves has its free columns in [0, 1] and right-hand side r (b less the
// columns fixed to 1). A row vector d proves it infeasible where its Farkas margin
//   dᵀr − Σ_{j free} max(0, (Aᵀd)_j)
// is positive (any feasible x has dᵀr = xᵀAᵀd ≤ that sum). Freeing a fixed column j changes the
// margin by exactly −w_j, w_j = max(0, (Aᵀd)_j) for a column fixed to 0 and max(0, −(Aᵀd)_j) for
// one fixed to 1 (its column goes back into r and joins the sum). So undoing fixings whose w add
// up to less than the margin leaves an LP that d still proves infeasible: a solve there is wasted.
#include "shapematch/lp.hpp"
#include "shapematch/sparse.hpp"

#include <algorithm>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace shapematch::detail {

class CertificateBlame {
public:
  // `d`: one value per row of `lp` (0 on rows no longer open).
  CertificateBlame(const LpProblem& lp, std::vector<double> d) : d_(std::move(d)) {
    for (int64_t i = 0; i < lp.rows() && i < static_cast<int64_t>(d_.size()); ++i) {
      if (d_[i] == 0.0) continue;
      for (uint32_t k = lp.a.row_ptr[i]; k < lp.a.row_ptr[i + 1]; ++k) {
        const uint32_t e = lp.a.entry[k];
        a_[col_of(e)] += is_negative(e) ? -d_[i] : d_[i];
      }
    }
  }
  // The margin of d on the LP that the state (`value`: −1 free, 0, 1 per column; `rhs`: b less the
  // columns fixed to 1) leaves. Positive: that LP is infeasible.
  double margin(const std::vector<int8_t>& value, const std::vector<int64_t>& rhs) const {
    double m = 0.0;
    for (size_t i = 0; i < d_.size() && i < rhs.size(); ++i) m += d_[i] * static_cast<double>(rhs[i]);
    for (const auto& [j, a] : a_)
      if (value[j] < 0 && a > 0.0) m -= a;
    return m;
  }
  // What freeing column j, fixed to v, takes off the margin.
  double weight(int64_t j, int v) const {
    const auto it = a_.find(j);
    if (it == a_.end()) return 0.0;
    return v ? std::max(0.0, -it->second) : std::max(0.0, it->second);
  }
  const std::vector<double>& d() const { return d_; }

private:
  std::vector<double> d_;
  std::unordered_map<int64_t, double> a_;  // (Aᵀd)_j over the columns of d's rows
};

// The certificate's weights along a trail of assignments (`assigned`, in order, with `value` per
// column), cut into steps at `starts` (each step's first position in `assigned`, increasing, the
// first 0). `decision` names, per column, whether it was a fixing of its step (a decision) rather
// than propagated. Each decision is charged what it and the assignments after it up to the next
// decision weigh (fixings go in one at a time, each followed by its propagation); each step, what
// all its assignments weigh: the exact amount that undoing it takes off the margin.
struct TrailWeights {
  std::vector<double> step;                          // per step
  std::vector<std::pair<int64_t, double>> decision;  // (column, weight), in trail order
};

template <class IsDecision>
TrailWeights trail_weights(const CertificateBlame& blame, const std::vector<int64_t>& assigned,
                           const std::vector<int8_t>& value, const std::vector<size_t>& starts,
                           IsDecision&& decision) {
  TrailWeights w;
  w.step.assign(starts.size(), 0.0);
  size_t s = 0;
  for (size_t t = 0; t < assigned.size(); ++t) {
    while (s + 1 < starts.size() && t >= starts[s + 1]) ++s;
    const int64_t j = assigned[t];
    const double wj = blame.weight(j, value[j]);
    if (decision(j)) w.decision.push_back({j, 0.0});
    w.step[s] += wj;
    if (!w.decision.empty()) w.decision.back().second += wj;
  }
  return w;
}

// The decisions to release first: the heaviest, until their weights add up to the margin (at least
// one), out of those that weigh anything at all. `count` > 0 asks for that many instead.
inline std::vector<int64_t> heaviest_decisions(std::vector<std::pair<int64_t, double>> decisions, double margin,
                                               size_t count = 0) {
  decisions.erase(std::remove_if(decisions.begin(), decisions.end(), [](const auto& p) { return !(p.second > 0.0); }),
                  decisions.end());
  std::stable_sort(decisions.begin(), decisions.end(), [](const auto& p, const auto& q) { return p.second > q.second; });
  std::vector<int64_t> out;
  double sum = 0.0;
  for (const auto& [j, wj] : decisions) {
    if (count > 0 ? out.size() >= count : (!out.empty() && sum >= margin)) break;
    out.push_back(j);
    sum += wj;
  }
  return out;
}

}  // namespace shapematch::detail
