#pragma once
// An exact proof that an LP is infeasible, looked for near a few rows (RoundingOptions::
// local_proof): the rows within `depth` steps of them (a step: from a row to its columns, from a
// column to its rows), every column those rows touch, and no other row. That is a relaxation of
// the LP (rows dropped, columns kept in [0, 1]), so Clp's Farkas ray on it proves the whole LP
// infeasible too, with the rows it needs. A first-order solve that stalls short of feasible in a
// few rows (TOSCA_r dog3-dog8 at full resolution: 7 of 3.3 M rows) leaves that question open;
// where the clash is local, this answers it in seconds and names the rows exactly. Kept apart
// from the rounding loop so that it is tested on its own.
#include "shapematch/lp.hpp"
#include "shapematch/sparse.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace shapematch::detail {

struct LocalProof {
  bool proved = false;
  int depth = -1;               // of the last relaxation solved (-1: none)
  int64_t rows = 0, cols = 0;   // its size
  std::vector<int64_t> support; // proved: the rows of `lp` the ray needs, increasing
  std::vector<double> ray;      // its value on each (zero elsewhere: a ray of `lp` itself)
};

// The relaxation of `lp` to its rows `keep` (increasing) and every column they touch: costs 0
// (a feasibility problem), b and bounds kept. `cols` receives the columns, increasing.
inline LpProblem relaxation_on_rows(const LpProblem& lp, const std::vector<int64_t>& keep,
                                    std::vector<int64_t>& cols) {
  std::vector<int64_t> row_new(lp.rows(), -1);
  for (size_t i = 0; i < keep.size(); ++i) row_new[keep[i]] = static_cast<int64_t>(i);
  std::vector<char> touched(lp.cols(), 0);
  for (int64_t r : keep)
    for (uint32_t k = lp.a.row_ptr[r]; k < lp.a.row_ptr[r + 1]; ++k) touched[col_of(lp.a.entry[k])] = 1;
  cols.clear();
  for (int64_t j = 0; j < lp.cols(); ++j)
    if (touched[j]) cols.push_back(j);
  LpProblem out;
  out.at.rows = static_cast<int64_t>(cols.size());
  out.at.cols = static_cast<int64_t>(keep.size());
  out.at.row_ptr.assign(1, 0);
  for (int64_t j : cols) {
    for (uint32_t k = lp.at.row_ptr[j]; k < lp.at.row_ptr[j + 1]; ++k) {
      const uint32_t e = lp.at.entry[k];
      const int64_t r = row_new[col_of(e)];
      if (r >= 0) out.at.entry.push_back(static_cast<uint32_t>(r) | (e & SignedCsr::kNegative));
    }
    out.at.row_ptr.push_back(static_cast<uint32_t>(out.at.entry.size()));
  }
  out.a = transpose(out.at);
  out.b.resize(keep.size());
  for (size_t i = 0; i < keep.size(); ++i) out.b[i] = lp.b[keep[i]];
  out.c.assign(cols.size(), 0.0);
  return out;
}

// Looks for a proof around `seeds` (rows of `lp`), depth 0, 1, … up to `max_depth`, while the
// relaxation has at most `max_cols` columns and the solves have taken under `max_seconds`. `exact` must be an exact solver (Clp) that returns
// a Farkas ray in `y` for an infeasible LP; a ray that does not check out (farkas_rate ≤ 0 either
// way round) proves nothing.
inline LocalProof local_infeasibility(const LpProblem& lp, std::vector<int64_t> seeds, int max_depth,
                                      int64_t max_cols, LpSolver& exact, double max_seconds = 600.0) {
  LocalProof p;
  std::sort(seeds.begin(), seeds.end());
  seeds.erase(std::unique(seeds.begin(), seeds.end()), seeds.end());
  seeds.erase(std::remove_if(seeds.begin(), seeds.end(), [&](int64_t r) { return r < 0 || r >= lp.rows(); }),
              seeds.end());
  std::vector<int64_t> keep = std::move(seeds), cols;
  double spent = 0.0;
  for (int depth = 0; depth <= max_depth && !keep.empty(); ++depth) {
    if (depth > 0) {  // one step out: every row of the columns the last relaxation had
      std::vector<char> in(lp.rows(), 0);
      for (int64_t r : keep) in[r] = 1;
      for (int64_t j : cols)
        for (uint32_t k = lp.at.row_ptr[j]; k < lp.at.row_ptr[j + 1]; ++k) in[col_of(lp.at.entry[k])] = 1;
      const size_t before = keep.size();
      keep.clear();
      for (int64_t r = 0; r < lp.rows(); ++r)
        if (in[r]) keep.push_back(r);
      if (keep.size() == before) break;  // (the whole component, solved already)
    }
    LpProblem relaxed = relaxation_on_rows(lp, keep, cols);
    if (static_cast<int64_t>(cols.size()) > max_cols) break;
    p.depth = depth;
    p.rows = static_cast<int64_t>(keep.size());
    p.cols = static_cast<int64_t>(cols.size());
    SolverParams params;
    params.threads = 1;
    params.farkas_ray = true;
    params.time_limit = max_seconds - spent;
    if (!(params.time_limit > 0.0)) break;
    const LpResult r = exact.solve(relaxed, params);
    spent += r.seconds;
    if (r.status != LpStatus::Infeasible) {
      if (r.status == LpStatus::Optimal) continue;
      break;  // (the exact solver gave up: nothing more to learn further out)
    }
    std::vector<double> d = r.y;
    if (d.size() != keep.size()) break;
    if (!(farkas_rate(relaxed, d) > 0.0)) {
      for (double& v : d) v = -v;
      if (!(farkas_rate(relaxed, d) > 0.0)) break;
    }
    double largest = 0.0;
    for (double v : d) largest = std::max(largest, std::abs(v));
    for (size_t i = 0; i < d.size(); ++i)
      if (std::abs(d[i]) > 1e-9 * largest) {
        p.support.push_back(keep[i]);
        p.ray.push_back(d[i]);
      }
    p.proved = true;
    return p;
  }
  return p;
}

}  // namespace shapematch::detail
