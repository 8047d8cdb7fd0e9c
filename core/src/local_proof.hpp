#pragma once
// An exact proof that an LP is infeasible, looked for near a few rows (RoundingOptions::
// local_proof_columns): some of its rows, every column they touch, and no other row. That is a
// relaxation of the LP (rows dropped, columns kept in [0, 1]), so Clp's Farkas ray on it proves
// the whole LP infeasible too, with the rows it needs. A first-order solve that stalls short of
// feasible in a few rows (TOSCA_r dog3-dog8 at full resolution: 7 of 3.5 M rows) leaves that
// question open; where the clash is local, this answers it and names the rows exactly. Kept apart
// from the rounding loop so that it is tested on its own.
#include "shapematch/lp.hpp"
#include "shapematch/sparse.hpp"
#include "shapematch/system.hpp"
#include "stalled_rows.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace shapematch::detail {

struct LocalProof {
  bool proved = false;
  // How the search ended: "proved", "feasible" (every relaxation up to the depth, or the whole
  // component), "column cap", "time limit", "no ray" (Clp's infeasible without one that checks
  // out) or "solver" (Clp stopped otherwise); "no rows" where there was nothing to solve.
  const char* ended = "no rows";
  int depth = -1;                // of the last relaxation solved (-1: none)
  int64_t rows = 0, cols = 0;    // its size
  // "column cap": the size of the relaxation that passed the cap (not solved; 0 otherwise), so a
  // log can say how far past it the region had grown.
  int64_t capped_rows = 0, capped_cols = 0;
  std::vector<int64_t> support;  // proved: the rows of `lp` the ray needs, increasing
  // Its value on each: a ray of the relaxation. Where nothing was merged it is one of `lp` itself
  // (zero elsewhere); where a merged row has a positive value it is not (each merged column counts
  // once in `lp`, the slack once in all), though the support's rows are infeasible all the same.
  std::vector<double> ray;
};

// A relaxation of `lp` on its rows `keep` (increasing): every column they touch, costs 0 (a
// feasibility problem), b and bounds kept; except that where `merge`, the columns of a partition
// row (every entry +1, b = 1: a face's projection row) that no other kept row has become one slack
// column of that row. Still a relaxation: their sum lies in [0, 1] in any feasible x, as the
// slack does. A face's row has thousands of columns, most of them far from the rows kept; merged,
// the relaxation grows with the rows kept, not with every column a kept face row reaches.
struct Relaxation {
  LpProblem lp;
  std::vector<int64_t> cols;        // lp's columns kept one by one (its first columns), increasing
  std::vector<int64_t> slack_rows;  // then one slack column per such row (its index in `keep`)
};

inline bool is_partition_row(const LpProblem& lp, int64_t r) {
  if (lp.b[r] != 1.0) return false;
  for (uint32_t k = lp.a.row_ptr[r]; k < lp.a.row_ptr[r + 1]; ++k)
    if (lp.a.entry[k] & SignedCsr::kNegative) return false;
  return true;
}

// The plan of a relaxation: its columns and slacks, `lp` left empty (its size known before it is
// built).
inline Relaxation plan_relaxation(const LpProblem& lp, const std::vector<int64_t>& keep, bool merge) {
  Relaxation out;
  std::vector<uint8_t> count(lp.cols(), 0);  // kept rows per column, up to 2
  for (int64_t r : keep)
    for (uint32_t k = lp.a.row_ptr[r]; k < lp.a.row_ptr[r + 1]; ++k) {
      uint8_t& c = count[col_of(lp.a.entry[k])];
      if (c < 2) ++c;
    }
  std::vector<char> one_by_one(lp.cols(), 0);
  for (size_t i = 0; i < keep.size(); ++i) {
    const int64_t r = keep[i];
    const bool partition = merge && is_partition_row(lp, r);
    bool slack = false;
    for (uint32_t k = lp.a.row_ptr[r]; k < lp.a.row_ptr[r + 1]; ++k) {
      const uint32_t j = col_of(lp.a.entry[k]);
      if (partition && count[j] == 1) slack = true;
      else one_by_one[j] = 1;
    }
    if (slack) out.slack_rows.push_back(static_cast<int64_t>(i));
  }
  for (int64_t j = 0; j < lp.cols(); ++j)
    if (one_by_one[j]) out.cols.push_back(j);
  return out;
}

// Builds a planned relaxation into plan.lp.
inline void build_relaxation(const LpProblem& lp, const std::vector<int64_t>& keep, Relaxation& plan) {
  std::vector<int64_t> row_new(lp.rows(), -1);
  for (size_t i = 0; i < keep.size(); ++i) row_new[keep[i]] = static_cast<int64_t>(i);
  LpProblem& rl = plan.lp;
  rl.at.rows = static_cast<int64_t>(plan.cols.size() + plan.slack_rows.size());
  rl.at.cols = static_cast<int64_t>(keep.size());
  rl.at.row_ptr.assign(1, 0);
  for (int64_t j : plan.cols) {
    for (uint32_t k = lp.at.row_ptr[j]; k < lp.at.row_ptr[j + 1]; ++k) {
      const uint32_t e = lp.at.entry[k];
      const int64_t r = row_new[col_of(e)];
      if (r >= 0) rl.at.entry.push_back(static_cast<uint32_t>(r) | (e & SignedCsr::kNegative));
    }
    rl.at.row_ptr.push_back(static_cast<uint32_t>(rl.at.entry.size()));
  }
  for (int64_t i : plan.slack_rows) {
    rl.at.entry.push_back(static_cast<uint32_t>(i));
    rl.at.row_ptr.push_back(static_cast<uint32_t>(rl.at.entry.size()));
  }
  rl.a = transpose(rl.at);
  rl.b.resize(keep.size());
  for (size_t i = 0; i < keep.size(); ++i) rl.b[i] = lp.b[keep[i]];
  rl.c.assign(rl.at.rows, 0.0);
}

inline Relaxation relaxation_on_rows(const LpProblem& lp, const std::vector<int64_t>& keep, bool merge) {
  Relaxation r = plan_relaxation(lp, keep, merge);
  build_relaxation(lp, keep, r);
  return r;
}

// A ray d proves infeasibility only with a margin above rounding: its Farkas rate over the scale
// of bᵀd's terms (a near-ray of a feasible LP has a rate of about 0).
inline bool proves_infeasible(const LpProblem& lp, const std::vector<double>& d) {
  double scale = 0.0;
  for (size_t i = 0; i < d.size(); ++i) scale += std::abs(d[i]) * (1.0 + std::abs(lp.b[i]));
  return farkas_rate(lp, d) > 1e-9 * scale;
}

// The rows of `lp` one step out from `keep` (increasing): every row of the columns they touch.
inline std::vector<int64_t> rows_one_step_out(const LpProblem& lp, const std::vector<int64_t>& keep) {
  std::vector<char> in(lp.rows(), 0);
  for (int64_t r : keep) {
    in[r] = 1;
    for (uint32_t k = lp.a.row_ptr[r]; k < lp.a.row_ptr[r + 1]; ++k) {
      const uint32_t j = col_of(lp.a.entry[k]);
      for (uint32_t q = lp.at.row_ptr[j]; q < lp.at.row_ptr[j + 1]; ++q) in[col_of(lp.at.entry[q])] = 1;
    }
  }
  std::vector<int64_t> out;
  for (int64_t r = 0; r < lp.rows(); ++r)
    if (in[r]) out.push_back(r);
  return out;
}

// Looks for a proof on the rows `rows_at(0)`, `rows_at(1)`, … (each increasing, none smaller than
// the last; empty: nothing further; no larger: skipped) up to `max_depth`, while the relaxation
// has at most `max_cols` columns and under `max_seconds` have gone (building included).
// `exact`: Clp, which returns a Farkas ray in `y` for an infeasible LP (SolverParams::farkas_ray),
// or a first-order solver, whose dual at its stop is tried as one (at zero cost an infeasible
// LP's dual grows along a ray); either way a ray that does not check out on the relaxation
// (proves_infeasible, either way round) proves nothing, and a first-order "optimal" is feasible
// only to its tolerance.
template <class RowsAt>
LocalProof local_infeasibility_on(const LpProblem& lp, RowsAt&& rows_at, int max_depth, int64_t max_cols,
                                  LpSolver& exact, double max_seconds, bool merge) {
  LocalProof p;
  const Stopwatch clock;
  size_t last = 0;
  for (int depth = 0; depth <= max_depth; ++depth) {
    if (clock.seconds() >= max_seconds) {
      p.ended = "time limit";
      break;
    }
    const std::vector<int64_t> keep = rows_at(depth);
    if (keep.empty()) break;
    if (keep.size() <= last) continue;  // (solved already; a region's next ring may add rows)
    last = keep.size();
    Relaxation relaxed = plan_relaxation(lp, keep, merge);
    const int64_t cols = static_cast<int64_t>(relaxed.cols.size() + relaxed.slack_rows.size());
    if (cols > max_cols) {  // (before building it)
      p.ended = "column cap";
      p.capped_rows = static_cast<int64_t>(keep.size());
      p.capped_cols = cols;
      break;
    }
    build_relaxation(lp, keep, relaxed);
    SolverParams params;
    params.threads = 1;
    params.farkas_ray = true;
    params.time_limit = max_seconds - clock.seconds();
    params.tolerance = 1e-6;  // (first-order solvers: a relaxation feasible to 1e-4 may not be)
    if (!(params.time_limit > 0.0)) {
      p.ended = "time limit";
      break;
    }
    p.depth = depth;
    p.rows = static_cast<int64_t>(keep.size());
    p.cols = cols;
    const LpResult r = exact.solve(relaxed.lp, params);
    if (r.status == LpStatus::Optimal) {
      p.ended = "feasible";
      continue;
    }
    // A first-order solver's dual at its cap is tried as a ray too: at zero cost an infeasible
    // LP's dual grows along one (the check below decides).
    if (r.y.size() != keep.size()) {
      p.ended = r.status == LpStatus::TimeLimit ? "time limit" : r.status == LpStatus::Infeasible ? "no ray" : "solver";
      break;
    }
    // Its tiniest entries dropped where it still proves infeasibility without them.
    double largest = 0.0;
    for (double v : r.y) largest = std::max(largest, std::abs(v));
    std::vector<double> d;
    for (double sign : {1.0, -1.0})
      for (double cut : {1e-9 * largest, 0.0})
        if (d.empty()) {
          std::vector<double> t(r.y.size());
          for (size_t i = 0; i < t.size(); ++i) t[i] = std::abs(r.y[i]) > cut ? sign * r.y[i] : 0.0;
          if (proves_infeasible(relaxed.lp, t)) d = std::move(t);
        }
    if (d.empty()) {
      p.ended = r.status == LpStatus::Infeasible ? "no ray" : r.status == LpStatus::TimeLimit ? "time limit" : "solver";
      break;
    }
    for (size_t i = 0; i < d.size(); ++i)
      if (d[i] != 0.0) {
        p.support.push_back(keep[i]);
        p.ray.push_back(d[i]);
      }
    p.proved = true;
    p.ended = "proved";
    return p;
  }
  return p;
}

// local_infeasibility_on the rows within 0, 1, 2 … steps of `seeds` (rows_one_step_out), nothing
// merged: the ray, zero elsewhere, is a ray of `lp` itself.
inline LocalProof local_infeasibility(const LpProblem& lp, std::vector<int64_t> seeds, int max_depth,
                                      int64_t max_cols, LpSolver& exact, double max_seconds = 600.0) {
  std::sort(seeds.begin(), seeds.end());
  seeds.erase(std::unique(seeds.begin(), seeds.end()), seeds.end());
  seeds.erase(std::remove_if(seeds.begin(), seeds.end(), [&](int64_t r) { return r < 0 || r >= lp.rows(); }),
              seeds.end());
  std::vector<int64_t> keep = std::move(seeds);
  const auto rows_at = [&](int depth) {
    if (depth > 0) keep = rows_one_step_out(lp, keep);
    return keep;
  };
  return local_infeasibility_on(lp, rows_at, max_depth, max_cols, exact, max_seconds, false);
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

// local_infeasibility_on one X region alone: the rows of the columns over the X faces within
// `rings` rings of `faces` (rows_over_x_faces; `cols` as there), far columns merged. How coarse to
// fine checks a proof's region again in a widened LP before solving that.
inline LocalProof proof_over_x_region(const ProductSpace& space, const LpProblem& lp, const std::vector<int64_t>& cols,
                                      const std::vector<int>& faces, int rings, int64_t max_cols, LpSolver& solver,
                                      double max_seconds) {
  const std::vector<int64_t> rows = x_region_rows(space, lp, cols, faces, rings);
  return local_infeasibility_on(
      lp, [&](int depth) { return depth == 0 ? rows : std::vector<int64_t>{}; }, 0, max_cols, solver, max_seconds, true);
}

}  // namespace shapematch::detail
