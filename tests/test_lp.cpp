#include "shapematch/errors.hpp"
#include "shapematch/lp.hpp"
#include "shapematch/matching.hpp"
#include "shapematch/shapes.hpp"
#include "test_helpers.hpp"

#include <doctest/doctest.h>

#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <random>

using namespace shapematch;

using test::dense_lp;

TEST_CASE("clp: tiny LPs with known optima and an infeasible one") {
  for (const std::string solver : {"clp-dual", "clp-barrier"}) {
    CAPTURE(solver);
    // min x0 + 2 x1  s.t. x0 + x1 = 1  →  1 at x = (1, 0).
    LpResult r = solve_lp(dense_lp({{1, 1}}, {1}, {1, 2}), solver);
    REQUIRE(r.status == LpStatus::Optimal);
    CHECK(r.objective == doctest::Approx(1.0));
    CHECK(r.x[0] == doctest::Approx(1.0));
    CHECK(r.lower_bound == doctest::Approx(1.0).epsilon(1e-7));
    // min −x0 + x2  s.t. x0 − x1 = 0, x1 + x2 = 1  →  −1 at x = (1, 1, 0).
    r = solve_lp(dense_lp({{1, -1, 0}, {0, 1, 1}}, {0, 1}, {-1, 0, 1}), solver);
    REQUIRE(r.status == LpStatus::Optimal);
    CHECK(r.objective == doctest::Approx(-1.0));
    // The box makes x0 + x1 = 3 impossible.
    r = solve_lp(dense_lp({{1, 1}}, {3}, {1, 1}), solver);
    CHECK(r.status == LpStatus::Infeasible);
  }
}

namespace {
volatile std::sig_atomic_t g_interrupted = 0;
extern "C" void note_interrupt(int) { g_interrupted = 1; }
}  // namespace

TEST_CASE("clp: leaves SIGINT to the program (match's stop on a signal)") {
  // Clp's own interrupt handling would take SIGINT during a solve (cutting the LP short) and put
  // the program's handler back without its flags (SA_RESETHAND: a second Ctrl-C stops at once).
  struct sigaction mine {}, before {}, after {};
  mine.sa_handler = note_interrupt;
  sigemptyset(&mine.sa_mask);
  mine.sa_flags = SA_RESETHAND;
  REQUIRE(sigaction(SIGINT, &mine, &before) == 0);
  for (const std::string solver : {"clp-dual", "clp-barrier"}) {
    CAPTURE(solver);
    LpResult r = solve_lp(dense_lp({{1, 1}}, {1}, {1, 2}), solver);
    CHECK(r.status == LpStatus::Optimal);
    REQUIRE(sigaction(SIGINT, nullptr, &after) == 0);
    CHECK((after.sa_handler == &note_interrupt));
    CHECK((after.sa_flags & SA_RESETHAND) != 0);
  }
  sigaction(SIGINT, &before, nullptr);
  CHECK(g_interrupted == 0);
}

TEST_CASE("clp: the dual simplex names the rows of an infeasible LP that clash") {
  // Row 0 (x0 + x1 = 3) is impossible in the box; rows 1 and 2 are fine on their own.
  const LpResult r = solve_lp(dense_lp({{1, 1, 0, 0}, {0, 0, 1, 1}, {0, 0, 1, -1}}, {3, 1, 0}, {1, 1, 1, 2}),
                              "clp-dual");
  REQUIRE(r.status == LpStatus::Infeasible);
  REQUIRE(r.y.size() == 3);
  MESSAGE("ray " << r.y[0] << " " << r.y[1] << " " << r.y[2]);
  CHECK(std::abs(r.y[0]) > 0.0);
  CHECK(std::abs(r.y[1]) < 1e-12 * std::abs(r.y[0]));
  CHECK(std::abs(r.y[2]) < 1e-12 * std::abs(r.y[0]));
}

TEST_CASE("clp: a mesh against itself has LP optimum 0; a deformed copy a positive one") {
  const Mesh x = shapes::octahedron();
  const Mesh y = test::deformed(x, [](const Eigen::Vector3d& p) {
    return Eigen::Vector3d(1.3 * p.x() + 0.1 * p.z(), p.y(), 0.8 * p.z() + 0.05 * p.x() * p.y());
  });
  const Geometry gx = compute_geometry(x), gy = compute_geometry(y);

  const MatchingLp self = build_matching_lp(x, gx, x, gx);
  const LpResult r0 = solve_lp(self.lp, "clp-dual");
  REQUIRE(r0.status == LpStatus::Optimal);
  CHECK(std::abs(r0.objective) < 1e-9);

  const MatchingLp m = build_matching_lp(x, gx, y, gy);
  const LpResult dual = solve_lp(m.lp, "clp-dual");
  const LpResult barrier = solve_lp(m.lp, "clp-barrier");
  REQUIRE(dual.status == LpStatus::Optimal);
  REQUIRE(barrier.status == LpStatus::Optimal);
  CHECK(dual.objective > 1e-6);
  CHECK(std::abs(dual.objective - barrier.objective) <= 1e-6 * std::abs(dual.objective));
  // The certified bound from Clp's duals is tight, and never above the optimum.
  CHECK(dual.lower_bound <= dual.objective + 1e-9 * std::abs(dual.objective));
  CHECK(dual.lower_bound == doctest::Approx(dual.objective).epsilon(1e-6));
  CHECK(dual.primal_residual < 1e-9);
}

TEST_CASE("lp: the certified lower bound holds for arbitrary duals") {
  const Mesh x = shapes::tetrahedron();
  const Mesh y = test::deformed(x, [](const Eigen::Vector3d& p) { return Eigen::Vector3d(p.x(), 1.5 * p.y(), p.z()); });
  const Geometry gx = compute_geometry(x), gy = compute_geometry(y);
  const MatchingLp m = build_matching_lp(x, gx, y, gy);
  const LpResult opt = solve_lp(m.lp, "clp-dual");
  REQUIRE(opt.status == LpStatus::Optimal);
  std::mt19937 rng(1);
  std::normal_distribution<double> n(0.0, 0.3);
  for (int k = 0; k < 50; ++k) {
    std::vector<double> y = opt.y;
    for (auto& v : y) v += n(rng) * (k % 5) * 0.1;
    CHECK(certified_lower_bound(m.lp, y) <= opt.objective * (1 + 1e-9));
  }
}

TEST_CASE("lp: with costs all non-negative the certified bound is never below 0") {
  // x0 + x1 = 1 in the box, costs 1 and 2: optimum 1. L(y) = y + min(0, 1 − y) + min(0, 2 − y).
  const LpProblem costs = dense_lp({{1, 1}}, {1}, {1, 2});
  CHECK(certified_lower_bound(costs, {1.0}) == doctest::Approx(1.0));  // the optimum's dual
  CHECK(certified_lower_bound(costs, {0.5}) == doctest::Approx(0.5));
  CHECK(certified_lower_bound(costs, {-5.0}) == 0.0);  // L = −5
  CHECK(certified_lower_bound(costs, {4.0}) == 0.0);   // L = 4 − 3 − 2 = −1
  // A negative cost: 0 bounds nothing, L(y) as it is.
  const LpProblem negative = dense_lp({{1, 1}}, {1}, {1, -2});
  CHECK(certified_lower_bound(negative, {-5.0}) == doctest::Approx(-5.0));  // −5 + min(0, 6) + min(0, 3)
  CHECK(std::isnan(certified_lower_bound(costs, {std::nan("")})));
}

TEST_CASE("lp: the Farkas rate is positive along an infeasible LP's ray and never on a feasible LP") {
  // x0 + x1 = 3 in the box: d = 1 gives 3 − 2 = 1 > 0; Clp's ray likewise.
  const LpProblem bad = dense_lp({{1, 1, 0, 0}, {0, 0, 1, 1}, {0, 0, 1, -1}}, {3, 1, 0}, {1, 1, 1, 2});
  CHECK(farkas_rate(bad, {1.0, 0.0, 0.0}) == doctest::Approx(1.0));
  const LpResult r = solve_lp(bad, "clp-dual");
  REQUIRE(r.status == LpStatus::Infeasible);
  CHECK(std::abs(farkas_rate(bad, r.y)) > 0.0);  // Clp's sign convention may be either
  CHECK(std::max(farkas_rate(bad, r.y), farkas_rate(bad, std::vector<double>{-r.y[0], -r.y[1], -r.y[2]})) > 0.0);
  // A feasible matching LP: no direction at all grows without limit.
  const Mesh x = shapes::tetrahedron();
  const Mesh y = test::deformed(x, [](const Eigen::Vector3d& p) { return Eigen::Vector3d(p.x(), 1.5 * p.y(), p.z()); });
  const MatchingLp m = build_matching_lp(x, compute_geometry(x), y, compute_geometry(y));
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int k = 0; k < 50; ++k) {
    std::vector<double> d(m.lp.rows());
    for (auto& v : d) v = n(rng);
    CHECK(farkas_rate(m.lp, d) <= 1e-9);
  }
  CHECK(farkas_rate(m.lp, {}) == -std::numeric_limits<double>::infinity());  // a wrong size
}

namespace {
// max cᵀx over the LP's feasible set, by Clp on −c.
double largest_objective(LpProblem p) {
  for (double& v : p.c) v = -v;
  const LpResult r = solve_lp(p, "clp-dual");
  REQUIRE(r.status == LpStatus::Optimal);
  return -r.objective / p.objective_scale;
}
}  // namespace

TEST_CASE("lp: the objective upper bound is at least every feasible objective, and tight where rows cover") {
  // x0 + x1 = 1 covers x0 and x1; x1 − x2 = 0 covers nothing. Bound 1·max(2, 3) + 5 = 8, and
  // x = (0, 1, 1) reaches it.
  const LpProblem small = dense_lp({{1, 1, 0}, {0, 1, -1}}, {1, 0}, {2, 3, 5});
  CHECK(objective_upper_bound(small) == doctest::Approx(8.0));
  CHECK(largest_objective(small) == doctest::Approx(8.0));

  // Random LPs, some rows all +1, feasible by construction.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const int m = 4 + trial % 5, n = 10 + trial;
    std::vector<std::vector<int>> rows(m, std::vector<int>(n, 0));
    std::vector<double> xs(n), c(n), b(m, 0.0);
    for (int j = 0; j < n; ++j) {
      xs[j] = u(rng);
      c[j] = 2.0 * u(rng) - 0.7;
    }
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < n; ++j) {
        const double r = u(rng);
        rows[i][j] = r < 0.6 ? 0 : (i < m / 2 || r < 0.8) ? 1 : -1;
        b[i] += rows[i][j] * xs[j];
      }
    const LpProblem p = dense_lp(rows, b, c);
    CAPTURE(trial);
    CHECK(objective_upper_bound(p) >= largest_objective(p) - 1e-9);
  }

  // A matching LP: every product triangle lies in a face's projection row, so the bound is a
  // sum over faces, far below the sum of all positive costs.
  const Mesh x = shapes::octahedron();
  const Mesh y = test::deformed(x, [](const Eigen::Vector3d& p) { return Eigen::Vector3d(1.4 * p.x(), p.y(), 0.7 * p.z()); });
  const MatchingLp mlp = build_matching_lp(x, compute_geometry(x), y, compute_geometry(y));
  const double bound = objective_upper_bound(mlp.lp);
  CHECK(bound >= largest_objective(mlp.lp) - 1e-9);
  double positive = 0.0;
  for (double v : mlp.lp.c) positive += std::max(0.0, v);
  CHECK(bound < positive / 5);
}

TEST_CASE("lp: MPS export and problem checks") {
  LpProblem p = dense_lp({{1, 1}}, {1}, {1, 2});
  const auto path = std::filesystem::temp_directory_path() / "shapematch_test.mps";
  write_mps(p, path.string());
  std::ifstream f(path);
  std::string first;
  std::getline(f, first);
  CHECK(first.rfind("NAME", 0) == 0);
  std::filesystem::remove(path);

  p.c.pop_back();
  CHECK_THROWS_AS(p.check(), InvalidInputError);
  CHECK_THROWS_AS(make_solver("simplex-magic"), InvalidInputError);
}

TEST_CASE("lp: the binary LP file holds the problem bit for bit; a damaged file is an error naming it") {
  const Mesh x = shapes::octahedron();
  const Mesh y = test::deformed(x, [](const Eigen::Vector3d& p) { return Eigen::Vector3d(1.2 * p.x(), p.y(), 0.9 * p.z()); });
  const Geometry gx = compute_geometry(x), gy = compute_geometry(y);
  const LpProblem lp = build_matching_lp(x, gx, y, gy).lp;
  const test::TempDir dir;
  const std::string path = (dir.path / "octahedron.smlp").string();
  write_lp(lp, path);
  const LpProblem back = read_lp(path);
  CHECK(back.a.rows == lp.a.rows);
  CHECK(back.a.cols == lp.a.cols);
  CHECK(back.a.row_ptr == lp.a.row_ptr);
  CHECK(back.a.entry == lp.a.entry);
  CHECK(back.at.row_ptr == lp.at.row_ptr);  // rebuilt, the same
  CHECK(back.at.entry == lp.at.entry);
  CHECK(back.b == lp.b);
  CHECK(back.c == lp.c);
  CHECK(back.objective_scale == lp.objective_scale);
  // Solved from the file, the same optimum.
  CHECK(solve_lp(back, "clp-dual").objective == doctest::Approx(solve_lp(lp, "clp-dual").objective).epsilon(1e-12));

  std::string bytes;
  {
    std::ifstream in(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  auto message = [&](const std::string& content) {
    const std::string p = dir.file("bad.smlp", content);
    try {
      read_lp(p);
    } catch (const InvalidInputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK(message(bytes.substr(0, bytes.size() - 8)).find("bad.smlp: sizes") != std::string::npos);
  CHECK(message(bytes.substr(0, 10)).find("bad.smlp: truncated") != std::string::npos);
  CHECK(message("OFF\n3 1 0\n").find("not a shapematch LP file") != std::string::npos);
  std::string corrupt = bytes;
  const size_t entries = 4 + 4 + 3 * 8 + 8 + 4 * size_t(lp.rows() + 1);
  corrupt[entries + 1] = char(0x7f);  // a column index far out of range
  CHECK(message(corrupt).find("out of range") != std::string::npos);
  std::string nan = bytes;
  std::memset(nan.data() + nan.size() - 8, 0xff, 8);  // the last cost: NaN
  CHECK(message(nan).find("not finite") != std::string::npos);
  CHECK_THROWS_AS(read_lp((dir.path / "missing.smlp").string()), IoError);
}
