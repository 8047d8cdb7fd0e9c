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
#include <stdexcept>
#include <vector>

namespace shapematch::detail {

// `y` (one value per row of `lp`) or its negative, whichever proves `lp` infeasible (its Farkas
// rate positive; a first-order proof at zero cost is one, Clp's ray comes with Clp's sign); empty
// where neither does (a costed first-order proof is a dual point, not a ray).
inline std::vector<double> oriented_certificate(const LpProblem& lp, std::vector<double> y) {
  if (y.size() != size_t(lp.rows())) return {};
  if (farkas_rate(lp, y) > 0.0) return y;
  for (double& v : y) v = -v;
  if (farkas_rate(lp, y) > 0.0) return y;
  return {};
}

class CertificateBlame {
public:
  // `d`: one value per row of `lp` (0 on rows no longer open). Both are kept by reference.
  CertificateBlame(const LpProblem& lp, const std::vector<double>& d) : lp_(lp), d_(d) {
    if (d.size() != size_t(lp.rows())) throw std::invalid_argument("CertificateBlame: one value per row");
  }
  CertificateBlame(const LpProblem&, std::vector<double>&&) = delete;
  // (Aᵀd)_j; with `part`, over the rows of part p alone.
  double pressure(int64_t j, const std::vector<int32_t>* part = nullptr, int32_t p = 0) const {
    double a = 0.0;
    for (uint32_t k = lp_.at.row_ptr[j]; k < lp_.at.row_ptr[j + 1]; ++k) {
      const uint32_t e = lp_.at.entry[k];
      if (part && (*part)[col_of(e)] != p) continue;
      a += is_negative(e) ? -d_[col_of(e)] : d_[col_of(e)];
    }
    return a;
  }
  // The margin of d on the LP that the state (`value`: −1 free, 0, 1 per column; `rhs`: b less the
  // columns fixed to 1) leaves. Positive: that LP is infeasible.
  double margin(const std::vector<int8_t>& value, const std::vector<int64_t>& rhs) const {
    return margins(value, rhs, {}, 1).front();
  }
  // The same per part, where d joins the certificates of independent parts of the LP (`part`: per
  // row, its part in [0, parts), −1 for none; empty: all one part): each, zero elsewhere, is a
  // Farkas vector of the whole LP, and one that no longer proves it infeasible says nothing of the
  // others. (Fixings released can join parts: a column then counts in each with its rows there.)
  std::vector<double> margins(const std::vector<int8_t>& value, const std::vector<int64_t>& rhs,
                              const std::vector<int32_t>& part, int32_t parts) const {
    std::vector<double> m(static_cast<size_t>(std::max(parts, 1)), 0.0);
    std::vector<std::pair<int64_t, int32_t>> free;  // the free columns of d's rows, with their part
    for (int64_t i = 0; i < lp_.rows(); ++i) {
      const int32_t p = part.empty() ? 0 : part[i];
      if (d_[i] == 0.0 || p < 0) continue;
      m[p] += d_[i] * static_cast<double>(rhs[i]);
      for (uint32_t k = lp_.a.row_ptr[i]; k < lp_.a.row_ptr[i + 1]; ++k)
        if (value[col_of(lp_.a.entry[k])] < 0) free.push_back({col_of(lp_.a.entry[k]), p});
    }
    std::sort(free.begin(), free.end());
    free.erase(std::unique(free.begin(), free.end()), free.end());
    for (const auto& [j, p] : free) m[p] -= std::max(0.0, pressure(j, part.empty() ? nullptr : &part, p));
    return m;
  }
  // margin() where d is zero outside `rows` (each once): without a pass over every row.
  double margin_over(const std::vector<int64_t>& rows, const std::vector<int8_t>& value,
                     const std::vector<int64_t>& rhs) const {
    double m = 0.0;
    std::vector<int64_t> free;
    for (int64_t i : rows) {
      m += d_[i] * static_cast<double>(rhs[i]);
      for (uint32_t k = lp_.a.row_ptr[i]; k < lp_.a.row_ptr[i + 1]; ++k)
        if (value[col_of(lp_.a.entry[k])] < 0) free.push_back(col_of(lp_.a.entry[k]));
    }
    std::sort(free.begin(), free.end());
    free.erase(std::unique(free.begin(), free.end()), free.end());
    for (int64_t j : free) m -= std::max(0.0, pressure(j));
    return m;
  }
  // What freeing column j, fixed to v, takes off the margin.
  double weight(int64_t j, int v) const {
    const double a = pressure(j);
    return v ? std::max(0.0, -a) : std::max(0.0, a);
  }

private:
  const LpProblem& lp_;
  const std::vector<double>& d_;
};

// The certificate's weights along a trail of assignments, cut into steps at `starts` (each step's
// first position on the trail, increasing, the first 0). `trail(visit)` calls visit(j, fixed) for
// each assignment in order, `fixed` where it was a fixing (a decision) rather than propagated;
// `value` gives each column's value. Each decision is charged what it and the assignments after it
// up to the next decision weigh (fixings go in one at a time, each followed by its propagation);
// each step, what all its assignments weigh: the exact amount that undoing it takes off the margin.
struct TrailWeights {
  std::vector<double> step;                          // per step
  std::vector<std::pair<int64_t, double>> decision;  // (column, weight), in trail order
};

template <class Trail>
TrailWeights trail_weights(const CertificateBlame& blame, Trail&& trail, const std::vector<int8_t>& value,
                           const std::vector<size_t>& starts) {
  TrailWeights w;
  w.step.assign(std::max<size_t>(starts.size(), 1), 0.0);
  size_t s = 0, t = 0;
  trail([&](int64_t j, bool fixed) {
    while (s + 1 < starts.size() && t >= starts[s + 1]) ++s;
    ++t;
    const double wj = blame.weight(j, value[j]);
    if (fixed) w.decision.push_back({j, 0.0});
    w.step[s] += wj;
    if (!w.decision.empty()) w.decision.back().second += wj;
  });
  return w;
}

// The decisions to release first: the heaviest (ties in trail order), until their weights add up
// to the margin (at least one), of those that weigh anything at all.
inline std::vector<int64_t> heaviest_decisions(std::vector<std::pair<int64_t, double>> decisions, double margin) {
  std::stable_sort(decisions.begin(), decisions.end(), [](const auto& p, const auto& q) { return p.second > q.second; });
  std::vector<int64_t> out;
  double sum = 0.0;
  for (const auto& [j, wj] : decisions) {
    if (!(wj > 0.0) || (!out.empty() && sum >= margin)) break;
    out.push_back(j);
    sum += wj;
  }
  return out;
}

}  // namespace shapematch::detail
