#include "shapematch/rounding.hpp"
#include "parallel.hpp"
#include "failed_from.hpp"
#include "failing_again.hpp"
#include "release_reach.hpp"
#include "certificate_blame.hpp"
#include "part_search.hpp"
#include "solve_in_parts.hpp"
#include "local_proof.hpp"
#include "stalled_rows.hpp"

#include "shapematch/errors.hpp"
#include "shapematch/geometry.hpp"
#include "shapematch/system.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <deque>
#include <exception>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <set>
#include <unordered_map>
#include <unordered_set>

namespace shapematch {
using detail::SearchEnd;
using detail::search_part;
namespace {

// The fixing state: each variable free (−1), 0 or 1, and for every row its residual right-hand
// side and number of free +1 / −1 entries. Unit propagation keeps it consistent.
struct FixState {
  std::vector<int8_t> value;
  std::vector<int64_t> rhs;
  std::vector<int32_t> free_pos, free_neg;
  int64_t unsatisfied = 0;  // rows with rhs ≠ 0
  int64_t ones = 0, zeros = 0;
};

class Fixer {
public:
  explicit Fixer(const LpProblem& lp) : lp_(lp) {
    s_.value.assign(lp.cols(), -1);
    s_.rhs.resize(lp.rows());
    s_.free_pos.assign(lp.rows(), 0);
    s_.free_neg.assign(lp.rows(), 0);
    // Rows are independent: counted in parallel (a fixer is built for every propagation pass,
    // and reads every entry of A).
    detail::parallel_rows(lp.a.row_ptr, 0, [&](int64_t i) {
      s_.rhs[i] = std::llround(lp.b[i]);
      for (uint32_t k = lp.a.row_ptr[i]; k < lp.a.row_ptr[i + 1]; ++k)
        ++(is_negative(lp.a.entry[k]) ? s_.free_neg : s_.free_pos)[i];
    });
    for (int64_t i = 0; i < lp.rows(); ++i) s_.unsatisfied += s_.rhs[i] != 0;
  }

  const FixState& state() const { return s_; }
  // Every assignment since `mark()` can be taken back, propagation included, at the cost of what
  // it changed: rounding backtracks over several rounds without keeping copies of the state.
  size_t mark() const { return trail_.size(); }
  // The variables assigned since `mark`, in order (each fixing followed by what it propagated).
  std::vector<int64_t> assigned_since(size_t mark) const {
    std::vector<int64_t> out;
    out.reserve(trail_.size() - std::min(mark, trail_.size()));
    for (size_t t = mark; t < trail_.size(); ++t) out.push_back(trail_[t] & ~kFixed);
    return out;
  }
  // Visits each assignment since `mark` in order as (variable, whether `fix` set it rather than
  // propagation), without copying the trail.
  template <class Visit>
  void visit_since(size_t mark, Visit&& visit) const {
    for (size_t t = mark; t < trail_.size(); ++t) visit(static_cast<int64_t>(trail_[t] & ~kFixed), (trail_[t] & kFixed) != 0);
  }
  void undo_to(size_t mark) {
    while (trail_.size() > mark) {
      const int64_t j = trail_.back() & ~kFixed;
      trail_.pop_back();
      const int v = s_.value[j];
      s_.value[j] = -1;
      --(v ? s_.ones : s_.zeros);
      for (uint32_t k = lp_.at.row_ptr[j]; k < lp_.at.row_ptr[j + 1]; ++k) {
        const uint32_t e = lp_.at.entry[k];
        const int64_t i = col_of(e);
        const bool neg = is_negative(e);
        ++(neg ? s_.free_neg : s_.free_pos)[i];
        if (v) {
          const bool was = s_.rhs[i] != 0;
          s_.rhs[i] += neg ? -1 : 1;
          s_.unsatisfied += (s_.rhs[i] != 0) - was;
        }
      }
    }
  }
  // Rows still short of their right-hand side: where rounding is stuck when it gives up.
  std::vector<int64_t> unsatisfied_rows() const {
    std::vector<int64_t> rows;
    for (int64_t i = 0; i < static_cast<int64_t>(s_.rhs.size()); ++i)
      if (s_.rhs[i] != 0) rows.push_back(i);
    return rows;
  }
  // The row at which the last failed propagation found a contradiction.
  int64_t failed_row() const { return failed_row_; }

  // Fixes the variables and propagates; false if that proves the system infeasible.
  bool fix(const std::vector<std::pair<int64_t, int>>& assignments) {
    std::deque<int64_t> queue;
    for (const auto& [j, v] : assignments)
      if (!assign(j, v, queue, true)) return false;
    return propagate(queue);
  }

  // Propagates from every row (used once at the start). Rows marked in `skip` are left out, as
  // if they were not there.
  bool propagate_all(const std::vector<char>* skip = nullptr) {
    std::deque<int64_t> queue;
    for (int64_t i = 0; i < lp_.rows(); ++i)
      if (!skip || !(*skip)[i]) queue.push_back(i);
    skip_ = skip;
    const bool ok = propagate(queue);
    skip_ = nullptr;
    return ok;
  }

private:
  bool assign(int64_t j, int v, std::deque<int64_t>& queue, bool fixed = false) {
    if (s_.value[j] >= 0) return s_.value[j] == v;
    s_.value[j] = static_cast<int8_t>(v);
    // < 2^31 columns (build_constraints checks): the top bit says whether `fix` set it
    trail_.push_back(static_cast<uint32_t>(j) | (fixed ? kFixed : 0u));
    ++(v ? s_.ones : s_.zeros);
    for (uint32_t k = lp_.at.row_ptr[j]; k < lp_.at.row_ptr[j + 1]; ++k) {
      const uint32_t e = lp_.at.entry[k];
      const int64_t i = col_of(e);
      const bool neg = is_negative(e);
      --(neg ? s_.free_neg : s_.free_pos)[i];
      if (v) {
        const bool was = s_.rhs[i] != 0;
        s_.rhs[i] -= neg ? -1 : 1;
        s_.unsatisfied += (s_.rhs[i] != 0) - was;
      }
      queue.push_back(i);
    }
    return true;
  }

  // A row's free entries can reach [−free_neg, free_pos]: outside is infeasible, at either end
  // every free entry is determined.
  bool propagate(std::deque<int64_t>& queue) {
    while (!queue.empty()) {
      const int64_t i = queue.front();
      queue.pop_front();
      const int64_t r = s_.rhs[i], pos = s_.free_pos[i], neg = s_.free_neg[i];
      if (skip_ && (*skip_)[i]) continue;
      if (r > pos || r < -neg) {
        failed_row_ = i;
        return false;
      }
      if (pos + neg == 0 || (r != pos && r != -neg)) continue;
      // r == pos: + entries 1, − entries 0; r == −neg: − entries 1, + entries 0.
      const bool plus_is_one = r == pos && !(r == -neg && pos == 0);
      for (uint32_t k = lp_.a.row_ptr[i]; k < lp_.a.row_ptr[i + 1]; ++k) {
        const uint32_t e = lp_.a.entry[k];
        const int64_t j = col_of(e);
        if (s_.value[j] >= 0) continue;
        const int v = (is_negative(e) != plus_is_one) ? 1 : 0;
        if (!assign(j, v, queue)) {
          failed_row_ = i;
          return false;
        }
      }
    }
    return true;
  }

  const LpProblem& lp_;
  FixState s_;
  int64_t failed_row_ = -1;
  static constexpr uint32_t kFixed = 1u << 31;
  std::vector<uint32_t> trail_;  // assigned variables, in order (kFixed: by `fix`)
  const std::vector<char>* skip_ = nullptr;
};

// The LP over the free variables and the rows that still contain one.
struct Reduced {
  LpProblem lp;
  std::vector<int64_t> cols, rows;
  double fixed_cost = 0.0;  // scaled cost of the variables fixed to 1
};

// The LP over `cols`, each row i of theirs renumbered to row_new[i], with right-hand side `b`
// (one per new row) and the same costs.
LpProblem restrict_lp(const LpProblem& full, const std::vector<int64_t>& cols, const std::vector<int64_t>& row_new,
                      std::vector<double> b) {
  LpProblem lp;
  SignedCsr& at = lp.at;
  at.rows = static_cast<int64_t>(cols.size());
  at.cols = static_cast<int64_t>(b.size());
  at.row_ptr.assign(1, 0);
  for (int64_t j : cols) {
    for (uint32_t k = full.at.row_ptr[j]; k < full.at.row_ptr[j + 1]; ++k) {
      const uint32_t e = full.at.entry[k];
      at.entry.push_back(static_cast<uint32_t>(row_new[col_of(e)]) | (e & SignedCsr::kNegative));
    }
    at.row_ptr.push_back(static_cast<uint32_t>(at.entry.size()));
  }
  lp.a = transpose(at);
  lp.b = std::move(b);
  lp.c.resize(cols.size());
  for (size_t j = 0; j < cols.size(); ++j) lp.c[j] = full.c[cols[j]];
  lp.objective_scale = full.objective_scale;
  return lp;
}

Reduced reduce(const LpProblem& full, const FixState& s) {
  Reduced r;
  std::vector<int64_t> row_new(full.rows(), -1);
  for (int64_t i = 0; i < full.rows(); ++i)
    if (s.free_pos[i] + s.free_neg[i] > 0) {
      row_new[i] = static_cast<int64_t>(r.rows.size());
      r.rows.push_back(i);
    }
  for (int64_t j = 0; j < full.cols(); ++j) {
    if (s.value[j] < 0) r.cols.push_back(j);
    else if (s.value[j] == 1) r.fixed_cost += full.c[j];
  }
  std::vector<double> b(r.rows.size());
  for (size_t i = 0; i < r.rows.size(); ++i) b[i] = static_cast<double>(s.rhs[r.rows[i]]);
  r.lp = restrict_lp(full, r.cols, row_new, std::move(b));
  return r;
}

// The independent parts of an LP: its connected components, two rows joined where a column has
// entries in both, each with its columns and rows (increasing) and its own LP. Late in rounding
// the open faces form separate patches, and one whole LP makes every patch wait for the slowest:
// a first-order solve runs to its cap wherever one patch is infeasible or ill-conditioned, and
// its iterate is then rounded everywhere.
struct Part {
  LpProblem lp;
  std::vector<int64_t> cols, rows;  // in the split LP's numbering
};

// The LP itself as its one part: columns and rows numbered as they are; `lp` left empty (the
// caller uses the LP itself, not a copy).
Part whole_part(const LpProblem& lp) {
  Part p;
  p.cols.resize(lp.cols());
  p.rows.resize(lp.rows());
  std::iota(p.cols.begin(), p.cols.end(), 0);
  std::iota(p.rows.begin(), p.rows.end(), 0);
  return p;
}

// The geometric mean of the positive weights among `cols` (0 where none is): a part whose
// columns came from several parts of the last round starts between their primal weights.
double part_weight(const std::vector<double>& weight, const std::vector<int64_t>& cols) {
  double sum = 0.0;
  int64_t count = 0;
  for (int64_t j : cols)
    if (weight[j] > 0.0 && std::isfinite(weight[j])) {
      sum += std::log(weight[j]);
      ++count;
    }
  return count > 0 ? std::exp(sum / double(count)) : 0.0;
}

// Empty where the LP is a single part.
std::vector<Part> split_into_parts(const LpProblem& lp) {
  const int64_t m = lp.rows(), n = lp.cols();
  std::vector<int64_t> parent(m);
  std::iota(parent.begin(), parent.end(), 0);
  const auto find = [&](int64_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (int64_t j = 0; j < n; ++j) {
    const uint32_t begin = lp.at.row_ptr[j], end = lp.at.row_ptr[j + 1];
    for (uint32_t k = begin + 1; k < end; ++k) {
      const int64_t p = find(col_of(lp.at.entry[begin])), q = find(col_of(lp.at.entry[k]));
      if (p != q) parent[std::max(p, q)] = std::min(p, q);
    }
  }
  std::vector<int64_t> part_of(m, -1), local(m);
  std::vector<Part> parts;
  int64_t roots = 0;
  for (int64_t i = 0; i < m; ++i) roots += find(i) == i;
  if (roots <= 1) return parts;  // one part: the LP itself
  for (int64_t i = 0; i < m; ++i) {
    const int64_t root = find(i);
    if (part_of[root] < 0) {
      part_of[root] = static_cast<int64_t>(parts.size());
      parts.emplace_back();
    }
    Part& part = parts[part_of[root]];
    local[i] = static_cast<int64_t>(part.rows.size());
    part.rows.push_back(i);
  }
  for (int64_t j = 0; j < n; ++j)  // a column without rows would be free of every constraint
    if (lp.at.row_ptr[j + 1] > lp.at.row_ptr[j])
      parts[part_of[find(col_of(lp.at.entry[lp.at.row_ptr[j]]))]].cols.push_back(j);
  for (Part& part : parts) {
    std::vector<double> b(part.rows.size());
    for (size_t i = 0; i < part.rows.size(); ++i) b[i] = lp.b[part.rows[i]];
    part.lp = restrict_lp(lp, part.cols, local, std::move(b));
  }
  return parts;
}

// The same LP, entry for entry (the exact solver's result on one is its result on the other).
bool same_lp(const LpProblem& p, const LpProblem& q) {
  return p.a.rows == q.a.rows && p.a.cols == q.a.cols && p.objective_scale == q.objective_scale && p.b == q.b &&
         p.c == q.c && p.a.row_ptr == q.a.row_ptr && p.a.entry == q.a.entry;
}

// The entries that carry a certificate y: those where |y_i| is a tenth of the largest or more.
std::vector<int64_t> carrying_rows(const std::vector<double>& y) {
  double largest = 0.0;
  for (double v : y) largest = std::max(largest, std::abs(v));
  std::vector<int64_t> out;
  if (!(largest > 0.0)) return out;
  for (size_t i = 0; i < y.size(); ++i)
    if (std::abs(y[i]) >= 0.1 * largest) out.push_back(static_cast<int64_t>(i));
  return out;
}

// The rows a primal iterate `x` of `lp` leaves furthest from b: |Ax − b| at least a tenth of the
// largest (RoundingOptions::blame_residual), mapped to the full LP by `rows`, sorted. Logged with
// the largest and the relative residual (debug).
std::vector<int64_t> residual_rows(const LpProblem& lp, const std::vector<double>& x, const std::vector<int64_t>& rows) {
  std::vector<int64_t> out;
  if (x.size() != size_t(lp.cols())) return out;
  std::vector<double> ax(lp.rows());
  spmv(lp.a, x.data(), ax.data());
  double largest = 0.0, sum2 = 0.0, b2 = 0.0;
  for (int64_t i = 0; i < lp.rows(); ++i) {
    ax[i] = std::abs(ax[i] - lp.b[i]);
    largest = std::max(largest, ax[i]);
    sum2 += ax[i] * ax[i];
    b2 += lp.b[i] * lp.b[i];
  }
  if (!(largest > 0.0)) return out;
  for (int64_t i = 0; i < lp.rows(); ++i)
    if (ax[i] >= 0.1 * largest && i < static_cast<int64_t>(rows.size())) out.push_back(rows[i]);
  std::sort(out.begin(), out.end());
  spdlog::debug("stalled iterate: |Ax − b| at most {:.3g} ({:.3g} relative), {} of {} rows within a tenth of it", largest,
                std::sqrt(sum2) / (1.0 + std::sqrt(b2)), out.size(), lp.rows());
  return out;
}

// The smallest angle of a triangle (degrees) and its area over `mean` (the mesh's mean face
// area): a degenerate face is one place an LP can be infeasible only locally.
double face_area(const Mesh& m, int f) {
  const auto& t = m.faces[f];
  return 0.5 * (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]).norm();
}
std::string face_shape(const Mesh& m, int f, double mean) {
  const auto& t = m.faces[f];
  double smallest = 180.0;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d u = m.vertices[t[(i + 1) % 3]] - m.vertices[t[i]];
    const Eigen::Vector3d v = m.vertices[t[(i + 2) % 3]] - m.vertices[t[i]];
    smallest = std::min(smallest, std::atan2(u.cross(v).norm(), u.dot(v)) * 180.0 / M_PI);
  }
  return fmt::format("min angle {:.1f}°, area {:.2f}× mean", smallest, face_area(m, f) / mean);
}

// Debug log of the rows `residual_rows` names (at most 12): their kind (closedness of a product
// edge, π_X or π_Y of a face), Ax against b and their largest columns, with the shapes of the
// faces there, so a stall can be told from a degenerate face or a cut-off neighbourhood.
void describe_stalled_rows(const ProductSpace& space, const LpProblem& full, const Reduced& red,
                           const std::vector<double>& x, const std::vector<int64_t>& stalled) {
  if (!spdlog::should_log(spdlog::level::debug) || x.size() != size_t(red.lp.cols())) return;
  const Mesh& X = space.x();
  const Mesh& Y = space.y();
  std::vector<double> ax(red.lp.rows());
  spmv(red.lp.a, x.data(), ax.data());
  auto tuple = [](const std::array<int, 3>& v) { return fmt::format("({},{},{})", v[0], v[1], v[2]); };
  const auto mean_area = [](const Mesh& m) {
    double total = 0.0;
    for (int f = 0; f < m.num_faces(); ++f) total += face_area(m, f);
    return total / m.num_faces();
  };
  const double mean_x = mean_area(X), mean_y = mean_area(Y);
  for (size_t n = 0; n < stalled.size() && n < 12; ++n) {
    const int64_t row = stalled[n];
    const auto at = std::lower_bound(red.rows.begin(), red.rows.end(), row);
    if (at == red.rows.end() || *at != row) continue;
    const int64_t i = at - red.rows.begin();
    const detail::RowPlace place = detail::row_place(space, full, row);
    std::string kind;
    if (place.kind == detail::RowPlace::pi_y)
      kind = fmt::format("π_Y of Y face {} ({})", place.face, face_shape(Y, place.face, mean_y));
    else if (place.kind == detail::RowPlace::pi_x)
      kind = fmt::format("π_X of X face {} ({})", place.face, face_shape(X, place.face, mean_x));
    else {
      kind = "closedness of";
      for (const auto& [u, w] : place.edge) kind += fmt::format(" ({},{})", u, w);
    }
    // Its columns, largest first.
    std::vector<std::pair<double, int64_t>> cols;
    for (uint32_t k = red.lp.a.row_ptr[i]; k < red.lp.a.row_ptr[i + 1]; ++k) {
      const int64_t j = col_of(red.lp.a.entry[k]);
      cols.emplace_back(x[j], red.cols[j]);
    }
    std::sort(cols.begin(), cols.end(), std::greater<>());
    std::string list;
    std::set<int> fx, fy;
    for (size_t k = 0; k < cols.size(); ++k) {
      const ProductTriangle t = space[cols[k].second];
      if (k < 6) list += fmt::format(" {}→{} {:.3f};", tuple(t.a), tuple(t.b), cols[k].first);
      if (t.fa >= 0) fx.insert(t.fa);
      if (t.fb >= 0) fy.insert(t.fb);
    }
    spdlog::debug("stalled row {} ({}): Ax {:.4f}, b {}, {} columns:{}", row, kind, ax[i], red.lp.b[i], cols.size(),
                  list);
    if ((fx.empty() && fy.empty()) || fx.size() + fy.size() > 16) continue;  // (a π row's: hundreds)
    std::string shapes;
    for (int f : fx) shapes += fmt::format(" X{} {};", f, face_shape(X, f, mean_x));
    for (int f : fy) shapes += fmt::format(" Y{} {};", f, face_shape(Y, f, mean_y));
    spdlog::debug("  its columns' faces:{}", shapes);
  }
}

// `lp` solved cold with every cost 0 (set aside and put back after): a feasibility problem,
// whose proof of infeasibility holds no ordinary duals, only the clash.
LpResult solve_at_zero_cost(LpProblem& lp, SolverParams params, LpSolver& solver) {
  params.initial_x.clear();
  params.initial_y.clear();
  std::vector<double> costs(lp.c.size(), 0.0);
  std::swap(costs, lp.c);
  LpResult z;
  try {
    z = solver.solve(lp, params);
  } catch (...) {
    std::swap(costs, lp.c);
    throw;
  }
  std::swap(costs, lp.c);
  return z;
}

// The parameters of a zero-cost pre-test: cold, at most `cap` iterations, no divergence watch (at
// zero cost a growing dual is the proof being found, not a reason to stop), and its own tolerance
// where one is given (> 0): at zero cost "optimal" only says the residual is that small. (Cold
// also where `params` carries the whole LP's warm start: PretestCache's verdicts rely on it.)
SolverParams pretest_params(const SolverParams& params, int64_t cap, double tolerance) {
  SolverParams zp = params;
  zp.initial_x.clear();
  zp.initial_y.clear();
  zp.max_iterations = std::min(params.max_iterations, cap);
  if (tolerance > 0.0) zp.tolerance = tolerance;
  zp.stop_on_divergence = false;
  zp.patient_divergence_watch = false;
  zp.snapshot = {};  // (not the solve a checkpoint would go on from)
  zp.exact_state = false;
  zp.resume_state = nullptr;
  return zp;
}

bool looks_infeasible(const LpResult& r) {
  // Far above: those LPs' bounds were 3-60x their objectives; at 5 % above, feasible LPs that had
  // not converged by the cap (bound 5.34, objective 5.01) were undone round after round.
  return r.status == LpStatus::IterationLimit && r.lower_bound > r.objective + 0.5 * (1.0 + std::abs(r.objective));
}

}  // namespace

uint64_t detail::constraint_fingerprint(const LpProblem& lp) {
  // splitmix64's finaliser over each word folded in: a change anywhere changes the result.
  uint64_t h = 0x9e3779b97f4a7c15ull;
  auto add = [&h](uint64_t v) {
    h ^= v + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    h ^= h >> 30;
    h *= 0xbf58476d1ce4e5b9ull;
    h ^= h >> 27;
    h *= 0x94d049bb133111ebull;
    h ^= h >> 31;
  };
  add(uint64_t(lp.a.rows));
  add(uint64_t(lp.a.cols));
  for (uint32_t p : lp.a.row_ptr) add(p);
  for (uint32_t e : lp.a.entry) add(e);
  for (double v : lp.b) add(std::bit_cast<uint64_t>(v));
  return h;
}

JoinedSolve detail::solve_in_parts(const LpProblem& lp, SolverParams params, LpSolver& solver, LpSolver* exact,
                                   int64_t exact_below, const SolverParams& exact_params, bool split,
                                   const ExactCap& cap, ExactCache* cache,
                                   const std::vector<double>* warm_weight,
                                   const std::function<void(const LpProblem&)>& slow_part, double slow_part_seconds,
                                   const ZeroCostPretest& pretest) {
  JoinedSolve out;
  std::vector<Part> parts;
  if (split) parts = split_into_parts(lp);
  const bool whole = parts.empty();
  if (whole) parts.push_back(whole_part(lp));
  out.parts = static_cast<int64_t>(parts.size());
  LpResult& r = out.r;
  r.status = LpStatus::Optimal;
  r.objective = 0.0;
  r.lower_bound = 0.0;
  r.x.assign(lp.cols(), 0.0);
  r.y.assign(lp.rows(), 0.0);
  out.proof.assign(lp.rows(), 0.0);
  out.weight.assign(lp.cols(), 0.0);
  const bool weighted = warm_weight && warm_weight->size() == size_t(lp.cols());
  std::vector<double> suspect_proof(lp.rows(), 0.0);
  bool infeasible = false;
  // An infeasible part's proof, where it is a Farkas certificate of the part, into out.certificate.
  int32_t certified = 0;
  const auto certify = [&](const LpProblem& plp, const std::vector<int64_t>& rows, const std::vector<double>& y) {
    const std::vector<double> c = detail::oriented_certificate(plp, y);
    if (c.empty()) return;
    out.certificate.resize(lp.rows(), 0.0);
    out.certificate_part.resize(lp.rows(), -1);
    const int32_t index = certified++;
    for (size_t i = 0; i < rows.size() && i < c.size(); ++i) {
      out.certificate[rows[i]] = c[i];
      out.certificate_part[rows[i]] = index;
    }
  };
  int64_t exactly = 0, largest = 0, reused = 0, first_order_largest = 0;
  std::vector<ExactCache::Entry> kept;  // this call's new exact results, for the next calls (cache)
  // The parts below this go to the exact solver: exact_below, or less where parts reached its cap.
  int64_t below = cache ? std::min(exact_below, cache->capped_below) : exact_below;
  // A part's parameters: `params` with its own slice of the whole LP's warm start, which is
  // moved out first so that copying `params` per part does not copy it.
  std::vector<double> warm_x, warm_y;
  // params.snapshot is the whole LP's: a part's solve calls it with its own iterate in the point
  // the round would leave were it to end there (part_snapshot below).
  std::function<void(const SolveSnapshot&)> whole_snapshot = std::move(params.snapshot);
  params.snapshot = {};
  const double every = params.snapshot_seconds;
  Stopwatch since_saved;
  if (!whole) {
    warm_x = std::move(params.initial_x);
    warm_y = std::move(params.initial_y);
    params.initial_x.clear();
    params.initial_y.clear();
  }
  // First every part the first-order solver would take, at zero cost for at most
  // pretest.iterations, cold: without costs PDHG's dual grows along the Farkas ray alone, so an
  // infeasible part is proved in a fraction of the costed iterations (see solve_at_zero_cost's
  // callers). Where one is, the round has failed, and the other parts' costed solves (up to the
  // cap each, at full resolution minutes) would go unused: none runs.
  // A part's LP at zero cost: a split part's own LP in place (its costs put back after), the
  // whole LP (const here) as a copy.
  auto at_zero_cost = [&](Part& part, const SolverParams& p) {
    if (!whole) return solve_at_zero_cost(part.lp, p, solver);
    LpProblem zero = lp;
    return solve_at_zero_cost(zero, p, solver);
  };
  std::vector<int64_t> pretested(parts.size(), 0);  // iterations, added to the part's costed solve
  // Part k's first-order parameters: `params` with the part's slice of the warm start (in `own`;
  // `params` itself for the whole LP) and its ω.
  const auto first_order_params = [&](size_t k, SolverParams& own) -> SolverParams& {
    const double w = weighted ? part_weight(*warm_weight, parts[k].cols) : 0.0;
    if (whole) {
      if (w > 0.0) params.initial_primal_weight = w;
      return params;
    }
    own = params;
    if (w > 0.0) own.initial_primal_weight = w;
    if (!warm_x.empty()) {
      for (int64_t j : parts[k].cols) own.initial_x.push_back(warm_x[j]);
      for (int64_t i : parts[k].rows) own.initial_y.push_back(warm_y[i]);
    }
    return own;
  };
  const bool first_order_pretest = pretest.iterations > 0 && solver.name().rfind("pdhg", 0) == 0;
  // Part k's pre-test parameters, and its key in the pre-test's cache (its fingerprint, a pass
  // over the part's rows, taken once per part).
  std::vector<std::optional<PretestCache::Key>> keys(parts.size());
  const auto pretest_of = [&](size_t k) {
    const LpProblem& plp = whole ? lp : parts[k].lp;
    SolverParams zp = pretest_params(params, pretest.iterations, pretest.tolerance);
    if (weighted) zp.initial_primal_weight = part_weight(*warm_weight, parts[k].cols);
    if (pretest.cache && !keys[k])
      keys[k] = PretestCache::Key{constraint_fingerprint(plp), plp.rows(),    plp.cols(),
                                  plp.nonzeros(),              zp.max_iterations, zp.tolerance,
                                  zp.initial_primal_weight};
    return std::pair{zp, keys[k].value_or(PretestCache::Key{})};
  };
  const auto in_cache = [&](const PretestCache::Key& key) {
    return std::find_if(pretest.cache->entries.begin(), pretest.cache->entries.end(),
                        [&](const PretestCache::Entry& e) { return e.key == key; });
  };
  // With pretest.skip_below: each part's costed solve first, for at most that many iterations; one
  // optimal by then needs no pre-test (its result stands), the others go on from there after it.
  // (Not a part the cache already passes: split in two, its solve would only lose its restarts.)
  std::vector<std::optional<LpResult>> quick(parts.size());
  if (first_order_pretest && pretest.skip_below > 0)
    for (size_t k = 0; k < parts.size(); ++k) {
      const LpProblem& plp = whole ? lp : parts[k].lp;
      if (exact && plp.cols() < below) continue;
      if (pretest.cache && in_cache(pretest_of(k).second) != pretest.cache->entries.end()) continue;
      SolverParams own;
      SolverParams q = first_order_params(k, own);
      if (q.max_iterations <= pretest.skip_below) continue;
      q.max_iterations = pretest.skip_below;
      quick[k] = solver.solve(plp, q);
      spdlog::debug("rounding: a part of {} variables, its first {} iterations: {} ({:.2f} s; residual {:.3g} "
                    "relative, {:.3g} in a row)",
                    plp.cols(), quick[k]->iterations, to_string(quick[k]->status), quick[k]->seconds,
                    quick[k]->primal_residual, quick[k]->row_residual);
    }
  // Optimal in its first iterations within the residual bounds (a NaN, none computed, passes
  // none), or proved infeasible there (its costed proof stands; proved again at zero cost below
  // for the clash alone).
  const auto skips_pretest = [&](const LpResult& q) {
    if (q.status == LpStatus::Infeasible) return true;
    return q.status == LpStatus::Optimal &&
           (pretest.skip_residual <= 0.0 || q.primal_residual <= pretest.skip_residual) &&
           (pretest.skip_row <= 0.0 || q.row_residual <= pretest.skip_row);
  };
  if (first_order_pretest) {
    std::vector<PretestCache::Entry> fresh;  // this call's new verdicts short of a proof, for the next calls
    for (size_t k = 0; k < parts.size(); ++k) {
      const LpProblem& plp = whole ? lp : parts[k].lp;
      if (exact && plp.cols() < below) continue;
      if (quick[k] && skips_pretest(*quick[k])) continue;
      auto [zp, key] = pretest_of(k);
      if (pretest.cache) {
        auto it = in_cache(key);
        if (it != pretest.cache->entries.end()) {
          spdlog::debug("rounding: a part of {} variables unchanged since its pre-test, which did not prove it "
                        "infeasible: not tested again",
                        plp.cols());
          ++pretest.cache->reused;
          it->unused = -1;  // seen in this call (0 after the ageing below)
          continue;
        }
      }
      const LpResult z = at_zero_cost(parts[k], zp);
      spdlog::debug("rounding: a part of {} variables at zero cost: {} in {} iterations ({:.2f} s)", plp.cols(),
                    to_string(z.status), z.iterations, z.seconds);
      pretested[k] = z.iterations;
      out.pretest_seconds += z.seconds;
      r.iterations = std::max(r.iterations, z.iterations);
      if (z.status != LpStatus::Infeasible) {
        // (A time limit depends on what is left of the run's time, not on the part.)
        if (pretest.cache && (z.status == LpStatus::Optimal || z.status == LpStatus::IterationLimit))
          fresh.push_back({key});
        continue;
      }
      infeasible = true;
      out.failed_rows.insert(out.failed_rows.end(), parts[k].rows.begin(), parts[k].rows.end());
      for (size_t i = 0; i < parts[k].rows.size() && i < z.y.size(); ++i) out.proof[parts[k].rows[i]] = z.y[i];
      certify(plp, parts[k].rows, z.y);
    }
    if (pretest.cache) {
      // Kept until kKeepCalls calls in a row have not had the part (as ExactCache).
      std::erase_if(pretest.cache->entries,
                    [](PretestCache::Entry& e) { return ++e.unused >= PretestCache::kKeepCalls; });
      pretest.cache->entries.insert(pretest.cache->entries.end(), fresh.begin(), fresh.end());
    }
    if (infeasible) {
      // (The first iterations of the parts that had them count too.)
      for (size_t k = 0; k < parts.size(); ++k)
        if (quick[k]) r.iterations = std::max(r.iterations, quick[k]->iterations + pretested[k]);
      r.status = LpStatus::Infeasible;
      r.objective = std::numeric_limits<double>::quiet_NaN();
      spdlog::debug("LP in {} independent parts: proved infeasible at zero cost, no costed solve", parts.size());
      return out;
    }
  }
  for (size_t k = 0; k < parts.size(); ++k) {
    Part& part = parts[k];
    const LpProblem& plp = whole ? lp : part.lp;
    largest = std::max<int64_t>(largest, plp.cols());
    const bool use_exact = exact && plp.cols() < below;
    // The first-order solver's parameters: `params` with the part's slice of the warm start (made
    // only where that solver runs).
    SolverParams own;
    auto first_order = [&]() -> SolverParams& { return first_order_params(k, own); };
    double asked = 0.0;  // the ω this part's first-order solve was asked to start from
    // Part k's iterate in the whole LP's point: the parts before it as they ended, those after it
    // as they start (the warm start, or 0).
    const auto part_snapshot = [&, k](const SolveSnapshot& at) {
      // (Not once a part failed: its zeros would stand in the point, and the round is undone.)
      if (infeasible || out.suspect) return;
      since_saved.reset();
      if (whole) return whole_snapshot(at);
      SolveSnapshot w;
      w.primal_weight = at.primal_weight;
      w.iterations = at.iterations;
      w.seconds = at.seconds;
      w.x = warm_x.empty() ? std::vector<double>(lp.cols(), 0.0) : warm_x;
      w.y = warm_y.empty() ? std::vector<double>(lp.rows(), 0.0) : warm_y;
      for (size_t q = 0; q < k; ++q) {
        for (int64_t j : parts[q].cols) w.x[j] = r.x[j];
        for (int64_t i : parts[q].rows) w.y[i] = r.y[i];
      }
      for (size_t j = 0; j < parts[k].cols.size() && j < at.x.size(); ++j) w.x[parts[k].cols[j]] = at.x[j];
      for (size_t i = 0; i < parts[k].rows.size() && i < at.y.size(); ++i) w.y[parts[k].rows[i]] = at.y[i];
      whole_snapshot(w);
    };
    // A stop asked for (request_stop) between two parts: the round so far saved as the timed
    // snapshots save it (the parts before this one as they ended), then left off here, not after
    // the rest of the round's parts (Clp's take up to a minute each at full resolution). Only
    // where that save is made: otherwise the round goes on to its end, whose decisions are saved
    // then (a throw here would lose those since the last throttled save).
    if (k > 0 && stop_requested() != 0 && whole_snapshot && !infeasible && !out.suspect) {
      SolveSnapshot here;
      // (The largest first-order part's ω so far, as a timed snapshot would carry; 0: none, PDHG's own.)
      if (std::isfinite(out.end_weight) && out.end_weight > 0.0) here.primal_weight = out.end_weight;
      part_snapshot(here);
      throw Stopped("stopped between the parts of a round's LP");
    }
    auto first_order_solve = [&]() {
      SolverParams& p = first_order();
      asked = p.initial_primal_weight;
      if (whole_snapshot) {  // (the costed solve only: not the pre-test)
        p.snapshot = part_snapshot;
        // Every `every` seconds over the round, not per part: parts each shorter than that still
        // save where the round is longer.
        p.snapshot_seconds = every;
        p.snapshot_first_seconds = std::max(every - since_saved.seconds(), 0.0);
      }
      LpResult costed;
      if (!quick[k]) {
        costed = solver.solve(plp, p);
      } else if (quick[k]->status != LpStatus::IterationLimit || quick[k]->x.size() != size_t(plp.cols()) ||
                 quick[k]->y.size() != size_t(plp.rows())) {
        costed = std::move(*quick[k]);  // optimal (or ended otherwise) in its first iterations
      } else {
        // On from where the first iterations left it (its restarts' state aside).
        LpResult& q = *quick[k];
        SolverParams rest = p;
        rest.initial_x = std::move(q.x);
        rest.initial_y = std::move(q.y);
        if (std::isfinite(q.primal_weight) && q.primal_weight > 0.0) rest.initial_primal_weight = q.primal_weight;
        rest.max_iterations = std::max<int64_t>(p.max_iterations - q.iterations, 1);
        rest.time_limit -= q.seconds;
        costed = solver.solve(plp, rest);
        costed.iterations += q.iterations;
        costed.seconds += q.seconds;
      }
      quick[k].reset();
      p.snapshot = {};  // (it refers to this part)
      p.snapshot_first_seconds = -1.0;
      costed.iterations += pretested[k];
      return costed;
    };
    exactly += use_exact;
    // The exact solver's parameters (first, or after the first-order solver's numerical trouble):
    // a pivot cap where asked (its iterations are pivots), and a time cap, the shorter of the cap
    // and the LP's own limit. (A copy: exact_params holds no warm start.)
    SolverParams exact_own = exact_params;
    const bool pivot_cap = cap.pivots_per_column > 0.0;
    if (pivot_cap) {
      const double pivots = cap.pivots_per_column * double(std::max<int64_t>(plp.cols(), 1000));
      exact_own.max_iterations = std::min<int64_t>(exact_params.max_iterations, std::max<int64_t>(int64_t(pivots), 1));
    }
    if (cap.seconds > 0.0) exact_own.time_limit = std::min(exact_params.time_limit, cap.seconds);
    const bool time_cap = std::isfinite(exact_own.time_limit);
    ExactCache::Entry* same = nullptr;
    if (use_exact && cache)
      for (ExactCache::Entry& e : cache->entries)
        if (e.max_iterations == exact_own.max_iterations && e.time_limit == exact_own.time_limit && same_lp(e.lp, plp)) {
          same = &e;
          break;
        }
    LpResult s = same ? same->r : use_exact ? exact->solve(plp, exact_own) : first_order_solve();
    if (same) {
      same->unused = -1;  // seen in this call (0 after the call's ageing below)
      ++reused;
    } else if (use_exact) {
      // The exact solver's work per part, for sizing its pivot cap (exact_pivots_per_column):
      // every part in -v logs, a slow one (seconds to minutes of simplex on a part of its size)
      // in any log.
      const double per_column = double(s.iterations) / double(std::max<int64_t>(plp.cols(), 1));
      const bool slow = s.seconds >= slow_part_seconds;
      spdlog::log(slow ? spdlog::level::info : spdlog::level::debug,
                  "rounding: {} on a part of {} variables: {} in {} pivots ({:.2f} per column, {:.1f} s)",
                  exact->name(), plp.cols(), to_string(s.status), s.iterations, per_column, s.seconds);
      if (slow && slow_part) slow_part(plp);
    }
    // One solver's numerical trouble on a part is the other's to try: measured, Clp gave up on a
    // part of FAUST_r 043-063's finest rounding (round 19 of a 24-minute run), which ended it.
    // (The exact solver only where a part is not far above its size: Clp on millions of columns
    // takes hours.)
    // Stopped at a cap, Clp has no answer (its point is a dual simplex's, not primal feasible):
    // the part is the first-order solver's.
    const bool at_cap = use_exact && ((pivot_cap && s.status == LpStatus::IterationLimit) ||
                                      (time_cap && s.status == LpStatus::TimeLimit));
    const bool failed = s.status == LpStatus::NumericalTrouble ||
                        (s.status != LpStatus::Infeasible && s.x.size() != size_t(plp.cols())) || at_cap;
    if (at_cap && cache && plp.cols() < below) {
      below = plp.cols();
      cache->capped_below = below;
      spdlog::info("rounding: {} stopped at its cap on a part of {} variables: parts of that size or larger go to {} "
                   "from now on",
                   exact->name(), plp.cols(), solver.name());
    }
    // The exact solver's failures are kept too: the same part would fail the same way. (Not one at
    // its cap: capped_below sends that part elsewhere from now on. Measured, deformation-transfer
    // cat 0002-0009 at full resolution with --exact-pivots-per-column 2: rounds 13 and 15 of level
    // 6 each spent 10 minutes of Clp at its cap on the same 29 011-column part before PDHG took it.)
    if (use_exact && cache && !same && !at_cap)
      kept.push_back({plp, exact_own.max_iterations, exact_own.time_limit, s, -1});
    if (failed && (use_exact || (exact && plp.cols() <= 10 * std::max<int64_t>(exact_below, 1)))) {
      spdlog::warn("rounding: {} {} on a part of {} variables ({}); trying {}",
                   use_exact ? exact->name() : solver.name(), same ? "failed before" : "failed", plp.cols(),
                   to_string(s.status), use_exact ? solver.name() : exact->name());
      const int64_t before = s.iterations;
      s = use_exact ? first_order_solve() : exact->solve(plp, exact_own);
      s.iterations = std::max(s.iterations, before);
      exactly += use_exact ? -1 : 1;
    }
    r.iterations = std::max(r.iterations, s.iterations);
    if (s.status == LpStatus::NumericalTrouble) {
      r.status = s.status;
      return out;
    }
    if (s.status == LpStatus::Infeasible && s.solver == solver.name() && s.solver.rfind("pdhg", 0) == 0 && !s.y.empty() &&
        std::any_of(plp.c.begin(), plp.c.end(), [](double c) { return c != 0.0; })) {
      // A first-order proof is a dual point whose bound passed the largest objective. Next to a
      // ray still short, its ordinary duals (about the costs) can be its large entries and name
      // rows that take no part in the clash (measured on the rounding test's two_causes with its
      // alternatives at cost 10: the proof named the other cause, and the round after it failed
      // again). The same part at zero cost has no ordinary duals: its proof is the clash alone.
      // (Under the pre-tests' own tolerance where given: this part has no feasible point, so
      // "optimal" at zero cost only means the solve stopped short of the narrower proof.)
      SolverParams zp = first_order();
      if (pretest.tolerance > 0.0) zp.tolerance = pretest.tolerance;
      const LpResult z = at_zero_cost(part, zp);
      spdlog::debug("rounding: a part of {} variables proved infeasible ({} rows carry the proof); at zero cost {} in {} "
                    "iterations ({:.2f} s){}",
                    plp.cols(), carrying_rows(s.y).size(), to_string(z.status), z.iterations, z.seconds,
                    z.status == LpStatus::Infeasible ? fmt::format(", {} rows carry it", carrying_rows(z.y).size()) : "");
      if (z.status == LpStatus::Infeasible && z.y.size() == s.y.size()) s.y = z.y;
      s.iterations += z.iterations;
      r.iterations = std::max(r.iterations, s.iterations);
    }
    if (s.status == LpStatus::Infeasible) {
      if (!infeasible) out.failed_rows.clear();  // drop the suspect parts' rows
      infeasible = true;
      out.failed_rows.insert(out.failed_rows.end(), part.rows.begin(), part.rows.end());
      for (size_t i = 0; i < part.rows.size() && i < s.y.size(); ++i) out.proof[part.rows[i]] = s.y[i];
      certify(plp, part.rows, s.y);
      if (s.y.empty())  // no ray (Clp): the whole part is the proof
        for (int64_t i : part.rows) out.proof[i] = 1.0;
      continue;
    }
    if (s.x.size() != part.cols.size()) {
      r.status = LpStatus::NumericalTrouble;
      return out;
    }
    if (s.status != LpStatus::Optimal && r.status == LpStatus::Optimal) r.status = s.status;
    if (s.status == LpStatus::IterationLimit || s.status == LpStatus::TimeLimit) {
      out.capped_cols.resize(lp.cols(), 0);
      for (int64_t j : part.cols) out.capped_cols[j] = 1;
    }
    if (looks_infeasible(s)) {
      out.suspect = true;
      if (!infeasible) out.failed_rows.insert(out.failed_rows.end(), part.rows.begin(), part.rows.end());
      for (size_t i = 0; i < part.rows.size(); ++i) suspect_proof[part.rows[i]] = s.y[i];
    }
    for (size_t j = 0; j < part.cols.size(); ++j) r.x[part.cols[j]] = s.x[j];
    for (size_t i = 0; i < part.rows.size() && i < s.y.size(); ++i) r.y[part.rows[i]] = s.y[i];
    if (std::isfinite(s.primal_weight) && s.primal_weight > 0.0) {
      for (int64_t j : part.cols) out.weight[j] = s.primal_weight;
      if (plp.cols() > first_order_largest) {
        first_order_largest = plp.cols();
        out.start_weight = asked;
        out.end_weight = s.primal_weight;
      }
    }
    r.objective += s.objective;
    r.lower_bound += s.lower_bound;
  }
  out.exact_parts = exactly;
  if (cache) {
    for (ExactCache::Entry& e : kept) cache->entries.push_back(std::move(e));
    std::erase_if(cache->entries, [](ExactCache::Entry& e) { return ++e.unused >= ExactCache::kKeepCalls; });
    cache->reused += reused;
    if (reused > 0) spdlog::debug("rounding: {} unchanged part(s) took their exact result of the last round", reused);
  }
  if (parts.size() > 1)
    spdlog::debug("LP in {} independent parts, largest {} variables, {} solved exactly", parts.size(), largest,
                  exactly);
  if (infeasible) {
    r.status = LpStatus::Infeasible;
    r.objective = std::numeric_limits<double>::quiet_NaN();
    out.suspect = false;
  } else if (out.suspect) {
    out.proof = std::move(suspect_proof);
  } else {
    out.proof.clear();
  }
  return out;
}

namespace {

// One step of shrinking a batch that cannot stay: halve it; a single fixing to 1 becomes one to
// 0. False where nothing is left to shrink (a single fixing to 0).
bool shrink_once(std::vector<std::pair<int64_t, int>>& batch) {
  if (batch.size() > 1) batch.resize(batch.size() / 2);
  else if (batch.front().second == 1) batch.front().second = 0;
  else return false;
  return true;
}

// Fixes the batch (largest first); a fixing that propagation proves infeasible is undone and
// replaced by fixing fewer: with `greedy`, every candidate that does not clash with the larger
// ones fixed before it (one propagation each); otherwise halving the batch down to the single
// largest. A single variable that cannot be 1 is fixed to 0 instead: each retry strictly shrinks
// the search space. Returns the batch actually applied (`batch` itself when nothing had to be
// undone). `mark` is the fixer's mark before the batch.
std::vector<std::pair<int64_t, int>> shrink_and_fix(Fixer& fixer, std::vector<std::pair<int64_t, int>> batch,
                                                    size_t mark, bool greedy) {
  // One at a time, each followed by its propagation: the same state as all at once where it goes
  // through (propagation's fixed point does not depend on the order), and the trail then says
  // which fixing propagated what (fixings_away_from).
  const auto fix_each = [&](const std::vector<std::pair<int64_t, int>>& b) {
    for (const auto& a : b)
      if (!fixer.fix({a})) return false;
    return true;
  };
  if (fix_each(batch)) return batch;
  fixer.undo_to(mark);
  if (greedy && batch.size() > 1) {
    std::vector<std::pair<int64_t, int>> kept;
    for (const auto& a : batch) {
      const size_t m = fixer.mark();
      if (fixer.fix({a})) kept.push_back(a);
      else fixer.undo_to(m);
    }
    if (!kept.empty()) return kept;
    batch.resize(1);  // not even the largest alone: it must be 0
    batch.front().second = 0;
  } else if (!shrink_once(batch)) {
    throw InfeasibleError("rounding: no consistent fixing exists (no binary solution)");
  }
  while (!fix_each(batch)) {
    fixer.undo_to(mark);
    if (!shrink_once(batch)) throw InfeasibleError("rounding: no consistent fixing exists (no binary solution)");
  }
  return batch;
}

// The rows that carry a Farkas certificate y (in the reduced LP's numbering; carrying_rows),
// mapped back to the full LP.
std::vector<int64_t> certificate_rows(const std::vector<double>& y, const std::vector<int64_t>& rows) {
  std::vector<int64_t> out;
  for (int64_t i : carrying_rows(y))
    if (i < static_cast<int64_t>(rows.size())) out.push_back(rows[i]);
  spdlog::debug("infeasibility certificate: {} of {} rows", out.size(), y.size());
  return out;
}

// The batch for a fractional LP (nothing above the threshold): the largest variables, each at
// least half the largest value, none sharing a row with b ≠ 0 (a face's coverage row) with an
// earlier one, up to `fraction` of the open faces; at least the single largest.
std::vector<std::pair<int64_t, int>> fractional_batch(const LpProblem& lp, const Reduced& red,
                                                      const std::vector<double>& x, const std::vector<int64_t>& order,
                                                      double fraction) {
  int64_t open_faces = 0;  // coverage rows still open, X and Y together
  for (int64_t i : red.rows) open_faces += lp.b[i] != 0.0;
  const int64_t limit = std::max<int64_t>(1, std::llround(fraction * double(open_faces) / 2.0));
  std::vector<std::pair<int64_t, int>> batch{{red.cols[order.front()], 1}};
  if (limit == 1) return batch;
  std::vector<char> taken(lp.rows(), 0);
  auto coverage_rows = [&](int64_t j, auto&& visit) {
    for (uint32_t k = lp.at.row_ptr[j]; k < lp.at.row_ptr[j + 1]; ++k)
      if (lp.b[col_of(lp.at.entry[k])] != 0.0) visit(col_of(lp.at.entry[k]));
  };
  coverage_rows(batch.front().first, [&](int64_t i) { taken[i] = 1; });
  const double top = x[order.front()];
  for (size_t n = 1; n < order.size() && int64_t(batch.size()) < limit; ++n) {
    const int64_t k = order[n];
    if (x[k] < 0.5 * top) break;
    bool clash = false;
    coverage_rows(red.cols[k], [&](int64_t i) { clash = clash || taken[i]; });
    if (clash) continue;
    coverage_rows(red.cols[k], [&](int64_t i) { taken[i] = 1; });
    batch.push_back({red.cols[k], 1});
  }
  return batch;
}

// The fixings of `batch` that an infeasibility proof after it (a Farkas certificate's rows,
// `proof`) does not blame. A fixing is blamed where it, or a variable its own propagation set
// (`assigned`: the trail since the batch, each fixing followed by what it propagated; where the
// batch went in whole, its propagation is nobody's), lies in a proof row or shares a row with
// a free variable of one. Its own propagation counts: a fixing acts through the zeros it sets,
// often several rows away. (Rows of every variable of a proof row blamed all 11 830 fixings at
// full resolution: a face's row reaches a thousand candidates.) Empty where the proof blames
// all of them or none (then it says nothing local).
std::vector<std::pair<int64_t, int>> fixings_away_from(const LpProblem& lp, const std::vector<int8_t>& value,
                                                       const std::vector<int64_t>& proof,
                                                       const std::vector<std::pair<int64_t, int>>& batch,
                                                       const std::vector<int64_t>& assigned,
                                                       int64_t* blamed_count = nullptr) {
  std::vector<char> near(lp.rows(), 0);  // proof rows and the rows of their free variables
  for (int64_t i : proof) {
    near[i] = 1;
    for (uint32_t k = lp.a.row_ptr[i]; k < lp.a.row_ptr[i + 1]; ++k) {
      const int64_t j = col_of(lp.a.entry[k]);
      if (value[j] >= 0) continue;
      for (uint32_t q = lp.at.row_ptr[j]; q < lp.at.row_ptr[j + 1]; ++q) near[col_of(lp.at.entry[q])] = 1;
    }
  }
  auto touches = [&](int64_t j) {
    for (uint32_t q = lp.at.row_ptr[j]; q < lp.at.row_ptr[j + 1]; ++q)
      if (near[col_of(lp.at.entry[q])]) return true;
    return false;
  };
  std::unordered_map<int64_t, size_t> position;  // batch variable -> its index in `batch`
  for (size_t n = 0; n < batch.size(); ++n) position[batch[n].first] = n;
  std::vector<char> blamed(batch.size(), 0);
  // Walk the trail: a batch variable opens its own segment; what follows it is its propagation,
  // unless it stands next to another batch variable (the batch went in whole: no owner).
  int64_t owner = -1;
  for (size_t t = 0; t < assigned.size(); ++t) {
    const auto it = position.find(assigned[t]);
    if (it != position.end()) {
      const bool in_run = (t + 1 < assigned.size() && position.count(assigned[t + 1])) ||
                          (t > 0 && position.count(assigned[t - 1]));
      owner = in_run ? -1 : static_cast<int64_t>(it->second);
      if (touches(assigned[t])) blamed[it->second] = 1;
    } else if (owner >= 0 && !blamed[owner] && touches(assigned[t])) {
      blamed[owner] = 1;
    }
  }
  std::vector<std::pair<int64_t, int>> kept;
  for (size_t n = 0; n < batch.size(); ++n)
    if (!blamed[n]) kept.push_back(batch[n]);
  const int64_t count = static_cast<int64_t>(batch.size() - kept.size());
  if (blamed_count) *blamed_count = count;
  if (kept.size() == batch.size()) kept.clear();
  spdlog::debug("rounding: the infeasibility proof ({} rows) blames {} of {} fixings", proof.size(), count,
                batch.size());
  return kept;
}

// The undecided regions of an LP's solution `x` (over red.cols): the rows of the free variables
// valued in (`band`, 1 − `band`), joined where such a variable lies in two; per row of `lp`, its
// region's representative row, −1 where no such variable lies in it.
std::vector<int64_t> undecided_regions(const LpProblem& lp, const Reduced& red, const std::vector<double>& x,
                                       double band) {
  std::vector<int64_t> parent(lp.rows(), -1);
  auto root = [&](int64_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (size_t k = 0; k < red.cols.size(); ++k) {
    if (!(x[k] > band && x[k] < 1.0 - band)) continue;
    const int64_t j = red.cols[k];
    int64_t first = -1;
    for (uint32_t q = lp.at.row_ptr[j]; q < lp.at.row_ptr[j + 1]; ++q) {
      const int64_t i = col_of(lp.at.entry[q]);
      if (parent[i] < 0) parent[i] = i;
      if (first < 0) first = root(i);
      else parent[root(i)] = first;
    }
  }
  for (int64_t i = 0; i < lp.rows(); ++i)
    if (parent[i] >= 0) parent[i] = root(i);
  return parent;
}

// The candidates of a big (greedy) round that stand away from the LP's undecided part: none of
// a candidate's rows may hold a free variable with a value strictly between `unsure` and
// 1 − `unsure`, nor lie within `margin` − 1 further steps of such a row through the closedness
// rows (b = 0; a face's coverage row reaches a thousand candidates and would spread everywhere).
// Why: a candidate next to a split region fixes that region's boundary to one of the LP's mixed
// alternatives, which the narrow reduced space often cannot complete; propagation does not see
// it, the next LP is infeasible, and every infeasibility proof costs a solve. Where nothing
// would be left: the largest candidate of each undecided region, at most the `fallback` share
// of the batch (the whole batch with a share of 1).
std::vector<std::pair<int64_t, int>> away_from_undecided(const LpProblem& lp, const Reduced& red,
                                                         const std::vector<int8_t>& value, const std::vector<double>& x,
                                                         const std::vector<std::pair<int64_t, int>>& batch,
                                                         double unsure, int margin, double fallback) {
  if (margin <= 0 || batch.empty()) return batch;
  const auto away = [&](double band) {
    std::vector<char> undecided(lp.rows(), 0);
    std::vector<int64_t> frontier;
    for (size_t k = 0; k < red.cols.size(); ++k) {
      if (!(x[k] > band && x[k] < 1.0 - band)) continue;
      const int64_t j = red.cols[k];
      for (uint32_t q = lp.at.row_ptr[j]; q < lp.at.row_ptr[j + 1]; ++q) {
        const int64_t i = col_of(lp.at.entry[q]);
        if (!undecided[i]) {
          undecided[i] = 1;
          frontier.push_back(i);
        }
      }
    }
    for (int step = 1; step < margin; ++step) {
      std::vector<int64_t> next;
      for (int64_t i : frontier) {
        if (lp.b[i] != 0.0) continue;
        for (uint32_t k = lp.a.row_ptr[i]; k < lp.a.row_ptr[i + 1]; ++k) {
          const int64_t j = col_of(lp.a.entry[k]);
          if (value[j] >= 0) continue;
          for (uint32_t q = lp.at.row_ptr[j]; q < lp.at.row_ptr[j + 1]; ++q) {
            const int64_t r = col_of(lp.at.entry[q]);
            if (lp.b[r] == 0.0 && !undecided[r]) {
              undecided[r] = 1;
              next.push_back(r);
            }
          }
        }
      }
      frontier = std::move(next);
    }
    std::vector<std::pair<int64_t, int>> kept;
    for (const auto& a : batch) {
      bool near = false;
      for (uint32_t q = lp.at.row_ptr[a.first]; q < lp.at.row_ptr[a.first + 1] && !near; ++q)
        near = undecided[col_of(lp.at.entry[q])];
      if (!near) kept.push_back(a);
    }
    spdlog::debug("rounding: {} of {} candidates stand away from variables in ({}, {}) (margin {})", kept.size(),
                  batch.size(), band, 1.0 - band, margin);
    return kept;
  };
  // A converged LP repeats its iterate, so a round that keeps few candidates keeps few again
  // (full resolution: 2-3 % of 8 800, 150 fixings per round). Then only the strongly split
  // variables count, and where even they surround every candidate, the fallback below.
  auto kept = away(unsure);
  if (4 * kept.size() >= batch.size()) return kept;
  if (unsure < 0.3) kept = away(0.3);
  if (!kept.empty()) return kept;
  // Nothing stands away: the whole batch with a share of 1 (the default up to the fifty-first
  // session); otherwise the largest candidate of each undecided region (undecided_regions), at
  // most the share of the batch (it is sorted largest first). Two fixed in one region pick two of
  // its mixed alternatives. Measured, FAUST_r 043-065 without WKS, level 6 at full resolution
  // (two stretches of one run, not one state): with the largest eighth (57 of 451 candidates, all
  // next to undecided variables) 10 of 12 such rounds left an infeasible LP (one proof blamed 56
  // of the 57), and 20 rounds at 595 k free variables went fix, fail, trim (13 365 fixings to 1
  // before and after); one per region (2-3 fixings) left an infeasible LP after 81 of 110, but
  // each trim cost one fixing and 1-3 s: from 789 k free variables to 245 k in 14 minutes.
  if (fallback >= 1.0) return batch;
  const size_t take = std::clamp<size_t>(static_cast<size_t>(std::ceil(fallback * double(batch.size()))), 1, batch.size());
  const std::vector<int64_t> region = undecided_regions(lp, red, x, unsure);
  // (A candidate in no region, kept out only by the margin's closedness steps, counts as in one
  // region shared by all such: -2.)
  std::unordered_set<int64_t> used;
  std::vector<std::pair<int64_t, int>> out;
  for (const auto& a : batch) {
    if (out.size() == take) break;
    std::vector<int64_t> mine;
    for (uint32_t q = lp.at.row_ptr[a.first]; q < lp.at.row_ptr[a.first + 1]; ++q) {
      const int64_t r = region[col_of(lp.at.entry[q])];
      if (r >= 0) mine.push_back(r);
    }
    if (mine.empty()) mine.push_back(-2);
    if (std::any_of(mine.begin(), mine.end(), [&](int64_t r) { return used.count(r) > 0; })) continue;
    used.insert(mine.begin(), mine.end());
    out.push_back(a);
  }
  spdlog::debug("rounding: none stands away; {} of {} candidates, one per undecided region they lie in (at most {})",
                out.size(), batch.size(), take);
  return out;
}

}  // namespace

detail::SearchEnd detail::search_part(const LpProblem& plp, LpSolver& exact, const SolverParams& params, int64_t max_nodes,
                              std::vector<int8_t>& value, int64_t& nodes, std::optional<LpResult>* root, bool backjump,
                              SearchStats* stats, std::vector<SearchProof>* proofs) {
  SearchStats local;
  SearchStats& st = stats ? *stats : local;
  if (proofs) proofs->clear();
  bool proved = proofs != nullptr;  // every failure so far came with a proof
  Fixer f(plp);
  const bool consistent = f.propagate_all();
  struct Branch {
    size_t mark;
    int64_t col;
    int value;                      // the value being tried: 1 first, then 0
    std::vector<int32_t> conflict;  // levels below whose decisions its failed values needed
  };
  std::vector<Branch> stack;
  // The proof of a failed propagation: the row it stopped at, whose free entries can no longer
  // reach its right-hand side (d = ±e_i; empty where that row does not show it).
  const auto row_proof = [&] {
    std::vector<double> d;
    const int64_t i = f.failed_row();
    if (i < 0 || i >= plp.rows()) return d;
    const FixState& s = f.state();
    const double sign = s.rhs[i] > s.free_pos[i] ? 1.0 : s.rhs[i] < -s.free_neg[i] ? -1.0 : 0.0;
    if (sign != 0.0) {
      d.assign(plp.rows(), 0.0);
      d[i] = sign;
    }
    return d;
  };
  // The levels below the top whose decisions, with the top's, the proof `d` (one value per row of
  // plp, on the state as it stands) needs: those it weighs anything on, where their decisions
  // propagated afresh from the root still leave it a positive margin; else all of them.
  // (With `proofs`, d goes there too, with the decisions returned and the top's.)
  constexpr size_t kMaxProofs = 256;
  const auto needed = [&](const std::vector<double>& d) {
    ++st.failures;
    const int32_t top = static_cast<int32_t>(stack.size()) - 1;
    std::vector<int32_t> all(static_cast<size_t>(top));
    std::iota(all.begin(), all.end(), 0);
    const auto keep = [&](const std::vector<int32_t>& levels) {
      if (!proved) return levels;
      if (d.empty() || proofs->size() >= kMaxProofs) {  // (beyond that, too many to weigh)
        proved = false;
        proofs->clear();
        return levels;
      }
      SearchProof proof;
      for (size_t i = 0; i < d.size(); ++i)
        if (d[i] != 0.0) proof.d.push_back({static_cast<int64_t>(i), d[i]});
      for (int32_t l : levels) proof.decisions.push_back({stack[l].col, stack[l].value});
      proof.decisions.push_back({stack.back().col, stack.back().value});
      proofs->push_back(std::move(proof));
      return levels;
    };
    if (!backjump || d.empty() || top == 0) return keep(all);
    const CertificateBlame blame(plp, d);
    double largest = 0.0;
    for (double v : d) largest = std::max(largest, std::abs(v));
    const double noise = 1e-9 * largest;
    const FixState& s = f.state();
    if (!(blame.margin(s.value, s.rhs) > noise)) return keep(all);
    std::vector<size_t> starts;  // each level's first position on the trail since the first
    for (const Branch& b : stack) starts.push_back(b.mark - stack.front().mark);
    const std::vector<double> weight =
        trail_weights(blame, [&](auto&& visit) { f.visit_since(stack.front().mark, visit); }, s.value, starts).step;
    std::vector<int32_t> some;
    for (int32_t l = 0; l < top; ++l)
      if (weight[l] > 0.0) some.push_back(l);
    if (some.size() == all.size()) return keep(all);
    Fixer g(plp);
    bool holds = !g.propagate_all();
    for (int32_t l : some) holds = holds || !g.fix({{stack[l].col, stack[l].value}});
    holds = holds || !g.fix({{stack.back().col, stack.back().value}});
    holds = holds || blame.margin(g.state().value, g.state().rhs) > noise;
    if (!holds) return keep(all);
    ++st.short_nogoods;
    return keep(some);
  };
  // The top branch's value has failed, needing the decisions of levels `why`: the next value to
  // try. Where both have failed, the decisions their failures needed alone leave no solution:
  // back to the deepest of them (the levels between are not tried again), whose value has then
  // failed needing the others. False where none is left: no binary solution.
  const auto retreat = [&](std::vector<int32_t> why) {
    while (!stack.empty()) {
      Branch& b = stack.back();
      b.conflict.insert(b.conflict.end(), why.begin(), why.end());
      std::sort(b.conflict.begin(), b.conflict.end());
      b.conflict.erase(std::unique(b.conflict.begin(), b.conflict.end()), b.conflict.end());
      f.undo_to(b.mark);
      if (b.value == 1) {
        b.value = 0;
        if (f.fix({{b.col, 0}})) return true;
        why = needed(row_proof());
        continue;
      }
      why = std::move(b.conflict);
      stack.pop_back();
      if (why.empty()) {  // the root's state alone leaves none
        if (!stack.empty()) {
          ++st.jumps;
          st.levels_skipped += static_cast<int64_t>(stack.size());
        }
        return false;
      }
      const size_t deepest = static_cast<size_t>(why.back());
      if (deepest + 1 < stack.size()) {
        ++st.jumps;
        st.levels_skipped += static_cast<int64_t>(stack.size() - deepest - 1);
        f.undo_to(stack[deepest + 1].mark);
        stack.resize(deepest + 1);
      }
      why.pop_back();
    }
    return false;
  };
  if (!consistent) {  // the part's fixings alone leave none: the row propagation stopped at
    if (proved) {
      const std::vector<double> d = row_proof();
      if (d.empty()) proofs->clear();
      else {
        proofs->push_back({});
        for (size_t i = 0; i < d.size(); ++i)
          if (d[i] != 0.0) proofs->back().d.push_back({static_cast<int64_t>(i), d[i]});
      }
    }
    return SearchEnd::none;
  }
  const auto finish = [&] {
    value.resize(plp.cols());
    for (int64_t j = 0; j < plp.cols(); ++j) value[j] = f.state().value[j] == 1 ? 1 : 0;
    return SearchEnd::found;
  };
  for (;;) {
    if (f.state().unsatisfied == 0) return finish();  // what is still free is 0
    if (++nodes > max_nodes) return SearchEnd::node_limit;
    const Reduced red = reduce(plp, f.state());
    // (The stack is empty at the root only: a retreat that empties it ends the search.)
    const bool at_root = stack.empty() && root;
    if (at_root && !root->has_value()) *root = exact.solve(red.lp, params);
    const LpResult s = at_root ? **root : exact.solve(red.lp, params);
    if (s.status == LpStatus::Infeasible) {
      if (stack.empty()) return SearchEnd::infeasible;
      std::vector<double> d;  // the solver's ray, on plp's rows
      if (backjump || proofs) {
        const std::vector<double> y = oriented_certificate(red.lp, s.y);
        if (!y.empty()) {
          d.assign(plp.rows(), 0.0);
          for (size_t i = 0; i < red.rows.size(); ++i) d[red.rows[i]] = y[i];
        }
      }
      if (!retreat(needed(d))) return SearchEnd::none;
      continue;
    }
    if (s.status != LpStatus::Optimal || s.x.size() != red.cols.size())
      return SearchEnd::node_limit;  // no answer: as good as running out of nodes
    constexpr double kIntegral = 1e-6;
    int64_t branch = -1;
    for (size_t k = 0; k < red.cols.size(); ++k)
      if (s.x[k] > kIntegral && s.x[k] < 1.0 - kIntegral && (branch < 0 || s.x[k] > s.x[branch])) branch = k;
    if (branch < 0) {  // an integral vertex: it satisfies A x = b, so it is a solution
      std::vector<std::pair<int64_t, int>> all;
      for (size_t k = 0; k < red.cols.size(); ++k) all.push_back({red.cols[k], s.x[k] > 0.5 ? 1 : 0});
      const size_t mark = f.mark();
      if (f.fix(all) && f.state().unsatisfied == 0) return finish();
      f.undo_to(mark);  // rounding error in the vertex: branch instead
      branch = 0;
      for (size_t k = 1; k < red.cols.size(); ++k)
        if (std::abs(s.x[k] - 0.5) < std::abs(s.x[branch] - 0.5)) branch = k;
    }
    stack.push_back({f.mark(), red.cols[branch], 1, {}});
    if (!f.fix({{red.cols[branch], 1}}) && !retreat(needed(row_proof()))) return SearchEnd::none;
  }
}

namespace {
// The columns within `depth` row-column-row steps of `rows` in the LP's graph (fixed or free):
// the neighbourhood whose fixings are released where a part has no binary solution.
std::vector<char> columns_near(const LpProblem& lp, const std::vector<int64_t>& rows, int depth) {
  std::vector<char> row_seen(lp.rows(), 0), col_seen(lp.cols(), 0);
  std::vector<int64_t> frontier;
  for (int64_t i : rows)
    if (!row_seen[i]) {
      row_seen[i] = 1;
      frontier.push_back(i);
    }
  for (int step = 0; step < depth && !frontier.empty(); ++step) {
    std::vector<int64_t> next;
    for (int64_t i : frontier)
      for (uint32_t k = lp.a.row_ptr[i]; k < lp.a.row_ptr[i + 1]; ++k) {
        const int64_t j = col_of(lp.a.entry[k]);
        if (col_seen[j]) continue;
        col_seen[j] = 1;
        for (uint32_t q = lp.at.row_ptr[j]; q < lp.at.row_ptr[j + 1]; ++q) {
          const int64_t r = col_of(lp.at.entry[q]);
          if (!row_seen[r]) {
            row_seen[r] = 1;
            next.push_back(r);
          }
        }
      }
    frontier = std::move(next);
  }
  return col_seen;
}

}  // namespace

int64_t propagation_conflict(const LpProblem& lp, const std::vector<char>& skip) {
  if (!skip.empty() && static_cast<int64_t>(skip.size()) != lp.rows())
    throw InvalidInputError("propagation: need one skip flag per row");
  Fixer fixer(lp);
  return fixer.propagate_all(skip.empty() ? nullptr : &skip) ? -1 : fixer.failed_row();
}

std::vector<int64_t> close_pockets(const ProductSpace& space, const std::vector<int64_t>& gamma, int64_t* closed) {
  if (closed) *closed = 0;
  const Mesh& X = space.x();
  const Mesh& Y = space.y();
  // Side 0: ET triangles, an edge of X over faces of Y; side 1: TE, an edge of Y over faces of X.
  // In canonical form the edge part is (tail, head, head) and the fan part a face from some corner.
  struct Part {
    std::array<int, 3> edge, fan;
    int face;
  };
  auto part = [](const ProductTriangle& t, int side) {
    return side == 0 ? Part{t.a, t.b, t.fb} : Part{t.b, t.a, t.fa};
  };
  auto is_edge_over_face = [](const ProductTriangle& t, int side) {
    const auto& e = side == 0 ? t.a : t.b;
    return (side == 0 ? t.fa < 0 && t.fb >= 0 : t.fb < 0 && t.fa >= 0) && e[0] != e[1] && e[1] == e[2];
  };
  struct Pocket {
    int side, w;
    std::vector<int64_t> members;  // indices into the space
    std::vector<int64_t> to;       // their replacements, -1 until found
  };
  std::vector<Pocket> pockets;
  for (int side = 0; side < 2; ++side) {
    const Mesh& F = side == 0 ? Y : X;  // where the fan lies (the edge lies on the other)
    std::map<std::pair<int, int>, std::vector<int64_t>> by_edge;  // undirected edge -> Γ's triangles over it
    // Pairs (edge-side vertex, fan-side vertex) related by Γ, counted once per triangle.
    std::unordered_map<int64_t, int> paired;
    auto pair_key = [&](int e, int f) { return int64_t(e) * F.num_vertices() + f; };
    for (int64_t j : gamma) {
      const ProductTriangle t = space[j];
      const Part p = part(t, side);
      for (int i = 0; i < 3; ++i) {
        bool seen = false;
        for (int k = 0; k < i; ++k) seen = seen || (p.edge[k] == p.edge[i] && p.fan[k] == p.fan[i]);
        if (!seen) ++paired[pair_key(p.edge[i], p.fan[i])];
      }
      if (is_edge_over_face(t, side))
        by_edge[{std::min(p.edge[0], p.edge[1]), std::max(p.edge[0], p.edge[1])}].push_back(j);
    }
    if (by_edge.empty()) continue;
    std::vector<std::vector<int>> faces_at(F.num_vertices());
    for (int f = 0; f < F.num_faces(); ++f)
      for (int v : F.faces[f]) faces_at[v].push_back(f);
    for (const auto& [edge, over] : by_edge) {
      for (const int u : {edge.first, edge.second}) {
        const int w = u == edge.first ? edge.second : edge.first;
        // The tips: fan-side vertices paired with u; a pocket is one connected set K of them.
        std::map<int, std::vector<int64_t>> at_tip;  // tip -> triangles pairing u with it
        for (int64_t j : over) {
          const Part p = part(space[j], side);
          for (int i = 0; i < 3; ++i)
            if (p.edge[i] == u) at_tip[p.fan[i]].push_back(j);
        }
        std::set<int> left;
        for (const auto& [tip, js] : at_tip) left.insert(tip);
        while (!left.empty()) {
          std::vector<int> k{*left.begin()};
          left.erase(left.begin());
          for (size_t n = 0; n < k.size(); ++n)  // grow K along F's edges within the tips
            for (int f : faces_at[k[n]])
              for (int v : F.faces[f])
                if (left.erase(v)) k.push_back(v);
          const std::set<int> kset(k.begin(), k.end());
          std::set<int64_t> members;
          for (int v : k) members.insert(at_tip[v].begin(), at_tip[v].end());
          // The pocket must be the whole star of K, and pair w only with vertices outside K.
          std::set<int> star;
          for (int v : k) star.insert(faces_at[v].begin(), faces_at[v].end());
          bool ok = members.size() == star.size();
          for (int64_t j : members) {
            const Part p = part(space[j], side);
            ok = ok && star.count(p.face);
            for (int i = 0; i < 3; ++i) ok = ok && (p.edge[i] == u) == (kset.count(p.fan[i]) > 0);
          }
          // A tear only: nothing outside the pocket pairs u with K (at_tip[v] lists each of the
          // pocket's triangles that pair u with v once).
          for (int v : k) ok = ok && paired.at(pair_key(u, v)) == static_cast<int>(at_tip[v].size());
          if (ok) pockets.push_back({side, w, {members.begin(), members.end()}, {}});
        }
      }
    }
  }
  if (pockets.empty()) return gamma;
  // The replacement of each member: its face with the whole fan on w, (w, w, w) x face.
  auto replacement = [&](const Pocket& pk, int64_t j) {
    const ProductTriangle t = space[j];
    return pk.side == 0 ? ProductTriangle{{pk.w, pk.w, pk.w}, Y.faces[t.fb], -1, t.fb}
                        : ProductTriangle{X.faces[t.fa], {pk.w, pk.w, pk.w}, t.fa, -1};
  };
  for (auto& pk : pockets) pk.to.assign(pk.members.size(), -1);
  if (space.is_full()) {
    for (auto& pk : pockets)
      for (size_t n = 0; n < pk.members.size(); ++n) pk.to[n] = space.index_in_full(replacement(pk, pk.members[n]));
  } else {  // one scan of the listed space
    auto key_of = [&](const ProductTriangle& t) {  // a VT or TV triangle by its vertex and face
      return t.fb >= 0 ? int64_t(t.a[0]) * Y.num_faces() + t.fb : -1 - (int64_t(t.b[0]) * X.num_faces() + t.fa);
    };
    std::unordered_map<int64_t, std::pair<ProductTriangle, int64_t*>> wanted;
    for (auto& pk : pockets)
      for (size_t n = 0; n < pk.members.size(); ++n) {
        const ProductTriangle r = replacement(pk, pk.members[n]);
        wanted[key_of(r)] = {r, &pk.to[n]};
      }
    for (int64_t j = 0; j < space.size(); ++j) {
      const ProductTriangle t = space[j];
      const bool vt = t.fa < 0 && t.a[0] == t.a[1] && t.a[1] == t.a[2];
      const bool tv = t.fb < 0 && t.b[0] == t.b[1] && t.b[1] == t.b[2];
      if (!vt && !tv) continue;
      const auto it = wanted.find(key_of(t));
      if (it != wanted.end() && t == it->second.first) *it->second.second = j;
    }
  }
  // A pocket is replaced whole or not at all (a reduced space may lack part of its replacement);
  // two pockets never share a triangle (each face is covered once), but be sure.
  std::unordered_map<int64_t, int64_t> replace;  // old index -> new index
  for (const auto& pk : pockets) {
    bool ok = std::none_of(pk.to.begin(), pk.to.end(), [](int64_t i) { return i < 0; });
    for (int64_t j : pk.members) ok = ok && !replace.count(j);
    if (!ok) continue;
    for (size_t n = 0; n < pk.members.size(); ++n) replace[pk.members[n]] = pk.to[n];
    if (closed) ++*closed;
  }
  std::vector<int64_t> out;
  out.reserve(gamma.size());
  for (int64_t j : gamma) {
    const auto it = replace.find(j);
    out.push_back(it == replace.end() ? j : it->second);
  }
  std::sort(out.begin(), out.end());
  return out;
}

bool satisfies_exactly(const LpProblem& lp, const std::vector<int64_t>& gamma) {
  std::vector<int64_t> ax(lp.rows(), 0);
  for (int64_t j : gamma) {
    if (j < 0 || j >= lp.cols()) return false;
    for (uint32_t k = lp.at.row_ptr[j]; k < lp.at.row_ptr[j + 1]; ++k)
      ax[col_of(lp.at.entry[k])] += is_negative(lp.at.entry[k]) ? -1 : 1;
  }
  for (int64_t i = 0; i < lp.rows(); ++i)
    if (ax[i] != std::llround(lp.b[i]) || std::abs(lp.b[i] - std::round(lp.b[i])) > 0) return false;
  return true;
}

namespace {
// Round 1's optimum over the whole LP, for the alternative roundings to start from.
struct FirstOptimum {
  std::vector<double> x, y;
  double primal_weight = 0.0;
  double seconds = 0.0;
  int64_t iterations = 0;
  LpResult result;  // round 1's LP in the full LP's units, without x and y
};

// One rounding with options.threshold (round_to_graph_surface's alternatives aside); keeps round
// 1's optimum in `keep` where it is given and round 1 ended optimal.
RoundingResult round_once(const ProductSpace& space, const LpProblem& lp, const std::vector<double>& energy,
                          const RoundingOptions& options, const std::function<void(const RoundingRound&)>& progress,
                          FirstOptimum* keep) {
  auto solver = make_solver(options.solver);
  std::unique_ptr<LpSolver> exact_solver;  // for the small last rounds (exact_below)
  detail::ExactCache exact_cache;           // its results on the last round's parts
  detail::PretestCache pretest_cache;       // the zero-cost pre-test's verdicts on them
  RoundingResult result;
  Fixer fixer(lp);
  if (!fixer.propagate_all())
    throw InfeasibleError("rounding: the matching LP is infeasible (found before any fixing)", {fixer.failed_row()});

  // The next round's warm start over the whole LP: where round 1 goes on from carried fixings
  // with a given one (a run gone on from a rounding checkpoint: where its round 1 is undone, round
  // 2 starts there too), that one; then each round's iterate.
  const bool given_start = !options.start_ones.empty() && options.lp.initial_x.size() == size_t(lp.cols()) &&
                           options.lp.initial_y.size() == size_t(lp.rows());
  std::vector<double> x_full = given_start ? options.lp.initial_x : std::vector<double>(lp.cols(), 0.0);
  std::vector<double> y_full = given_start ? options.lp.initial_y : std::vector<double>(lp.rows(), 0.0);
  // Per column, the primal weight of the last first-order solve that had it (0: none yet), for
  // the next round's parts (carry_weights).
  std::vector<double> w_full(options.carry_weights ? lp.cols() : 0, 0.0);
  struct Step {
    size_t mark = 0;  // the fixer's mark before this fixing
    int64_t ones = 0, zeros = 0;
    std::vector<std::pair<int64_t, int>> batch;
    bool capped = false;  // fixed from an LP stopped at its iteration cap
  };
  std::vector<Step> history;  // the fixings so far, to undo when a later LP is infeasible
  std::unordered_set<int64_t> refuted;  // fixings to 1 an infeasibility proof blamed, not tried again
  detail::FailedFrom failed_from;        // and per state they were made from (remember_refuted)
  int backtracks = 0;
  // A partial Γ carried over (start_ones): fixings like any other, which backtracking may trim,
  // one per step of start_steps (or one in all).
  bool carried = false;
  const std::vector<int32_t>& steps = options.start_steps;
  if (!steps.empty() && (steps.size() != options.start_ones.size() ||
                         std::any_of(steps.begin(), steps.end(), [](int32_t k) { return k < 0; })))
    throw InvalidInputError("rounding: the start fixings' steps do not fit them");
  if (!options.start_ones.empty()) {
    for (int64_t j : options.start_ones)
      if (j < 0 || j >= lp.cols()) throw InvalidInputError("rounding: a start fixing names no variable");
    std::map<int32_t, std::vector<std::pair<int64_t, int>>> batches;  // by step, in order
    for (size_t k = 0; k < options.start_ones.size(); ++k)
      batches[steps.empty() ? 0 : steps[k]].push_back({options.start_ones[k], 1});
    size_t kept = 0;
    for (auto& [index, batch] : batches) {
      Step step{fixer.mark(), fixer.state().ones, fixer.state().zeros, {}, false};
      step.batch = shrink_and_fix(fixer, std::move(batch), step.mark, true);
      kept += step.batch.size();
      if (!step.batch.empty()) history.push_back(std::move(step));
    }
    spdlog::debug("rounding: starts from {} of {} carried fixings to 1 in {} steps", kept, options.start_ones.size(),
                  history.size());
    carried = !history.empty();
  }
  // Rounds in a row whose LP failed, and their seconds (stuck_after).
  int failing_rounds = 0;
  double failing_seconds = 0.0;
  // Round 1's LP (or the reference given for a carried start): the scale of stuck_after and of
  // the later rounds' iteration cap.
  double first_seconds = 0.0;
  int64_t first_iterations = 0;
  // Multiplies the later rounds' iteration cap: doubled each time a fixing from a capped LP is
  // undone whole (below), up to kMaxCapScale; a rounding gone on from a checkpoint starts where
  // the saved one had got (RoundingOptions::start_cap_scale).
  constexpr double kMaxCapScale = 16.0;
  if (!(options.start_cap_scale >= 1.0) || !std::isfinite(options.start_cap_scale))
    throw InvalidInputError("rounding: the start cap scale must be a finite number of at least 1");
  double cap_scale = std::min(options.start_cap_scale, kMaxCapScale);
  // Undoes the last fixing and applies less of it; where nothing of it can go (a single variable
  // that can be neither 1 nor 0), undoes the fixing before it as well, and so on back. Measured:
  // FAUST 020-024 at 4000 faces got stuck this way in round 15 and lost its whole level. Gives up
  // with the rows still open (so coarse to fine can widen there) when nothing is left to undo or
  // after max_backtracks.
  // With `away_from_proof` (the last fixing's assignments an infeasibility proof of the LP after
  // it does not blame: fixings_away_from), the last fixing first loses only those it blames: an
  // infeasible LP costs a full solve, and halving needs about log2(batch) of them where the fault
  // is local. Returns true where the last fixing was undone whole (one from a capped LP; see there).
  auto backtrack = [&](std::vector<std::pair<int64_t, int>> away_from_proof) {
    std::vector<int64_t> open = fixer.unsatisfied_rows();  // where it got stuck
    const int64_t ones_before = fixer.state().ones, zeros_before = fixer.state().zeros;
    for (bool first = true;; first = false) {
      if (history.empty() || ++backtracks > options.max_backtracks)
        throw InfeasibleError(history.empty() ? "rounding: no consistent fixing exists (no binary solution)"
                                              : "rounding: no binary solution found within " +
                                                    std::to_string(options.max_backtracks) +
                                                    " undone fixings since the last low of free variables",
                              std::move(open));
      Step& step = history.back();
      fixer.undo_to(step.mark);
      // A batch fixed from an iterate at its cap is undone whole, and the LP before it solved
      // again with a larger cap: such an iterate is far from the LP's optimum, and trimming its
      // batch by what each proof blames costs a solve per few fixings (measured, TOSCA_r horse0-5
      // at full resolution: 3 858 fixings from a capped round, then 9 infeasible rounds blaming
      // 5-46 each, the last ones identical).
      // Where the proof (for such a batch: every row of the infeasible parts) blames at most a
      // quarter of it, only those go (measured, FAUST_r 020-024 at full resolution with
      // --widen-around 3: certificates blamed 8 of 3 192 and then 3 of 3 184 fixings, and
      // undoing whole batches unwound three capped rounds, each LP then longer).
      const size_t blamed = step.batch.size() - away_from_proof.size();
      const bool few_blamed = !away_from_proof.empty() && 4 * blamed <= step.batch.size();
      if (first && step.capped && cap_scale < kMaxCapScale && !few_blamed) {
        cap_scale = std::min(2.0 * cap_scale, kMaxCapScale);
        spdlog::debug("rounding: undoing the {} fixings from a capped LP; the cap grows {}x", step.batch.size(),
                      cap_scale);
        history.pop_back();
        refuted.clear();
        return true;
      }
      auto smaller = step.batch;
      bool shrinkable = true;
      const bool by_proof = first && !away_from_proof.empty();
      if (by_proof) {
        // The blamed fixings are not tried again from this state: the next LP is the one before
        // them, which would put them first again (full resolution: the same two rounds, fix and
        // undo, for 100 rounds).
        std::unordered_set<int64_t> kept;
        for (const auto& k : away_from_proof) kept.insert(k.first);
        std::vector<int64_t> blamed_ones;
        for (const auto& a : step.batch)
          if (a.second == 1 && !kept.count(a.first)) blamed_ones.push_back(a.first);
        refuted.insert(blamed_ones.begin(), blamed_ones.end());
        // (the fixer is back at the state the step was made from)
        if (options.remember_refuted && !blamed_ones.empty())
          failed_from.blamed(detail::state_hash(fixer.state().value), blamed_ones);
        smaller = std::move(away_from_proof);
      }
      else shrinkable = shrink_once(smaller);  // (a single variable that cannot be 1 must be 0)
      if (shrinkable) {
        try {
          auto kept = shrink_and_fix(fixer, smaller, step.mark, false);  // if still infeasible, shrink further
          // The failed state again: fixings of this step as it was applied there (a subset of
          // that state) that propagate to as many assignments; its LP is the one just proved
          // infeasible.
          const std::set<std::pair<int64_t, int>> applied(step.batch.begin(), step.batch.end());
          const auto as_failed = [&] {
            if (fixer.state().ones != ones_before || fixer.state().zeros != zeros_before) return false;
            for (const auto& a : kept)
              if (!applied.count(a)) return false;
            return true;
          };
          // The fixings the proof left propagate to those it blamed: halve the whole batch
          // instead (measured, FAUST_r 021-029 at full resolution: the same round, 1 208 fixings
          // to 1 and an infeasible LP, five times in a row at 75 s each).
          if (by_proof && as_failed()) {
            fixer.undo_to(step.mark);
            smaller = step.batch;
            smaller.resize(std::max<size_t>(1, smaller.size() / 2));
            kept = shrink_and_fix(fixer, smaller, step.mark, false);
          }
          // Halves can bring it back too: trim on until the state differs (measured,
          // deformation-transfer gallop 0001-0017 without WKS at full resolution: after a trim
          // to 6 fixings the next LP had the failed one's 3 270 575 variables and iterations,
          // and took another 257 s to be proved infeasible again). A single fixing to 1 that
          // brings it back cannot be 1; one to 0 means an earlier step must go (the catch below).
          while (as_failed()) {
            fixer.undo_to(step.mark);
            if (!shrink_once(kept)) throw InfeasibleError("rounding: the step brings back the failed state whole");
            kept = shrink_and_fix(fixer, kept, step.mark, false);
          }
          step.batch = std::move(kept);
          return false;
        } catch (const InfeasibleError&) {
          fixer.undo_to(step.mark);
        }
      }
      history.pop_back();
      refuted.clear();  // an earlier state: what was refuted after it may hold again
      spdlog::debug("rounding: backtracking over an earlier fixing ({} left)", history.size());
    }
  };
  // Every solve's parameters without the warm start (copied per round: the whole LP's is
  // millions of values at full resolution).
  SolverParams base_params = options.lp;
  base_params.initial_x.clear();
  base_params.initial_y.clear();
  // (Round 1's resumed solve only, below: they belong to the LP under way that was saved.)
  base_params.initial_watch = {};
  base_params.iterations_before = 0;
  base_params.resume_state = nullptr;  // (RoundingOptions::resumed_state)
  base_params.exact_state = false;
  // Releases every fixing within reach of `rows` (columns_near, 2 steps, 4, 8 … where the same
  // part fails again (ReleaseReach), further until one is in reach) and propagates the rest again
  // from the state before the first round: where a part has no binary solution, the fault lies in
  // the fixings around it, not in the last ones made (parts are independent; the last fixing is
  // as likely in another). Returns how many went.
  std::unique_ptr<LpSolver> search_solver;
  int releases = 0;
  detail::ReleaseReach reach;
  detail::FailingAgain failing_again;  // release_after_trims
  // With `refute`, the released fixings to 1 join those not tried again while anything else
  // remains (the LP after the release would often pick them again: they came from its optimum;
  // and where two alternatives each fail, refuting only the last released swaps them forever).
  // Where the same part fails again and the next release would reach beyond release_reach_cap
  // steps: its rows, and no release (the rounding loop then calls itself stuck).
  std::vector<int64_t> reach_capped;
  const auto columns_of = [&](const std::vector<int64_t>& rows) {  // (a part's: does it fail again?)
    std::vector<int64_t> cols;
    for (int64_t i : rows)
      for (uint32_t k = lp.a.row_ptr[i]; k < lp.a.row_ptr[i + 1]; ++k) cols.push_back(col_of(lp.a.entry[k]));
    return cols;
  };
  auto release_around = [&](const std::vector<int64_t>& rows, bool refute, RoundingRound& info) -> int64_t {
    std::vector<int64_t> cols = columns_of(rows);
    const bool again = reach.same_part(cols);
    // (Before the count: a capped part uses up no release.)
    if (again && options.release_reach_cap > 0 && !history.empty() &&
        reach.first_depth(cols) > options.release_reach_cap) {
      reach_capped = rows;
      return 0;
    }
    if (++releases > options.max_releases || history.empty())
      throw InfeasibleError("rounding: no binary solution around a part after " + std::to_string(releases - 1) +
                                " releases of the fixings near it",
                            fixer.unsatisfied_rows());
    constexpr int kMaxDepth = 1 << 12;
    int64_t all = 0;  // fixings made so far
    for (const Step& st : history) all += static_cast<int64_t>(st.batch.size());
    for (int depth = reach.first_depth(cols); depth <= kMaxDepth; depth *= 2) {
      if (again && options.release_reach_cap > 0 && depth > options.release_reach_cap) {  // (nothing nearer)
        reach_capped = rows;
        return 0;
      }
      const std::vector<char> near = columns_near(lp, rows, depth);
      std::vector<std::pair<int64_t, int>> kept;
      for (const Step& st : history)
        for (const auto& a : st.batch)
          if (!near[a.first]) kept.push_back(a);
      if (static_cast<int64_t>(kept.size()) == all) continue;  // nothing within reach yet
      fixer.undo_to(history.front().mark);
      if (!refute) refuted.clear();  // (with it, what earlier releases refuted stays refuted)
      else
        for (const Step& st : history)
          for (const auto& a : st.batch)
            if (near[a.first] && a.second == 1) refuted.insert(a.first);
      history.clear();
      if (!kept.empty()) {  // (a step with an empty batch would have nothing to halve)
        Step rest{fixer.mark(), fixer.state().ones, fixer.state().zeros, {}, false};
        // Fewer fixings propagate to a subset of a consistent state, so this goes through whole.
        rest.batch = shrink_and_fix(fixer, kept, rest.mark, true);
        history.push_back(std::move(rest));
      }
      spdlog::debug("rounding: released {} of {} fixings within {} steps of the part",
                    all - static_cast<int64_t>(kept.size()), all, depth);
      reach.released(std::move(cols), depth);
      info.release_depth = depth;
      info.release_pool = all;
      return all - static_cast<int64_t>(kept.size());
    }
    throw InfeasibleError("rounding: no binary solution around a part, and no fixing near it",
                          fixer.unsatisfied_rows());
  };
  // The steps `before` (history as it was; `step_of`: each decision's step there) again without
  // the decisions `out`, from the first step that holds one (fewer fixings propagate to a subset
  // of a consistent state, so each goes through whole).
  // (`from`: the decisions whose first step to start at, where not `out`'s: putting back what
  // a release took out starts where it did.)
  const auto rebuild = [&](const std::vector<Step>& before, const std::unordered_map<int64_t, size_t>& step_of,
                           const std::unordered_set<int64_t>& out, const std::unordered_set<int64_t>* from = nullptr) {
    if (out.empty() && from && from->empty()) return;  // nothing was taken out: the steps are `before`
    size_t first = before.size();
    for (int64_t j : from ? *from : out)
      if (const auto it = step_of.find(j); it != step_of.end()) first = std::min(first, it->second);
    if (first == before.size()) first = 0;
    fixer.undo_to(before[first].mark);
    history.assign(before.begin(), before.begin() + static_cast<std::ptrdiff_t>(first));
    for (size_t k = first; k < before.size(); ++k) {
      Step again{fixer.mark(), fixer.state().ones, fixer.state().zeros, {}, before[k].capped};
      std::vector<std::pair<int64_t, int>> batch;
      for (const auto& a : before[k].batch)
        if (!out.count(a.first)) batch.push_back(a);
      if (batch.empty()) continue;
      again.batch = shrink_and_fix(fixer, std::move(batch), again.mark, true);
      history.push_back(std::move(again));
    }
  };
  // Where an infeasibility proof's margin outweighs all that undoing the last fixing could take
  // off it (certificate_blame.hpp), trimming or undoing that fixing only costs another solve of an
  // LP the same proof still refutes: release instead the fixings, of whatever step, that carry
  // the margin, heaviest first, until the proof no longer holds (checked on the state after them;
  // where it still does, the fixings weighed again there, up to 8 passes), keeping every other
  // fixing in its step. The released fixings to 1 are not made again from the state after the
  // release (remember_refuted), nor, while anything else remains, until a backtrack. Measured, TOSCA_r horse0-horse5 at full
  // resolution (seventy-ninth session's log, without it): proofs blamed 18 of 75, 3 of 57 and 1 of
  // 54 of the last fixings in turn, 5-15 minutes of zero-cost solving each, and the LP stayed
  // infeasible. False, with the fixings as they were, where no part's proof is a Farkas certificate
  // (a costed first-order proof, a part with no ray), the last fixing may carry its margin, or
  // nothing releasable does. `joined`: the round's solve (its certificate, over red's rows).
  auto release_by_certificate = [&](const Reduced& red, const JoinedSolve& joined, RoundingRound& info) {
    const std::vector<double>& certificate = joined.certificate;
    if (!options.certificate_release || history.empty() || certificate.empty() ||
        joined.certificate_part.size() != certificate.size() || backtracks >= options.max_backtracks)
      return false;
    std::vector<double> d(lp.rows(), 0.0);
    std::vector<int32_t> part(lp.rows(), -1);
    int32_t parts = 0;
    for (size_t i = 0; i < red.rows.size() && i < certificate.size(); ++i) {
      d[red.rows[i]] = certificate[i];
      part[red.rows[i]] = joined.certificate_part[i];
      parts = std::max(parts, joined.certificate_part[i] + 1);
    }
    if (parts == 0) return false;
    const detail::CertificateBlame blame(lp, d);
    // Each part's certificate scaled to margin 1 here (the solvers' scales are their own), so that
    // weights compare across parts; a part's that proves nothing on this state is dropped.
    {
      const std::vector<double> m = blame.margins(fixer.state().value, fixer.state().rhs, part, parts);
      for (int64_t i = 0; i < lp.rows(); ++i)
        if (part[i] >= 0) d[i] = m[part[i]] > 0.0 ? d[i] / m[part[i]] : 0.0;
    }
    double largest = 0.0;
    for (double v : d) largest = std::max(largest, std::abs(v));
    const double noise = 1e-9 * largest;
    // Proved infeasible while any part's margin is above the noise; their sum steers the release.
    const auto standing = [&](double* sum) {
      const std::vector<double> m = blame.margins(fixer.state().value, fixer.state().rhs, part, parts);
      bool any = false;
      *sum = 0.0;
      for (double v : m)
        if (v > noise) {
          any = true;
          *sum += v;
        }
      return any;
    };
    double margin = 0.0;
    if (!standing(&margin)) return false;
    const size_t base = history.front().mark;
    std::vector<size_t> starts;
    for (const Step& st : history) starts.push_back(st.mark - base);
    const detail::TrailWeights w = detail::trail_weights(
        blame, [&](auto&& visit) { fixer.visit_since(base, visit); }, fixer.state().value, starts);
    // Undoing steps from the last back changes the margin by exactly their weights: the LP before
    // the last step is infeasible too where margin − its weight stays positive, and no release at
    // all breaks the proof where margin − all of them does (propagation before the first step).
    double all = 0.0;
    for (double ws : w.step) all += ws;
    if (!(margin - w.step.back() > noise) || margin - all > noise) return false;
    const int64_t ones_before = fixer.state().ones, zeros_before = fixer.state().zeros;
    std::unordered_map<int64_t, size_t> step_of;  // decision -> its step
    for (size_t k = 0; k < history.size(); ++k)
      for (const auto& a : history[k].batch) step_of.emplace(a.first, k);
    const std::vector<Step> before = history;
    const auto rebuild_without = [&](const std::unordered_set<int64_t>& out) { rebuild(before, step_of, out); };
    // Released fixings' variables can be set again by the propagation of others (which carried
    // nothing while they came first): then the margin stands, and the next pass weighs the
    // fixings as they are now.
    constexpr int kPasses = 8;
    std::unordered_set<int64_t> out;
    double now = margin;
    detail::TrailWeights weights = w;
    for (int pass = 0; pass < kPasses; ++pass) {
      const std::vector<int64_t> chosen = detail::heaviest_decisions(weights.decision, now);
      if (chosen.empty()) break;
      out.insert(chosen.begin(), chosen.end());
      rebuild_without(out);
      if (!standing(&now)) {
        ++backtracks;
        std::vector<int64_t> ones;  // (a released fixing to 0 says nothing against a 1 there)
        for (const Step& st : before)
          for (const auto& a : st.batch)
            if (a.second == 1 && out.count(a.first)) ones.push_back(a.first);
        refuted.insert(ones.begin(), ones.end());
        if (options.remember_refuted) failed_from.blamed(detail::state_hash(fixer.state().value), ones);
        spdlog::debug("rounding: the proof's margin ({} part(s), each scaled to 1) outweighs what undoing the last "
                      "fixing frees ({:.4g}): released {} fixings that carry it in {} pass(es)",
                      parts, w.step.back(), out.size(), pass + 1);
        info.certificate_released = static_cast<int64_t>(out.size());
        info.fixed_to_one = fixer.state().ones - ones_before;
        info.fixed_to_zero = fixer.state().zeros - zeros_before;
        return true;
      }
      if (history.empty()) break;
      std::vector<size_t> at;
      for (const Step& st : history) at.push_back(st.mark - base);
      weights = detail::trail_weights(
          blame, [&](auto&& visit) { fixer.visit_since(base, visit); }, fixer.state().value, at);
    }
    rebuild(before, step_of, {}, &out);  // the same steps again
    if (fixer.state().ones != ones_before || fixer.state().zeros != zeros_before)
      throw SolverError("rounding: the fixings made again after a release attempt differ (a bug)");
    spdlog::debug("rounding: no release of up to {} fixings that carry the proof's margin {:.4g} breaks it", out.size(),
                  margin);
    return false;
  };
  // Where a search proved a part without a binary solution (every failure's Farkas vector, with
  // the decisions it needs: `proofs`, in the full LP's rows and columns), releases the fixings
  // outside the part that those proofs rest on: for each, the heaviest of the decisions made so
  // far (each charged with its propagation along the trail, certificate_blame.hpp), until they
  // outweigh its margin on the state with its decisions. A proof whose margin no release outside
  // the part could break says nothing about where to release. The released fixings to 1 are
  // refuted, as after a certificate release. Returns how many went (0: none, nothing changed).
  // A release within 2, 4, 8 … LP steps instead frees everything near the part (measured, TOSCA_r
  // horse0-horse5 at full resolution: the same part proved without a binary solution in 4 to 6
  // nodes three times, and the releases freed 286, 3 104 and 9 588 of about 11 000 fixings, the
  // last an 8.2 M-variable LP).
  auto release_by_search_proofs = [&](const std::vector<detail::SearchProof>& proofs, int* used) -> int64_t {
    *used = 0;
    if (!options.search_proof_release || history.empty() || proofs.empty()) return 0;
    std::vector<double> d(lp.rows(), 0.0);
    const detail::CertificateBlame blame(lp, d);
    std::vector<int32_t> owner;           // per column: the decision it came from (an index), −1: none
    std::vector<int64_t> decision_cols;  // those decisions' columns
    // The columns assigned before `mark` that the assignment of column j after it (by the
    // propagation of `decided`) rests on: the earlier assignments of a row that forced it, and
    // theirs in turn, back to before `mark` (at most a few thousand visited).
    const auto explain = [&](int64_t j, const std::unordered_map<int64_t, int64_t>& at,
                             const std::unordered_set<int64_t>& decided, std::vector<int64_t>& outside) {
      const FixState& st = fixer.state();
      const auto position = [&](int64_t k) -> int64_t {  // −1: before mark; max: free
        if (st.value[k] < 0) return std::numeric_limits<int64_t>::max();
        const auto it = at.find(k);
        return it == at.end() ? -1 : it->second;
      };
      std::vector<int64_t> queue{j};
      std::unordered_set<int64_t> seen{j};
      while (!queue.empty() && seen.size() < 4096) {
        const int64_t k = queue.back();
        queue.pop_back();
        if (decided.count(k)) continue;
        const int64_t pk = position(k);
        for (uint32_t q = lp.at.row_ptr[k]; q < lp.at.row_ptr[k + 1]; ++q) {
          const int64_t i = col_of(lp.at.entry[q]);
          int64_t r = std::llround(lp.b[i]), pos = 0, neg = 0;
          for (uint32_t e = lp.a.row_ptr[i]; e < lp.a.row_ptr[i + 1]; ++e) {
            const int64_t c = col_of(lp.a.entry[e]);
            if (c == k || position(c) > pk) ++(is_negative(lp.a.entry[e]) ? neg : pos);
            else if (st.value[c] == 1) r -= is_negative(lp.a.entry[e]) ? -1 : 1;
          }
          if (r != pos && r != -neg) continue;  // (as Fixer::propagate decides)
          const bool plus_is_one = r == pos && !(r == -neg && pos == 0);
          if (((is_negative(lp.at.entry[q]) != plus_is_one) ? 1 : 0) != st.value[k]) continue;
          for (uint32_t e = lp.a.row_ptr[i]; e < lp.a.row_ptr[i + 1]; ++e) {
            const int64_t c = col_of(lp.a.entry[e]);
            const int64_t pc = position(c);
            if (c == k || pc >= pk) continue;
            if (pc < 0) outside.push_back(c);
            else if (seen.insert(c).second) queue.push_back(c);
          }
          break;  // one reason is enough
        }
      }
    };
    // The decisions to release, on the fixings as they stand, for the proofs that still hold
    // (`standing`) and can be broken from outside (`breakable`). A fixed column of a proof's row
    // weighs on the decision it came from; one that the proof's own decisions propagated, on each
    // decision behind the assignments its propagation rested on.
    const auto weigh = [&](int* standing, int* breakable) {
      *standing = *breakable = 0;
      owner.assign(lp.cols(), -1);
      decision_cols.clear();
      fixer.visit_since(history.front().mark, [&](int64_t j, bool fixed) {
        if (fixed) decision_cols.push_back(j);
        if (!decision_cols.empty()) owner[j] = static_cast<int32_t>(decision_cols.size() - 1);
      });
      std::vector<int64_t> chosen;
      for (const auto& proof : proofs) {
        std::vector<int64_t> rows;
        double largest = 0.0;
        for (const auto& [i, v] : proof.d) {
          d[i] = v;
          rows.push_back(i);
          largest = std::max(largest, std::abs(v));
        }
        // (Where propagation fails on the way, its partial state is the one the proof refutes.)
        const size_t mark = fixer.mark();
        for (const auto& a : proof.decisions)
          if (!fixer.fix({a})) break;
        const double margin = blame.margin_over(rows, fixer.state().value, fixer.state().rhs);
        std::unordered_map<int64_t, double> weight;  // per decision outside the part (its column)
        double total = 0.0;
        if (margin > 1e-9 * largest) {
          std::unordered_map<int64_t, int64_t> at;  // the assignments since mark: their order
          fixer.visit_since(mark, [&](int64_t j, bool) { at.emplace(j, static_cast<int64_t>(at.size())); });
          std::unordered_set<int64_t> decided;
          for (const auto& a : proof.decisions) decided.insert(a.first);
          std::unordered_set<int64_t> seen;
          for (int64_t i : rows)
            for (uint32_t k = lp.a.row_ptr[i]; k < lp.a.row_ptr[i + 1]; ++k) {
              const int64_t j = col_of(lp.a.entry[k]);
              if (fixer.state().value[j] < 0 || !seen.insert(j).second) continue;
              const double w = blame.weight(j, fixer.state().value[j]);
              if (!(w > 0.0)) continue;
              std::vector<int64_t> outside;
              if (!at.count(j)) outside.push_back(j);
              else explain(j, at, decided, outside);
              std::unordered_set<int64_t> behind;
              for (int64_t c : outside)
                if (owner[c] >= 0) behind.insert(decision_cols[owner[c]]);
              for (int64_t o : behind) weight[o] += w;
              if (!behind.empty()) total += w;
            }
        }
        fixer.undo_to(mark);
        for (int64_t i : rows) d[i] = 0.0;
        if (!(margin > 1e-9 * largest)) continue;
        ++*standing;
        if (total < margin) continue;
        ++*breakable;
        std::vector<std::pair<int64_t, double>> heavy(weight.begin(), weight.end());
        std::sort(heavy.begin(), heavy.end());  // (ties in weight: by column, whatever the map's order)
        for (const int64_t j : detail::heaviest_decisions(std::move(heavy), margin)) chosen.push_back(j);
      }
      return chosen;
    };
    std::unordered_map<int64_t, size_t> step_of;
    for (size_t k = 0; k < history.size(); ++k)
      for (const auto& a : history[k].batch) step_of.emplace(a.first, k);
    const std::vector<Step> before = history;
    const int64_t ones_before = fixer.state().ones, zeros_before = fixer.state().zeros;
    // A released fixing's variable can be set again by the propagation of others (which carried
    // nothing while it came first): the proofs are weighed again on the state after each release,
    // up to 8 passes (measured, horse0-horse5 at full resolution: 2 fixings released, both set
    // again, the same search and release every 4 rounds).
    std::unordered_set<int64_t> out;
    int standing = 0, breakable = 0;
    for (int pass = 0; pass < 8 && !history.empty(); ++pass) {
      const std::vector<int64_t> chosen = weigh(&standing, &breakable);
      if (pass == 0) *used = breakable;
      const size_t had = out.size();
      out.insert(chosen.begin(), chosen.end());
      if (out.size() == had) break;
      rebuild(before, step_of, out);
    }
    if (out.empty()) return 0;
    if (fixer.state().ones == ones_before && fixer.state().zeros == zeros_before) {
      rebuild(before, step_of, {}, &out);  // nothing changed: the same steps again, and the other release
      if (fixer.state().ones != ones_before || fixer.state().zeros != zeros_before)
        throw SolverError("rounding: the fixings made again after a release attempt differ (a bug)");
      return 0;
    }
    if (++releases > options.max_releases)
      throw InfeasibleError("rounding: no binary solution around a part after " + std::to_string(releases - 1) +
                                " releases of the fixings near it",
                            fixer.unsatisfied_rows());
    std::vector<int64_t> ones;
    for (const Step& st : before)
      for (const auto& a : st.batch)
        if (a.second == 1 && out.count(a.first)) ones.push_back(a.first);
    refuted.clear();
    refuted.insert(ones.begin(), ones.end());
    if (options.remember_refuted) failed_from.blamed(detail::state_hash(fixer.state().value), ones);
    spdlog::debug("rounding: {} of the search's {} proofs rest on fixings outside their parts; {} still stand after "
                  "releasing {}",
                  *used, proofs.size(), standing, out.size());
    return static_cast<int64_t>(out.size());
  };
  // Finishes every part of `red` by search; parts without a binary solution release the fixings
  // around them. Fills the round's counts. False, with nothing fixed or released, where a part's
  // LP has no solution at all: that is an LP round's question, whose proof trims the last fixing
  // (a release frees the fixings of whole regions: measured, FAUST_r 043-063's level 6 at full
  // resolution, a search right after a fixing found a 16 321-variable part's root LP infeasible
  // and released 634 fixings, 825 k variables, where trimming the last fixing was due).
  auto search_round = [&](const Reduced& red, RoundingRound& info) {
    if (!search_solver) search_solver = make_solver("clp-dual");
    std::vector<Part> parts = split_into_parts(red.lp);
    const bool whole = parts.empty();
    if (whole) parts.push_back(whole_part(red.lp));
    std::vector<std::pair<int64_t, int>> found;
    std::vector<int64_t> stuck;
    std::vector<detail::SearchProof> stuck_proofs;
    bool all_proved = true;  // every part left without a solution was proved so
    int64_t nodes = 0;
    // Every part's root first (one node each), so that no search is spent on a round that goes
    // to the LP; a part whose root is integral is finished there.
    std::vector<SearchEnd> root(parts.size());
    std::vector<std::optional<LpResult>> root_lp(parts.size());  // each solved once
    std::vector<std::vector<int8_t>> value(parts.size());
    detail::SearchStats stats;
    std::vector<std::vector<detail::SearchProof>> proofs(parts.size());
    for (size_t k = 0; k < parts.size(); ++k) {
      const LpProblem& plp = whole ? red.lp : parts[k].lp;
      int64_t one = 0;
      root[k] = search_part(plp, *search_solver, base_params, 1, value[k], one, &root_lp[k], options.search_backjump,
                            &stats, &proofs[k]);
      nodes += one;
      if (root[k] == SearchEnd::infeasible) {
        spdlog::debug("rounding: a part of {} variables has no LP solution at its search's root: solved as a round "
                      "instead",
                      plp.cols());
        return false;
      }
    }
    for (size_t k = 0; k < parts.size(); ++k) {
      const Part& part = parts[k];
      const LpProblem& plp = whole ? red.lp : part.lp;
      SearchEnd end = root[k];
      if (end == SearchEnd::node_limit)
        end = search_part(plp, *search_solver, base_params, options.search_nodes, value[k], nodes, &root_lp[k],
                          options.search_backjump, &stats, &proofs[k]);
      if (end == SearchEnd::found) {
        ++info.searched_parts;
        for (size_t j = 0; j < part.cols.size(); ++j) found.push_back({red.cols[part.cols[j]], value[k][j]});
      } else {
        for (int64_t i : part.rows) stuck.push_back(red.rows[i]);
        // Its proofs in the full LP's numbering, where the search proved it has no binary solution.
        if (end != SearchEnd::none || proofs[k].empty()) all_proved = false;
        for (detail::SearchProof& proof : proofs[k]) {
          for (auto& [i, v] : proof.d) i = red.rows[part.rows[i]];
          for (auto& [j, v] : proof.decisions) j = red.cols[part.cols[j]];
          stuck_proofs.push_back(std::move(proof));
        }
      }
    }
    info.parts = static_cast<int64_t>(parts.size());
    info.iterations = nodes;
    const int64_t ones = fixer.state().ones, zeros = fixer.state().zeros;
    if (!found.empty()) {
      Step step{fixer.mark(), ones, zeros, {}, false};
      // Each part's solution satisfies its rows exactly, and parts share none.
      if (!fixer.fix(found)) throw SolverError("rounding: a searched part's solution does not fit (a bug)");
      step.batch = std::move(found);
      history.push_back(std::move(step));
    }
    if (!stuck.empty()) {
      info.undone = true;
      int used = 0;
      // First where a part fails (a release by proofs is cheap and local); where the same part
      // fails again, the releases within 2, 4, 8 … steps follow as before (measured, horse0-horse5
      // at full resolution: released by proofs each time, the same part failed again 4-9 rounds
      // later, five times, 8-16 fixings each, until max_releases widened the level).
      std::vector<int64_t> cols = columns_of(stuck);
      if (all_proved && !reach.same_part(cols)) info.released = release_by_search_proofs(stuck_proofs, &used);
      if (info.released > 0) {
        reach.released(std::move(cols), 1);
        info.search_proof_released = info.released;
        spdlog::debug("rounding: released {} fixings that {} of the search's {} proofs rest on", info.released, used,
                      stuck_proofs.size());
      } else {
        info.released = release_around(stuck, false, info);
      }
    }
    info.fixed_to_one = fixer.state().ones - ones;
    info.fixed_to_zero = fixer.state().zeros - zeros;
    double cost = 0.0;
    for (int64_t j = 0; j < lp.cols(); ++j)
      if (fixer.state().value[j] == 1) cost += lp.c[j];
    info.objective = lp.objective_scale * cost;
    spdlog::debug("rounding: searched {} parts in {} nodes, {} finished; {} failed nodes, {} proved by fewer than all "
                  "decisions above, {} jumps over {} levels",
                  parts.size(), nodes, info.searched_parts, stats.failures, stats.short_nogoods, stats.jumps,
                  stats.levels_skipped);
    return true;
  };
  int64_t fewest_free = std::numeric_limits<int64_t>::max();
  int stalled = 0;
  Stopwatch since_low;  // since fewest_free was set
  bool waited = false;  // the last round fixed nothing: only capped parts were left
  // Work (iterations times free variables, which unlike seconds is the same on every run) of
  // round 1 and of the rounds after it (give_up_after).
  double first_work = 0.0, later_work = 0.0;
  // The fixings to 1 made so far, sorted. Only the decisions: what propagation forced to 1 in
  // this space need not follow in a wider one, and follows from them in this one.
  // `steps` gets the step of each (parallel; a column in two steps, were there one, in its first).
  const auto decisions = [&](std::vector<int32_t>& steps) {
    std::vector<std::pair<int64_t, int32_t>> made;
    for (size_t k = 0; k < history.size(); ++k)
      for (const auto& a : history[k].batch)
        if (a.second == 1 && fixer.state().value[a.first] == 1) made.push_back({a.first, static_cast<int32_t>(k)});
    std::sort(made.begin(), made.end());
    made.erase(std::unique(made.begin(), made.end(), [](const auto& a, const auto& b) { return a.first == b.first; }),
               made.end());
    std::vector<int64_t> ones;
    ones.reserve(made.size());
    steps.clear();
    for (const auto& [j, k] : made) {
      ones.push_back(j);
      steps.push_back(k);
    }
    return ones;
  };
  const auto record = [&](RoundingRound& info, const Stopwatch& clock) {
    info.seconds = clock.seconds() - info.feasibility_seconds;
    info.cap_scale = cap_scale;
    if (info.round > 1) later_work += double(info.iterations) * double(info.variables);
    result.rounds.push_back(info);
    if (progress) progress(info);
    if (options.decided) {
      std::vector<int32_t> steps;
      const std::vector<int64_t> ones = decisions(steps);
      options.decided(info, ones, steps, result.first_lp.lower_bound, x_full, y_full);
    }
  };
  // Giving up where the caller can widen (stuck_after): the fixings to 1 so far and the iterate go with it.
  const auto stuck = [&](const std::string& what, std::vector<int64_t> rows) {
    std::vector<int32_t> steps;
    std::vector<int64_t> ones = decisions(steps);
    return StuckError(what, std::move(rows), std::move(ones), x_full, y_full, std::move(steps));
  };
  // A part that failed again where the release would reach beyond release_reach_cap: stuck there.
  const auto throw_if_reach_capped = [&] {
    if (reach_capped.empty()) return;
    const std::string what = "rounding: the same part failed again after releases reaching " +
                             std::to_string(options.release_reach_cap) + " steps around it (--release-reach-cap)";
    if (options.stuck_after > 0.0) throw stuck(what, std::move(reach_capped));
    throw InfeasibleError(what, std::move(reach_capped));
  };
  // The round's iterate over the whole LP, the next round's warm start.
  const auto keep_iterate = [&](const Reduced& red, const JoinedSolve& joined) {
    const LpResult& r = joined.r;
    for (size_t j = 0; j < red.cols.size(); ++j) x_full[red.cols[j]] = r.x[j];
    for (size_t i = 0; i < red.rows.size(); ++i) y_full[red.rows[i]] = i < r.y.size() ? r.y[i] : 0.0;
    if (w_full.empty()) return;
    if (joined.weight.size() == red.cols.size()) {
      for (size_t j = 0; j < red.cols.size(); ++j)
        if (joined.weight[j] > 0.0) w_full[red.cols[j]] = joined.weight[j];
    } else if (std::isfinite(r.primal_weight) && r.primal_weight > 0.0) {  // round 1: one solve
      for (int64_t j : red.cols) w_full[j] = r.primal_weight;
    }
  };
  // Rounds that went forward (fixed, searched or waited) and those after which the free variables
  // stood at a new low: max_rounds counts the first without the second (RoundingOptions::max_rounds).
  for (int round = 1, forward = 0, lows = 0; fixer.state().unsatisfied > 0; ++round) {
    Stopwatch clock;
    Reduced red = reduce(lp, fixer.state());  // (round 1's costs are set aside for its pre-test)
    const bool new_low = red.lp.cols() < fewest_free;
    // (Not the round after a release, whose "low" is only the reset: releases are bounded apart.)
    if (new_low && round > 1 && fewest_free != std::numeric_limits<int64_t>::max()) ++lows;
    // Out of rounds: no binary solution found in this space. An InfeasibleError with the open
    // rows lets coarse to fine widen there rather than give up the whole run.
    const bool idle_out = forward - lows >= options.max_rounds;
    if (idle_out || (options.max_total_rounds > 0 && forward >= options.max_total_rounds)) {
      const std::string what =
          idle_out ? "rounding did not reach a binary solution: " + std::to_string(options.max_rounds) +
                         " of its rounds brought no new low of free variables (raise --max-rounds or lower "
                         "--threshold)"
                   : "rounding did not reach a binary solution in " + std::to_string(options.max_total_rounds) +
                         " rounds";
      if (options.stuck_after > 0.0) throw stuck(what, fixer.unsatisfied_rows());
      throw InfeasibleError(what, fixer.unsatisfied_rows());
    }
    if (new_low) {
      fewest_free = red.lp.cols();
      stalled = 0;
      since_low.reset();
      // max_backtracks counts the fixings undone since the last new low: a budget for being
      // stuck, not for a long end game. Measured, FAUST_r 043-065 at full resolution: 176 rounds
      // from 789 k free variables to 220 k, 161 of them trims, the rounding gave up at its 201st
      // undone fixing (at most 61 trims between two lows) and the level started afresh in a
      // widened space (an 11.5 M-variable first LP). (The round after a release is such a low too:
      // the budget starts afresh there, as the stall rule does; max_releases bounds those.)
      backtracks = 0;
    } else {
      ++stalled;
    }
    if (round > 1 && options.search_below > 0 && red.lp.cols() <= options.search_below &&
        stalled >= options.search_stall) {
      RoundingRound info;
      info.round = round;
      info.variables = red.lp.cols();
      info.constraints = red.lp.rows();
      info.search = true;
      if (search_round(red, info)) {
        throw_if_reach_capped();
        ++forward;
        if (info.undone) {
          // A release frees far more than the rounds after it fix at once: the stall rule starts
          // afresh, as after a release on a failed LP (below). Measured, TOSCA_r horse0-horse5 at
          // full resolution: a search released 2 955 fixings, the stall clock ran on from the low
          // before it, and 57 rounds later, right after the first round after another release (a
          // 5.6 M-variable LP, 22 minutes), the rounding was called stuck: 3 498 of 3 758 faces
          // widened.
          fewest_free = std::numeric_limits<int64_t>::max();
          stalled = 0;
          since_low.reset();
        }
        record(info, clock);
        continue;
      }
    }
    if (options.give_up_after > 0.0 && round > 1 && first_work > 0.0 && later_work > options.give_up_after * first_work)
      throw stuck("rounding: gave up, its rounds after the first took " + fmt::format("{:.2f}", later_work / first_work) +
                      " times round 1's work (iterations × variables)",
                  fixer.unsatisfied_rows());
    if (options.stuck_after > 0.0 && options.stuck_stalled > 0 && round > 1 && stalled >= options.stuck_stalled &&
        since_low.seconds() > options.stuck_after * first_seconds)
      throw stuck("rounding: stuck, no fewer free variables than " + std::to_string(fewest_free) + " for " +
                      std::to_string(stalled) + " rounds (" + fmt::format("{:.0f}", since_low.seconds()) + " s)",
                  fixer.unsatisfied_rows());
    SolverParams params = base_params;
    // The warm start over the whole LP (the last round's iterate, or round 1's given one) cut to
    // what propagation left free.
    const bool given = options.lp.initial_x.size() == size_t(lp.cols()) && options.lp.initial_y.size() == size_t(lp.rows());
    if (round > 1 || given) {
      const std::vector<double>& wx = round > 1 ? x_full : options.lp.initial_x;
      const std::vector<double>& wy = round > 1 ? y_full : options.lp.initial_y;
      params.initial_x.resize(red.cols.size());
      params.initial_y.resize(red.rows.size());
      for (size_t j = 0; j < red.cols.size(); ++j) params.initial_x[j] = wx[red.cols[j]];
      for (size_t i = 0; i < red.rows.size(); ++i) params.initial_y[i] = wy[red.rows[i]];
    }
    // Rounds after a fixing; a start from carried fixings makes round 1 one of them (solved in
    // parts, capped, its failures undone), only its bound is no one's.
    const bool after_fixing = round > 1 || carried;
    // After a fixing, an infeasible LP undoes it: that needs a proof, not a suspicion.
    if (after_fixing) params.stop_on_divergence = false;
    // (Not the first round: its relaxation and bound are the chosen solver's.)
    const bool exact = after_fixing && options.exact_below > 0 && options.solver != "clp-dual";
    if (exact && !exact_solver) exact_solver = make_solver("clp-dual");
    const SolverParams& exact_params = base_params;
    // A cap for the first-order solver only (simplex iterations are another unit); the exact
    // solver gets the parts below exact_below without it.
    if (after_fixing && options.later_round_iterations > 0 && options.solver.rfind("pdhg", 0) == 0) {
      const int64_t reference = round > 1 ? first_iterations : options.reference_iterations;
      const double cap = std::max(double(options.later_round_min_iterations),
                                  std::floor(options.later_round_iterations * double(reference)));
      params.max_iterations = std::min<int64_t>(params.max_iterations, static_cast<int64_t>(cap_scale * cap));
    }
    if (!after_fixing && options.first_max_iterations > 0)
      params.max_iterations = std::min(params.max_iterations, options.first_max_iterations);
    if (!after_fixing && round == 1) {  // (gone on from a snapshot: what is left of round 1's limits)
      params.max_iterations = std::max<int64_t>(params.max_iterations - options.resumed_iterations, 1);
      params.time_limit -= options.resumed_seconds;
      // Its restarts and divergence watch about as they would have been (SolverParams says how far);
      // a round 1 that is not gone on from a snapshot (an alternative's among them) watches afresh.
      params.iterations_before = options.resumed_iterations;
      if (options.resumed_iterations > 0) params.initial_watch = options.lp.initial_watch;
      if (options.resumed_iterations > 0) params.resume_state = options.resumed_state;
    }
    // An iterate of red.lp over the whole LP: fixed variables at their values, rows it lacks at 0.
    auto full_x = [&](const std::vector<double>& reduced) {
      std::vector<double> x(lp.cols());
      for (int64_t j = 0; j < lp.cols(); ++j) x[j] = fixer.state().value[j] == 1 ? 1.0 : 0.0;
      for (size_t j = 0; j < red.cols.size(); ++j) x[red.cols[j]] = reduced[j];
      return x;
    };
    auto full_y = [&](const std::vector<double>& reduced) {
      std::vector<double> y(lp.rows(), 0.0);
      for (size_t i = 0; i < red.rows.size() && i < reduced.size(); ++i) y[red.rows[i]] = reduced[i];
      return y;
    };
    JoinedSolve joined;
    double round_one_weight = 0.0;  // the ω round 1's (first) solve was asked to start from
    bool round_one_cold = false;     // round 1's solve starts from nothing (not a warm start, a checkpoint)
    int64_t pretest_iterations = 0;  // round 1's solve at zero cost (feasibility_iterations)
    double pretest_seconds = 0.0;
    if (!after_fixing) {
      round_one_weight = params.initial_primal_weight;
      round_one_cold = params.initial_x.empty() && options.resumed_iterations == 0;
      if (options.first_lp) options.first_lp(red.lp);
      // Round 1's solve (not its pre-test) over the whole LP, for a checkpoint (first_snapshot).
      // (Set below, after the pre-test's parameters are taken; reset after the solve.)
      int64_t snapshot_iterations = options.resumed_iterations;  // (after a probe: its iterations too)
      double snapshot_seconds = options.resumed_seconds;
      auto snapshot = [&](const SolveSnapshot& s) {
        SolveSnapshot whole;
        whole.x = full_x(s.x);
        whole.y = full_y(s.y);
        whole.primal_weight = s.primal_weight;
        whole.iterations = snapshot_iterations + s.iterations;
        whole.seconds = snapshot_seconds + s.seconds;
        whole.watch = s.watch;
        whole.state = s.state;  // (over red.lp, which a run gone on from it builds again)
        options.first_snapshot(whole, params.stop_on_divergence);
      };
      if (options.feasibility_iterations > 0 && options.solver.rfind("pdhg", 0) == 0) {
        // Without costs there are no ordinary duals to converge first: PDHG proves an infeasible
        // LP in a fraction of the iterations (and names only the clash); a feasible one's point
        // it finds not always sooner (hence the cap). Only its verdict is kept.
        SolverParams zp = pretest_params(params, options.feasibility_iterations, options.feasibility_tolerance);
        zp.initial_primal_weight = 0.0;
        const LpResult z = solve_at_zero_cost(red.lp, zp, *solver);
        pretest_iterations = z.iterations;
        pretest_seconds = z.seconds;
        spdlog::debug("rounding: round 1's LP at zero cost: {} in {} iterations ({:.2f} s)", to_string(z.status),
                      z.iterations, z.seconds);
        if (z.status == LpStatus::Infeasible) {
          spdlog::info("rounding: round 1's LP ({} variables) is infeasible, proved at zero cost in {} iterations "
                       "({:.1f} s)",
                       red.lp.cols(), z.iterations, z.seconds);
          throw ZeroCostInfeasible("rounding: the matching LP is infeasible (proved at zero cost)",
                                   certificate_rows(z.y, red.rows));
        }
        // A point within the tolerance of feasible: the costed solve converges at that tolerance
        // too, so a stop on divergence could only be a false alarm (unwatched, it cannot run on
        // forever the way an infeasible LP does).
        if (z.status == LpStatus::Optimal) {
          params.stop_on_divergence = false;
          params.patient_divergence_watch = false;
        }
      }
      if (options.first_snapshot && options.snapshot_seconds > 0.0) {
        params.snapshot_seconds = options.snapshot_seconds;
        params.snapshot = snapshot;
        params.exact_state = true;
      }
      // The divergence bound is the whole LP's: this one leaves out what propagation fixed to 1.
      if (std::isfinite(params.divergence_bound)) params.divergence_bound -= lp.objective_scale * red.fixed_cost;
      if (options.probe && options.probe_tolerance > params.tolerance) {
        SolverParams loose = params;
        loose.tolerance = options.probe_tolerance;
        // (Its snapshots go on as iterates: a run gone on from one solves at the tight tolerance, where
        // the uninterrupted probe would have stopped at the loose one and priced.)
        loose.exact_state = false;
        LpResult p = solver->solve(red.lp, loose);
        if (p.status == LpStatus::Optimal && p.x.size() == red.cols.size() && p.y.size() == red.rows.size()) {
          options.probe(full_x(p.x), full_y(p.y), p.primal_weight);
          params.initial_x = std::move(p.x);
          params.initial_y = std::move(p.y);
          if (std::isfinite(p.primal_weight) && p.primal_weight > 0.0) params.initial_primal_weight = p.primal_weight;
          params.max_iterations = std::max<int64_t>(params.max_iterations - p.iterations, 1);
          params.time_limit -= p.seconds;
          snapshot_iterations += p.iterations;
          snapshot_seconds += p.seconds;
          params.initial_watch = {};  // (a new solve, as it is uninterrupted)
          params.iterations_before = 0;
          params.resume_state = nullptr;
          joined.r = solver->solve(red.lp, params);
          joined.r.iterations += p.iterations;
          joined.r.seconds += p.seconds;
        } else {
          joined.r = std::move(p);
        }
      } else {
        joined.r = solver->solve(red.lp, params);
      }
      if (joined.r.status == LpStatus::Infeasible) {
        joined.proof = joined.r.y;
        joined.certificate = detail::oriented_certificate(red.lp, joined.r.y);
        if (!joined.certificate.empty()) joined.certificate_part.assign(joined.certificate.size(), 0);
      }
      params.snapshot = {};  // (it refers to this block)
    } else {
      std::vector<double> warm_weight;
      if (!w_full.empty()) {
        warm_weight.resize(red.cols.size());
        for (size_t j = 0; j < red.cols.size(); ++j) warm_weight[j] = w_full[red.cols[j]];
      }
      // The round's iterate so far as the next round's warm start, for a checkpoint (round_snapshot).
      bool saved = false;  // (by such a snapshot in this round)
      const bool snapshots = options.round_snapshot && options.snapshot_seconds > 0.0;
      if (snapshots) {
        params.snapshot_seconds = options.snapshot_seconds;
        params.snapshot = [&](const SolveSnapshot& s) {
          saved = true;  // (first: a caller's save may end in Stopped, as match's does on a stop)
          options.round_snapshot(full_x(s.x), full_y(s.y), s.primal_weight);
        };
      }
      try {
        joined = detail::solve_in_parts(red.lp, std::move(params), *solver, exact ? exact_solver.get() : nullptr,
                                        options.exact_below, exact_params, options.split_parts,
                                        {options.exact_pivots_per_column, options.exact_part_seconds}, &exact_cache,
                                        &warm_weight, options.slow_part, options.slow_part_seconds,
                                        {.iterations = options.later_feasibility_iterations,
                                         .tolerance = options.feasibility_tolerance,
                                         .cache = &pretest_cache,
                                         .skip_below = options.later_feasibility_skip_below,
                                         .skip_residual = options.later_feasibility_skip_residual,
                                         .skip_row = options.later_feasibility_skip_row});
      } catch (const Stopped&) {
        // A stop where this round saved nothing (a part's zero-cost pre-test or first short solve,
        // which keep no snapshot): the rounds before it, whose `decided` the caller's throttle may
        // not have saved yet, go with this round's warm start as a snapshot does, then the stop
        // goes on. (Before, up to a minute of rounds at full resolution was lost.)
        if (snapshots && !saved && !result.rounds.empty()) {
          spdlog::debug("rounding: stopped in round {} before its LP saved anything: saving its warm start", round);
          options.round_snapshot(x_full, y_full, 0.0);
        }
        throw;
      }
    }
    const LpResult& r = joined.r;
    // Round 1's iterate over the whole LP, for first_iterate and (an optimum) for the alternatives.
    if (round == 1 && (options.first_iterate || keep) && r.x.size() == red.cols.size()) {
      std::vector<double> x = full_x(r.x), y(lp.rows(), 0.0);
      const bool diverged = r.status == LpStatus::Diverging;
      const std::vector<double>& dual = diverged ? r.last_y : r.y;
      double growth = 0.0;
      if (diverged)
        for (double g : r.y) growth = std::max(growth, std::abs(g));
      if (dual.size() == red.rows.size())
        for (size_t i = 0; i < red.rows.size(); ++i)
          if (!diverged || i >= r.y.size() || std::abs(r.y[i]) <= 0.01 * growth) y[red.rows[i]] = dual[i];
      if (keep && r.status == LpStatus::Optimal && r.y.size() == red.rows.size()) {
        keep->x = x;
        keep->y = y;
        keep->primal_weight = std::isfinite(r.primal_weight) ? r.primal_weight : 0.0;
        keep->seconds = clock.seconds() - pretest_seconds + options.resumed_seconds;
        keep->iterations = r.iterations + options.resumed_iterations;
        // As result.first_lp below (which a failing first_iterate never reaches), without vectors.
        keep->result = r;
        keep->result.x = {};
        keep->result.y = {};
        keep->result.last_y = {};
        keep->result.objective += lp.objective_scale * red.fixed_cost;
        keep->result.lower_bound += lp.objective_scale * red.fixed_cost;
      }
      if (options.first_iterate) options.first_iterate(x, y, r.primal_weight);
    }
    RoundingRound info;
    info.round = round;
    info.variables = red.lp.cols();
    info.constraints = red.lp.rows();
    info.status = r.status;
    info.iterations = r.iterations;
    info.parts = joined.parts;
    info.exact_parts = joined.exact_parts;
    if (after_fixing) {
      info.start_primal_weight = joined.start_weight;
      info.primal_weight = joined.end_weight;
    } else {
      info.start_primal_weight = round_one_weight;
      info.primal_weight = r.primal_weight;
    }
    info.objective = r.objective + lp.objective_scale * red.fixed_cost;
    info.feasibility_iterations = pretest_iterations;
    info.feasibility_seconds = pretest_seconds;
    info.later_pretest_seconds = joined.pretest_seconds;
    if (round == 1) {  // in the units of the full LP: add what propagation fixed to 1 before it
      first_seconds = options.reference_seconds > 0.0 ? options.reference_seconds
                                                      : clock.seconds() - pretest_seconds + options.resumed_seconds;
      first_iterations =
          options.reference_iterations > 0 ? options.reference_iterations : r.iterations + options.resumed_iterations;
      first_work = double(first_iterations) * double(red.lp.cols());
      result.first_lp = r;
      result.first_lp.objective += lp.objective_scale * red.fixed_cost;
      result.first_lp.lower_bound += lp.objective_scale * red.fixed_cost;
    }

    if (r.status == LpStatus::Diverging) {  // only asked for in round 1 (above)
      std::vector<int64_t> rows = certificate_rows(r.y, red.rows);
      const std::vector<int64_t> stalled = residual_rows(red.lp, r.x, red.rows);
      describe_stalled_rows(space, lp, red, r.x, stalled);
      std::vector<int64_t> both = rows;
      std::sort(both.begin(), both.end());
      const size_t growth = both.size();
      both.insert(both.end(), stalled.begin(), stalled.end());
      std::inplace_merge(both.begin(), both.begin() + growth, both.end());
      both.erase(std::unique(both.begin(), both.end()), both.end());
      spdlog::debug("rounding: {} of the stalled iterate's {} rows lie outside the dual growth's {}{}",
                    both.size() - growth, stalled.size(), growth, options.blame_residual ? " (blamed too)" : "");
      if (options.blame_residual) rows = std::move(both);
      // (Not from start_ones: a proof would be of the LP with those fixings, not of the LP.)
      if (options.local_proof_columns > 0 && !stalled.empty() && options.start_ones.empty()) {
        Stopwatch local_clock;
        const std::unique_ptr<LpSolver> local_solver = make_solver(options.local_proof_solver);
        // The X region around the stalled rows, 0, 1, 2 … rings out: its rows, face rows' far
        // columns merged (local_proof.hpp; rows one step out reach a million columns at once).
        std::vector<int64_t> seeds;  // (in the reduced LP's numbering)
        for (int64_t row : stalled) {
          const auto at = std::lower_bound(red.rows.begin(), red.rows.end(), row);
          if (at != red.rows.end() && *at == row) seeds.push_back(at - red.rows.begin());
        }
        const std::vector<int> seed_faces = detail::x_faces_of_rows(space, red.lp, red.cols, r.x, seeds);
        const auto region_rows = [&](int rings) {
          return detail::x_region_rows(space, red.lp, red.cols, seed_faces, rings);
        };
        detail::LocalProof proof =
            detail::local_infeasibility_on(red.lp, region_rows, options.local_proof_depth,
                                           options.local_proof_columns, *local_solver, options.local_proof_seconds, true);
        for (int64_t& i : proof.support) i = red.rows[i];
        spdlog::debug("rounding: local proof near the stalled rows ({} X faces): {}; last solved {} rings out, {} rows and "
                      "{} columns{} ({:.2f} s)",
                      seed_faces.size(), proof.ended, proof.depth, proof.rows, proof.cols,
                      proof.capped_cols > 0 ? fmt::format("; the next, {} rows and {} columns, past the cap",
                                                          proof.capped_rows, proof.capped_cols)
                                            : "",
                      local_clock.seconds());
        if (proof.proved) {
          spdlog::debug("rounding: its Farkas ray needs {} rows", proof.support.size());
          throw LocalInfeasible(fmt::format("rounding: the matching LP is infeasible ({}'s ray on {} rows over the X "
                                            "faces within {} rings of its stalled residual)",
                                            options.local_proof_solver, proof.rows, proof.depth),
                                proof.support, seed_faces, proof.depth);
        }
      }
      throw InfeasibleError(r.lower_bound + lp.objective_scale * red.fixed_cost > options.lp.divergence_bound
                                ? "rounding: the matching LP's optimum lies above its divergence bound (PDHG)"
                                : "rounding: the matching LP is probably infeasible (PDHG diverging)",
                            std::move(rows), false);
    }
    // A later round (or part of one) at its cap whose certified bound lies well above its own
    // objective behaves like an infeasible LP (its dual grows along a Farkas ray; the proof takes
    // longer than the cap). Fixing from such an iterate made every LP after it infeasible (full
    // resolution: 60 rounds of undoing), so it is undone like one, its growing dual naming the
    // rows to blame.
    const bool suspect = joined.suspect && !history.empty();
    if (r.status == LpStatus::Infeasible || suspect) {
      // The last fixing left an infeasible LP that propagation could not see: undo it, fix less.
      if (suspect)
        spdlog::debug("round {}: LP at its cap with its bound far above its objective: undone as infeasible", round);
      if (history.empty())
        throw InfeasibleError("rounding: the matching LP is infeasible", certificate_rows(joined.proof, red.rows));
      info.undone = true;
      std::vector<int64_t> failed;  // the failed parts' rows, in the full LP's numbering
      for (int64_t i : joined.failed_rows) failed.push_back(red.rows[i]);
      // What is left of the last fixing (nothing where one from a capped LP was undone whole).
      // A batch from a capped LP is blamed by the whole parts that failed: its iterate was far
      // from the optimum everywhere near them, not only on the certificate's rows.
      const std::vector<int64_t> proof_rows = certificate_rows(joined.proof, red.rows);
      std::vector<int64_t> blame = proof_rows;
      if (history.back().capped && !failed.empty()) blame = failed;
      // Parts are independent, so a failed part that no fixing of the last round touches failed
      // because of earlier fixings (its LP had stopped at its cap before, or the last fixing was
      // trimmed to what lies elsewhere), or has not failed yet: it only looks infeasible at its
      // cap. Measured, FAUST_r 020-021 at full resolution (converged_first): a 578 589-variable
      // part looked infeasible after the last round fixed 27 in other parts, and halving those 27
      // solved the same LP five times.
      // The same part failing again after trims of the last fixing: the fault lies in fixings
      // around it that the trims do not reach (earlier rounds', or ones propagation puts back),
      // so those are released instead (release_after_trims).
      const int trims = failing_again.failed(failed);
      const bool again =
          options.release_after_trims > 0 && trims >= options.release_after_trims && releases < options.max_releases;
      int64_t touched = -1;
      std::vector<std::pair<int64_t, int>> away;  // what the proof leaves of the last fixing
      if (!history.back().batch.empty())
        away = fixings_away_from(lp, fixer.state().value, blame.empty() ? failed : blame, history.back().batch,
                                 fixer.assigned_since(history.back().mark), &touched);
      const bool proven = r.status == LpStatus::Infeasible;
      if (proven && release_by_certificate(red, joined, info)) {
        // (released where the proof lies: neither a trim of the last fixing nor a release around a part)
      } else if (touched == 0 && !proven && cap_scale < kMaxCapScale) {
        cap_scale = std::min(2.0 * cap_scale, kMaxCapScale);
        spdlog::debug("round {}: a part at its cap looks infeasible, away from the last fixing: it goes on from its "
                      "iterate, the cap {}x",
                      round, cap_scale);
        keep_iterate(red, joined);
        info.undone = false;
        ++forward;
      } else if ((touched == 0 || again) && !failed.empty() && failed.size() < red.rows.size()) {
        const int64_t ones = fixer.state().ones, zeros = fixer.state().zeros;
        // Around the proof's rows where it names fewer than the failed parts have: a part of
        // millions of variables borders most fixings (measured, TOSCA_r cat2-cat9 at full
        // resolution: a release around a 2.6 M-variable part's rows freed 4 387 of 10 840 fixings
        // to 1, and a later one 5 983 of 7 209; the round after the first had 8.1 M variables and
        // took 27 minutes. Around the proof's 2 617 rows of the part's 869 603, the same state
        // released 234, its next LP 2.8 M variables). Where that is not enough, the part fails
        // again and the next release reaches further. (The proof's own rows also where a capped
        // batch was blamed by the whole failed parts.)
        const std::vector<int64_t>& around =
            !proof_rows.empty() && proof_rows.size() < failed.size() ? proof_rows : failed;
        spdlog::debug("round {}: a part failed {} ({} rows, the proof {}): releasing the fixings around it", round,
                      touched == 0 ? "away from the last fixing" : "again after a trim", failed.size(),
                      proof_rows.size());
        info.released = release_around(around, true, info);
        throw_if_reach_capped();
        info.fixed_to_one = fixer.state().ones - ones;
        info.fixed_to_zero = fixer.state().zeros - zeros;
        // A release frees far more than the next rounds fix at once; measured from the low
        // before it, the stall rule gave up 12 rounds later (FAUST_r 024-043 at full resolution:
        // a low of 52 543 free variables, then 142 288 to 623 929 after the release), and its
        // widening covered the faces of every open row. So too after a release away from the
        // last fixing: the same pair (thirty-fourth session, `--curvature-radius 0.05`) stalled
        // through 15 trims, released 870 fixings (785 504 variables free again) and was declared
        // stuck two rounds later, widening 5 989 of 10 002 faces.
        fewest_free = std::numeric_limits<int64_t>::max();
        stalled = 0;
        since_low.reset();
      } else {
        // (Without a proof, or for a single fixing, nothing local: halve.)
        if (blame.empty() || history.back().batch.size() < 2) away.clear();
        const bool whole = backtrack(std::move(away));
        info.fixed_to_one = whole ? 0 : fixer.state().ones - history.back().ones;
        info.fixed_to_zero = whole ? 0 : fixer.state().zeros - history.back().zeros;
        if (!whole) failing_again.trimmed();
      }
      record(info, clock);
      ++failing_rounds;
      failing_seconds += info.seconds;
      std::vector<int64_t> where = failed.empty() ? proof_rows : failed;
      if (options.stuck_after > 0.0 && failing_rounds >= options.stuck_rounds && !where.empty() &&
          failing_seconds > options.stuck_after * first_seconds)
        throw stuck("rounding: stuck, the LPs after its fixings failed " + std::to_string(failing_rounds) +
                        " rounds in a row (" + fmt::format("{:.0f}", failing_seconds) + " s)",
                    std::move(where));
      continue;
    }
    failing_rounds = 0;
    failing_seconds = 0.0;
    failing_again.solved();
    if (r.status == LpStatus::NumericalTrouble || r.x.size() != size_t(red.lp.cols()))
      throw SolverError(std::string("rounding: LP solve failed (") + to_string(r.status) + ")");
    keep_iterate(red, joined);

    // Candidates above the threshold, largest first; if none, the single largest.
    std::vector<int64_t> order(red.cols.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int64_t p, int64_t q) { return r.x[p] > r.x[q]; });
    // Refuted fixings are left out while anything else remains, with those blamed from this
    // state before, where the rounding has been here already.
    if (!failed_from.empty()) {
      const std::vector<int64_t> again = failed_from.recall(detail::state_hash(fixer.state().value));
      size_t added = 0;
      for (int64_t j : again) added += refuted.insert(j).second;
      if (added > 0)
        spdlog::debug("rounding: back at a state seen before: {} fixings blamed from it are left out", added);
    }
    if (!refuted.empty()) {
      std::vector<int64_t> open;
      for (int64_t k : order)
        if (!refuted.count(red.cols[k])) open.push_back(k);
      if (open.empty() || r.x[open.front()] <= 0.0) refuted.clear();
      else order = std::move(open);
    }
    // Parts that converged are fixed first; a part at its cap goes on from its iterate in the
    // next round (its warm start), and is fixed from an unconverged iterate only where nothing
    // else is left and it has already had one round more. Measured, FAUST_r 020-021 at full
    // resolution: fixings from a capped 213 000-variable part beside 6 parts solved exactly made
    // the LPs after them infeasible for 10 rounds, each undoing a capped round with a doubled cap.
    bool capped = r.status == LpStatus::IterationLimit || r.status == LpStatus::TimeLimit;
    if (options.converged_first && !joined.capped_cols.empty()) {
      std::vector<int64_t> settled;
      for (int64_t k : order)
        if (!joined.capped_cols[k]) settled.push_back(k);
      if (!settled.empty() && r.x[settled.front()] > options.threshold) {
        order = std::move(settled);
        capped = false;
        waited = false;
      } else if (!waited) {
        waited = true;
        ++forward;
        spdlog::debug("round {}: only parts at their cap are left; they go on from their iterate", round);
        record(info, clock);
        continue;
      } else {
        waited = false;
      }
    }
    // A time limit below the solver's set-up leaves a cold round 1 no iterate to round: each round
    // would then fix one variable from nothing (measured: match --time-limit 0.01, 268 rounds in
    // 30 s). (A warm start's iterate, e.g. from a checkpoint, is one.)
    if (round == 1 && round_one_cold && r.status == LpStatus::TimeLimit && r.iterations == 0)
      throw SolverError(fmt::format("rounding: round {}'s LP reached its time limit ({:g} s) before its first "
                                    "iteration; allow more time per LP (--time-limit)",
                                    round, options.lp.time_limit));
    if (capped)
      spdlog::warn("round {}: LP ended with status {}; rounding its current iterate", round, to_string(r.status));
    std::vector<std::pair<int64_t, int>> batch;
    for (int64_t k : order) {
      if (r.x[k] <= options.threshold) break;
      batch.push_back({red.cols[k], 1});
    }
    if (batch.empty()) batch = fractional_batch(lp, red, r.x, order, options.fractional_batch);

    ++forward;
    Step step{fixer.mark(), fixer.state().ones, fixer.state().zeros, {}, capped};
    const int64_t ones = step.ones, zeros = step.zeros;
    try {
      const bool greedy = red.lp.cols() > options.greedy_above;
      if (greedy)
        batch = away_from_undecided(lp, red, fixer.state().value, r.x, batch, options.greedy_unsure,
                                    options.greedy_margin, options.greedy_fallback);
      step.batch = shrink_and_fix(fixer, batch, step.mark, greedy);
      info.undone = step.batch != batch;
      history.push_back(std::move(step));
    } catch (const InfeasibleError&) {  // not even the largest can be 1 or 0: an earlier fixing is wrong
      fixer.undo_to(step.mark);
      info.undone = true;
      backtrack({});
    }
    info.fixed_to_one = fixer.state().ones - ones;
    info.fixed_to_zero = fixer.state().zeros - zeros;
    record(info, clock);
  }

  // Every row is satisfied: the remaining free variables are 0.
  const FixState& s = fixer.state();
  for (int64_t j = 0; j < lp.cols(); ++j)
    if (s.value[j] == 1) result.gamma.push_back(j);
  if (!satisfies_exactly(lp, result.gamma))
    throw SolverError("rounding produced a Γ that violates A x = b (a bug); nothing was written");
  if (options.close_pockets) {
    result.gamma = close_pockets(space, result.gamma, &result.pockets_closed);
    if (result.pockets_closed > 0) {
      if (!satisfies_exactly(lp, result.gamma))
        throw SolverError("closing pockets broke A x = b (a bug); nothing was written");
      spdlog::debug("rounding: closed {} pockets", result.pockets_closed);
    }
  }
  for (int64_t j : result.gamma) result.energy += energy[j];
  if (result.rounds.empty()) {  // propagation alone decided everything (tiny problems)
    SolverParams whole = options.lp;
    whole.initial_watch = {};
    whole.iterations_before = 0;
    result.first_lp = solver->solve(lp, whole);
  }
  if (options.start_ones.empty()) result.lower_bound = result.first_lp.lower_bound;
  else if (options.start_dual.size() == size_t(lp.rows())) result.lower_bound = certified_lower_bound(lp, options.start_dual);
  else result.lower_bound = -std::numeric_limits<double>::infinity();
  result.gap = relative_gap(result.energy, result.lower_bound);
  result.threshold = options.threshold;
  return result;
}
}  // namespace

RoundingResult round_to_graph_surface(const ProductSpace& space, const LpProblem& lp, const std::vector<double>& energy,
                                      const RoundingOptions& options,
                                      const std::function<void(const RoundingRound&)>& progress) {
  if (static_cast<int64_t>(energy.size()) != lp.cols() || space.size() != lp.cols())
    throw InvalidInputError("rounding: the space, the LP and the energies disagree in size");
  const bool alternatives =
      !options.alternative_thresholds.empty() && options.start_ones.empty() && lp.cols() <= options.alternatives_below;
  FirstOptimum first;
  RoundingResult best;
  std::exception_ptr failed;  // the first rounding's error (alternatives_after_failure)
  try {
    best = round_once(space, lp, energy, options, progress, alternatives ? &first : nullptr);
  } catch (const SolverError& e) {
    if (!options.alternatives_after_failure || first.x.empty()) throw;
    spdlog::info("rounding: threshold {} found no Γ ({}); trying the alternatives", options.threshold, e.what());
    failed = std::current_exception();
    best.energy = std::numeric_limits<double>::infinity();
    best.threshold = options.threshold;
  }
  best.tried.push_back({options.threshold, failed ? std::numeric_limits<double>::quiet_NaN() : best.energy});
  if (first.x.empty()) return best;  // no alternatives, or round 1 not optimal (nothing to restart from)
  for (double t : options.alternative_thresholds) {
    if (std::any_of(best.tried.begin(), best.tried.end(), [&](const auto& p) { return p.first == t; })) continue;
    RoundingOptions alt = options;
    alt.decided = {};  // (the caller follows the main rounding, whose Γ this one only competes with)
    alt.threshold = t;
    alt.alternative_thresholds.clear();
    alt.first_iterate = {};
    alt.probe = {};
    alt.probe_tolerance = 0.0;
    alt.first_snapshot = {};
    alt.round_snapshot = {};
    alt.resumed_iterations = 0;  // (its round 1 is that optimum's)
    alt.resumed_seconds = 0.0;
    alt.resumed_state = nullptr;
    alt.first_max_iterations = 0;
    alt.feasibility_iterations = 0;  // (round 1 was optimal)
    alt.lp.initial_x = first.x;  // round 1 starts at its optimum: it only confirms it
    alt.lp.initial_y = first.y;
    alt.lp.initial_primal_weight = first.primal_weight;
    alt.reference_seconds = first.seconds;  // the later rounds' caps and the stuck rule as the first's
    alt.reference_iterations = first.iterations;
    Stopwatch clock;
    try {
      RoundingResult r = round_once(space, lp, energy, alt, {}, nullptr);
      const bool lower = r.energy < best.energy;
      spdlog::info("rounding: threshold {} gives energy {:.6g} in {} rounds ({:.2f} s) against {:.6g} with {}{}", t,
                   r.energy, r.rounds.size(), clock.seconds(), best.energy, best.threshold,
                   lower ? ": its Γ goes on" : "");
      best.tried.push_back({t, r.energy});
      if (lower) {
        // The bound stays the first LP's (both solves certify the same LP; the better one counts).
        // After a failed first rounding, round 1's optimum is that LP's (FirstOptimum).
        if (failed) best.lower_bound = first.result.lower_bound, best.first_lp = first.result;
        r.lower_bound = std::max(r.lower_bound, best.lower_bound);
        r.first_lp = std::move(best.first_lp);
        r.gap = relative_gap(r.energy, r.lower_bound);
        r.tried = std::move(best.tried);
        best = std::move(r);
      }
    } catch (const SolverError& e) {  // that rounding found no Γ (or its LP gave up): the others stand
      spdlog::info("rounding: threshold {} found no Γ ({}, {:.2f} s)", t, e.what(), clock.seconds());
      best.tried.push_back({t, std::numeric_limits<double>::quiet_NaN()});
    }
  }
  if (failed && !std::isfinite(best.energy)) std::rethrow_exception(failed);
  return best;
}

double relative_gap(double energy, double bound) {
  // An energy that meets its bound to rounding error has no gap, also when both are ~0 (the
  // identity of a shape with itself), where the relative formula would read 100 %.
  const double slack = energy - bound;
  if (slack <= 1e-9 * std::max(1.0, std::abs(energy))) return 0.0;
  // Relative to the bound where it is positive; a bound of 0 or below (a weak dual: the bound is
  // clamped at 0 where every cost is >= 0) says nothing of scale: relative to the energy then.
  return bound > 0.0 ? slack / bound : slack / std::max(std::abs(energy), 1e-300);
}

GraphSurfaceCheck check_graph_surface(const ProductSpace& space, const std::vector<int64_t>& gamma) {
  const Mesh& X = space.x();
  const Mesh& Y = space.y();
  GraphSurfaceCheck check;
  std::vector<int> cover_x(X.num_faces(), 0), cover_y(Y.num_faces(), 0);
  bool orientation = true;
  auto is_rotation = [](const std::array<int, 3>& t, const std::array<int, 3>& f) {
    for (int r = 0; r < 3; ++r)
      if (t[0] == f[r] && t[1] == f[(r + 1) % 3] && t[2] == f[(r + 2) % 3]) return true;
    return false;
  };
  for (int64_t j : gamma) {
    const ProductTriangle t = space[j];
    if (t.fa >= 0) {
      ++cover_x[t.fa];
      orientation = orientation && is_rotation(t.a, X.faces[t.fa]);
    }
    if (t.fb >= 0) {
      ++cover_y[t.fb];
      orientation = orientation && is_rotation(t.b, Y.faces[t.fb]);
    }
  }
  check.covers_x = std::all_of(cover_x.begin(), cover_x.end(), [](int c) { return c == 1; });
  check.covers_y = std::all_of(cover_y.begin(), cover_y.end(), [](int c) { return c == 1; });
  check.orientation = orientation;

  // Continuity (Theorem 1 b, c), read as: Γ relates every point of one shape to a connected
  // set of the other. For a vertex v that set, its fibre, is the union of the simplices of the
  // other shape paired with v in the product triangles through v (a vertex in a real triangle,
  // an edge or a whole face where v is blown up); for an edge e, the simplices paired with its
  // interior together with both end points' fibres. Pieces are vertex sets, connected when they
  // share a vertex. An edge's two faces then map to touching patches. (Requiring the pieces of
  // one edge to connect without the rest of its end points' fibres is too strict: a blown-up
  // vertex can attach to the rest through a neighbouring edge.)
  using Piece = std::vector<int>;
  struct Side {
    std::vector<std::vector<Piece>> vertex_fibre, edge_interior;
  };
  Side sx{std::vector<std::vector<Piece>>(X.num_vertices()), std::vector<std::vector<Piece>>(X.num_edges())};
  Side sy{std::vector<std::vector<Piece>>(Y.num_vertices()), std::vector<std::vector<Piece>>(Y.num_edges())};
  auto add = [](const Mesh& mesh, Side& side, const std::array<int, 3>& a, const std::array<int, 3>& b) {
    for (int i = 0; i < 3; ++i) {
      if ((i > 0 && a[0] == a[i]) || (i > 1 && a[1] == a[i])) continue;  // each distinct vertex once
      Piece fibre;
      for (int k = 0; k < 3; ++k)
        if (a[k] == a[i]) fibre.push_back(b[k]);
      side.vertex_fibre[a[i]].push_back(std::move(fibre));
    }
    for (int i = 0; i < 3; ++i) {
      const int u = a[i], w = a[(i + 1) % 3];
      if (u == w) continue;
      // A real triangle pairs its edge u-w with b's edge (or vertex) at the same positions; a
      // triangle degenerate onto u-w pairs the edge's interior with all of b.
      const bool stretched = a[(i + 2) % 3] == u || a[(i + 2) % 3] == w;
      side.edge_interior[mesh.edge_index(u, w)].push_back(stretched ? Piece(b.begin(), b.end())
                                                                    : Piece{b[i], b[(i + 1) % 3]});
      if (stretched) break;  // its other "edge" is the same edge reversed
    }
  };
  for (int64_t j : gamma) {
    const ProductTriangle t = space[j];
    add(X, sx, t.a, t.b);
    add(Y, sy, t.b, t.a);
  }
  auto connected = [](const std::vector<const std::vector<Piece>*>& groups) {
    std::vector<const Piece*> pieces;
    for (const auto* g : groups)
      for (const Piece& p : *g) pieces.push_back(&p);
    if (pieces.size() <= 1) return true;
    std::vector<bool> reached(pieces.size(), false);
    std::vector<size_t> stack{0};
    reached[0] = true;
    size_t count = 1;
    while (!stack.empty()) {
      const Piece& p = *pieces[stack.back()];
      stack.pop_back();
      for (size_t q = 0; q < pieces.size(); ++q) {
        if (reached[q]) continue;
        const bool touch = std::any_of(p.begin(), p.end(), [&](int v) {
          return std::find(pieces[q]->begin(), pieces[q]->end(), v) != pieces[q]->end();
        });
        if (touch) {
          reached[q] = true;
          ++count;
          stack.push_back(q);
        }
      }
    }
    return count == pieces.size();
  };
  auto broken = [&](const Mesh& mesh, const Side& side, int64_t& vertices, int64_t& edges) {
    vertices = edges = 0;
    for (int v = 0; v < mesh.num_vertices(); ++v) vertices += !connected({&side.vertex_fibre[v]});
    for (int e = 0; e < mesh.num_edges(); ++e) {
      const auto [u, w] = mesh.edges[e];
      edges += !connected({&side.edge_interior[e], &side.vertex_fibre[u], &side.vertex_fibre[w]});
    }
  };
  if (check.covers_x && check.covers_y) {
    broken(X, sx, check.discontinuous_vertices_x, check.discontinuous_edges_x);
    broken(Y, sy, check.discontinuous_vertices_y, check.discontinuous_edges_y);
    check.continuous = check.discontinuous_vertices_x == 0 && check.discontinuous_edges_x == 0 &&
                       check.discontinuous_vertices_y == 0 && check.discontinuous_edges_y == 0;
  }
  return check;
}

namespace {

// Moves vertices of `from` to other partners in their fibre (`candidates`) while that lowers the
// number of inverted images among their faces, then the number of degenerate ones. Γ keeps
// orientation everywhere, but one partner per vertex can invert a face where Γ blows a vertex up
// or stretches an edge; another partner from the same fibre usually does not.
void untangle(const Mesh& from, const Mesh& to, const std::vector<std::vector<int>>& candidates,
              std::vector<int>& map) {
  const Geometry g = compute_geometry(to);
  std::vector<std::vector<int>> vf(from.num_vertices());
  for (int f = 0; f < from.num_faces(); ++f)
    for (int v : from.faces[f]) vf[v].push_back(f);
  auto face_cost = [&](int f) {  // an inverted image weighs more than any number of degenerate ones
    const auto& t = from.faces[f];
    const int o = image_orientation(to, g, map[t[0]], map[t[1]], map[t[2]]);
    return int64_t(o < 0 ? 1000 : o == 0 ? 1 : 0);
  };
  auto cost = [&](int v) {
    int64_t c = 0;
    for (int f : vf[v]) c += face_cost(f);
    return c;
  };
  for (int sweep = 0; sweep < 8; ++sweep) {
    bool changed = false;
    for (int v = 0; v < from.num_vertices(); ++v) {
      if (candidates[v].size() < 2) continue;
      const int current = map[v];
      int best = current;
      int64_t best_cost = cost(v);
      if (best_cost == 0) continue;
      for (int c : candidates[v]) {
        if (c == current) continue;
        map[v] = c;
        const int64_t k = cost(v);
        if (k < best_cost) best_cost = k, best = c;
      }
      map[v] = best;
      changed = changed || best != current;
    }
    if (!changed) break;
  }
  // What single moves cannot fix, a face's three corners moved together may (bounded search).
  for (int f = 0; f < from.num_faces(); ++f) {
    const auto& t = from.faces[f];
    if (image_orientation(to, g, map[t[0]], map[t[1]], map[t[2]]) >= 0) continue;
    const auto &c0 = candidates[t[0]], &c1 = candidates[t[1]], &c2 = candidates[t[2]];
    if (c0.size() * c1.size() * c2.size() > 4096) continue;
    // The three stars overlap: count each face of their union once, so that a lower total
    // means fewer inverted faces, never more.
    std::vector<int> star(vf[t[0]]);
    star.insert(star.end(), vf[t[1]].begin(), vf[t[1]].end());
    star.insert(star.end(), vf[t[2]].begin(), vf[t[2]].end());
    std::sort(star.begin(), star.end());
    star.erase(std::unique(star.begin(), star.end()), star.end());
    auto total = [&] {
      int64_t c = 0;
      for (int h : star) c += face_cost(h);
      return c;
    };
    std::array<int, 3> best{map[t[0]], map[t[1]], map[t[2]]};
    int64_t best_cost = total();
    for (int a : c0)
      for (int b : c1)
        for (int c : c2) {
          map[t[0]] = a, map[t[1]] = b, map[t[2]] = c;
          const int64_t k = total();
          if (k < best_cost) best_cost = k, best = {a, b, c};
        }
    map[t[0]] = best[0], map[t[1]] = best[1], map[t[2]] = best[2];
  }
}

}  // namespace

VertexMaps vertex_maps(const ProductSpace& space, const std::vector<int64_t>& gamma, bool untangle_maps) {
  VertexMaps maps;
  maps.x_to_y.assign(space.x().num_vertices(), -1);
  maps.y_to_x.assign(space.y().num_vertices(), -1);
  // Two passes: partners from triangles real on both sides first, then any.
  for (int pass = 0; pass < 2; ++pass)
    for (int64_t j : gamma) {
      const ProductTriangle t = space[j];
      if (pass == 0 && (t.fa < 0 || t.fb < 0)) continue;
      for (int i = 0; i < 3; ++i) {
        if (maps.x_to_y[t.a[i]] < 0) maps.x_to_y[t.a[i]] = t.b[i];
        if (maps.y_to_x[t.b[i]] < 0) maps.y_to_x[t.b[i]] = t.a[i];
      }
    }
  // Every vertex's fibre: the partners Γ pairs it with, position by position.
  std::vector<std::vector<int>> fibre_x(maps.x_to_y.size()), fibre_y(maps.y_to_x.size());
  for (int64_t j : gamma) {
    const ProductTriangle t = space[j];
    for (int i = 0; i < 3; ++i) {
      fibre_x[t.a[i]].push_back(t.b[i]);
      fibre_y[t.b[i]].push_back(t.a[i]);
    }
  }
  for (auto* fibres : {&fibre_x, &fibre_y})
    for (auto& f : *fibres) {
      std::sort(f.begin(), f.end());
      f.erase(std::unique(f.begin(), f.end()), f.end());
    }
  if (untangle_maps && std::find(maps.x_to_y.begin(), maps.x_to_y.end(), -1) == maps.x_to_y.end() &&
      std::find(maps.y_to_x.begin(), maps.y_to_x.end(), -1) == maps.y_to_x.end()) {
    untangle(space.x(), space.y(), fibre_x, maps.x_to_y);
    untangle(space.y(), space.x(), fibre_y, maps.y_to_x);
  }
  return maps;
}

}  // namespace shapematch
