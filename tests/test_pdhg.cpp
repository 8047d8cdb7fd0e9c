#include "shapematch/errors.hpp"
#include "shapematch/matching.hpp"
#include "shapematch/pdhg.hpp"
#include "shapematch/shapes.hpp"
#include "test_helpers.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <set>

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

SolverParams tight(double tol = 1e-5) {
  SolverParams p;
  p.tolerance = tol;
  p.max_iterations = 400000;
  return p;
}

}  // namespace

TEST_CASE("pdhg-cpu: tiny LPs with known optima") {
  // min x0 + 2 x1  s.t. x0 + x1 = 1  →  1.
  LpResult r = solve_lp(from_rows(2, {{{0, 1}, {1, 1}}}, {1}, {1, 2}), "pdhg-cpu", tight());
  REQUIRE(r.status == LpStatus::Optimal);
  CHECK(r.objective == doctest::Approx(1.0).epsilon(1e-5));
  CHECK(r.lower_bound <= 1.0 + 1e-12);
  // min −x0 + x2  s.t. x0 − x1 = 0, x1 + x2 = 1  →  −1.
  r = solve_lp(from_rows(3, {{{0, 1}, {1, -1}}, {{1, 1}, {2, 1}}}, {0, 1}, {-1, 0, 1}), "pdhg-cpu", tight());
  REQUIRE(r.status == LpStatus::Optimal);
  CHECK(r.objective == doctest::Approx(-1.0).epsilon(1e-5));
  CHECK(r.lower_bound <= -1.0 + 1e-12);
}

TEST_CASE("pdhg-cpu: infeasibility is a status, found quickly") {
  // x0 + x1 = 3 is outside the box: found by presolve.
  LpResult r = solve_lp(from_rows(2, {{{0, 1}, {1, 1}}}, {3}, {1, 1}), "pdhg-cpu", tight());
  CHECK(r.status == LpStatus::Infeasible);
  // Each row alone is satisfiable, together they are not: x0 + x1 = 2 forces x0 = 1, x0 − x2 = −1 forces x0 = 0.
  r = solve_lp(from_rows(3, {{{0, 1}, {1, 1}}, {{0, 1}, {2, -1}}}, {2, -1}, {1, 0, 0}), "pdhg-cpu", tight());
  CHECK(r.status == LpStatus::Infeasible);
  CHECK(r.iterations < 20000);
}

TEST_CASE("pdhg-cpu: random structured LPs agree with Clp; the bound never exceeds the optimum") {
  std::mt19937 rng(42);
  for (int trial = 0; trial < 6; ++trial) {
    const LpProblem p = random_lp(40 + 10 * trial, 150 + 30 * trial, 3, rng);
    const LpResult exact = solve_lp(p, "clp-dual");
    REQUIRE(exact.status == LpStatus::Optimal);
    const LpResult r = solve_lp(p, "pdhg-cpu", tight(1e-5));
    CAPTURE(trial);
    REQUIRE(r.status == LpStatus::Optimal);
    CHECK(std::abs(r.objective - exact.objective) <= 1e-4 * std::max(1.0, std::abs(exact.objective)));
    CHECK(r.lower_bound <= exact.objective + 1e-9 * std::max(1.0, std::abs(exact.objective)));
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
  SolverParams params = tight(1e-5);
  const LpResult r = solve_lp(m.lp, "pdhg-cpu", params);
  REQUIRE(r.status == LpStatus::Optimal);
  CHECK(std::abs(r.objective - exact.objective) <= 1e-4 * std::abs(exact.objective));
  CHECK(r.lower_bound <= exact.objective * (1 + 1e-9));
  CHECK(r.lower_bound >= exact.objective * (1 - 1e-3));

  // Warm start from the optimum needs far fewer iterations than a cold start.
  params.initial_x = r.x;
  params.initial_y = r.y;
  const LpResult warm = solve_lp(m.lp, "pdhg-cpu", params);
  REQUIRE(warm.status == LpStatus::Optimal);
  CHECK(warm.iterations * 4 <= r.iterations);
}
