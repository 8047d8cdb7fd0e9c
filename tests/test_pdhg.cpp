#include "divergence_watch.hpp"
#include "pdhg_backend.hpp"
#include "scaled_norm.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/matching.hpp"
#include "shapematch/pdhg.hpp"
#include "shapematch/shapes.hpp"
#include "test_helpers.hpp"
#include "parallel.hpp"
#include "thread_pool.hpp"

#include <doctest/doctest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <memory>
#include <set>
#include <tuple>

using namespace shapematch;

namespace {

LpProblem from_rows(int64_t cols, const std::vector<std::vector<std::pair<int, int>>>& rows, std::vector<double> b,
                    std::vector<double> c) {
  LpProblem p;
  p.a.rows = static_cast<int64_t>(rows.size());
  p.a.cols = cols;
  p.a.row_ptr.push_back(0);
  for (const auto& r : rows) {
    for (const auto& [j, s] : r) p.a.entry.push_back(static_cast<uint32_t>(j) | (s < 0 ? SignedCsr::kNegative : 0u));
    p.a.row_ptr.push_back(static_cast<uint32_t>(p.a.entry.size()));
  }
  p.at = transpose(p.a);
  p.b = std::move(b);
  p.c = std::move(c);
  return p;
}

// A random LP with the matching LP's structure: ±1 entries, a few per column, 0 ≤ x ≤ 1, and
// b = A x* for a random x* in the box so that it is feasible.
LpProblem random_lp(int64_t m, int64_t n, int per_column, std::mt19937& rng) {
  std::uniform_int_distribution<int64_t> row(0, m - 1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<std::vector<std::pair<int, int>>> rows(m);
  std::vector<double> xs(n), c(n);
  for (int64_t j = 0; j < n; ++j) {
    std::set<int64_t> used;
    while (int(used.size()) < per_column) used.insert(row(rng));
    for (int64_t i : used) rows[i].push_back({int(j), u(rng) < 0.5 ? -1 : 1});
    xs[j] = u(rng) < 0.3 ? 1.0 : (u(rng) < 0.5 ? 0.0 : u(rng));
    c[j] = u(rng) * 2.0 - 0.5;
  }
  for (auto& r : rows) std::sort(r.begin(), r.end());
  std::vector<double> b(m, 0.0);
  for (int64_t i = 0; i < m; ++i)
    for (const auto& [j, s] : rows[i]) b[i] += s * xs[j];
  return from_rows(n, rows, b, c);
}

// Both native backends: fp64 (the shaders' oracle) and fp32 with the dual kept relative to its
// anchor. Every solver-level test below holds for each.
const char* const kNative[] = {"pdhg-cpu", "pdhg-cpu-f32"};

SolverParams tight(double tol = 1e-5) {
  SolverParams p;
  p.tolerance = tol;
  p.max_iterations = 400000;
  return p;
}

// The matching LP of an octahedron and a sheared, bent copy of it (small, not the identity).
MatchingLp sheared_octahedron_lp() {
  const Mesh x = shapes::octahedron();
  const Mesh y = test::deformed(x, [](const Eigen::Vector3d& p) {
    return Eigen::Vector3d(1.3 * p.x() + 0.1 * p.z(), p.y(), 0.8 * p.z() + 0.05 * p.x() * p.y());
  });
  return build_matching_lp(x, compute_geometry(x), y, compute_geometry(y));
}

}  // namespace

TEST_CASE("scaled norm: Lanczos meets the exact largest singular value from below, in few steps") {
  // Random ±1 matrices with the matching LP's shape, scaled by arbitrary positive diagonals; the
  // reference is Eigen's SVD of the dense D_r A D_c.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.2, 3.0);
  for (auto [m, n, per] : {std::tuple{40, 90, 3}, std::tuple{150, 400, 4}, std::tuple{300, 1000, 5}}) {
    const LpProblem p = random_lp(m, n, per, rng);
    std::vector<double> r(m), d(n);
    for (auto& v : r) v = u(rng);
    for (auto& v : d) v = u(rng);
    Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(m, n);
    for (int64_t i = 0; i < m; ++i)
      for (uint32_t k = p.a.row_ptr[i]; k < p.a.row_ptr[i + 1]; ++k)
        dense(i, col_of(p.a.entry[k])) = r[i] * d[col_of(p.a.entry[k])] * (is_negative(p.a.entry[k]) ? -1.0 : 1.0);
    const double exact = Eigen::JacobiSVD<Eigen::MatrixXd>(dense).singularValues()(0);
    const detail::NormEstimate e = detail::scaled_norm(p.a, p.at, r, d, 200, 1e-3, 2, 1.0, 1e300);
    CAPTURE(m);
    CHECK(e.norm <= exact * (1 + 1e-12));
    CHECK(e.norm >= exact * (1 - 1e-3));  // what the solver's 1 % margin must cover
    CHECK(e.residual <= 1e-3);
    CHECK(e.steps < 60);
    // Stopping at the cap: the first step whose estimate reaches it.
    const detail::NormEstimate capped = detail::scaled_norm(p.a, p.at, r, d, 200, 1e-3, 2, 1.0, 0.5 * exact);
    CHECK(capped.norm >= 0.5 * exact);
    CHECK(capped.steps <= e.steps);
  }
}

TEST_CASE("pdhg-cpu: tiny LPs with known optima") {
  for (const char* solver : kNative) {
    CAPTURE(solver);
    // min x0 + 2 x1  s.t. x0 + x1 = 1  →  1.
    LpResult r = solve_lp(from_rows(2, {{{0, 1}, {1, 1}}}, {1}, {1, 2}), solver, tight());
    REQUIRE(r.status == LpStatus::Optimal);
    CHECK(r.objective == doctest::Approx(1.0).epsilon(1e-5));
    CHECK(r.lower_bound <= 1.0 + 1e-12);
    // min −x0 + x2  s.t. x0 − x1 = 0, x1 + x2 = 1  →  −1.
    r = solve_lp(from_rows(3, {{{0, 1}, {1, -1}}, {{1, 1}, {2, 1}}}, {0, 1}, {-1, 0, 1}), solver, tight());
    REQUIRE(r.status == LpStatus::Optimal);
    CHECK(r.objective == doctest::Approx(-1.0).epsilon(1e-5));
    CHECK(r.lower_bound <= -1.0 + 1e-12);
  }
}

TEST_CASE("pdhg-cpu: the residual in a row shows a local fault the relative residual lets pass") {
  // 4 000 rows x_2i + x_2i+1 = 1 at costs 1 and 2, started at their optimum (x_2i = 1, y = 1), and
  // a chain x_c0 = 1, x_ck − x_ck+1 = 0 of 100 columns at no cost, started at 0: ‖Ax−b‖₂ / (1 +
  // ‖b‖₂) is 1/64 there, so at --tol 0.02 the relative criterion holds while the chain is still
  // on its way (a fixing in a rounding round's part of 10⁵ rows is such a chain).
  constexpr int kRows = 4000, kChain = 100;
  std::vector<std::vector<std::pair<int, int>>> rows;
  std::vector<double> b(kRows, 1.0), c;
  for (int i = 0; i < kRows; ++i) {
    rows.push_back({{2 * i, 1}, {2 * i + 1, 1}});
    c.insert(c.end(), {1.0, 2.0});
  }
  const int c0 = 2 * kRows;
  rows.push_back({{c0, 1}});
  b.push_back(1.0);
  for (int k = 0; k + 1 < kChain; ++k) {
    rows.push_back({{c0 + k, 1}, {c0 + k + 1, -1}});
    b.push_back(0.0);
  }
  c.resize(c0 + kChain, 0.0);
  const LpProblem lp = from_rows(c0 + kChain, rows, b, c);
  SolverParams params;
  params.tolerance = 0.02;
  params.threads = 1;
  params.initial_x.assign(c0 + kChain, 0.0);
  for (int i = 0; i < kRows; ++i) params.initial_x[2 * i] = 1.0;
  params.initial_y.assign(lp.rows(), 0.0);
  std::fill(params.initial_y.begin(), params.initial_y.begin() + kRows, 1.0);
  for (const char* solver : kNative) {
    CAPTURE(solver);
    const LpResult loose = solve_lp(lp, solver, params);
    REQUIRE(loose.status == LpStatus::Optimal);
    CHECK(loose.primal_residual <= 0.02);
    // The worst row, recomputed here from x.
    double worst = 0.0;
    for (size_t i = 0; i < rows.size(); ++i) {
      double ax = 0.0;
      for (const auto& [j, sgn] : rows[i]) ax += sgn * loose.x[j];
      worst = std::max(worst, std::abs(ax - b[i]));
    }
    CHECK(loose.row_residual == doctest::Approx(worst).epsilon(1e-12));
    CHECK(loose.row_residual > 1e-2);
    CHECK(loose.row_residual > 5.0 * loose.primal_residual);
  }
}

TEST_CASE("pdhg-cpu: infeasibility is a status, found quickly") {
  // x0 + x1 = 3 is outside the box: found by presolve.
  for (const char* solver : kNative) {
    CAPTURE(solver);
    LpResult r = solve_lp(from_rows(2, {{{0, 1}, {1, 1}}}, {3}, {1, 1}), solver, tight());
    CHECK(r.status == LpStatus::Infeasible);
    // Each row alone is satisfiable, together they are not: x0 + x1 = 2 forces x0 = 1, x0 − x2 = −1 forces x0 = 0.
    r = solve_lp(from_rows(3, {{{0, 1}, {1, 1}}, {{0, 1}, {2, -1}}}, {2, -1}, {1, 0, 0}), solver, tight());
    CHECK(r.status == LpStatus::Infeasible);
    CHECK(r.iterations < 20000);
  }
}

TEST_CASE("pdhg-cpu: random structured LPs agree with Clp; the bound never exceeds the optimum") {
  std::mt19937 rng(42);
  for (int trial = 0; trial < 6; ++trial) {
    const LpProblem p = random_lp(40 + 10 * trial, 150 + 30 * trial, 3, rng);
    const LpResult exact = solve_lp(p, "clp-dual");
    REQUIRE(exact.status == LpStatus::Optimal);
    CAPTURE(trial);
    for (const char* solver : kNative) {
      CAPTURE(solver);
      const LpResult r = solve_lp(p, solver, tight(1e-5));
      REQUIRE(r.status == LpStatus::Optimal);
      CHECK(std::abs(r.objective - exact.objective) <= 1e-4 * std::max(1.0, std::abs(exact.objective)));
      CHECK(r.lower_bound <= exact.objective + 1e-9 * std::max(1.0, std::abs(exact.objective)));
    }
  }
}

TEST_CASE("pdhg-cpu: matching LPs agree with Clp within 1e-4 relative") {
  const Mesh x = shapes::octahedron();
  const Mesh y = test::deformed(x, [](const Eigen::Vector3d& p) {
    return Eigen::Vector3d(1.3 * p.x() + 0.1 * p.z(), p.y(), 0.8 * p.z() + 0.05 * p.x() * p.y());
  });
  const Geometry gx = compute_geometry(x), gy = compute_geometry(y);
  const MatchingLp m = build_matching_lp(x, gx, y, gy);
  const LpResult exact = solve_lp(m.lp, "clp-dual");
  REQUIRE(exact.status == LpStatus::Optimal);
  // fp32 iterates without the anchored dual stalled on this LP at a gap of ~1e-5 (docs/architecture.md,
  // "Precision"): the fp32 backend must reach the same tolerance.
  for (const char* solver : kNative) {
      CAPTURE(solver);
      SolverParams params = tight(1e-5);
      const LpResult r = solve_lp(m.lp, solver, params);
      REQUIRE(r.status == LpStatus::Optimal);
      CHECK(std::abs(r.objective - exact.objective) <= 1e-4 * std::abs(exact.objective));
      CHECK(r.lower_bound <= exact.objective * (1 + 1e-9));
      CHECK(r.lower_bound >= exact.objective * (1 - 1e-3));

      // Warm start from the optimum needs far fewer iterations than a cold start.
      params.initial_x = r.x;
      params.initial_y = r.y;
      const LpResult warm = solve_lp(m.lp, solver, params);
      REQUIRE(warm.status == LpStatus::Optimal);
      CHECK(warm.iterations * 4 <= r.iterations);
  }
}

TEST_CASE("pdhg-cpu: a warm start goes on with the primal weight its solve ended with") {
  const MatchingLp m = sheared_octahedron_lp();
  SolverParams params = tight(1e-5);
  const LpResult r = solve_lp(m.lp, "pdhg-cpu", params);
  REQUIRE(r.status == LpStatus::Optimal);
  REQUIRE(std::isfinite(r.primal_weight));
  CHECK(r.primal_weight > 0.0);
  CHECK(std::isnan(solve_lp(m.lp, "clp-dual").primal_weight));

  // The same LP with its costs moved a little: from the old optimum, with the old ω, and with
  // PDHG's own initial ω (1).
  LpProblem moved = m.lp;
  for (int64_t j = 0; j < moved.cols(); ++j) moved.c[j] *= 1.0 + 0.05 * std::sin(double(j));
  params.initial_x = r.x;
  params.initial_y = r.y;
  const LpResult reset = solve_lp(moved, "pdhg-cpu", params);
  params.initial_primal_weight = r.primal_weight;
  const LpResult carried = solve_lp(moved, "pdhg-cpu", params);
  params.initial_x.clear();
  params.initial_y.clear();
  params.initial_primal_weight = 0.0;
  const LpResult cold = solve_lp(moved, "pdhg-cpu", params);
  REQUIRE(reset.status == LpStatus::Optimal);
  REQUIRE(carried.status == LpStatus::Optimal);
  REQUIRE(cold.status == LpStatus::Optimal);
  MESSAGE("iterations: cold " << cold.iterations << ", warm at ω 1 " << reset.iterations << ", warm at ω "
                              << r.primal_weight << " " << carried.iterations);
  CHECK(std::abs(carried.objective - cold.objective) <= 1e-4 * std::abs(cold.objective));
  CHECK(carried.iterations <= reset.iterations);
  CHECK(carried.iterations < cold.iterations);
}

TEST_CASE("pdhg-cpu: a snapshot is a point the solve can start again from, near where it was") {
  const MatchingLp m = sheared_octahedron_lp();
  SolverParams params = tight(1e-6);
  std::vector<SolveSnapshot> seen;
  params.snapshot_seconds = 1e-9;  // (at every residual check)
  params.snapshot = [&](const SolveSnapshot& s) { seen.push_back(s); };
  const LpResult whole = solve_lp(m.lp, "pdhg-cpu", params);
  REQUIRE(whole.status == LpStatus::Optimal);
  REQUIRE(seen.size() >= 2);
  for (const SolveSnapshot& s : seen) {
    CHECK(s.x.size() == size_t(m.lp.cols()));
    CHECK(s.y.size() == size_t(m.lp.rows()));
    CHECK(s.primal_weight > 0.0);
    CHECK(s.iterations <= whole.iterations);
    CHECK(s.seconds <= whole.seconds);
  }
  CHECK(seen.back().seconds > seen.front().seconds);
  CHECK(seen.back().iterations > seen.front().iterations);
  // From the last one, with its ω: the rest of the solve, not all of it, to the same optimum.
  const SolveSnapshot& last = seen.back();
  SolverParams again = tight(1e-6);
  again.initial_x = last.x;
  again.initial_y = last.y;
  again.initial_primal_weight = last.primal_weight;
  const LpResult rest = solve_lp(m.lp, "pdhg-cpu", again);
  REQUIRE(rest.status == LpStatus::Optimal);
  MESSAGE("whole " << whole.iterations << " iterations, snapshot at " << last.iterations << ", the rest "
                   << rest.iterations);
  CHECK(rest.iterations <= whole.iterations - last.iterations + 64);
  CHECK(std::abs(rest.objective - whole.objective) <= 1e-5 * (1.0 + std::abs(whole.objective)));
  // Gone on with the iterations before it counted (SolverParams::iterations_before), its restarts
  // come as they would have: the rest of the solve, where the plain warm start restarts as a cold
  // one (at every residual check at first, each restart moving ω) and takes up to 4× as long.
  // Measured here: three random LPs of 2 176, 1 216 and 4 032 iterations, gone on from every
  // snapshot past the middle: 10 432 iterations plain against 5 440 counted (5 696 left).
  int64_t plain_sum = 0, counted_sum = 0, left_sum = 0;
  for (int trial = 0; trial < 3; ++trial) {
    CAPTURE(trial);
    std::mt19937 rng(5 + trial);
    const LpProblem p = random_lp(70 + 20 * trial, 240 + 40 * trial, 3, rng);
    SolverParams q = tight(1e-8);
    std::vector<SolveSnapshot> snaps;
    q.snapshot_seconds = 1e-9;
    q.snapshot = [&](const SolveSnapshot& s) { snaps.push_back(s); };
    const LpResult all = solve_lp(p, "pdhg-cpu", q);
    REQUIRE(all.status == LpStatus::Optimal);
    for (size_t k = 0; k < snaps.size(); k += 1 + snaps.size() / 6) {
      if (2 * snaps[k].iterations < all.iterations) continue;
      CAPTURE(snaps[k].iterations);
      SolverParams from = tight(1e-8);
      from.initial_x = snaps[k].x;
      from.initial_y = snaps[k].y;
      from.initial_primal_weight = snaps[k].primal_weight;
      const LpResult plain = solve_lp(p, "pdhg-cpu", from);
      from.iterations_before = snaps[k].iterations;
      const LpResult counted = solve_lp(p, "pdhg-cpu", from);
      CHECK(counted.status == LpStatus::Optimal);
      CHECK(counted.iterations <= all.iterations - snaps[k].iterations + 128);
      plain_sum += plain.iterations;
      counted_sum += counted.iterations;
      left_sum += all.iterations - snaps[k].iterations;
    }
  }
  MESSAGE("gone on past the middle: " << plain_sum << " iterations plain, " << counted_sum << " counted (" << left_sum
                                      << " left)");
  CHECK(counted_sum < plain_sum);
  {  // (A cold solve has none before it: the count is not used.)
    SolverParams cold = tight(1e-6);
    const LpResult a = solve_lp(m.lp, "pdhg-cpu", cold);
    cold.iterations_before = 1000000;
    CHECK(solve_lp(m.lp, "pdhg-cpu", cold).iterations == a.iterations);
  }
  // Unset or at 0 seconds: never called.
  params.snapshot_seconds = 0.0;
  seen.clear();
  solve_lp(m.lp, "pdhg-cpu", params);
  CHECK(seen.empty());
  // The first call after its own wait (here none), then every snapshot_seconds (here never again).
  params.snapshot_seconds = 1e9;
  solve_lp(m.lp, "pdhg-cpu", params);
  CHECK(seen.empty());
  params.snapshot_first_seconds = 0.0;
  solve_lp(m.lp, "pdhg-cpu", params);
  REQUIRE(seen.size() == 1);
  CHECK(seen.front().iterations == 64);  // (at the first residual check)
}

TEST_CASE("pdhg-cpu: going on from a snapshot's state repeats the uninterrupted solve bit for bit") {
  // SolverParams::exact_state: each snapshot carries the iterate, its anchor, the step, ω and the
  // restart and watch counters; a solve given one of them (resume_state) makes the iterations the
  // uninterrupted one made after it: the same iterates, restarts and end, bit for bit.
  const auto same = [](const LpResult& a, const LpResult& b) {
    CHECK(a.status == b.status);
    CHECK(a.x == b.x);
    CHECK(a.y == b.y);
    CHECK(a.primal_weight == b.primal_weight);
    // (NaN for a diverging solve's objective: no point to evaluate)
    CHECK((a.objective == b.objective || (std::isnan(a.objective) && std::isnan(b.objective))));
    CHECK(a.lower_bound == b.lower_bound);
  };
  struct Case {
    LpProblem lp;
    bool watched;  // (an infeasible LP stopped by the divergence watch: its windows go on too)
  };
  std::vector<Case> cases;
  cases.push_back({sheared_octahedron_lp().lp, false});
  for (int trial = 0; trial < 2; ++trial) {
    std::mt19937 rng(11 + trial);
    cases.push_back({random_lp(70 + 30 * trial, 260, 3, rng), false});
  }
  cases.push_back({from_rows(3, {{{0, 1}, {1, 1}}, {{0, 1}, {1, 1}, {2, -1}}}, {1, 1.5}, {800, 900, 1e4}), true});
  int resumed = 0, after_restart = 0;
  for (size_t c = 0; c < cases.size(); ++c) {
    CAPTURE(c);
    const LpProblem& p = cases[c].lp;
    SolverParams params = tight(1e-8);
    params.threads = 1;
    params.max_iterations = 20000;
    params.stop_on_divergence = cases[c].watched;
    params.exact_state = true;
    std::vector<SolveSnapshot> seen;
    params.snapshot_seconds = 1e-9;  // (at every residual check)
    params.snapshot = [&](const SolveSnapshot& s) { seen.push_back(s); };
    const LpResult whole = solve_lp(p, "pdhg-cpu", params);
    REQUIRE(seen.size() >= 4);
    CHECK((whole.status == (cases[c].watched ? LpStatus::Diverging : LpStatus::Optimal)));
    for (size_t k = 0; k < seen.size(); k += 1 + seen.size() / 7) {
      CAPTURE(seen[k].iterations);
      REQUIRE(seen[k].state != nullptr);
      const SolverState& st = *seen[k].state;
      CHECK(st.solver == "pdhg-cpu");
      CHECK(st.iterations == seen[k].iterations);
      CHECK(st.x.size() == size_t(p.cols()));
      CHECK(st.y0.size() == size_t(p.rows()));
      if (st.since_restart == 0) ++after_restart;
      SolverParams from = params;
      from.snapshot = {};
      from.resume_state = seen[k].state;
      from.max_iterations = params.max_iterations - seen[k].iterations;
      const LpResult rest = solve_lp(p, "pdhg-cpu", from);
      CHECK(rest.iterations == whole.iterations - seen[k].iterations);
      same(rest, whole);
      ++resumed;
    }
    // Another LP of the same sizes (other costs, another right-hand side, another objective scale),
    // other options, or another solver: the state is not theirs, and is ignored.
    SolverParams plain = params;
    plain.snapshot = {};
    SolverParams given = plain;
    given.resume_state = seen[seen.size() / 2].state;
    LpProblem other = p;
    for (double& v : other.c) v += 0.25;
    same(solve_lp(other, "pdhg-cpu", given), solve_lp(other, "pdhg-cpu", plain));
    other = p;
    other.b[0] += 0.125;
    same(solve_lp(other, "pdhg-cpu", given), solve_lp(other, "pdhg-cpu", plain));
    other = p;
    other.objective_scale *= 2.0;
    same(solve_lp(other, "pdhg-cpu", given), solve_lp(other, "pdhg-cpu", plain));
    PdhgOptions reflected;
    reflected.reflection = 0.9;
    PdhgSolver otherwise(PdhgBackendKind::Cpu, reflected);
    same(otherwise.solve(p, given), otherwise.solve(p, plain));
    same(solve_lp(p, "pdhg-cpu-f32", given), solve_lp(p, "pdhg-cpu-f32", plain));
    // On another thread count its sums add in another order: the same point goes on (the state's
    // device says where it was made), to the same end within the tolerance.
    CHECK(seen.back().state->device == "cpu (1 threads)");
    if (!cases[c].watched) {
      SolverParams wider = given;
      wider.threads = 2;
      const LpResult on = solve_lp(p, "pdhg-cpu", wider);
      CHECK(on.status == LpStatus::Optimal);
      CHECK(std::abs(on.objective - whole.objective) <= 1e-6 * (1.0 + std::abs(whole.objective)));
      // (From the state, halfway: about the rest of the solve, not all of it.)
      const int64_t rest = whole.iterations - seen[seen.size() / 2].iterations;
      CHECK(on.iterations <= rest + rest / 2 + 64);
      CHECK(on.iterations < whole.iterations);
    }
  }
  {  // At the iteration cap the loop ends: no state there (a solve gone on from it would make one more).
    SolverParams capped = tight(1e-12);
    capped.max_iterations = 256;
    capped.exact_state = true;
    std::vector<SolveSnapshot> at;
    capped.snapshot_seconds = 1e-9;
    capped.snapshot = [&](const SolveSnapshot& s) { at.push_back(s); };
    REQUIRE(solve_lp(cases[0].lp, "pdhg-cpu", capped).status == LpStatus::IterationLimit);
    REQUIRE(at.size() == 4);
    CHECK(at[2].state != nullptr);
    CHECK(at[3].state == nullptr);
  }
  MESSAGE(resumed << " solves gone on from a state, " << after_restart << " of them just after a restart");
  CHECK(after_restart >= 1);
  CHECK(after_restart < resumed);
  // The fp32 backend keeps its dual relative to the anchor in single precision: no state.
  SolverParams f32 = tight(1e-6);
  f32.exact_state = true;
  std::vector<SolveSnapshot> seen;
  f32.snapshot_seconds = 1e-9;
  f32.snapshot = [&](const SolveSnapshot& s) { seen.push_back(s); };
  solve_lp(sheared_octahedron_lp().lp, "pdhg-cpu-f32", f32);
  REQUIRE_FALSE(seen.empty());
  CHECK(seen.front().state == nullptr);
  // Without exact_state, none either (two copies of the iterate more: only where asked).
  f32.exact_state = false;
  seen.clear();
  solve_lp(sheared_octahedron_lp().lp, "pdhg-cpu", f32);
  REQUIRE_FALSE(seen.empty());
  CHECK(seen.front().state == nullptr);
}

TEST_CASE("pdhg-cpu: the cold primal weight starts cold solves only; an explicit ω wins") {
  const Mesh x = shapes::octahedron();
  const Mesh y = test::deformed(x, [](const Eigen::Vector3d& p) { return Eigen::Vector3d(1.2 * p.x(), p.y(), 0.9 * p.z()); });
  const MatchingLp m = build_matching_lp(x, compute_geometry(x), y, compute_geometry(y));
  // One check interval, no restart yet: ω where it stopped is the ω it started from.
  SolverParams params;
  params.max_iterations = 64;
  params.threads = 1;
  params.cold_primal_weight = 7.0;
  CHECK(solve_lp(m.lp, "pdhg-cpu", params).primal_weight == 7.0);
  params.initial_primal_weight = 3.0;
  CHECK(solve_lp(m.lp, "pdhg-cpu", params).primal_weight == 3.0);
  params.initial_primal_weight = 0.0;
  params.initial_x.assign(size_t(m.lp.cols()), 0.5);  // a warm start: PDHG's own ω (1)
  params.initial_y.assign(size_t(m.lp.rows()), 0.0);
  CHECK(solve_lp(m.lp, "pdhg-cpu", params).primal_weight == 1.0);
  params.initial_x.clear();
  params.initial_y.clear();
  params.cold_primal_weight = 0.0;
  CHECK(solve_lp(m.lp, "pdhg-cpu", params).primal_weight == 1.0);
}

TEST_CASE("pdhg-cpu: the cold restart fraction applies to cold solves only") {
  // Small enough for milliseconds, slow enough that restarts are artificial ones, not decay.
  const Mesh x = shapes::bent_finger(0.0, 6, 5);
  const Mesh y = shapes::bent_finger(60.0, 6, 5);
  const MatchingLp m = build_matching_lp(x, compute_geometry(x), y, compute_geometry(y));
  SolverParams params;
  params.threads = 1;
  params.tolerance = 1e-8;
  const LpResult plain = solve_lp(m.lp, "pdhg-cpu", params);
  PdhgOptions sooner;
  sooner.restart_artificial = 0.2;
  const LpResult by_options = PdhgSolver(PdhgBackendKind::Cpu, sooner).solve(m.lp, params);
  params.cold_restart_artificial = 0.2;
  const LpResult cold = solve_lp(m.lp, "pdhg-cpu", params);
  REQUIRE(plain.status == LpStatus::Optimal);
  REQUIRE(cold.status == LpStatus::Optimal);
  MESSAGE("iterations at 0.36 " << plain.iterations << ", at 0.2 " << cold.iterations);
  // The parameter is the option, for a cold start…
  CHECK(cold.iterations == by_options.iterations);
  CHECK(cold.objective == by_options.objective);
  CHECK(cold.primal_weight == by_options.primal_weight);
  // … and it changes the run (else the checks above would hold for an ignored parameter).
  CHECK((cold.iterations != plain.iterations || cold.primal_weight != plain.primal_weight));
  // A warm start keeps the solver's own fraction.
  params.initial_x.assign(size_t(m.lp.cols()), 0.5);
  params.initial_y.assign(size_t(m.lp.rows()), 0.0);
  const LpResult warm = solve_lp(m.lp, "pdhg-cpu", params);
  params.cold_restart_artificial = 0.0;
  const LpResult warm_plain = solve_lp(m.lp, "pdhg-cpu", params);
  CHECK(warm.iterations == warm_plain.iterations);
  CHECK(warm.objective == warm_plain.objective);
  CHECK(warm.primal_weight == warm_plain.primal_weight);
}

TEST_CASE("thread pool: every chunk runs exactly once, loop after loop") {
  for (const int threads : {1, 2, 3, 5}) {
    detail::ThreadPool pool(threads);
    CHECK(pool.size() == threads);
    std::vector<std::atomic<int>> runs(40);
    for (int loop = 0; loop < 3000; ++loop) {
      const int chunks = loop % 41;  // 0 chunks included; more chunks than threads and fewer
      pool.run(chunks, [&](int c) { runs[c].fetch_add(1); });
      for (int c = 0; c < chunks; ++c) REQUIRE(runs[c].exchange(0) == 1);
      for (int c = chunks; c < 40; ++c) REQUIRE(runs[c].load() == 0);
    }
  }
}

TEST_CASE("thread pool: a chunk that throws is rethrown to the caller after every chunk ran") {
  for (const int threads : {1, 2, 4}) {
    CAPTURE(threads);
    detail::ThreadPool pool(threads);
    for (int loop = 0; loop < 200; ++loop) {
      std::atomic<int> ran{0};
      const int bad = loop % 7;
      CHECK_THROWS_AS(pool.run(7,
                               [&](int c) {
                                 ran.fetch_add(1);
                                 if (c == bad) throw std::runtime_error("chunk failed");
                               }),
                      std::runtime_error);
      CHECK(ran.load() == 7);
      // The pool is still usable afterwards.
      std::atomic<int> again{0};
      pool.run(5, [&](int) { again.fetch_add(1); });
      CHECK(again.load() == 5);
    }
  }
}

TEST_CASE("parallel_sort: the same order as std::sort for any number of threads") {
  std::mt19937_64 rng(3);
  for (const int64_t n : {0, 1, 1000, 65536 * 3 + 17}) {
    std::vector<int64_t> v(n);
    for (auto& x : v) x = int64_t(rng() % 50000);  // many equal keys
    std::vector<int64_t> expected = v;
    std::sort(expected.begin(), expected.end());
    for (const int threads : {1, 2, 3, 4}) {
      CAPTURE(n);
      CAPTURE(threads);
      std::vector<int64_t> w = v;
      detail::parallel_sort(w.data(), n, threads);
      CHECK(w == expected);
    }
  }
}

TEST_CASE("parallel_rows: every row once, with rows of very different lengths") {
  // Many short rows, then a few long ones (a matching LP's A), and the reverse.
  for (const bool long_first : {false, true}) {
    std::vector<uint32_t> row_ptr{0};
    for (int i = 0; i < 60000; ++i) {
      const bool is_long = long_first ? i < 40 : i >= 59960;
      row_ptr.push_back(row_ptr.back() + (is_long ? 3000 : 3));
    }
    for (const int threads : {1, 2, 3, 4}) {
      CAPTURE(long_first);
      CAPTURE(threads);
      std::vector<std::atomic<int>> seen(row_ptr.size() - 1);
      detail::parallel_rows(row_ptr, threads, [&](int64_t i) { seen[i].fetch_add(1); });
      int64_t wrong = 0;
      for (auto& v : seen) wrong += v.load() != 1;
      CHECK(wrong == 0);
    }
  }
  detail::parallel_rows(std::vector<uint32_t>{0}, 2, [](int64_t) { FAIL("no rows to visit"); });
}

TEST_CASE("scaled_norm: the same estimate for any number of threads") {
  // Large enough for several blocks of the blocked vector sums and several chunks per loop.
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(0.2, 3.0);
  const LpProblem p = random_lp(20000, 50000, 4, rng);
  std::vector<double> r(p.rows()), d(p.cols());
  for (auto& v : r) v = u(rng);
  for (auto& v : d) v = u(rng);
  const detail::NormEstimate one = detail::scaled_norm(p.a, p.at, r, d, 40, 1e-6, 1, 1.0, 1e300);
  CHECK(one.steps > 10);
  for (const int threads : {2, 3, 4}) {
    const detail::NormEstimate e = detail::scaled_norm(p.a, p.at, r, d, 40, 1e-6, threads, 1.0, 1e300);
    CAPTURE(threads);
    CHECK(e.norm == one.norm);
    CHECK(e.residual == one.residual);
    CHECK(e.steps == one.steps);
  }
  // A lower bound: ‖Ã‖ ≥ ‖Ãx‖/‖x‖ for x = 1.
  std::vector<double> ax(p.rows()), ones(p.cols());
  for (int64_t j = 0; j < p.cols(); ++j) ones[j] = d[j];
  spmv(p.a, ones.data(), ax.data());
  double num = 0.0;
  for (int64_t i = 0; i < p.rows(); ++i) num += r[i] * r[i] * ax[i] * ax[i];
  CHECK(one.norm >= std::sqrt(num / double(p.cols())));
}

TEST_CASE("parallel_chunks: a chunk that throws is rethrown after every chunk ran") {
  for (const int threads : {1, 2, 4}) {
    for (const int bad : {0, threads - 1}) {
      CAPTURE(threads);
      CAPTURE(bad);
      std::atomic<int64_t> covered{0};
      CHECK_THROWS_AS(detail::parallel_chunks(100000, threads,
                                              [&](int64_t b, int64_t e, int chunk) {
                                                covered.fetch_add(e - b);
                                                if (chunk == bad) throw std::runtime_error("chunk failed");
                                              }),
                      std::runtime_error);
      CHECK(covered.load() == 100000);
    }
  }
}

// The native backend splits rows into chunks of equal cost, sums rows in pairs and hands chunks
// to whichever thread is free; none of that may change an iterate, only the grouping of the
// reported sums (which split evenly by thread count, as before).
TEST_CASE("pdhg-cpu: iterates are bitwise the same on any number of threads") {
  // Rows of 0..12 entries, an odd count, then long rows at the end like the π rows of A.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int64_t n = 3001, m = 2001;
  SignedCsr a;
  a.rows = m;
  a.cols = n;
  a.row_ptr.push_back(0);
  for (int64_t i = 0; i < m; ++i) {
    std::set<uint32_t> cols;
    const int count = i >= m - 9 ? 300 + int(i % 3) * 57 : int(rng() % 13);
    while (int(cols.size()) < count) cols.insert(uint32_t(rng() % n));
    for (const uint32_t j : cols) a.entry.push_back(j | (u(rng) < 0.5 ? SignedCsr::kNegative : 0u));
    a.row_ptr.push_back(uint32_t(a.entry.size()));
  }
  const SignedCsr at = transpose(a);
  detail::ScaledLp lp;
  lp.a = &a;
  lp.at = &at;
  std::vector<double> x(n), y(m);
  for (int64_t j = 0; j < n; ++j) {
    lp.col_scale.push_back(0.5 + u(rng));
    lp.c.push_back(2.0 * u(rng) - 0.5);
    x[j] = u(rng) < 0.3 ? 0.0 : u(rng) / lp.col_scale.back();
  }
  for (int64_t i = 0; i < m; ++i) {
    lp.row_scale.push_back(0.5 + u(rng));
    lp.b.push_back(3.0 * u(rng) - 1.0);
    y[i] = 2.0 * u(rng) - 1.0;
  }
  const detail::Step step{0.05, 0.05, 1.0};

  const auto run = [&](int threads, std::vector<double>& xhat, std::vector<double>& yhat) {
    const auto backend = detail::make_cpu_backend(threads);
    backend->load(lp, x, y);
    backend->iterate(1, 0, step);
    backend->iterate(63, 1, step);
    backend->restart();
    const detail::BatchStats s = backend->iterate(64, 0, step);
    backend->read(xhat, yhat);
    return s;
  };
  // One iteration against the kernel formulas of pdhg_backend.hpp, each row summed in entry order
  // except A's long rows (> kLongRow entries; the last nine): lane t mod kLongLanes, then the tree.
  {
    const auto backend = detail::make_cpu_backend(3);
    backend->load(lp, x, y);
    backend->iterate(1, 0, step);
    std::vector<double> xhat, yhat;
    backend->read(xhat, yhat);
    const auto row_sum = [](const SignedCsr& mat, int64_t i, const std::vector<double>& v) {
      double s = 0.0;
      for (uint32_t k = mat.row_ptr[i]; k < mat.row_ptr[i + 1]; ++k)
        s += is_negative(mat.entry[k]) ? -v[col_of(mat.entry[k])] : v[col_of(mat.entry[k])];
      return s;
    };
    const auto a_row_sum = [&](int64_t i, const std::vector<double>& v) {
      const uint32_t begin = a.row_ptr[i], count = a.row_ptr[i + 1] - begin;
      if (count <= detail::kLongRow) return row_sum(a, i, v);
      std::vector<double> lane(detail::kLongLanes, 0.0);
      for (uint32_t t = 0; t < count; ++t) {
        const uint32_t e = a.entry[begin + t];
        lane[t % detail::kLongLanes] += is_negative(e) ? -v[col_of(e)] : v[col_of(e)];
      }
      for (uint32_t h = detail::kLongLanes / 2; h > 0; h /= 2)
        for (uint32_t l = 0; l < h; ++l) lane[l] += lane[l + h];
      return lane[0];
    };
    REQUIRE(a.row_ptr[m] - a.row_ptr[m - 1] > detail::kLongRow);
    std::vector<double> yr(m), xr(n);
    for (int64_t i = 0; i < m; ++i) yr[i] = lp.row_scale[i] * y[i];
    int64_t wrong_x = 0, wrong_y = 0;
    for (int64_t j = 0; j < n; ++j) {
      const double d = lp.col_scale[j];
      const double xh = std::clamp(x[j] - step.tau * (lp.c[j] - d * row_sum(at, j, yr)), 0.0, 1.0 / d);
      xr[j] = d * (2.0 * xh - x[j]);
      wrong_x += xh != xhat[j];
    }
    for (int64_t i = 0; i < m; ++i)
      wrong_y += y[i] + step.sigma * (lp.b[i] - lp.row_scale[i] * a_row_sum(i, xr)) != yhat[i];
    CHECK(wrong_x == 0);
    CHECK(wrong_y == 0);
  }

  std::vector<double> x1, y1;
  const detail::BatchStats s1 = run(1, x1, y1);
  CHECK(s1.dx2 > 0.0);  // the iterates moved
  CHECK(std::count(x1.begin(), x1.end(), 0.0) < n);
  for (const int threads : {2, 3, 8}) {
    CAPTURE(threads);
    std::vector<double> xt, yt;
    const detail::BatchStats st = run(threads, xt, yt);
    CHECK(std::memcmp(xt.data(), x1.data(), n * sizeof(double)) == 0);
    CHECK(std::memcmp(yt.data(), y1.data(), m * sizeof(double)) == 0);
    CHECK(std::abs(st.dx2 - s1.dx2) <= 1e-12 * s1.dx2);
    CHECK(std::abs(st.residual2 - s1.residual2) <= 1e-12 * s1.residual2);
  }
}

TEST_CASE("pdhg-cpu: a diverging infeasible LP stops early when asked, with the dual's growth as its ray") {
  // x0 + x1 = 1 and x0 + x1 = 1.5: each row alone is satisfiable, together they are not. With
  // large costs, the dual bound needs a long way to pass the largest feasible objective.
  const LpProblem p = from_rows(3, {{{0, 1}, {1, 1}}, {{0, 1}, {1, 1}, {2, -1}}}, {1, 1.5}, {800, 900, 1e4});
  for (const char* solver : kNative) {
    CAPTURE(solver);
    SolverParams params = tight();
    params.max_iterations = 50000;
    const LpResult proof = solve_lp(p, solver, params);
    REQUIRE(proof.status == LpStatus::Infeasible);  // without the option: a proof, however long
    params.stop_on_divergence = true;
    const LpResult r = solve_lp(p, solver, params);
    CHECK(r.status == LpStatus::Diverging);
    CHECK(r.iterations < proof.iterations);
    REQUIRE(r.y.size() == 2);
    // The ray of this LP is (−1, +1): both rows, opposite signs.
    CHECK(r.y[0] < 0);
    CHECK(r.y[1] > 0);
    CHECK(std::abs(r.y[0] + r.y[1]) < 0.2 * std::abs(r.y[1]));
    CHECK(farkas_rate(p, r.y) > 0.0);  // a certificate on its own here
    CHECK(std::string(to_string(r.status)) == "diverging");
  }
}

TEST_CASE("pdhg-cpu: a solve started again from a snapshot watches on where its watch was") {
  // The LP above, watched: each snapshot carries the watch's state (the windows seen so far), and
  // a warm solve given a state goes on from it: one window short of the creeping rule's stop, it
  // stops at its first window's end, which a fresh watch never does (it compares windows).
  const LpProblem p = from_rows(3, {{{0, 1}, {1, 1}}, {{0, 1}, {1, 1}, {2, -1}}}, {1, 1.5}, {800, 900, 1e4});
  constexpr int64_t kWindow = detail::DivergenceWatch::kWindow;
  for (const char* solver : kNative) {
    CAPTURE(solver);
    SolverParams params = tight();
    params.max_iterations = 50000;
    params.stop_on_divergence = true;
    std::vector<SolveSnapshot> seen;
    params.snapshot_seconds = 1e-9;  // (at every residual check)
    params.snapshot = [&](const SolveSnapshot& s) { seen.push_back(s); };
    const LpResult whole = solve_lp(p, solver, params);
    REQUIRE(whole.status == LpStatus::Diverging);
    REQUIRE(whole.iterations > kWindow);
    const SolveSnapshot* at_window = nullptr;  // the first snapshot after a window's end
    for (const SolveSnapshot& s : seen) {
      CHECK(s.watch.windows == s.iterations / kWindow);
      if (!at_window && s.watch.windows == 1) at_window = &s;
    }
    REQUIRE(at_window != nullptr);
    CHECK(at_window->watch.bound != 0.0);  // (the window's numbers, not a fresh state's)
    SolverParams again = params;
    again.snapshot = {};
    again.initial_x = at_window->x;
    again.initial_y = at_window->y;
    again.initial_primal_weight = at_window->primal_weight;
    again.max_iterations = kWindow;
    DivergenceWatchState near_stop = at_window->watch;
    near_stop.creeping = 3;                   // (kCreepingWindows − 1)
    near_stop.primal = near_stop.gap = 0.0;  // (any residual is flat, any gap growing)
    again.initial_watch = near_stop;
    const LpResult on = solve_lp(p, solver, again);
    CHECK(on.status == LpStatus::Diverging);
    CHECK(on.iterations == kWindow);
    again.initial_watch = {};
    CHECK(solve_lp(p, solver, again).status == LpStatus::IterationLimit);
    // A cold solve is a new one: the state is not used.
    SolverParams cold = params;
    cold.snapshot = {};
    cold.initial_watch = near_stop;
    CHECK(solve_lp(p, solver, cold).iterations == whole.iterations);
    // Unwatched, a snapshot's watch stays fresh.
    seen.clear();
    params.stop_on_divergence = false;
    params.max_iterations = 4 * kWindow;
    solve_lp(p, solver, params);
    REQUIRE_FALSE(seen.empty());
    CHECK(seen.back().watch == DivergenceWatchState{});
  }
}

TEST_CASE("pdhg-cpu: an infeasible LP's ray names the rows of the infeasibility, its dual costly rows too") {
  // x0 + x1 = 1 and x0 + x1 − x2 = 1.5 clash (their ray is (−1, +1, 0)); x3 + x4 = 1 beside them
  // costs 10 either way, its ordinary dual 10. The proof's dual point holds that 10 next to a ray
  // only about twice as long, so its large entries name all three rows; the dual's growth after
  // the proof (PdhgOptions::ray_iterations), the first two alone.
  const LpProblem p =
      from_rows(5, {{{0, 1}, {1, 1}}, {{0, 1}, {1, 1}, {2, -1}}, {{3, 1}, {4, 1}}}, {1, 1.5, 1}, {0, 0, 0, 10, 10});
  auto largest = [](const std::vector<double>& v) {
    double top = 0.0;
    for (double e : v) top = std::max(top, std::abs(e));
    return top;
  };
  PdhgOptions ray;
  ray.ray_iterations = 256;
  for (const PdhgBackendKind backend : {PdhgBackendKind::Cpu, PdhgBackendKind::CpuF32}) {
    const LpResult r = PdhgSolver(backend, ray).solve(p, tight());
    REQUIRE(r.status == LpStatus::Infeasible);
    REQUIRE(r.y.size() == 3);
    CHECK(std::abs(r.y[2]) >= 0.1 * largest(r.y));
    REQUIRE(r.ray.size() == 3);
    CHECK(farkas_rate(p, r.ray) > 0.0);
    CHECK(r.ray[0] < 0.0);
    CHECK(r.ray[1] > 0.0);
    CHECK(std::abs(r.ray[2]) < 0.01 * largest(r.ray));
  }
  // Without the iterations after the proof (the default): no ray.
  const LpResult r = solve_lp(p, "pdhg-cpu", tight());
  CHECK(r.status == LpStatus::Infeasible);
  CHECK(r.ray.empty());
}

TEST_CASE("pdhg-cpu: feasible LPs never stop as diverging") {
  std::mt19937 rng(5);
  SolverParams params = tight(1e-8);
  params.stop_on_divergence = true;
  int64_t longest = 0;
  for (int trial = 0; trial < 4; ++trial) {
    const LpProblem p = random_lp(40 + 10 * trial, 150 + 30 * trial, 3, rng);
    CAPTURE(trial);
    const LpResult r = solve_lp(p, "pdhg-cpu", params);
    CHECK(r.status == LpStatus::Optimal);
    longest = std::max(longest, r.iterations);
  }
  CHECK(longest > 2048);  // the watch looked at least once (its window is 512 iterations)
  const Mesh x = shapes::icosphere(1);
  const Mesh y = test::deformed(x, [](const Eigen::Vector3d& q) { return Eigen::Vector3d(1.5 * q.x(), q.y(), 0.7 * q.z()); });
  const MatchingLp m = build_matching_lp(x, compute_geometry(x), y, compute_geometry(y));
  CHECK(solve_lp(m.lp, "pdhg-cpu", params).status == LpStatus::Optimal);
}

TEST_CASE("pdhg-cpu: a watched LP whose certified bound passes divergence_bound stops there, feasible or not") {
  std::mt19937 rng(5);
  const LpProblem p = random_lp(70, 240, 3, rng);
  for (const char* solver : kNative) {
    CAPTURE(solver);
    SolverParams params = tight(1e-6);
    params.stop_on_divergence = true;
    params.patient_divergence_watch = true;
    const LpResult whole = solve_lp(p, solver, params);
    CAPTURE(std::string(to_string(whole.status)));
    REQUIRE(whole.status == LpStatus::Optimal);
    REQUIRE(whole.iterations > 1024);  // (windows of 512: room for a stop before the optimum)
    // Below the optimum: a dual iterate proves more, and the solve stops at that window's end.
    params.divergence_bound = whole.objective - 1e-4 * (1.0 + std::abs(whole.objective));
    const LpResult stopped = solve_lp(p, solver, params);
    MESSAGE("optimal " << whole.objective << " in " << whole.iterations << " iterations; stopped at "
                       << stopped.iterations << " with a certified bound of " << stopped.lower_bound);
    CHECK(stopped.status == LpStatus::Diverging);
    CHECK(stopped.iterations < whole.iterations);
    CHECK(stopped.iterations % 512 == 0);
    {  // Cold, never at the first window (its "growth" would be the whole dual): a bound just under
       // what the dual proves at 512 iterations stops it at 1 024 at the earliest.
      SolverParams early = tight(1e-6);
      early.max_iterations = 512;
      const LpResult at512 = solve_lp(p, solver, early);
      SolverParams cold = params;
      cold.divergence_bound = certified_lower_bound(p, at512.y) - 1e-9;
      CHECK(solve_lp(p, solver, cold).iterations >= 1024);
    }
    CHECK(stopped.lower_bound > params.divergence_bound);
    CHECK(stopped.lower_bound <= whole.objective + 1e-6 * (1.0 + std::abs(whole.objective)));
    REQUIRE(stopped.last_y.size() == size_t(p.rows()));
    CHECK(certified_lower_bound(p, stopped.last_y) > params.divergence_bound);
    {  // From a warm start's dual that proves it already: at the first window.
      SolverParams warm = params;
      warm.initial_y = whole.y;
      const LpResult first = solve_lp(p, solver, warm);
      CHECK(first.status == LpStatus::Diverging);
      CHECK(first.iterations == 512);
      CHECK(first.lower_bound > warm.divergence_bound);
    }
    // Above the optimum no dual gets there: the same solve, iteration for iteration.
    params.divergence_bound = whole.objective + 0.05 * (1.0 + std::abs(whole.objective));
    const LpResult above = solve_lp(p, solver, params);
    CHECK(above.status == LpStatus::Optimal);
    CHECK(above.iterations == whole.iterations);
    // Unwatched, the bound is not looked at.
    params.divergence_bound = whole.objective - 0.05 * (1.0 + std::abs(whole.objective));
    params.stop_on_divergence = false;
    CHECK(solve_lp(p, solver, params).status == LpStatus::Optimal);
  }
}

TEST_CASE("pdhg: the divergence watch on the windows of measured full-resolution LPs") {
  // (primal residual, gap, objective, bound) at the end of each 512-iteration window, tolerance
  // 3e-3, from the logs of the FAUST_r and TOSCA_r runs in docs/results-log.md.
  struct Window {
    double primal, gap, objective, bound;
  };
  auto first_stop = [](const std::vector<Window>& windows, double tolerance = 3e-3, bool patient = false) {
    detail::DivergenceWatch watch(tolerance, patient);
    for (size_t w = 0; w < windows.size(); ++w)
      if (watch.diverging(windows[w].primal, windows[w].gap, windows[w].objective, windows[w].bound)) return int(w);
    return -1;
  };
  // FAUST_r 020-024's infeasible finest LP: the gap doubles each window, the residual still falls.
  CHECK(first_stop({{2.55e-2, 1.74e-2, 21.31, 22.06}, {1.22e-2, 3.67e-2, 23.21, 24.98},
                    {8.25e-3, 6.45e-2, 24.24, 27.58}, {7.53e-3, 1.14e-1, 24.79, 31.15}}) == 1);
  // Its widened, feasible LP: the gap stays near the tolerance.
  CHECK(first_stop({{2.38e-2, 1.33e-3, 20.28, 20.33}, {9.97e-3, 1.15e-3, 21.75, 21.80},
                    {4.89e-3, 2.02e-3, 22.27, 22.36}, {2.79e-3, 1.14e-3, 22.60, 22.65}}) == -1);
  // A feasible LP of FAUST_r 020-021 (1.6 M variables) whose gap grew for a window before it
  // converged: the nearest any optimal LP came (gap 2.2e-2, bound 4 % above).
  CHECK(first_stop({{4.44e-2, 2.43e-2, 14.00, 14.70}, {6.18e-3, 8.91e-3, 15.53, 15.81},
                    {5.40e-3, 2.15e-2, 15.67, 16.36}, {2.62e-3, 4.87e-3, 16.32, 16.48},
                    {7.39e-5, 3.55e-3, 16.79, 16.67}}) == -1);
  // TOSCA_r horse0-5's finest LP: a slow climb, the bound pulling away from the objective (0.51,
  // 0.79, 1.15 above it): the third window (counting windows with a flat residual: the fifth).
  CHECK(first_stop({{1.54e-3, 4.07e-3, 62.05, 62.56}, {1.27e-3, 6.30e-3, 62.24, 63.03},
                    {1.16e-3, 9.16e-3, 62.34, 63.49}, {1.12e-3, 1.31e-2, 62.41, 64.07},
                    {1.10e-3, 1.69e-2, 62.46, 64.60}}) == 2);
  // FAUST_r 020-024's second infeasible finest LPs (sixteenth session), the residual still
  // falling: the bound 0.17, 0.48, 0.98 above the objective (the gap rule: the fourth window) …
  CHECK(first_stop({{2.51e-2, 4.16e-3, 20.20, 20.37}, {8.05e-3, 1.11e-2, 21.48, 21.96},
                    {5.13e-3, 2.17e-2, 21.99, 22.96}, {4.81e-3, 3.31e-2, 22.31, 23.84}}) == 2);
  // … and 0.15, 0.25, 0.26, 0.43, 0.54 (the gap rule: the seventh).
  CHECK(first_stop({{2.82e-2, 5.28e-3, 14.11, 14.26}, {1.23e-2, 8.26e-3, 15.15, 15.40},
                    {3.34e-3, 8.23e-3, 15.62, 15.88}, {2.49e-3, 1.35e-2, 15.79, 16.22},
                    {2.04e-3, 1.68e-2, 15.94, 16.48}, {1.89e-3, 2.53e-2, 16.00, 16.83},
                    {1.82e-3, 3.48e-2, 16.05, 17.21}}) == 4);
  // The widened, feasible LP after the first: the bound below the objective from 512 iterations.
  CHECK(first_stop({{3.74e-2, 3.57e-3, 18.93, 18.79}, {1.36e-2, 4.18e-3, 20.02, 19.85},
                    {4.00e-3, 4.59e-3, 20.38, 20.20}, {1.26e-3, 3.79e-3, 20.53, 20.38},
                    {8.21e-4, 3.14e-3, 20.56, 20.44}}) == -1);
  // The cat's feasible warm re-solve after pricing at full resolution: the bound above and
  // rising slowly for 11 000 iterations (0.77, 1.15, 1.30, 1.34, 1.27, 1.28 …), never twice as far.
  CHECK(first_stop({{3.53e-3, 3.83e-3, 99.60, 100.37}, {2.61e-3, 5.72e-3, 99.81, 100.96},
                    {2.26e-3, 6.48e-3, 99.90, 101.20}, {2.09e-3, 6.64e-3, 100.00, 101.34},
                    {2.13e-3, 6.30e-3, 100.10, 101.37}, {2.16e-3, 6.33e-3, 100.20, 101.48}}) == -1);
  // TOSCA_r horse0-5's 1 414-face first LP at the curvature radius 0.05 (tolerance 1e-3, the
  // watch off): the gap tripled and the bound climbed 1.4 in the second window, the residual still
  // 5.8e-2; then it fell 30× in one window, the bound went below the objective, and the LP
  // converged (gap 2.1e-3 at 3 840 iterations, when it was stopped). With the watch on, the gap
  // rule had stopped it at the second window; on the H200 that level widened 24 times in a row on
  // such stops.
  CHECK(first_stop({{7.608e-2, 6.977e-2, 2.344, 2.697}, {5.843e-2, 1.966e-1, 2.929, 4.364},
                    {1.853e-3, 4.766e-2, 4.890, 4.444}, {3.262e-4, 1.857e-2, 4.942, 4.762},
                    {1.504e-4, 1.106e-2, 4.927, 4.819}, {6.155e-4, 6.526e-3, 4.916, 4.853},
                    {2.333e-4, 2.891e-3, 4.906, 4.878}},
                   1e-3) == -1);
  // The same windows with the residual near feasible would stop at the second, as before.
  CHECK(first_stop({{7.608e-3, 6.977e-2, 2.344, 2.697}, {5.843e-3, 1.966e-1, 2.929, 4.364}}, 1e-3) == 1);
  // A flat residual with the bound far above and rising stops whatever the gap (made-up first
  // window; the second is FAUST_r 021-024's at 1 536 iterations with a smaller gap).
  CHECK(first_stop({{1.20e-2, 2.0e-2, 44.80, 46.0}, {1.16e-2, 2.5e-2, 45.56, 58.84}}) == 1);

  // Patient (a level that no longer trusts the watch): TOSCA_r dog3-dog8's finest LP of 12.7 M
  // variables (fifty-fourth session), 4 608 to 9 728 iterations: the residual flat at 3.65e-3,
  // the gap over the tolerance from the third window and growing, the bound rising. The watch
  // stops it at the creeping rule's fourth window; patient, after eight (9 216 iterations).
  const std::vector<Window> dog = {
      {3.705e-3, 2.442e-3, 2.1709, 2.1815}, {3.673e-3, 2.646e-3, 2.1733, 2.1848}, {3.652e-3, 3.592e-3, 2.1746, 2.1903},
      {3.652e-3, 4.778e-3, 2.1756, 2.1965}, {3.651e-3, 6.057e-3, 2.1764, 2.2029}, {3.655e-3, 7.323e-3, 2.1770, 2.2091},
      {3.661e-3, 8.373e-3, 2.1783, 2.2151}, {3.667e-3, 1.063e-2, 2.1793, 2.2261}, {3.671e-3, 1.347e-2, 2.1800, 2.2395},
      {3.674e-3, 1.646e-2, 2.1805, 2.2535}, {3.676e-3, 1.945e-2, 2.1810, 2.2675}};
  CHECK(first_stop(dog) == 5);
  CHECK(first_stop(dog, 3e-3, true) == 9);
  {  // A watch made from another's state after five windows goes on as that one would; a fresh
     // one counts its windows again (a run gone on from a checkpoint, SolveSnapshot::watch).
    detail::DivergenceWatch first(3e-3, true);
    for (int w = 0; w < 5; ++w) CHECK_FALSE(first.diverging(dog[w].primal, dog[w].gap, dog[w].objective, dog[w].bound));
    detail::DivergenceWatch on(3e-3, true, first.state()), fresh(3e-3, true);
    int on_stop = -1, fresh_stop = -1;
    for (int w = 5; w < int(dog.size()); ++w) {
      if (on_stop < 0 && on.diverging(dog[w].primal, dog[w].gap, dog[w].objective, dog[w].bound)) on_stop = w;
      if (fresh_stop < 0 && fresh.diverging(dog[w].primal, dog[w].gap, dog[w].objective, dog[w].bound)) fresh_stop = w;
    }
    CHECK(on_stop == 9);
    CHECK(fresh_stop == -1);
  }
  // A window that breaks the climb (the residual falling 30 %) starts the count again.
  std::vector<Window> broken = dog;
  broken[6].primal = 2.4e-3;
  CHECK(first_stop(broken, 3e-3, true) == -1);
  // Patient, the windows above that stop impatiently do not stop: the gap rule's, the far bound's,
  // horse0-5's slow climb (five windows).
  CHECK(first_stop({{2.55e-2, 1.74e-2, 21.31, 22.06}, {1.22e-2, 3.67e-2, 23.21, 24.98},
                    {8.25e-3, 6.45e-2, 24.24, 27.58}, {7.53e-3, 1.14e-1, 24.79, 31.15}},
                   3e-3, true) == -1);
  CHECK(first_stop({{1.20e-2, 2.0e-2, 44.80, 46.0}, {1.16e-2, 2.5e-2, 45.56, 58.84}}, 3e-3, true) == -1);
  CHECK(first_stop({{1.54e-3, 4.07e-3, 62.05, 62.56}, {1.27e-3, 6.30e-3, 62.24, 63.03},
                    {1.16e-3, 9.16e-3, 62.34, 63.49}, {1.12e-3, 1.31e-2, 62.41, 64.07},
                    {1.10e-3, 1.69e-2, 62.46, 64.60}},
                   3e-3, true) == -1);
}
