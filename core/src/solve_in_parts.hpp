#pragma once
// A later rounding round's LP, solved part by part (rounding.cpp); here for its tests.
#include "shapematch/lp.hpp"

#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

namespace shapematch::detail {

// A later round's LP solved part by part: parts with fewer than `exact_below` columns by the exact
// solver, the others by `solver` from the warm start in `params` (given for the whole LP), and the
// results joined. The joined status is Infeasible where a part is, the iteration limit where a
// part stopped there; `proof` holds the duals of the parts that are infeasible, or (where none
// is) that behave like it at their cap (`suspect`: certified bound far above the objective),
// zero elsewhere, so that the blame stays with them. A part that one solver gives up on
// (numerical trouble) goes to the other (`exact` up to 10 × exact_below columns); where both
// fail, so does the join. With `cap.pivots_per_column` > 0 the exact solver stops after that
// many pivots per column of the part (at least 1 000 columns' worth), with `cap.seconds` > 0 after
// that many seconds (or the LP's own time limit where shorter), and the part goes to `solver` as where it gives up; with a `cache`, the parts
// of its size or larger go to `solver` from then on (ExactCache::capped_below). With `warm_weight` (one value per column, 0: none) a part solved
// by `solver` starts from the geometric mean of its columns' positive values as its primal weight.
// With `pretest.iterations` > 0 every such part is first solved at zero cost for at most that
// many iterations (RoundingOptions::later_feasibility_iterations), to `pretest.tolerance` where
// it is > 0 (RoundingOptions::feasibility_tolerance); where one is proved infeasible
// there, the join is infeasible with those parts' certificates, and nothing else is solved.
// `pretest.tolerance` also governs the re-proof at zero cost of a part the costed solve proved
// infeasible (even with the pre-test off); `pretest.cache` keeps its verdicts (PretestCache).
// With `pretest.skip_below` > 0 each such part (with a larger cap, and not passed by the cache)
// has its costed solve first, for at most that many iterations: a part optimal by then (within
// `pretest.skip_residual` and `pretest.skip_row` where > 0) or proved infeasible there is not
// pre-tested and that result stands; one at that iteration limit is pre-tested and its costed
// solve goes on from there.
struct JoinedSolve {
  LpResult r;
  std::vector<double> proof;
  // The infeasible parts' proofs that are Farkas certificates, each oriented so that its rate is
  // positive (oriented_certificate), zero elsewhere; empty where no part is infeasible.
  std::vector<double> certificate;
  // Per row, which of those certificates it carries (0, 1, … in the order found; −1: none).
  std::vector<int32_t> certificate_part;
  bool suspect = false;
  int64_t parts = 1, exact_parts = 0;
  // Every row of the parts that are infeasible (or, where none is, suspect), in the LP's
  // numbering: wider than the certificate's rows, for blaming a batch from a capped LP.
  std::vector<int64_t> failed_rows;
  // 1 for the columns of parts that stopped at their iteration (or time) limit; empty where none did.
  std::vector<char> capped_cols;
  // Per column, the primal weight ω its part's first-order solve ended with (0 where the exact
  // solver solved it, or the part was infeasible): the rounding keeps the last positive one per
  // column for the next round's parts (`warm_weight`).
  std::vector<double> weight;
  // The largest first-order part's ω: what it was asked to start from (0: the solver's own) and
  // where it ended (NaN: no first-order part).
  double start_weight = 0.0;
  double end_weight = std::numeric_limits<double>::quiet_NaN();
  double pretest_seconds = 0.0;  // of the zero-cost pre-tests (`pretest`), all parts together
};
// The exact solver's results on the parts of the last call, for the next one: a part whose LP has
// not changed since (no fixing reached it) gets its result again instead of a new solve. The
// solver is deterministic, so the result is the same, not an approximation of it. Measured:
// FAUST_r 021-024's finest rounding solved one unchanged part of fewer than 30 000 columns with
// Clp six times, 146 697 pivots and 5-7.5 minutes each, once with a round between that lacked it.
// So a result is kept until kKeepCalls calls in a row have not had its part. A run's path can
// still change with it: the stuck rule (stuck_after) counts failing rounds' seconds, and a reused
// result costs none. Measured on that pair (docs/results-log.md, thirty-eighth session): the five
// repeats took 32 s instead of 1 554, the rounding went on past the round where it had given up,
// and the run ended at a lower energy by another path. A failure (numerical trouble, or the
// pivot cap reached) is kept as well, and such a part goes to the first-order solver at once.
struct ExactCache {
  static constexpr int kKeepCalls = 4;
  struct Entry {
    LpProblem lp;
    int64_t max_iterations = 0;
    double time_limit = 0.0;
    LpResult r;
    int unused = 0;  // calls since its part was last seen
  };
  std::vector<Entry> entries;
  int64_t reused = 0;  // over all calls
  // The fewest columns of a part that reached the exact solver's cap (ExactCap): the parts of
  // this size or larger go to the first-order solver from then on, as if exact_below were this.
  // Measured (seventieth session, FAUST_r 043-063's level 6 at full resolution): Clp stopped at
  // its cap on parts of 24-26 k columns after 150-165 s, round after round, and took 400 s to
  // prove one infeasible, where PDHG proved such parts in 0.1-8 s; with them under exact_below
  // 10 000 the level finished in 39 s after 30 minutes of trims.
  int64_t capped_below = std::numeric_limits<int64_t>::max();
};

// Where the exact solver stops on a part and gives it to the first-order solver (0: no cap).
struct ExactCap {
  double pivots_per_column = 0.0;  // RoundingOptions::exact_pivots_per_column
  double seconds = 0.0;            // RoundingOptions::exact_part_seconds
};

// The zero-cost pre-test's verdicts on the parts of the last calls: a part whose constraints have
// not changed since (no fixing reached it) and that the pre-test did not prove infeasible then is
// not tested again. The pre-test starts cold, so with the same rows, right-hand side, cap,
// tolerance and starting weight its verdict is the same. Measured (seventieth session, FAUST_r
// 043-063 at full resolution): the same three parts of 44 k-978 k columns hit the 2 048-iteration
// cap round after round, 31 s of each 100-160 s round. Keyed by a 64-bit fingerprint of the part's
// rows and right-hand side (and its sizes), not a copy: the parts are millions of entries.
struct PretestCache {
  static constexpr int kKeepCalls = 4;
  // What the verdict depends on: the part's constraints, the cap, the tolerance, the starting ω.
  struct Key {
    uint64_t fingerprint = 0;
    int64_t rows = 0, cols = 0, nonzeros = 0, max_iterations = 0;
    double tolerance = 0.0, weight = 0.0;
    bool operator==(const Key&) const = default;
  };
  struct Entry {
    Key key;
    int unused = 0;  // calls since its part was last seen
  };
  std::vector<Entry> entries;
  int64_t reused = 0;  // over all calls
};

// The zero-cost pre-test of solve_in_parts: off where `iterations` is 0.
struct ZeroCostPretest {
  int64_t iterations = 0;
  double tolerance = 0.0;  // 0: the solve's own
  PretestCache* cache = nullptr;
  // > 0: each part's costed solve runs first for at most this many iterations; a part optimal by
  // then is not pre-tested (RoundingOptions::later_feasibility_skip_below).
  int64_t skip_below = 0;
  // … and only where its relative primal residual is at most this (0: any optimal one)
  double skip_residual = 0.0;
  // … and its largest violation of a row, ‖Ax−b‖∞, at most this (0: any; the skip's own bound,
  // RoundingOptions::later_feasibility_skip_row).
  double skip_row = 0.0;
};

// A fingerprint of an LP's constraints (sizes, rows of A, b): equal for equal constraints.
uint64_t constraint_fingerprint(const LpProblem& lp);

JoinedSolve solve_in_parts(const LpProblem& lp, SolverParams params, LpSolver& solver, LpSolver* exact,
                           int64_t exact_below, const SolverParams& exact_params, bool split,
                           const ExactCap& cap = {}, ExactCache* cache = nullptr,
                           const std::vector<double>* warm_weight = nullptr,
                           const std::function<void(const LpProblem&)>& slow_part = {},
                           double slow_part_seconds = 10.0, const ZeroCostPretest& pretest = {});

}  // namespace shapematch::detail

namespace shapematch {
using detail::JoinedSolve;
}
