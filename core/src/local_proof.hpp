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

// The columns of `lp` that its rows `keep` touch, increasing.
inline std::vector<int64_t> columns_of_rows(const LpProblem& lp, const std::vector<int64_t>& keep) {
  std::vector<char> touched(lp.cols(), 0);
  for (int64_t r : keep)
    for (uint32_t k = lp.a.row_ptr[r]; k < lp.a.row_ptr[r + 1]; ++k) touched[col_of(lp.a.entry[k])] = 1;
  std::vector<int64_t> cols;
  for (int64_t j = 0; j < lp.cols(); ++j)
    if (touched[j]) cols.push_back(j);
  return cols;
}

// The relaxation of `lp` to its rows `keep` (increasing) and the columns they touch, `cols`
// (columns_of_rows): costs 0 (a feasibility problem), b and bounds kept.
inline LpProblem relaxation_on_rows(const LpProblem& lp, const std::vector<int64_t>& keep,
                                    const std::vector<int64_t>& cols) {
  std::vector<int64_t> row_new(lp.rows(), -1);
  for (size_t i = 0; i < keep.size(); ++i) row_new[keep[i]] = static_cast<int64_t>(i);
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

// A ray d proves infeasibility only with a margin above rounding: its Farkas rate over the scale
// of bᵀd's terms (a near-ray of a feasible LP has a rate of about 0).
inline bool proves_infeasible(const LpProblem& lp, const std::vector<double>& d) {
  double scale = 0.0;
  for (size_t i = 0; i < d.size(); ++i) scale += std::abs(d[i]) * (1.0 + std::abs(lp.b[i]));
  return farkas_rate(lp, d) > 1e-9 * scale;
}

// Looks for a proof around `seeds` (rows of `lp`), depth 0, 1, … up to `max_depth`, while the
// relaxation has at most `max_cols` columns and the solves have taken under `max_seconds`.
// `exact` must be an exact solver (Clp) that returns a Farkas ray in `y` for an infeasible LP
// (SolverParams::farkas_ray); a ray that does not check out on `lp` itself (proves_infeasible,
// either way round) proves nothing.
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
    cols = columns_of_rows(lp, keep);
    if (static_cast<int64_t>(cols.size()) > max_cols) break;  // (before building it)
    const LpProblem relaxed = relaxation_on_rows(lp, keep, cols);
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
    if (r.status == LpStatus::Optimal) continue;
    if (r.status != LpStatus::Infeasible || r.y.size() != keep.size()) break;  // (gave up, or no ray)
    // The ray on lp's rows, zero off the relaxation; its tiniest entries dropped where it still
    // proves infeasibility without them.
    const auto on_lp = [&](double sign, double cut) {
      std::vector<double> d(lp.rows(), 0.0);
      for (size_t i = 0; i < keep.size(); ++i)
        if (std::abs(r.y[i]) > cut) d[keep[i]] = sign * r.y[i];
      return d;
    };
    double largest = 0.0;
    for (double v : r.y) largest = std::max(largest, std::abs(v));
    std::vector<double> d;
    for (double sign : {1.0, -1.0})
      for (double cut : {1e-9 * largest, 0.0})
        if (d.empty()) {
          std::vector<double> t = on_lp(sign, cut);
          if (proves_infeasible(lp, t)) d = std::move(t);
        }
    if (d.empty()) break;
    for (int64_t i = 0; i < lp.rows(); ++i)
      if (d[i] != 0.0) {
        p.support.push_back(i);
        p.ray.push_back(d[i]);
      }
    p.proved = true;
    return p;
  }
  return p;
}

// local_infeasibility on a reduced LP (`reduced`, whose row i is row rows[i] of a larger LP,
// `rows` increasing), with seeds and support in the larger LP's numbering (seeds it lacks are
// left out).
inline LocalProof local_infeasibility_within(const LpProblem& reduced, const std::vector<int64_t>& rows,
                                             const std::vector<int64_t>& seeds, int max_depth, int64_t max_cols,
                                             LpSolver& exact, double max_seconds = 600.0) {
  std::vector<int64_t> local;
  for (int64_t row : seeds) {
    const auto at = std::lower_bound(rows.begin(), rows.end(), row);
    if (at != rows.end() && *at == row) local.push_back(at - rows.begin());
  }
  LocalProof p = local_infeasibility(reduced, std::move(local), max_depth, max_cols, exact, max_seconds);
  for (int64_t& i : p.support) i = rows[i];
  return p;
}

}  // namespace shapematch::detail
