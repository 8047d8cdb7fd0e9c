#include "shapematch/constraints.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/matching.hpp"
#include "shapematch/rounding.hpp"
#include "shapematch/shapes.hpp"
#include "shapematch/system.hpp"
#include "certificate_blame.hpp"
#include "failed_from.hpp"
#include "failing_again.hpp"
#include "local_proof.hpp"
#include "part_search.hpp"
#include "release_reach.hpp"
#include "solve_in_parts.hpp"
#include "stalled_rows.hpp"
#include "test_helpers.hpp"

#include <doctest/doctest.h>

#include <csignal>
#include <map>
#include <set>
#include <numeric>

using namespace shapematch;

namespace {

// The dolphins at 30 faces: for tests that solve the whole LP exactly several times.
const MatchingLp& dolphins_30() {
  static const Mesh x = decimate(shapes::dolphin(0, 5), 30), y = decimate(shapes::dolphin(-40, 45), 30);
  static const MatchingLp m = build_matching_lp(x, compute_geometry(x), y, compute_geometry(y));
  return m;
}

// The dolphins at 60 faces, one bent: a pair small enough for many rounds, built once (the space
// refers to its meshes, which live as long as the test binary).
const MatchingLp& dolphins_60() {
  static const Mesh x = decimate(shapes::dolphin(0, 5), 60), y = decimate(shapes::dolphin(-40, 45), 60);
  static const MatchingLp m = build_matching_lp(x, compute_geometry(x), y, compute_geometry(y));
  return m;
}

// A dolphin against a bumpy ball at 60 faces: a fractional LP (the dolphins' are integral) whose
// roundings alone by 0.3, 0.5 and 0.7 end at three energies (measured 16.61, 16.00, 16.26).
const MatchingLp& dolphin_ball_60() {
  static const Mesh x = decimate(shapes::dolphin(0, 0), 60);
  static const Mesh y = [] {
    std::mt19937 rng(8);
    std::uniform_real_distribution<double> u(-0.2, 0.2);
    return decimate(test::deformed(shapes::icosphere(2),
                                   [&](const Eigen::Vector3d& p) { return Eigen::Vector3d(p * (1 + u(rng))); }),
                    60);
  }();
  static const MatchingLp m = build_matching_lp(x, compute_geometry(x), y, compute_geometry(y));
  return m;
}

// Threshold 0 (several rounds on the dolphins above), every round's LP on PDHG (none exact).
RoundingOptions every_round_on_pdhg() {
  RoundingOptions o;
  o.solver = "pdhg-cpu";
  o.exact_below = 0;
  o.threshold = 0.0;
  return o;
}

// Every round on PDHG and nothing but the rounds (no search, no second threshold, no pocket
// closing): what the snapshot and stop tests follow round by round.
RoundingOptions pdhg_rounds_alone() {
  RoundingOptions o;
  o.solver = "pdhg-cpu";
  o.exact_below = 0;
  o.search_below = 0;
  o.alternative_thresholds = {};
  o.close_pockets = false;
  return o;
}

// max |A x − b| over the whole LP.
double max_residual(const LpProblem& lp, const std::vector<double>& x) {
  std::vector<double> ax(lp.rows(), 0.0);
  for (int64_t j = 0; j < lp.cols(); ++j)
    for (uint32_t k = lp.at.row_ptr[j]; k < lp.at.row_ptr[j + 1]; ++k)
      ax[col_of(lp.at.entry[k])] += (is_negative(lp.at.entry[k]) ? -1.0 : 1.0) * x[j];
  double r = 0.0;
  for (int64_t i = 0; i < lp.rows(); ++i) r = std::max(r, std::abs(ax[i] - lp.b[i]));
  return r;
}

}  // namespace

TEST_CASE("rounding: a mesh against itself rounds to the identity with zero gap") {
  // A perturbed octahedron: the regular one has symmetries of zero energy, this one only the identity.
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-0.15, 0.15);
  const Mesh x = test::deformed(shapes::octahedron(),
                                [&](const Eigen::Vector3d& p) { return Eigen::Vector3d(p.x() + u(rng), p.y() + u(rng), p.z() + u(rng)); });
  const Geometry g = compute_geometry(x);
  const MatchingLp m = build_matching_lp(x, g, x, g);
  for (const std::string solver : {"pdhg-cpu", "clp-dual"}) {
    CAPTURE(solver);
    RoundingOptions o;
    o.solver = solver;
    const RoundingResult r = round_to_graph_surface(m.space, m.lp, m.energy, o);
    CHECK(satisfies_exactly(m.lp, r.gamma));
    CHECK(r.energy == doctest::Approx(0.0).epsilon(1e-12));
    CHECK(r.lower_bound <= 1e-9);
    CHECK(r.gap == 0.0);  // not 100 % because the bound is ~0
    const VertexMaps maps = vertex_maps(m.space, r.gamma);
    for (int v = 0; v < x.num_vertices(); ++v) {
      CHECK(maps.x_to_y[v] == v);
      CHECK(maps.y_to_x[v] == v);
    }
    CHECK(check_graph_surface(m.space, r.gamma).ok());
  }
}

TEST_CASE("rounding: the relative gap is relative to a positive bound, else to the energy") {
  CHECK(relative_gap(2.2, 2.0) == doctest::Approx(0.1));
  CHECK(relative_gap(0.0, 0.0) == 0.0);          // a shape with itself
  CHECK(relative_gap(1.0, 1.0 - 1e-12) == 0.0);  // met to rounding error
  CHECK(relative_gap(5.0, 0.0) == doctest::Approx(1.0));   // a bound of 0 (clamped weak dual): 100 %, not 1e300
  CHECK(relative_gap(5.0, -1.0) == doctest::Approx(1.2));  // (a bound below 0: relative to the energy too)
}

TEST_CASE("rounding: a deformed pair rounds to a verified graph surface within the paper's bounds") {
  // Same connectivity, different pose: the bundled finger's generator at low resolution.
  const Mesh x = shapes::bent_finger(10, 5, 6), y = shapes::bent_finger(60, 5, 6);
  const Geometry gx = compute_geometry(x), gy = compute_geometry(y);
  const MatchingLp m = build_matching_lp(x, gx, y, gy);
  RoundingOptions o;
  o.solver = "pdhg-cpu";
  std::vector<RoundingRound> seen;
  const RoundingResult r =
      round_to_graph_surface(m.space, m.lp, m.energy, o, [&](const RoundingRound& k) { seen.push_back(k); });
  CHECK(seen.size() == r.rounds.size());
  CHECK(r.rounds.size() <= 20);
  CHECK(satisfies_exactly(m.lp, r.gamma));
  CHECK(r.energy >= r.lower_bound - 1e-9);
  CHECK(r.gap >= -1e-9);
  CHECK(r.gap <= 0.5);
  const GraphSurfaceCheck t = check_graph_surface(m.space, r.gamma);
  CHECK(t.covers_x);
  CHECK(t.covers_y);
  CHECK(t.orientation);
  CHECK(t.continuous);
  // Same connectivity, near-isometric poses: most vertices should map to themselves.
  const VertexMaps maps = vertex_maps(m.space, r.gamma);
  int same = 0;
  for (int v = 0; v < x.num_vertices(); ++v) same += maps.x_to_y[v] == v;
  MESSAGE("vertices mapped to themselves: ", same, " of ", x.num_vertices());
  CHECK(same >= x.num_vertices() * 3 / 4);
  MESSAGE("finger pair: ", m.lp.cols(), " variables, ", r.rounds.size(), " rounds, gap ", r.gap);

  // The checks can fail: drop one product triangle, or swap in a reversed face.
  auto broken = r.gamma;
  broken.pop_back();
  CHECK_FALSE(satisfies_exactly(m.lp, broken));
  CHECK_FALSE(check_graph_surface(m.space, broken).ok());
}

TEST_CASE("rounding: after each round it hands out its decisions, and a rounding from them keeps them") {
  // Threshold 0 on the dolphins at 60 faces: several rounds (see the clashing-candidates test).
  const MatchingLp& m = dolphins_60();
  RoundingOptions o = every_round_on_pdhg();
  o.alternative_thresholds = {};  // one rounding
  o.close_pockets = false;        // (which may replace decided triangles)
  struct Call {
    int round;
    std::vector<int64_t> ones;
    std::vector<int32_t> steps;
    double bound;
    std::vector<double> x, y;
  };
  std::vector<Call> calls;
  o.decided = [&](const RoundingRound& r, const std::vector<int64_t>& ones, const std::vector<int32_t>& steps,
                  double bound, const std::vector<double>& x, const std::vector<double>& y) {
    calls.push_back({r.round, ones, steps, bound, x, y});
  };
  const RoundingResult r = round_to_graph_surface(m.space, m.lp, m.energy, o);
  REQUIRE(r.rounds.size() >= 2);
  REQUIRE(calls.size() == r.rounds.size());
  for (size_t k = 0; k < calls.size(); ++k) {
    CAPTURE(k);
    CHECK(calls[k].round == int(k) + 1);
    CHECK(std::is_sorted(calls[k].ones.begin(), calls[k].ones.end()));
    CHECK(std::adjacent_find(calls[k].ones.begin(), calls[k].ones.end()) == calls[k].ones.end());
    CHECK(calls[k].steps.size() == calls[k].ones.size());
    for (int32_t step : calls[k].steps) CHECK((step >= 0 && step <= int(k)));  // a step per round at most
    CHECK(calls[k].bound == r.first_lp.lower_bound);
    CHECK(calls[k].x.size() == size_t(m.lp.cols()));  // the next round's warm start, over the whole LP
    CHECK(calls[k].y.size() == size_t(m.lp.rows()));
  }
  CHECK(std::any_of(calls.front().x.begin(), calls.front().x.end(), [](double v) { return v > 0.0; }));
  REQUIRE_FALSE(calls.front().ones.empty());
  for (int64_t j : calls.back().ones) CHECK(std::binary_search(r.gamma.begin(), r.gamma.end(), j));
  // Gone on from round 1's decisions: an exact graph surface that keeps every one of them.
  RoundingOptions from = o;
  from.decided = {};
  from.start_ones = calls.front().ones;
  const RoundingResult g = round_to_graph_surface(m.space, m.lp, m.energy, from);
  CHECK(satisfies_exactly(m.lp, g.gamma));
  CHECK(check_graph_surface(m.space, g.gamma).ok());
  for (int64_t j : calls.front().ones) CHECK(std::binary_search(g.gamma.begin(), g.gamma.end(), j));
  // … and from them with round 1's iterate as its warm start (what a checkpoint keeps with them):
  // the same guarantees, its first LP no longer than the cold one.
  from.lp.initial_x = calls.front().x;
  from.lp.initial_y = calls.front().y;
  const RoundingResult w = round_to_graph_surface(m.space, m.lp, m.energy, from);
  CHECK(satisfies_exactly(m.lp, w.gamma));
  CHECK(check_graph_surface(m.space, w.gamma).ok());
  for (int64_t j : calls.front().ones) CHECK(std::binary_search(w.gamma.begin(), w.gamma.end(), j));
  MESSAGE("gone on from round 1's decisions: its first round ", g.rounds.front().iterations, " iterations cold, ",
          w.rounds.front().iterations, " warm");
  CHECK(w.rounds.front().iterations <= g.rounds.front().iterations);
}

TEST_CASE("rounding: a round's LP under way is snapshot as the next warm start, and a rounding goes on from it") {
  // Threshold 0 on the dolphins at 60 faces: several rounds on PDHG. Snapshots at every residual
  // check of the rounds from fixings (not round 1, which first_snapshot covers), each the point
  // the round would hand `decided` were it to end there.
  const MatchingLp& m = dolphin_ball_60();
  RoundingOptions o = pdhg_rounds_alone();
  o.later_feasibility_iterations = 0;  // (the costed solves alone: what a snapshot shortens)
  struct Decided {
    std::vector<int64_t> ones;
    std::vector<int32_t> steps;
    std::vector<double> x, y;
  };
  std::vector<Decided> decided;
  struct Snap {
    size_t after;  // decided calls before it: it is inside round after + 1
    std::vector<double> x, y;
  };
  std::vector<Snap> snaps;
  o.decided = [&](const RoundingRound&, const std::vector<int64_t>& ones, const std::vector<int32_t>& steps, double,
                  const std::vector<double>& x, const std::vector<double>& y) { decided.push_back({ones, steps, x, y}); };
  o.snapshot_seconds = 1e-9;  // (at every residual check)
  o.round_snapshot = [&](const std::vector<double>& x, const std::vector<double>& y, double omega) {
    CHECK(omega > 0.0);
    snaps.push_back({decided.size(), x, y});
  };
  const RoundingResult r = round_to_graph_surface(m.space, m.lp, m.energy, o);
  REQUIRE(r.rounds.size() >= 2);
  REQUIRE_FALSE(snaps.empty());
  for (const Snap& s : snaps) {
    CHECK(s.after >= 1);  // none in round 1
    CHECK(s.x.size() == size_t(m.lp.cols()));
    CHECK(s.y.size() == size_t(m.lp.rows()));
  }
  // The longest later round with snapshots; its last snapshot against the round before's iterate.
  size_t round = 0;  // index into r.rounds
  for (const Snap& s : snaps)
    if (round == 0 || r.rounds[s.after].iterations > r.rounds[round].iterations) round = s.after;
  const Snap* last = nullptr;
  for (const Snap& s : snaps)
    if (s.after == round) last = &s;
  REQUIRE(last != nullptr);
  RoundingOptions from = o;
  from.decided = {};
  from.round_snapshot = {};
  from.start_ones = decided[round - 1].ones;
  from.start_steps = decided[round - 1].steps;
  from.lp.initial_x = decided[round - 1].x;
  from.lp.initial_y = decided[round - 1].y;
  const RoundingResult before = round_to_graph_surface(m.space, m.lp, m.energy, from);
  from.lp.initial_x = last->x;
  from.lp.initial_y = last->y;
  const RoundingResult inside = round_to_graph_surface(m.space, m.lp, m.energy, from);
  MESSAGE("round " << round + 1 << ": " << r.rounds[round].iterations << " iterations; gone on from the round before's "
                   << "iterate " << before.rounds.front().iterations << ", from its last snapshot "
                   << inside.rounds.front().iterations);
  CHECK(inside.rounds.front().iterations < before.rounds.front().iterations);
  CHECK(satisfies_exactly(m.lp, inside.gamma));
  CHECK(check_graph_surface(m.space, inside.gamma).ok());
  for (int64_t j : decided[round - 1].ones) CHECK(std::binary_search(inside.gamma.begin(), inside.gamma.end(), j));
  // Without snapshot_seconds: never called.
  o.snapshot_seconds = 0.0;
  snaps.clear();
  round_to_graph_surface(m.space, m.lp, m.energy, o);
  CHECK(snaps.empty());
}

TEST_CASE("rounding: a stop in a later round's pre-test saves that round's warm start before it goes on") {
  // A stop asked for after round 1 (its `decided` not saved, as the caller's throttle may leave it):
  // round 2's parts are pre-tested at zero cost first, which keep no snapshot, so PDHG stops there
  // at its set-up's end; the rounding hands round_snapshot the round's warm start (round 1's iterate,
  // the point `decided` had) before the Stopped goes on. A stop inside a costed solve saves there.
  const MatchingLp& m = dolphin_ball_60();
  struct Forget {  // (whatever fails: the stop does not outlive the test)
    ~Forget() { clear_stop(); }
  } forget;
  for (const bool pretested : {true, false}) {
    CAPTURE(pretested);
    RoundingOptions o = pdhg_rounds_alone();
    o.later_feasibility_iterations = pretested ? 4096 : 0;
    o.later_feasibility_skip_below = 0;  // (the pre-test first)
    std::vector<std::vector<double>> decided_x;
    o.decided = [&](const RoundingRound&, const std::vector<int64_t>&, const std::vector<int32_t>&, double,
                    const std::vector<double>& x, const std::vector<double>&) {
      decided_x.push_back(x);
      request_stop(SIGTERM);
    };
    o.snapshot_seconds = 1e9;  // (never by time: only the stop's)
    std::vector<std::pair<std::vector<double>, double>> snaps;
    // (As match's checkpoint callback does: after a save where a stop is asked for, Stopped.)
    o.round_snapshot = [&](const std::vector<double>& x, const std::vector<double>&, double omega) {
      snaps.push_back({x, omega});
      if (stop_requested() != 0) throw Stopped("after saving its checkpoint");
    };
    CHECK_THROWS_AS(round_to_graph_surface(m.space, m.lp, m.energy, o), Stopped);
    clear_stop();
    REQUIRE(decided_x.size() == 1);
    REQUIRE(snaps.size() == 1);  // (once: not again after a costed solve's own snapshot)
    if (pretested) {
      CHECK(snaps[0].first == decided_x[0]);
      CHECK(snaps[0].second == 0.0);
    } else {
      CHECK(snaps[0].second > 0.0);  // (the costed solve's, at its first residual check)
    }
  }
  CHECK(stop_requested() == 0);
}

TEST_CASE("rounding: a rounding gone on from decisions with their steps keeps the steps apart") {
  // The dolphin and the bumpy ball round in several rounds (see the budget test). Gone on from
  // the decisions before the last round, with their steps: those stay apart in the undo history,
  // as the next round's decisions show (a failing LP undoes the last of them first, as the
  // rounding that made them would have); without the steps they are one.
  const MatchingLp& m = dolphin_ball_60();
  RoundingOptions o;
  o.solver = "pdhg-cpu";
  o.lp.tolerance = 1e-3;
  std::vector<std::pair<std::vector<int64_t>, std::vector<int32_t>>> calls;
  o.decided = [&](const RoundingRound&, const std::vector<int64_t>& ones, const std::vector<int32_t>& steps, double,
                  const std::vector<double>&, const std::vector<double>&) { calls.push_back({ones, steps}); };
  const RoundingResult plain = round_to_graph_surface(m.space, m.lp, m.energy, o);
  REQUIRE(calls.size() > 2);
  REQUIRE(calls.size() == plain.rounds.size());
  const auto& [ones, steps] = calls[calls.size() - 2];
  REQUIRE(steps.size() == ones.size());
  REQUIRE(std::set<int32_t>(steps.begin(), steps.end()).size() >= 2);
  for (bool with_steps : {true, false}) {
    CAPTURE(with_steps);
    RoundingOptions from = o;
    from.start_ones = ones;
    from.start_steps = with_steps ? steps : std::vector<int32_t>{};
    std::vector<std::pair<std::vector<int64_t>, std::vector<int32_t>>> after;
    from.decided = [&](const RoundingRound&, const std::vector<int64_t>& a, const std::vector<int32_t>& s, double,
                       const std::vector<double>&, const std::vector<double>&) { after.push_back({a, s}); };
    const RoundingResult g = round_to_graph_surface(m.space, m.lp, m.energy, from);
    CHECK(satisfies_exactly(m.lp, g.gamma));
    REQUIRE_FALSE(after.empty());
    REQUIRE_FALSE(g.rounds.front().undone);
    std::map<int64_t, int32_t> step_of;
    for (size_t k = 0; k < after.front().first.size(); ++k) step_of[after.front().first[k]] = after.front().second[k];
    // (Steps that fixed nothing that stayed are not kept: renumbered in order.)
    std::map<int32_t, int32_t> renumbered;
    for (int32_t k : steps) renumbered.emplace(k, 0);
    int32_t next = 0;
    for (auto& [k, to] : renumbered) to = next++;
    for (size_t k = 0; k < ones.size(); ++k) {
      REQUIRE(step_of.count(ones[k]));
      CHECK(step_of[ones[k]] == (with_steps ? renumbered[steps[k]] : 0));
    }
  }
  // Steps that do not fit the fixings are refused.
  RoundingOptions wrong = o;
  wrong.decided = {};
  wrong.start_ones = ones;
  wrong.start_steps = {0};
  CHECK_THROWS_AS(round_to_graph_surface(m.space, m.lp, m.energy, wrong), InvalidInputError);
  wrong.start_steps.assign(ones.size(), -1);
  CHECK_THROWS_AS(round_to_graph_surface(m.space, m.lp, m.energy, wrong), InvalidInputError);
  wrong.start_ones.clear();
  wrong.start_steps = {0};
  CHECK_THROWS_AS(round_to_graph_surface(m.space, m.lp, m.energy, wrong), InvalidInputError);
}

TEST_CASE("rounding: round 1's first-order solve alone is snapshot, over the whole LP, resumed counts included") {
  // Threshold 0 on the dolphins at 60 faces: several rounds, each on PDHG, and a pre-test.
  const MatchingLp& m = dolphins_60();
  RoundingOptions o = every_round_on_pdhg();
  o.feasibility_iterations = 256;  // a pre-test, which is not snapshot
  std::vector<SolveSnapshot> seen;
  std::vector<bool> watched;
  int rounds_seen = 0, before_round_one = 0;
  o.snapshot_seconds = 1e-9;  // (at every residual check)
  o.first_snapshot = [&](const SolveSnapshot& s, bool w) {
    seen.push_back(s);
    watched.push_back(w);
    if (rounds_seen == 0) ++before_round_one;
  };
  const RoundingResult r =
      round_to_graph_surface(m.space, m.lp, m.energy, o, [&](const RoundingRound&) { ++rounds_seen; });
  REQUIRE(r.rounds.size() >= 2);
  REQUIRE_FALSE(seen.empty());
  CHECK(before_round_one == int(seen.size()));  // none from a later round
  for (const SolveSnapshot& s : seen) {
    CHECK(s.x.size() == size_t(m.lp.cols()));  // over the whole LP
    CHECK(s.y.size() == size_t(m.lp.rows()));
    CHECK(s.iterations <= r.rounds.front().iterations);  // round 1's own, not its pre-test's
  }
  // Gone on from a snapshot: its iterations and seconds count on.
  o.resumed_iterations = 1000;
  o.resumed_seconds = 50.0;
  seen.clear();
  round_to_graph_surface(m.space, m.lp, m.energy, o);
  REQUIRE_FALSE(seen.empty());
  CHECK(seen.front().iterations > 1000);
  CHECK(seen.front().seconds > 50.0);
  // … and round 1's cap is what is left of it: first_max_iterations less those before.
  REQUIRE(r.rounds.front().iterations > 50);  // (uncapped, it takes more)
  o.first_snapshot = {};
  o.feasibility_iterations = 0;
  o.first_max_iterations = 200;
  o.resumed_iterations = 150;
  const RoundingResult capped = round_to_graph_surface(m.space, m.lp, m.energy, o);
  CHECK(capped.rounds.front().iterations == 50);
}

TEST_CASE("rounding: later rounds stop at their iteration cap and still end exact") {
  // Threshold 0 on the dolphins at 60 faces: several rounds (see the clashing-candidates test).
  const MatchingLp& m = dolphins_60();
  RoundingOptions o;
  o.solver = "pdhg-cpu";
  o.exact_below = 0;  // every round on PDHG, so that the cap applies to each
  o.threshold = 0.0;
  o.later_round_iterations = 1e-9;
  o.later_round_min_iterations = 16;  // a floor far below what these rounds take
  o.later_feasibility_iterations = 0;   // the costed solves' cap alone (a pre-test's count in the round's)
  const RoundingResult r = round_to_graph_surface(m.space, m.lp, m.energy, o);
  REQUIRE(r.rounds.size() >= 2);
  for (size_t i = 1; i < r.rounds.size(); ++i) {
    CAPTURE(i);
    CHECK(r.rounds[i].iterations <= 16);
  }
  CHECK(satisfies_exactly(m.lp, r.gamma));
  CHECK(check_graph_surface(m.space, r.gamma).covers_x);
  // Without the cap, some later round runs longer (so the check above can fail).
  o.later_round_iterations = 0;
  const RoundingResult u = round_to_graph_surface(m.space, m.lp, m.energy, o);
  int64_t longest = 0;
  for (size_t i = 1; i < u.rounds.size(); ++i) longest = std::max(longest, u.rounds[i].iterations);
  CHECK(longest > 16);
  CHECK(r.rounds.front().cap_scale == 1.0);  // reported, from 1 (round 1 undoes nothing)
  for (const RoundingRound& round : r.rounds) CHECK(round.cap_scale >= 1.0);

  // Started at a multiple of the cap (a rounding gone on from a checkpoint): its later rounds
  // stop at that multiple, and it is reported from round 1 on.
  o.later_round_iterations = 1e-9;
  o.search_below = 0;  // (a search round counts nodes, uncapped)
  o.start_cap_scale = 4.0;
  const RoundingResult s = round_to_graph_surface(m.space, m.lp, m.energy, o);
  REQUIRE(s.rounds.size() >= 2);
  CHECK(s.rounds.front().cap_scale >= 4.0);
  int64_t longest_scaled = 0;
  for (size_t i = 1; i < s.rounds.size(); ++i) {
    CAPTURE(i);
    CHECK(s.rounds[i].iterations <= static_cast<int64_t>(16 * s.rounds[i - 1].cap_scale));
    longest_scaled = std::max(longest_scaled, s.rounds[i].iterations);
  }
  CHECK(longest_scaled > 16);  // past the unscaled cap
  CHECK(satisfies_exactly(m.lp, s.gamma));
  o.start_cap_scale = 0.5;
  CHECK_THROWS_AS(round_to_graph_surface(m.space, m.lp, m.energy, o), InvalidInputError);
}

TEST_CASE("rounding: a later LP solved in its independent parts has the optimum of the whole") {
  // Threshold 0 on the dolphins at 60 faces: many rounds, and late ones leave separate patches.
  // Every round after the first on Clp, so both runs agree exactly up to the first round solved
  // in parts, whose joined optimum must then be the whole LP's.
  const MatchingLp& m = dolphins_60();
  RoundingOptions o;
  o.solver = "pdhg-cpu";
  o.exact_below = m.lp.cols() + 1;
  o.threshold = 0.0;
  const RoundingResult split = round_to_graph_surface(m.space, m.lp, m.energy, o);
  o.split_parts = false;
  const RoundingResult whole = round_to_graph_surface(m.space, m.lp, m.energy, o);
  size_t k = 0;
  while (k < split.rounds.size() && split.rounds[k].parts == 1) ++k;
  REQUIRE(k < split.rounds.size());
  REQUIRE(k < whole.rounds.size());
  MESSAGE("round ", k + 1, ": ", split.rounds[k].variables, " variables in ", split.rounds[k].parts, " parts");
  CHECK(whole.rounds[k].parts == 1);
  CHECK(whole.rounds[k].variables == split.rounds[k].variables);
  CHECK(split.rounds[k].objective == doctest::Approx(whole.rounds[k].objective).epsilon(1e-9));
  for (const RoundingResult* r : {&split, &whole}) {
    CHECK(satisfies_exactly(m.lp, r->gamma));
    CHECK(check_graph_surface(m.space, r->gamma).ok());
  }
}

TEST_CASE("rounding: later rounds finished by search end in a verified graph surface") {
  // Threshold 0 on the dolphins at 60 faces (many rounds otherwise), every round after the first
  // searched: each part ends at an integral vertex or by branching, and the joined Γ must still
  // be exact and a graph surface, with an energy above the bound.
  const MatchingLp& m = dolphins_60();
  RoundingOptions o;
  o.solver = "pdhg-cpu";
  o.threshold = 0.0;
  o.search_stall = 0;
  o.search_below = m.lp.cols();
  const RoundingResult r = round_to_graph_surface(m.space, m.lp, m.energy, o);
  int64_t searched = 0;
  for (const RoundingRound& k : r.rounds) searched += k.searched_parts;
  MESSAGE(r.rounds.size(), " rounds, ", searched, " parts searched, gap ", r.gap);
  CHECK(searched > 0);
  CHECK(r.rounds.size() <= 3);  // the search leaves nothing open where every part has a solution
  CHECK(satisfies_exactly(m.lp, r.gamma));
  CHECK(check_graph_surface(m.space, r.gamma).covers_x);
  CHECK(check_graph_surface(m.space, r.gamma).orientation);
  CHECK(r.energy >= r.lower_bound - 1e-9);
}

TEST_CASE("rounding: round 1 starts from a warm start over the whole LP and hands its iterate out") {
  const Mesh x = shapes::bent_finger(10, 5, 6), y = shapes::bent_finger(60, 5, 6);
  const MatchingLp m = build_matching_lp(x, compute_geometry(x), y, compute_geometry(y));
  RoundingOptions o;
  o.solver = "pdhg-cpu";
  std::vector<double> x0, y0;
  int calls = 0;
  o.first_iterate = [&](const std::vector<double>& xs, const std::vector<double>& ys, double) {
    x0 = xs;
    y0 = ys;
    ++calls;
  };
  const RoundingResult cold = round_to_graph_surface(m.space, m.lp, m.energy, o);
  CHECK(calls == 1);
  REQUIRE(x0.size() == size_t(m.lp.cols()));
  REQUIRE(y0.size() == size_t(m.lp.rows()));
  CHECK(max_residual(m.lp, x0) < 0.05);  // over the whole LP, the fixed part included
  o.first_iterate = {};
  o.lp.initial_x = x0;
  o.lp.initial_y = y0;
  const RoundingResult warm = round_to_graph_surface(m.space, m.lp, m.energy, o);
  MESSAGE("round 1: ", cold.first_lp.iterations, " iterations cold, ", warm.first_lp.iterations, " warm");
  CHECK(warm.first_lp.iterations * 4 < cold.first_lp.iterations);
  CHECK(satisfies_exactly(m.lp, warm.gamma));
  CHECK(warm.first_lp.lower_bound == doctest::Approx(cold.first_lp.lower_bound).epsilon(1e-2));
}

TEST_CASE("rounding: round 1 probed at a looser tolerance hands that iterate out, then goes on to its own") {
  const MatchingLp& m = dolphins_60();
  RoundingOptions o;
  o.solver = "pdhg-cpu";
  o.lp.tolerance = 1e-5;
  const RoundingResult plain = round_to_graph_surface(m.space, m.lp, m.energy, o);
  REQUIRE(plain.first_lp.status == LpStatus::Optimal);

  std::vector<double> probe_x, final_x;
  int probes = 0;
  o.probe_tolerance = 1e-2;
  o.probe = [&](const std::vector<double>& x, const std::vector<double>& y, double) {
    CHECK(y.size() == size_t(m.lp.rows()));
    probe_x = x;
    ++probes;
  };
  o.first_iterate = [&](const std::vector<double>& x, const std::vector<double>&, double) { final_x = x; };
  const RoundingResult probed = round_to_graph_surface(m.space, m.lp, m.energy, o);
  CHECK(probes == 1);
  REQUIRE(probe_x.size() == size_t(m.lp.cols()));
  REQUIRE(final_x.size() == size_t(m.lp.cols()));
  MESSAGE("max |Ax - b|: probe ", max_residual(m.lp, probe_x), ", round 1 ", max_residual(m.lp, final_x),
          "; round 1 iterations ",
          probed.first_lp.iterations, " against ", plain.first_lp.iterations, " unprobed");
  CHECK(max_residual(m.lp, final_x) < 0.5 * max_residual(m.lp, probe_x));  // it went on past the probe
  CHECK(probed.first_lp.status == LpStatus::Optimal);
  CHECK(probed.first_lp.lower_bound == doctest::Approx(plain.first_lp.lower_bound).epsilon(1e-3));
  CHECK(satisfies_exactly(m.lp, probed.gamma));
  CHECK(check_graph_surface(m.space, probed.gamma).covers_x);

  // The probe may abandon the rounding; one not looser than the LP's own is never called.
  struct Abandon {};
  o.probe = [](const std::vector<double>&, const std::vector<double>&, double) { throw Abandon{}; };
  CHECK_THROWS_AS(round_to_graph_surface(m.space, m.lp, m.energy, o), Abandon);
  o.probe_tolerance = o.lp.tolerance;
  CHECK_NOTHROW(round_to_graph_surface(m.space, m.lp, m.energy, o));
}

TEST_CASE("rounding: alternative thresholds round again from round 1's optimum and keep the Γ of least energy") {
  const MatchingLp& m = dolphin_ball_60();
  RoundingOptions o;
  o.solver = "pdhg-cpu";
  o.lp.tolerance = 1e-3;
  o.alternative_thresholds = {};
  // The paths measured for this test: without the later pre-test, 0.3 and 0.5 end apart (with it
  // they end at the same Γ, and the comparison below would not show which one alternatives keep).
  o.later_feasibility_iterations = 0;
  std::map<double, double> alone;
  for (double t : {0.3, 0.5, 0.7}) {
    o.threshold = t;
    const RoundingResult r = round_to_graph_surface(m.space, m.lp, m.energy, o);
    REQUIRE(r.tried.size() == 1);
    CHECK(r.tried[0].first == t);
    CHECK(r.threshold == t);
    alone[t] = r.energy;
  }
  MESSAGE("energies alone: 0.3 ", alone[0.3], ", 0.5 ", alone[0.5], ", 0.7 ", alone[0.7]);
  CHECK(alone[0.3] != alone[0.5]);  // else this pair shows nothing

  o.threshold = 0.3;
  o.alternative_thresholds = {0.5, 0.3, 0.7};  // 0.3 again is not run twice
  int progress_calls = 0, first_iterates = 0;
  o.first_iterate = [&](const std::vector<double>&, const std::vector<double>&, double) { ++first_iterates; };
  const RoundingResult best =
      round_to_graph_surface(m.space, m.lp, m.energy, o, [&](const RoundingRound&) { ++progress_calls; });
  REQUIRE(best.tried.size() == 3);
  CHECK(best.tried[0] == std::pair<double, double>{0.3, alone[0.3]});  // the one asked for first, as alone
  double lowest = best.tried[0].second, at = 0.3;
  for (const auto& [t, e] : best.tried) {
    CHECK(std::isfinite(e));
    if (e < lowest) lowest = e, at = t;
  }
  MESSAGE("with alternatives: 0.5 ", best.tried[1].second, ", 0.7 ", best.tried[2].second);
  CHECK(best.energy == lowest);
  CHECK(best.threshold == at);
  CHECK(satisfies_exactly(m.lp, best.gamma));
  const GraphSurfaceCheck g = check_graph_surface(m.space, best.gamma);
  CHECK(g.covers_x);
  CHECK(g.orientation);
  double sum = 0.0;
  for (int64_t j : best.gamma) sum += m.energy[j];
  CHECK(sum == doctest::Approx(best.energy).epsilon(1e-12));
  // Only the rounding asked for reports progress and hands out round 1's iterate; the bound is its
  // round 1's (or better).
  CHECK(first_iterates == 1);
  o.alternative_thresholds = {};
  o.first_iterate = {};
  const RoundingResult plain = round_to_graph_surface(m.space, m.lp, m.energy, o);
  CHECK(progress_calls == int(plain.rounds.size()));
  CHECK(best.lower_bound >= plain.lower_bound);
  CHECK(best.lower_bound <= best.energy + 1e-9);
  // Here an alternative wins; it restarts at the optimum, so its round 1 only confirms it.
  CHECK(best.threshold != 0.3);
  CHECK(best.energy < alone[0.3]);
  CHECK(best.rounds.front().iterations * 4 < plain.first_lp.iterations);

  // Above alternatives_below, one rounding.
  o.alternative_thresholds = {0.5, 0.7};
  o.alternatives_below = m.lp.cols() - 1;
  CHECK(round_to_graph_surface(m.space, m.lp, m.energy, o).tried.size() == 1);
}

TEST_CASE("rounding: where the first rounding fails after an optimal round 1, the alternatives still try, if asked") {
  const MatchingLp& m = dolphin_ball_60();
  RoundingOptions o;
  o.solver = "pdhg-cpu";
  o.lp.tolerance = 1e-3;
  o.threshold = 0.3;
  o.alternative_thresholds = {};
  const RoundingResult plain = round_to_graph_surface(m.space, m.lp, m.energy, o);
  // The rounding at 0.3 fails right after its round 1 (its first_iterate callback throws, which
  // the alternatives do not call); the LP is the same.
  int failures = 0;
  o.first_iterate = [&](const std::vector<double>&, const std::vector<double>&, double) {
    ++failures;
    throw SolverError("the first rounding gives up (test)");
  };
  o.alternative_thresholds = {0.5, 0.7};
  CHECK_THROWS_AS(round_to_graph_surface(m.space, m.lp, m.energy, o), SolverError);  // not asked: as before
  o.alternatives_after_failure = true;
  const RoundingResult r = round_to_graph_surface(m.space, m.lp, m.energy, o);
  CHECK(failures == 2);
  REQUIRE(r.tried.size() == 3);
  CHECK(r.tried[0].first == 0.3);
  CHECK(std::isnan(r.tried[0].second));
  CHECK(r.threshold != 0.3);
  CHECK(r.energy == std::min(r.tried[1].second, r.tried[2].second));
  CHECK(satisfies_exactly(m.lp, r.gamma));
  CHECK(check_graph_surface(m.space, r.gamma).ok());
  // The bound is round 1's, which the failed rounding solved.
  CHECK(r.lower_bound >= plain.lower_bound - 1e-9);
  CHECK(r.lower_bound <= r.energy + 1e-9);
  CHECK(r.first_lp.iterations == plain.first_lp.iterations);
  MESSAGE("after the failure at 0.3: ", r.tried[1].second, " (0.5), ", r.tried[2].second, " (0.7), bound ",
          r.lower_bound);
  // Where no alternative finds a Γ either (one round is too few for this LP), the first error stands.
  o.first_iterate = [&](const std::vector<double>&, const std::vector<double>&, double) {
    throw SolverError("the first rounding gives up (test)");
  };
  o.max_total_rounds = 1;
  try {
    (void)round_to_graph_surface(m.space, m.lp, m.energy, o);
    FAIL("expected the first rounding's error");
  } catch (const SolverError& e) {
    CHECK(std::string(e.what()).find("(test)") != std::string::npos);
  }
}

TEST_CASE("rounding: round 1 stops at its own cap, rounds from its iterate, and its bound stays below the optimum") {
  const MatchingLp& m = dolphins_60();
  RoundingOptions o;
  o.solver = "pdhg-cpu";
  const RoundingResult full = round_to_graph_surface(m.space, m.lp, m.energy, o);
  REQUIRE(full.first_lp.status == LpStatus::Optimal);
  REQUIRE(full.first_lp.iterations > 128);
  o.first_max_iterations = 64;
  const RoundingResult capped = round_to_graph_surface(m.space, m.lp, m.energy, o);
  CHECK(capped.first_lp.status == LpStatus::IterationLimit);
  CHECK(capped.first_lp.iterations <= 64);
  // Later rounds keep their own caps (round 1's is not theirs): some runs past 64.
  int64_t longest = 0;
  for (size_t i = 1; i < capped.rounds.size(); ++i) longest = std::max(longest, capped.rounds[i].iterations);
  CHECK(longest > 64);
  CHECK(satisfies_exactly(m.lp, capped.gamma));
  CHECK(check_graph_surface(m.space, capped.gamma).covers_x);
  // An unconverged dual still gives a valid (weaker) bound.
  CHECK(capped.lower_bound <= full.first_lp.objective * (1 + 1e-3));
  CHECK(capped.lower_bound <= capped.energy);
}

TEST_CASE("rounding: max_rounds counts the rounds that bring no new low of free variables, max_total_rounds all") {
  const MatchingLp& m = dolphin_ball_60();
  RoundingOptions o;
  o.solver = "pdhg-cpu";
  o.lp.tolerance = 1e-3;
  o.alternative_thresholds = {};
  const RoundingResult plain = round_to_graph_surface(m.space, m.lp, m.energy, o);
  // Every round of this rounding leaves fewer free variables than any before it.
  REQUIRE(plain.rounds.size() >= 3);
  for (size_t i = 1; i < plain.rounds.size(); ++i) REQUIRE(plain.rounds[i].variables < plain.rounds[i - 1].variables);
  // So one round without a new low is enough for it; one round fewer than it made, in all, is not.
  o.max_rounds = 1;
  const RoundingResult one = round_to_graph_surface(m.space, m.lp, m.energy, o);
  CHECK(one.gamma == plain.gamma);
  CHECK(one.rounds.size() == plain.rounds.size());
  o.max_total_rounds = static_cast<int>(plain.rounds.size()) - 1;
  CHECK_THROWS_AS(round_to_graph_surface(m.space, m.lp, m.energy, o), InfeasibleError);
  o.max_total_rounds = static_cast<int>(plain.rounds.size());
  CHECK(round_to_graph_surface(m.space, m.lp, m.energy, o).gamma == plain.gamma);
}

TEST_CASE("rounding: limits end in an error, never a wrong answer") {
  const Mesh x = shapes::tetrahedron();
  const Mesh y = test::deformed(x, [](const Eigen::Vector3d& p) { return Eigen::Vector3d(p.x(), 2 * p.y(), p.z()); });
  const Geometry gx = compute_geometry(x), gy = compute_geometry(y);
  const MatchingLp m = build_matching_lp(x, gx, y, gy);
  RoundingOptions o;
  o.max_rounds = 0;
  CHECK_THROWS_AS(round_to_graph_surface(m.space, m.lp, m.energy, o), SolverError);
  std::vector<double> wrong_size(3, 0.0);
  CHECK_THROWS_AS(round_to_graph_surface(m.space, m.lp, wrong_size, {}), InvalidInputError);
}

TEST_CASE("rounding: the continuity check catches two faces that trade images") {
  // The identity of a sphere with itself, except that two faces far apart swap their images:
  // still one product triangle per face on both sides, each with its orientation, but the
  // vertices of both faces are now related to two distant places.
  const Mesh x = shapes::icosphere(1);
  const ProductSpace space = ProductSpace::full(x, x);
  std::vector<ProductTriangle> id = identity_matching(x);
  std::vector<int64_t> gamma;
  for (const auto& t : id) gamma.push_back(space.index_in_full(t));
  GraphSurfaceCheck c = check_graph_surface(space, gamma);
  REQUIRE(c.ok());
  CHECK(c.discontinuous_vertices_x == 0);
  CHECK(c.discontinuous_edges_y == 0);

  const int f = 0;
  int g = -1;
  double far = 0;
  auto centre = [&](int k) { return Eigen::Vector3d(x.vertices[x.faces[k][0]] + x.vertices[x.faces[k][1]] + x.vertices[x.faces[k][2]]); };
  for (int k = 0; k < x.num_faces(); ++k)
    if ((centre(k) - centre(f)).norm() > far) far = (centre(k) - centre(f)).norm(), g = k;
  auto with_image = [&](int from, int to) {
    ProductTriangle t{x.faces[from], x.faces[to], from, to};
    return space.index_in_full(t);
  };
  for (auto& j : gamma) {
    const ProductTriangle t = space[j];
    if (t.fa == f) j = with_image(f, g);
    else if (t.fa == g) j = with_image(g, f);
  }
  c = check_graph_surface(space, gamma);
  CHECK(c.covers_x);
  CHECK(c.covers_y);
  CHECK(c.orientation);
  CHECK_FALSE(c.continuous);
  CHECK_FALSE(c.ok());
  CHECK(c.discontinuous_vertices_x == 6);  // the three corners of each face
  CHECK(c.discontinuous_vertices_y == 6);
  CHECK(c.discontinuous_edges_x >= 6);
}

TEST_CASE("rounding: propagation names the row of a contradiction, and skipped rows are left out") {
  // x0 + x1 = 1, x0 = 1, x1 = 1: propagation fixes x0 = 1, then x1 = 0 and x1 = 1 clash.
  const LpProblem clash = test::dense_lp({{1, 1}, {1, 0}, {0, 1}}, {1, 1, 1}, {0, 0});
  const int64_t row = propagation_conflict(clash);
  CHECK(row >= 0);
  CHECK(row <= 2);
  CHECK(propagation_conflict(clash, {0, 0, 1}) == -1);  // without x1 = 1 it is consistent
  CHECK(propagation_conflict(clash, {1, 0, 0}) == -1);  // without the sum, too
  // A row no entry can satisfy is itself the contradiction.
  CHECK(propagation_conflict(test::dense_lp({{1, 1}, {0, 0}}, {1, 1}, {0, 0})) == 1);
  // A feasible system has none.
  CHECK(propagation_conflict(test::dense_lp({{1, 1, 0}, {0, 1, 1}}, {1, 1}, {0, 0, 0})) == -1);
  CHECK_THROWS_AS(propagation_conflict(clash, {0, 1}), InvalidInputError);
  // The rounding's error carries the row, for callers that widen the problem there.
  const Mesh x = shapes::octahedron();
  const Geometry g = compute_geometry(x);
  MatchingLp m = build_matching_lp(x, g, x, g);
  CHECK(propagation_conflict(m.lp) == -1);
  m.lp.b[m.lp.rows() - 1] = -1;  // a face of Y covered −1 times
  try {
    round_to_graph_surface(m.space, m.lp, m.energy);
    FAIL("no InfeasibleError");
  } catch (const InfeasibleError& e) {
    REQUIRE(e.rows().size() == 1);
    CHECK(e.rows()[0] == m.lp.rows() - 1);
    CHECK(propagation_conflict(m.lp) == m.lp.rows() - 1);
  }
}

TEST_CASE("rounding: a batch full of clashing candidates still ends in an exact graph surface, halved or greedy") {
  // Threshold 0: every variable the LP touches is a candidate, so fixings clash with larger ones
  // and must be taken back exactly (propagation included). Measured: fixing every candidate that
  // does not clash (greedy) ends in fewer rounds but at a 123 % gap on the 30-face bench pair,
  // against < 100 % for halving the batch; greedy only pays in rounds of millions of variables.
  const MatchingLp& m = dolphins_60();
  RoundingOptions o;
  o.solver = "pdhg-cpu";
  o.threshold = 0.0;
  const RoundingResult halved = round_to_graph_surface(m.space, m.lp, m.energy, o);
  o.greedy_above = 0;
  const RoundingResult greedy = round_to_graph_surface(m.space, m.lp, m.energy, o);
  for (const RoundingResult* r : {&halved, &greedy}) {
    CHECK(satisfies_exactly(m.lp, r->gamma));
    CHECK(check_graph_surface(m.space, r->gamma).ok());
    CHECK(r->energy >= r->lower_bound - 1e-9);
    REQUIRE(!r->rounds.empty());
    CHECK(r->rounds[0].undone);  // the clashes happened: the first batch did not go in whole
  }
  // Halving applies at most half of a clashing batch per round; greedy all that fit.
  CHECK(greedy.rounds[0].fixed_to_one > halved.rounds[0].fixed_to_one);
  CHECK(greedy.rounds.size() < halved.rounds.size());
  MESSAGE("threshold 0: halving ", halved.rounds.size(), " rounds, gap ", halved.gap, "; greedy ",
          greedy.rounds.size(), " rounds, gap ", greedy.gap);
}

namespace {

// Variables a, a', c, y1..y5, w1, w2, b1, b1', b2, b2'. a + a' = 1; a' = c; y_i + y_{i+1} + c = 1
// around a 5-cycle; y1 + ... + y5 + w1 + w2 = 2; b_k + b_k' = 1. a' and b_k' cost 10 (`cost`).
// `links` 1: b1 = 1 forces a = 1 too; 2: b1 and b2 force each other, and together a = 1; 3: a
// second way to c = 0, e = 1 (e + c + s = 1).
LpProblem cycle_behind_a_fixing(std::vector<double>& cost, int links = 0) {
  const int n = 14 + (links == 1 ? 1 : links == 2 ? 3 : links == 3 ? 2 : 0);
  std::vector<std::vector<int>> rows(10 + (links == 1 || links == 3 ? 1 : links == 2 ? 3 : 0), std::vector<int>(n, 0));
  rows[0][0] = rows[0][1] = 1;
  rows[1][1] = 1;
  rows[1][2] = -1;
  for (int i = 0; i < 5; ++i) rows[2 + i][3 + i] = rows[2 + i][3 + (i + 1) % 5] = rows[2 + i][2] = 1;
  for (int j = 3; j <= 9; ++j) rows[7][j] = 1;
  rows[8][10] = rows[8][11] = 1;
  rows[9][12] = rows[9][13] = 1;
  std::vector<double> b{1, 0, 1, 1, 1, 1, 1, 2, 1, 1};
  if (links == 1) {  // b1 + a' + s = 1 with a slack s: b1 = 1 forces a' = 0, hence a = 1
    rows[10][10] = rows[10][1] = rows[10][14] = 1;
    b.push_back(1);
  } else if (links == 2) {
    // b1 + b2' + s = 1 and b2 + b1' + s' = 1: b1 = b2; b1 + b2 + a' + s'' = 2: both 1 force
    // a' = 0. The LP has b1 = b2 = 0.9 above a = 0.8 (cost 10 a' + 20 (1 - b), b <= 1 - a'/2,
    // a' >= 1/5).
    rows[10][10] = rows[10][13] = rows[10][14] = 1;
    rows[11][12] = rows[11][11] = rows[11][15] = 1;
    rows[12][10] = rows[12][12] = rows[12][1] = rows[12][16] = 1;
    b.insert(b.end(), {1, 1, 2});
  } else if (links == 3) {
    rows[10][14] = rows[10][2] = rows[10][15] = 1;
    b.push_back(1);
  }
  cost.assign(n, 0.0);
  cost[1] = cost[11] = cost[13] = 10.0;
  return test::dense_lp(rows, b, cost);
}

// A product space with as many elements as `lp` has columns, for roundings of hand-made LPs
// (rounding reads only its size there).
ProductSpace stand_in_space(const LpProblem& lp) {
  const Mesh sphere = shapes::icosphere(1);
  const auto id = identity_matching(sphere);
  return ProductSpace::from_list(sphere, sphere, {id.begin(), id.begin() + lp.cols()});
}

// Rounds cycle_behind_a_fixing on a stand-in space of its size with PDHG, whose infeasibility
// proof is a dual point (Clp's names no rows), and checks A x = b.
RoundingResult round_cycle(RoundingOptions options, int links = 0,
                           const std::function<void(const RoundingRound&)>& progress = {}) {
  std::vector<double> cost;
  const LpProblem lp = cycle_behind_a_fixing(cost, links);
  const ProductSpace space = stand_in_space(lp);
  options.solver = "pdhg-cpu";
  options.exact_below = 0;
  RoundingResult r = round_to_graph_surface(space, lp, cost, options, progress);
  CHECK(satisfies_exactly(lp, r.gamma));
  return r;
}

}  // namespace

TEST_CASE("rounding: an infeasible LP after a fixing undoes only the fixings its proof blames, and not to retry them") {
  // The LP cycle_behind_a_fixing has a' = c = 1/5 (y = 2/5, the sum at its cap 2) and b = 1, so
  // round 1 fixes b1, b2 and a = 0.8. With a = 1 the cycle needs y = 1/2, a sum of 5/2:
  // infeasible, but no row alone says so, so only the next LP can. Its proof lies on the cycle, two rows away from a (a -> a' -> c,
  // by propagation) and away from b1 and b2: they stay fixed, where halving the batch would
  // have kept b1 alone.
  const RoundingResult r = round_cycle({});
  CHECK(r.energy == 10.0);  // a' = c = 1, b1 = b2 = 1
  REQUIRE(r.rounds.size() >= 2);
  CHECK(r.rounds[0].fixed_to_one == 3);
  CHECK(r.rounds[1].status == LpStatus::Infeasible);
  CHECK(r.rounds[1].undone);
  CHECK(r.rounds[1].fixed_to_one == 2);  // b1 and b2 again; halving: b1 alone
  // Round 3's LP is round 1's without b: a = 0.8 again. The proof refuted a from this state, so
  // it is not fixed again (without that: fixed, and round 4's LP infeasible once more).
  REQUIRE(r.rounds.size() >= 3);
  CHECK(r.rounds[2].fixed_to_one == 0);
  int infeasible = 0;
  for (const auto& k : r.rounds) infeasible += k.status == LpStatus::Infeasible;
  CHECK(infeasible == 1);
}

TEST_CASE("rounding: max_rounds runs out on the rounds after a trim, which bring no new low") {
  // cycle_behind_a_fixing: round 2's LP is infeasible and trims round 1's fixing, so the rounds
  // after it start with more free variables than round 2 had. At the start of each round the
  // rounds that went forward before it (their LP not infeasible) less those that brought a new
  // low (up to it, round 1 aside) are what max_rounds bounds: the rounding needs one more than
  // their peak, and runs out at the peak itself.
  const RoundingResult plain = round_cycle({});
  int forward = 0, lows = 0, peak = 0;
  int64_t fewest = std::numeric_limits<int64_t>::max();
  for (size_t k = 0; k < plain.rounds.size(); ++k) {
    const RoundingRound& round = plain.rounds[k];
    REQUIRE(round.status != LpStatus::IterationLimit);  // (no round undone on a suspicion)
    if (round.variables < fewest) {
      fewest = round.variables;
      lows += k > 0;
    }
    peak = std::max(peak, forward - lows);
    forward += round.status != LpStatus::Infeasible;
  }
  REQUIRE(peak >= 1);  // rounds without a new low happened
  RoundingOptions o;
  o.max_rounds = peak + 1;
  CHECK(round_cycle(o).gamma == plain.gamma);
  o.max_rounds = peak;
  CHECK_THROWS_AS(round_cycle(o), InfeasibleError);
}

TEST_CASE("rounding: a search right after a fixing whose LP has no solution leaves it to the LP round, not a release") {
  // cycle_behind_a_fixing with the search at once (no stall needed): round 1 fixes b1, b2 and a,
  // and with a = 1 the cycle's LP has no solution. The search's root LP finds that; it hands the
  // round to the LP, whose proof trims a alone, as without the search (a release instead would
  // free every fixing within two steps of the part, b1 and b2 with a).
  RoundingOptions options;
  options.search_stall = 0;
  const RoundingResult r = round_cycle(options);
  CHECK(r.energy == 10.0);
  REQUIRE(r.rounds.size() >= 3);
  CHECK(r.rounds[0].fixed_to_one == 3);
  CHECK_FALSE(r.rounds[1].search);
  CHECK(r.rounds[1].status == LpStatus::Infeasible);
  CHECK(r.rounds[1].undone);
  CHECK(r.rounds[1].fixed_to_one == 2);  // b1 and b2 kept
  for (const RoundingRound& k : r.rounds) CHECK(k.released == 0);
  CHECK(r.rounds.back().search);  // and the rest finished by search
}

TEST_CASE("rounding: a fixing from an LP at its iteration cap is undone whole, and the LP solved again longer") {
  // cycle_behind_a_fixing as above, with round 1 stopped at its cap, its iterate already past
  // the threshold on a, b1 and b2. The proof after it blames a alone, but an iterate at its cap
  // is not trusted for the rest either: all three fixings go (the rule above would keep b1, b2).
  RoundingOptions options;
  options.lp.max_iterations = 200;
  options.lp.threads = 1;  // the same iterates on any machine
  const RoundingResult r = round_cycle(options);
  CHECK(r.energy == 10.0);
  REQUIRE(r.rounds.size() >= 3);
  CHECK(r.rounds[0].status == LpStatus::IterationLimit);
  CHECK(r.rounds[0].fixed_to_one == 3);
  CHECK(r.rounds[1].status == LpStatus::Infeasible);
  CHECK(r.rounds[1].undone);
  CHECK(r.rounds[1].fixed_to_one == 0);  // nothing of round 1's batch is left
}

TEST_CASE("rounding: where the LPs after its fixings keep failing it gives up with its fixings, if asked") {
  // cycle_behind_a_fixing: round 2's LP is infeasible (a = 1 leaves the cycle no solution). With
  // stuck_rounds 1 and any time at all, that one failed round is "stuck": a StuckError naming the
  // failed rows (on the cycle) and carrying what is fixed to 1 after the proof trimmed a (b1,
  // b2), with an iterate over the whole LP. Off (stuck_after 0) the same rounds go on to Γ.
  RoundingOptions options;
  options.stuck_rounds = 1;
  options.stuck_after = 1e-12;
  std::vector<double> cost;
  const LpProblem lp = cycle_behind_a_fixing(cost);
  try {
    round_cycle(options);
    FAIL("no StuckError");
  } catch (const StuckError& e) {
    CHECK(!e.rows().empty());
    for (int64_t i : e.rows()) CHECK((i >= 1 && i <= 7));  // a' = c and the cycle's rows
    CHECK(e.ones() == std::vector<int64_t>{10, 12});       // b1, b2
    CHECK(e.steps().size() == e.ones().size());
    CHECK(e.x().size() == size_t(lp.cols()));
    CHECK(e.y().size() == size_t(lp.rows()));
  }
  options.stuck_after = 0.0;
  CHECK(round_cycle(options).energy == 10.0);
  // Not yet stuck where fewer rounds failed than stuck_rounds.
  options.stuck_after = 1e-12;
  options.stuck_rounds = 2;
  options.stuck_stalled = 0;
  CHECK(round_cycle(options).energy == 10.0);
}

TEST_CASE("rounding: where the free variables reach no new low for long it gives up, if asked") {
  // cycle_behind_a_fixing: round 2 starts with b1, b2 and a fixed, round 3 with a undone, more
  // free variables than round 2 had: one round without a new low. Only one LP fails, so the rule
  // on failing rounds (stuck_rounds 2) does not act.
  RoundingOptions options;
  options.stuck_rounds = 2;
  options.stuck_after = 1e-12;
  options.stuck_stalled = 1;
  try {
    round_cycle(options);
    FAIL("no StuckError");
  } catch (const StuckError& e) {
    CHECK(std::string(e.what()).find("no fewer free variables") != std::string::npos);
    CHECK(!e.rows().empty());  // the rows still open
    CHECK(e.ones() == std::vector<int64_t>{10, 12});  // b1, b2
  }
  options.stuck_stalled = 100;  // not that many rounds
  CHECK(round_cycle(options).energy == 10.0);
  options.stuck_stalled = 1;
  options.stuck_after = 1e3;  // nor that long
  CHECK(round_cycle(options).energy == 10.0);
}

TEST_CASE("rounding: a budget on the work of its later rounds gives up where they cost too much, if asked") {
  // Work is iterations × free variables, against round 1's. The dolphin and the bumpy ball round
  // in several rounds: a tiny budget gives up after round 2 (a StuckError, as stuck_after's, the
  // alternative thresholds not saving it unless asked, and under the same budget where asked); a
  // budget never spent leaves the rounding as it was.
  const MatchingLp& m = dolphin_ball_60();
  RoundingOptions o;
  o.solver = "pdhg-cpu";
  o.lp.tolerance = 1e-3;
  const RoundingResult plain = round_to_graph_surface(m.space, m.lp, m.energy, o);
  REQUIRE(plain.rounds.size() > 2);  // else the budget shows nothing here
  o.give_up_after = 1e-9;
  int rounds = 0;
  try {
    (void)round_to_graph_surface(m.space, m.lp, m.energy, o, [&](const RoundingRound&) { ++rounds; });
    FAIL("no StuckError");
  } catch (const StuckError& e) {
    CHECK(std::string(e.what()).find("gave up") != std::string::npos);
    CHECK(e.x().size() == size_t(m.lp.cols()));
  }
  CHECK(rounds == 2);
  o.alternatives_after_failure = true;
  CHECK_THROWS_AS(round_to_graph_surface(m.space, m.lp, m.energy, o), StuckError);
  o.give_up_after = 1e9;
  const RoundingResult budgeted = round_to_graph_surface(m.space, m.lp, m.energy, o);
  CHECK(budgeted.energy == plain.energy);
  CHECK(budgeted.gamma == plain.gamma);
  // A failed LP counts like any (cycle_behind_a_fixing: round 2's LP is infeasible): the
  // StuckError carries the fixings to 1 that stuck_after's would (b1, b2).
  RoundingOptions options;
  options.give_up_after = 1e-9;
  try {
    (void)round_cycle(options);
    FAIL("no StuckError");
  } catch (const StuckError& e) {
    CHECK(e.ones() == std::vector<int64_t>{10, 12});
  }
  options.give_up_after = 0.0;
  CHECK(round_cycle(options).energy == 10.0);
}

TEST_CASE("rounding: it starts from carried fixings to 1, trims them like any fixing, and certifies the bound given") {
  const RoundingResult plain = round_cycle({});
  // b1 and b2 carried: they are in Γ, and round 1's LP is what they leave.
  RoundingOptions options;
  options.start_ones = {10, 12};
  RoundingResult r = round_cycle(options);
  CHECK(r.energy == 10.0);
  CHECK(std::find(r.gamma.begin(), r.gamma.end(), 10) != r.gamma.end());
  CHECK(std::find(r.gamma.begin(), r.gamma.end(), 12) != r.gamma.end());
  REQUIRE(!r.rounds.empty());
  CHECK(r.rounds[0].variables < plain.rounds[0].variables);
  // Without a dual for it, no bound is claimed (round 1's is the fixings' LP's, not the whole's).
  CHECK(r.lower_bound == -std::numeric_limits<double>::infinity());
  // With the whole LP's first dual, its certified bound: the plain run's exactly. (Propagation
  // decides nothing before round 1 here, so that LP's rows are the whole LP's.)
  REQUIRE(plain.first_lp.y.size() == 10);
  options.start_dual = plain.first_lp.y;
  r = round_cycle(options);
  CHECK(r.lower_bound == doctest::Approx(plain.lower_bound));
  CHECK(r.gap == doctest::Approx(plain.gap));
  // A carried fixing that leaves no binary solution (a = 1) is trimmed by the proof after it.
  options.start_ones = {0, 10, 12};
  r = round_cycle(options);
  CHECK(r.energy == 10.0);
  CHECK(std::find(r.gamma.begin(), r.gamma.end(), 0) == r.gamma.end());
  // One naming no variable is invalid input.
  options.start_ones = {99};
  CHECK_THROWS_AS(round_cycle(options), InvalidInputError);
}

TEST_CASE("rounding: a certificate's margin falls by exactly the weight of each fixing freed") {
  // x0 + x1 + x2 = 1, x1 − x3 = 0, x2 + x3 + x4 = 1.
  const LpProblem lp = test::dense_lp({{1, 1, 1, 0, 0}, {0, 1, 0, -1, 0}, {0, 0, 1, 1, 1}}, {1, 0, 1}, {0, 0, 0, 0, 0});
  // The state x0 = 1, x2 = x3 = x4 = 0 (x1 free): r = (0, 0, 1).
  const std::vector<int8_t> value{1, -1, 0, 0, 0};
  const std::vector<int64_t> rhs{0, 0, 1};
  // d = (1, −1, 1): Aᵀd = (1, 0, 2, 2, 1), margin 1 − max(0, 0) = 1 > 0 (indeed x1 = x3 = 0 leaves
  // row 3 short). d' = (−1, 1, 0): Aᵀd' = (−1, 0, −1, −1, 0), a fixing to 1 against it (x0).
  const std::vector<double> d{1.0, -1.0, 1.0}, d2{-1.0, 1.0, 0.0};
  const detail::CertificateBlame blame(lp, d), blame2(lp, d2);
  const double m = blame.margin(value, rhs);
  CHECK(m == doctest::Approx(1.0));
  CHECK(blame.weight(0, 1) == 0.0);  // (Aᵀd)_0 = 1: a 1 there denies nothing
  CHECK(blame.weight(2, 0) == doctest::Approx(2.0));
  CHECK(blame.weight(4, 0) == doctest::Approx(1.0));
  CHECK(blame.weight(1, 0) == 0.0);
  CHECK(blame2.weight(0, 1) == doctest::Approx(1.0));
  CHECK(blame2.weight(2, 0) == 0.0);
  // Each freed on its own: the margin falls by its weight, whatever its value was.
  for (const detail::CertificateBlame* c : {&blame, &blame2})
    for (int64_t j : {0, 2, 3, 4}) {
      std::vector<int8_t> v = value;
      std::vector<int64_t> r = rhs;
      if (v[j] == 1)
        for (int64_t i = 0; i < lp.rows(); ++i)
          for (uint32_t k = lp.a.row_ptr[i]; k < lp.a.row_ptr[i + 1]; ++k)
            if (int64_t(col_of(lp.a.entry[k])) == j) r[i] += is_negative(lp.a.entry[k]) ? -1 : 1;
      v[j] = -1;
      CHECK(c->margin(v, r) == doctest::Approx(c->margin(value, rhs) - c->weight(j, value[j])));
    }
  // Along a trail x0 (a fixing), x2, x3 (its propagation), x4 (a fixing of the next step): each
  // fixing is charged its own segment, each step all of its assignments.
  const std::vector<std::pair<int64_t, bool>> trail{{0, true}, {2, false}, {3, false}, {4, true}};
  const detail::TrailWeights w = detail::trail_weights(
      blame,
      [&](auto&& visit) {
        for (const auto& [j, fixed] : trail) visit(j, fixed);
      },
      value, {0, 3});
  REQUIRE(w.step.size() == 2);
  CHECK(w.step[0] == doctest::Approx(4.0));
  CHECK(w.step[1] == doctest::Approx(1.0));
  REQUIRE(w.decision.size() == 2);
  CHECK(w.decision[0] == std::pair<int64_t, double>{0, 4.0});
  CHECK(w.decision[1] == std::pair<int64_t, double>{4, 1.0});
  // The heaviest first, up to the margin; none that weighs nothing.
  CHECK(detail::heaviest_decisions(w.decision, 1.0) == std::vector<int64_t>{0});
  CHECK(detail::heaviest_decisions(w.decision, 4.5) == std::vector<int64_t>{0, 4});
  CHECK(detail::heaviest_decisions({{7, 0.0}, {8, 2.0}}, 5.0) == std::vector<int64_t>{8});
  CHECK(detail::heaviest_decisions({{7, 0.0}}, 5.0).empty());
  // Two independent parts' certificates in one d (x0 + x1 = 3, x2 + x3 = 3, both in [0, 1]): each
  // has its own margin, and freeing a fixing of one leaves the other's.
  const LpProblem two = test::dense_lp({{1, 1, 0, 0}, {0, 0, 1, 1}}, {3, 3}, {0, 0, 0, 0});
  const std::vector<double> both{1.0, 2.0};
  const detail::CertificateBlame blame_two(two, both);
  const std::vector<int32_t> parts_of{0, 1};
  CHECK(blame_two.margins({-1, -1, -1, -1}, {3, 3}, parts_of, 2) == std::vector<double>{1.0, 2.0});
  // x0 fixed to 0 (weight 1): part 0 at 2 (> 1, infeasible still: x1 alone reaches 1 of 3)
  CHECK(blame_two.margins({0, -1, -1, -1}, {3, 3}, parts_of, 2) == std::vector<double>{2.0, 2.0});
  CHECK(blame_two.margin({0, -1, -1, -1}, {3, 3}) == doctest::Approx(4.0));
  // A column in both parts' rows (as after a release joins them) counts in each with its own rows:
  // x4 in both rows with 1 and −1, d = (1, 2): part 0 sees +1, part 1 sees −2 (nothing to take).
  const LpProblem joined = test::dense_lp({{1, 1, 0, 0, 1}, {0, 0, 1, 1, -1}}, {3, 3}, {0, 0, 0, 0, 0});
  const detail::CertificateBlame blame_joined(joined, both);
  CHECK(blame_joined.margins({-1, -1, -1, -1, -1}, {3, 3}, parts_of, 2) == std::vector<double>{0.0, 2.0});
  CHECK(blame_joined.margin({-1, -1, -1, -1, -1}, {3, 3}) == doctest::Approx(3.0));  // (Aᵀd)_4 = −1 as one
  // A proof's sign: the one whose rate is positive, none where neither is (x0 + x1 = 3 in [0, 1]).
  const LpProblem bad = test::dense_lp({{1, 1}}, {3}, {0, 0});
  CHECK(detail::oriented_certificate(bad, {-1.0}) == std::vector<double>{1.0});
  CHECK(detail::oriented_certificate(bad, {2.0}) == std::vector<double>{2.0});
  CHECK(detail::oriented_certificate(bad, {0.0}).empty());
  CHECK(detail::oriented_certificate(test::dense_lp({{1, 1}}, {1}, {0, 0}), {1.0}).empty());
}

TEST_CASE("rounding: a proof that undoing the last fixing cannot break releases the earlier fixing that carries it") {
  // cycle_behind_a_fixing carried in two steps: a (which leaves no binary solution: the cycle
  // needs c = 1/5), then b1 and b2 (harmless). Round 1's LP is infeasible; its proof lies on the
  // cycle, where b1 and b2 take nothing off its margin, so trimming them cannot help: a goes,
  // b1 and b2 stay, and the next LP is feasible.
  RoundingOptions options;
  options.start_ones = {0, 10, 12};
  options.start_steps = {0, 1, 1};
  const RoundingResult r = round_cycle(options);
  CHECK(r.energy == 10.0);
  CHECK(std::find(r.gamma.begin(), r.gamma.end(), 0) == r.gamma.end());
  CHECK(std::find(r.gamma.begin(), r.gamma.end(), 10) != r.gamma.end());
  CHECK(std::find(r.gamma.begin(), r.gamma.end(), 12) != r.gamma.end());
  REQUIRE(r.rounds.size() >= 2);
  CHECK(r.rounds[0].status == LpStatus::Infeasible);
  CHECK(r.rounds[0].certificate_released == 1);
  CHECK(r.rounds[0].fixed_to_one == -1);  // a alone
  int infeasible = 0;
  for (const auto& k : r.rounds) infeasible += k.status == LpStatus::Infeasible;
  CHECK(infeasible == 1);
  // Without it the proof trims the last step first: b1 and b2 go (by halves: the proof blames
  // neither), each time the same LP proved infeasible again, before a does.
  options.certificate_release = false;
  const RoundingResult plain = round_cycle(options);
  CHECK(plain.energy == 10.0);
  int plain_infeasible = 0;
  for (const auto& k : plain.rounds) {
    plain_infeasible += k.status == LpStatus::Infeasible;
    CHECK(k.certificate_released == 0);
  }
  CHECK(plain_infeasible > 1);
  CHECK(plain.rounds.size() > r.rounds.size());  // (5 against 3)
  // The culprit between two harmless steps: only its step goes, the others stay apart as they were
  // (what a checkpoint after that round keeps).
  options.certificate_release = true;
  options.start_ones = {10, 0, 12};
  options.start_steps = {0, 1, 2};
  std::vector<int64_t> ones_after;
  std::vector<int32_t> steps_after;
  options.decided = [&](const RoundingRound& round, const std::vector<int64_t>& ones, const std::vector<int32_t>& steps,
                        double, const std::vector<double>&, const std::vector<double>&) {
    if (round.round != 1) return;
    ones_after = ones;
    steps_after = steps;
  };
  const RoundingResult middle = round_cycle(options);
  CHECK(middle.energy == 10.0);
  REQUIRE(!middle.rounds.empty());
  CHECK(middle.rounds[0].certificate_released == 1);
  CHECK(ones_after == std::vector<int64_t>{10, 12});
  CHECK(steps_after == std::vector<int32_t>{0, 1});
  // Where the fixing that carries the margin is not the only way to it (e = 1 forces c = 0 as a
  // does, and weighs nothing while a comes first), releasing it leaves the proof standing; weighed
  // again on what is left, e carries it, and both go in one round.
  options.decided = {};
  options.start_ones = {0, 14, 10, 12};
  options.start_steps = {0, 1, 2, 2};
  const RoundingResult twice = round_cycle(options, 3);
  options.certificate_release = false;
  const RoundingResult twice_plain = round_cycle(options, 3);
  CHECK(twice.energy == 10.0);
  CHECK(twice_plain.energy == 10.0);
  REQUIRE(!twice.rounds.empty());
  CHECK(twice.rounds[0].certificate_released == 2);
  CHECK(twice.rounds[0].fixed_to_one == -2);
  int twice_infeasible = 0, twice_plain_infeasible = 0;
  for (const auto& k : twice.rounds) twice_infeasible += k.status == LpStatus::Infeasible;
  for (const auto& k : twice_plain.rounds) twice_plain_infeasible += k.status == LpStatus::Infeasible;
  CHECK(twice_infeasible == 1);
  CHECK(twice_plain_infeasible > 1);
}

TEST_CASE("rounding: a big round fixes only candidates away from the LP's undecided part") {
  // cycle_behind_a_fixing: a = 0.8 with a' = c = 0.2 next to it, b1 = b2 = 1 with b1' = b2' =
  // 0. Where every round counts as big (greedy_above 0), round 1 fixes b1 and b2 but not a (its
  // row holds a', undecided), so the LP after it is feasible; with the margin off it fixes all
  // three and the next LP is not.
  RoundingOptions options;
  options.greedy_above = 0;
  const RoundingResult away = round_cycle(options);
  CHECK(away.energy == 10.0);
  REQUIRE(away.rounds.size() >= 2);
  CHECK(away.rounds[0].fixed_to_one == 2);
  CHECK(!away.rounds[0].undone);
  // Round 2's LP keeps b and is feasible. (Then nothing stands away from a' and the whole batch,
  // a, goes in: the fallback that keeps rounding moving; round 3 undoes it.)
  CHECK(away.rounds[1].status == LpStatus::Optimal);
  options.greedy_margin = 0;
  const RoundingResult all = round_cycle(options);
  REQUIRE(all.rounds.size() >= 2);
  CHECK(all.rounds[0].fixed_to_one == 3);
  CHECK(all.rounds[1].status == LpStatus::Infeasible);
}

TEST_CASE("rounding: an LP with no binary solution ends in InfeasibleError naming the open rows") {
  // x0 + x1 = x1 + x2 = x2 + x0 = 1: the LP has x = 1/2, but no 0/1 point exists; fixing any
  // variable to 1 or to 0 is refuted by propagation, with nothing earlier to undo.
  const LpProblem odd = test::dense_lp({{1, 1, 0}, {0, 1, 1}, {1, 0, 1}}, {1, 1, 1}, {1, 1, 1});
  const Mesh t = shapes::tetrahedron();  // a space of three variables, only for the sizes
  const auto id = identity_matching(t);
  const ProductSpace space = ProductSpace::from_list(t, t, {id[0], id[1], id[2]});
  try {
    round_to_graph_surface(space, odd, {1, 1, 1});
    FAIL("no InfeasibleError");
  } catch (const InfeasibleError& e) {
    CHECK(e.rows().size() == 3);  // all three rows were open where it got stuck
  }
}

namespace {

// a + a' = 1 and x_i + x_j + a' = 1 for the three pairs of x1, x2, x3 (variables a, a', x1, x2,
// x3; a' costs 10): with a = 1 the x form an odd cycle whose only solution is x = 1/2, with
// a' = 1 they are all 0.
LpProblem odd_cycle_behind_a() {
  return test::dense_lp({{1, 1, 0, 0, 0}, {0, 1, 1, 1, 0}, {0, 1, 0, 1, 1}, {0, 1, 1, 0, 1}}, {1, 1, 1, 1},
                        {0, 10, 0, 0, 0});
}

// A space of five variables, only for the sizes.
ProductSpace five_variables() {
  static const Mesh o = shapes::octahedron();
  const auto id = identity_matching(o);
  return ProductSpace::from_list(o, o, {id[0], id[1], id[2], id[3], id[4]});
}

// Exact LPs, no backtracking over rounds, search as soon as the free variables are few enough:
// odd_cycle_behind_a's fixing of a can only go by a release.
RoundingOptions search_without_backtracking() {
  RoundingOptions options;
  options.solver = "clp-dual";
  options.max_backtracks = 0;
  options.search_stall = 0;
  return options;
}

}  // namespace

TEST_CASE("rounding: a fixing of an earlier round that leaves no binary solution is undone") {
  // odd_cycle_behind_a: a is free and a' costs 10, so the LP picks a = 1 (x = 1/2). Round 1
  // fixes a; round 2 finds that x1 can be neither 1 nor 0; only undoing round 1's fixing (a = 0)
  // leads to the binary solution.
  const LpProblem lp = odd_cycle_behind_a();
  const ProductSpace space = five_variables();
  RoundingOptions options;
  options.solver = "clp-dual";  // a vertex: x = 1/2 exactly, so round 2 has no candidate above 0.5
  const RoundingResult r = round_to_graph_surface(space, lp, {0, 10, 0, 0, 0}, options);
  CHECK(r.gamma == std::vector<int64_t>{1});
  CHECK(r.energy == 10.0);
  CHECK(r.lower_bound == doctest::Approx(0.0));
  REQUIRE(r.rounds.size() >= 2);
  CHECK(!r.rounds[0].undone);
  CHECK(r.rounds[1].undone);
  // Without backtracking over rounds the same LP ends in an error.
  options.max_backtracks = 0;
  CHECK_THROWS_AS(round_to_graph_surface(space, lp, {0, 10, 0, 0, 0}, options), InfeasibleError);
}

TEST_CASE("rounding: a stalled remainder is finished by search, releasing the fixings around a part with no binary solution") {
  // odd_cycle_behind_a: round 1 fixes a, and the x left in round 2 form an odd cycle with no
  // binary solution. Searched at once (search_stall 0), that part is proved to have none; the
  // fixing of a within two steps of it is released (not undone as the last fixing: backtracking
  // is off), and the search over the whole LP then branches past x = 1/2 to a' = 1.
  const LpProblem lp = odd_cycle_behind_a();
  const ProductSpace space = five_variables();
  RoundingOptions options = search_without_backtracking();
  const RoundingResult r = round_to_graph_surface(space, lp, {0, 10, 0, 0, 0}, options);
  CHECK(r.gamma == std::vector<int64_t>{1});
  CHECK(r.energy == 10.0);
  REQUIRE(r.rounds.size() == 3);
  CHECK(r.rounds[0].fixed_to_one == 1);   // a
  CHECK(r.rounds[1].variables == 3);      // the odd cycle
  CHECK(r.rounds[1].searched_parts == 0);
  CHECK(r.rounds[1].search);
  CHECK(!r.rounds[0].search);
  CHECK(r.rounds[1].released == 1);       // a again free
  CHECK(r.rounds[1].search_proof_released == 1);  // by the search's proofs:
  CHECK(r.rounds[1].release_depth == 0);          // no reach around the part
  CHECK(r.rounds[1].fixed_to_one == -1);
  CHECK(r.rounds[2].variables == 5);
  CHECK(r.rounds[2].searched_parts == 1);
  CHECK(r.rounds[2].iterations >= 2);     // x1 = 1 refuted, then the node with x1 = 0
  // Without the search, the same options end in an error.
  options.search_below = 0;
  CHECK_THROWS_AS(round_to_graph_surface(space, lp, {0, 10, 0, 0, 0}, options), InfeasibleError);
  // With the default stall of three rounds, rounding gets there by backtracking first.
  options.max_backtracks = RoundingOptions{}.max_backtracks;
  options.search_below = RoundingOptions{}.search_below;
  options.search_stall = RoundingOptions{}.search_stall;
  const RoundingResult b = round_to_graph_surface(space, lp, {0, 10, 0, 0, 0}, options);
  CHECK(b.gamma == std::vector<int64_t>{1});
  for (const RoundingRound& k : b.rounds) CHECK(k.searched_parts == 0);
}

TEST_CASE("rounding: the rounds after a search released fixings are not counted as stalled") {
  // odd_cycle_behind_a with search only up to 3 variables: round 1 fixes a, round 2 searches the
  // odd cycle and releases a, round 3 has 5 free variables again, more than round 2's low. With
  // the stall rule at its tightest (one round, any time), that round must still run its LP (the
  // release starts the rule afresh): it fixes a again, and round 4's search finds the cycle again
  // with no release left (max_releases 1), an InfeasibleError that is not a StuckError.
  const LpProblem lp = odd_cycle_behind_a();
  const ProductSpace space = five_variables();
  RoundingOptions options = search_without_backtracking();
  options.search_below = 3;
  options.max_releases = 1;
  options.stuck_after = 1e-12;
  options.stuck_rounds = 100;
  options.stuck_stalled = 1;
  // (A release by the search's proofs would refute a, and round 3 would not fix it again.)
  options.search_proof_release = false;
  std::vector<RoundingRound> seen;
  bool stuck = false;
  try {
    round_to_graph_surface(space, lp, {0, 10, 0, 0, 0}, options, [&](const RoundingRound& r) { seen.push_back(r); });
    FAIL("no InfeasibleError");
  } catch (const StuckError& e) {
    stuck = true;
    MESSAGE(std::string(e.what()));
  } catch (const InfeasibleError& e) {
    CHECK(std::string(e.what()).find("releases") != std::string::npos);
  }
  CHECK(!stuck);
  REQUIRE(seen.size() == 3);  // round 4 threw before reporting
  CHECK(seen[1].search);
  CHECK(seen[1].released == 1);
  CHECK(seen[1].release_depth == 2);  // around the part (not by proofs): the first reach, 2 LP steps
  CHECK(seen[1].release_pool == 1);   // of the one fixing made
  CHECK(seen[0].release_depth == 0);
  CHECK(!seen[2].search);
  CHECK(seen[2].variables == 5);
  CHECK(seen[2].fixed_to_one == 1);
}

TEST_CASE("rounding: a searched part with no binary solution and no fixing near it ends in InfeasibleError") {
  // a + a' = 1 (a' costs 10) beside an odd cycle x0 + x1 = x1 + x2 = x2 + x0 = 1 that shares no
  // row with it: round 1 fixes a, the search of round 2 proves the cycle has no binary solution,
  // and no fixing lies within reach of it to release. That ends in an error naming the cycle's
  // rows (coarse to fine widens there), not in rounds that release and search again.
  const LpProblem lp =
      test::dense_lp({{1, 1, 0, 0, 0}, {0, 0, 1, 1, 0}, {0, 0, 0, 1, 1}, {0, 0, 1, 0, 1}}, {1, 1, 1, 1}, {0, 10, 1, 1, 1});
  const Mesh o = shapes::octahedron();
  const auto id = identity_matching(o);
  const ProductSpace space = ProductSpace::from_list(o, o, {id[0], id[1], id[2], id[3], id[4]});
  RoundingOptions options;
  options.solver = "clp-dual";
  options.search_stall = 0;
  std::vector<RoundingRound> seen;
  try {
    round_to_graph_surface(space, lp, {0, 10, 1, 1, 1}, options, [&](const RoundingRound& r) { seen.push_back(r); });
    FAIL("no InfeasibleError");
  } catch (const InfeasibleError& e) {
    CHECK(e.rows() == std::vector<int64_t>{1, 2, 3});
  }
  REQUIRE(seen.size() == 1);  // round 2 threw before reporting
  CHECK(seen[0].fixed_to_one == 1);
}

namespace {

// A x of a 0/1 vector, keyed by what each row means: the product edge (closedness) or the face
// (coverage), so that two lists of product triangles can be compared row by row.
std::map<std::pair<int, int64_t>, int64_t> boundary_and_coverage(const Mesh& x, const Mesh& y,
                                                                 const std::vector<ProductTriangle>& list) {
  const ConstraintSystem cs = build_constraints(ProductSpace::from_list(x, y, list));
  std::map<std::pair<int, int64_t>, int64_t> out;
  for (int64_t i = 0; i < cs.a.rows; ++i) {
    int64_t sum = 0;
    for (uint32_t k = cs.a.row_ptr[i]; k < cs.a.row_ptr[i + 1]; ++k) sum += is_negative(cs.a.entry[k]) ? -1 : 1;
    const std::pair<int, int64_t> key = i < cs.closedness_rows ? std::pair<int, int64_t>{0, cs.row_edge[i]}
                                                               : std::pair<int, int64_t>{1, i - cs.closedness_rows};
    if (sum != 0) out[key] = sum;
  }
  return out;
}

// The indices of product triangles in a full space, sorted like a Γ.
std::vector<int64_t> sorted_indices(const ProductSpace& space, const std::vector<ProductTriangle>& list) {
  std::vector<int64_t> out;
  for (const auto& t : list) out.push_back(space.index_in_full(t));
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

TEST_CASE("rounding: a pocket is replaced by its fan collapsed onto the rim vertex, with the same A x") {
  // The tear found at 2000 faces on FAUST_r: an edge u-w of X stretched over the whole fan around
  // a vertex c of Y, u paired with c and with nothing near c otherwise.
  const Mesh x = shapes::icosphere(1);
  const Mesh& y = x;
  const ProductSpace space = ProductSpace::full(x, y);
  const int c = 0;
  const auto [u, w] = x.edges[7];
  REQUIRE(u != c);
  REQUIRE(w != c);
  std::vector<ProductTriangle> pocket, collapsed, mirror_pocket, mirror_collapsed;
  for (int g = 0; g < y.num_faces(); ++g) {
    const auto& f = y.faces[g];
    const int r = f[0] == c ? 0 : f[1] == c ? 1 : f[2] == c ? 2 : -1;
    if (r < 0) continue;
    const std::array<int, 3> from_c{f[r], f[(r + 1) % 3], f[(r + 2) % 3]};
    pocket.push_back({{u, w, w}, from_c, -1, g});
    collapsed.push_back({{w, w, w}, f, -1, g});
    // X and Y swapped: an edge of Y over the fan of X around c.
    mirror_pocket.push_back({from_c, {u, w, w}, g, -1});
    mirror_collapsed.push_back({f, {w, w, w}, g, -1});
  }
  REQUIRE(pocket.size() == 5);  // the icosphere's vertex 0 has five faces
  CHECK(boundary_and_coverage(x, y, pocket) == boundary_and_coverage(x, y, collapsed));
  CHECK(boundary_and_coverage(x, y, mirror_pocket) == boundary_and_coverage(x, y, mirror_collapsed));

  auto indices = [&](const std::vector<ProductTriangle>& list) { return sorted_indices(space, list); };
  int64_t closed = -1;
  CHECK(close_pockets(space, indices(pocket), &closed) == indices(collapsed));
  CHECK(closed == 1);
  CHECK(close_pockets(space, indices(mirror_pocket), &closed) == indices(mirror_collapsed));
  CHECK(closed == 1);
  // Both at once, and the same through a listed space (the replacements found by scanning it).
  std::vector<ProductTriangle> both = pocket, both_collapsed = collapsed;
  both.insert(both.end(), mirror_pocket.begin(), mirror_pocket.end());
  both_collapsed.insert(both_collapsed.end(), mirror_collapsed.begin(), mirror_collapsed.end());
  std::vector<ProductTriangle> listed = both;
  listed.insert(listed.end(), both_collapsed.begin(), both_collapsed.end());
  const ProductSpace small = ProductSpace::from_list(x, y, listed);
  std::vector<int64_t> first(both.size());
  std::iota(first.begin(), first.end(), 0);
  std::vector<int64_t> second(both.size());
  std::iota(second.begin(), second.end(), int64_t(both.size()));
  CHECK(close_pockets(small, first, &closed) == second);
  CHECK(closed == 2);
  // Without the replacement in the space, nothing changes.
  const ProductSpace without = ProductSpace::from_list(x, y, both);
  CHECK(close_pockets(without, first, &closed) == first);
  CHECK(closed == 0);

  // Not a tear when u meets c elsewhere (here: u blown up onto a face at c).
  std::vector<ProductTriangle> meets = pocket;
  meets.push_back({{u, u, u}, collapsed[0].b, -1, collapsed[0].fb});
  CHECK(close_pockets(space, indices(meets), &closed) == indices(meets));
  CHECK(closed == 0);
  // Not a whole fan: the rim's boundary would not match.
  std::vector<ProductTriangle> part(pocket.begin(), pocket.end() - 1);
  CHECK(close_pockets(space, indices(part), &closed) == indices(part));
  CHECK(closed == 0);
}

TEST_CASE("rounding: a pocket with two tips (an edge over the star of an edge) is replaced too") {
  // Measured on FAUST_r at 2000 faces after the one-tip pockets were closed: the rest had two
  // adjacent tips. u is paired with both ends of the edge c-d of Y, w with the star's rim.
  const Mesh x = shapes::icosphere(1);
  const Mesh& y = x;
  const ProductSpace space = ProductSpace::full(x, y);
  const auto [c, d] = y.edges[0];
  int u = -1, w = -1;
  for (const auto& e : x.edges)
    if (e[0] != c && e[0] != d && e[1] != c && e[1] != d) {
      u = e[0], w = e[1];
      break;
    }
  REQUIRE(u >= 0);
  std::vector<ProductTriangle> pocket, collapsed;
  for (int g = 0; g < y.num_faces(); ++g) {
    const auto& f = y.faces[g];
    int tips = 0;
    for (int v : f) tips += v == c || v == d;
    if (tips == 0) continue;
    // Canonical form: the single one of the two X vertices first, the face rotated to match.
    for (int r = 0; r < 3; ++r) {
      const std::array<int, 3> b{f[r], f[(r + 1) % 3], f[(r + 2) % 3]};
      const bool first_is_tip = b[0] == c || b[0] == d;
      if (tips == 1 && first_is_tip) pocket.push_back({{u, w, w}, b, -1, g});
      if (tips == 2 && !first_is_tip) pocket.push_back({{w, u, u}, b, -1, g});
    }
    collapsed.push_back({{w, w, w}, f, -1, g});
  }
  REQUIRE(pocket.size() == collapsed.size());
  REQUIRE(pocket.size() >= 8);  // two vertices of valence 5 or 6 that share two faces
  CHECK(boundary_and_coverage(x, y, pocket) == boundary_and_coverage(x, y, collapsed));
  auto indices = [&](const std::vector<ProductTriangle>& list) { return sorted_indices(space, list); };
  int64_t closed = -1;
  CHECK(close_pockets(space, indices(pocket), &closed) == indices(collapsed));
  CHECK(closed == 1);
}

TEST_CASE("rounding: an undone fixing whose blamed part comes back by propagation is halved, not repeated") {
  // cycle_behind_a_fixing, linked: b1 = 1 forces a' = 0 and a = 1.
  // Round 1 fixes a, b1 and b2; the next LP is infeasible and its proof blames a, but a follows
  // from b1 again: without the rule the state after undoing is the infeasible one (3 ones and
  // 5 zeros again) and the same LP is solved twice.
  RoundingOptions options;
  options.lp.threads = 1;  // the same iterates on any machine
  const RoundingResult r = round_cycle(options, 1);
  REQUIRE(r.rounds.size() >= 3);
  CHECK(r.rounds[0].fixed_to_one == 3);
  CHECK(r.rounds[1].status == LpStatus::Infeasible);
  CHECK(r.rounds[1].undone);
  CHECK(r.rounds[1].fixed_to_one + r.rounds[1].fixed_to_zero < r.rounds[0].fixed_to_one + r.rounds[0].fixed_to_zero);
  CHECK(r.rounds[2].status == LpStatus::Optimal);  // another LP than round 2's
}

TEST_CASE("rounding: an undone fixing whose every half comes back by propagation is not solved again") {
  // cycle_behind_a_fixing with two links: b1 and b2 force each other, and together a' = 0,
  // hence a = 1. Round 1 fixes b1, b2 and a (0.9, 0.9, 0.8); the next LP is infeasible (a = 1
  // leaves the cycle nothing). What a trim keeps, b1 and b2 or the larger half b1, brings back
  // all three: the failed state, whose LP was solved again before the rule. Now the single b1
  // cannot be 1: both b go to 0, which forces a' = 1 and with it everything left.
  RoundingOptions options;
  options.lp.threads = 1;
  const RoundingResult r = round_cycle(options, 2);
  REQUIRE(r.rounds.size() >= 2);
  CHECK(r.rounds[0].fixed_to_one == 3);
  CHECK(r.rounds[1].status == LpStatus::Infeasible);
  CHECK(r.rounds[1].undone);
  int infeasible = 0;
  for (const auto& k : r.rounds) infeasible += k.status == LpStatus::Infeasible;
  CHECK(infeasible == 1);  // before: 2, the second the same LP as the first
  CHECK(r.energy == 30.0);  // a' = b1' = b2' = 1: either b = 1 forces a = 1
}

TEST_CASE("rounding: a part at its iteration cap goes on from its iterate before it is fixed from it") {
  // The dolphins at 60 faces with every LP capped at 300 PDHG iterations: round 1 fixes from its
  // capped iterate (the first LP is not held back), and round 2's LP over the rest stops at its
  // cap too. It is not rounded then: round 3 goes on from its iterate, converges, and fixes. With
  // converged_first off, round 2 fixes from its capped iterate at once.
  const MatchingLp& m = dolphins_60();
  RoundingOptions o;
  o.solver = "pdhg-cpu";
  o.exact_below = 0;
  o.lp.max_iterations = 300;
  o.lp.threads = 1;  // the same iterates on any machine
  o.converged_first = true;
  const auto waits = [](const RoundingRound& k) {
    return k.status == LpStatus::IterationLimit && !k.undone && k.fixed_to_one == 0 && k.fixed_to_zero == 0;
  };
  const RoundingResult r = round_to_graph_surface(m.space, m.lp, m.energy, o);
  CHECK(satisfies_exactly(m.lp, r.gamma));
  CHECK(check_graph_surface(m.space, r.gamma).ok());
  REQUIRE(r.rounds.size() >= 3);
  CHECK(r.rounds[0].status == LpStatus::IterationLimit);
  CHECK(r.rounds[0].fixed_to_one > 0);
  CHECK(waits(r.rounds[1]));
  CHECK(r.rounds[2].fixed_to_one > 0);
  o.converged_first = false;
  const RoundingResult now = round_to_graph_surface(m.space, m.lp, m.energy, o);
  CHECK(satisfies_exactly(m.lp, now.gamma));
  REQUIRE(now.rounds.size() >= 2);
  CHECK(now.rounds[1].status == LpStatus::IterationLimit);
  CHECK(now.rounds[1].fixed_to_one > 0);
  for (const RoundingRound& k : now.rounds) CHECK(!waits(k));
}

namespace {
// A solver that always gives up, as Clp did on a part of a full-resolution rounding.
class GivingUp final : public LpSolver {
public:
  std::string name() const override { return "giving-up"; }
  LpResult solve(const LpProblem&, const SolverParams&) override {
    ++calls;
    LpResult r;
    r.status = LpStatus::NumericalTrouble;
    return r;
  }
  int calls = 0;
};
}  // namespace

TEST_CASE("rounding: a snapshot of a part under way is the whole LP's point: parts done as they ended, later ones as they start") {
  // Two independent copies of the octahedron's matching LP (the second with other costs), solved
  // in parts from a flat warm start, a snapshot at every residual check.
  const Mesh x = shapes::octahedron();
  const Mesh y = test::deformed(x, [](const Eigen::Vector3d& p) { return Eigen::Vector3d(1.2 * p.x(), p.y(), 0.9 * p.z()); });
  const MatchingLp m = build_matching_lp(x, compute_geometry(x), y, compute_geometry(y));
  const int64_t n = m.lp.cols(), rows = m.lp.rows();
  std::vector<std::vector<int>> dense(2 * rows, std::vector<int>(2 * n, 0));
  for (int64_t i = 0; i < rows; ++i)
    for (uint32_t k = m.lp.a.row_ptr[i]; k < m.lp.a.row_ptr[i + 1]; ++k) {
      const int v = is_negative(m.lp.a.entry[k]) ? -1 : 1;
      dense[i][col_of(m.lp.a.entry[k])] = v;
      dense[rows + i][n + col_of(m.lp.a.entry[k])] = v;
    }
  std::vector<double> b = m.lp.b, c = m.lp.c;
  b.insert(b.end(), m.lp.b.begin(), m.lp.b.end());
  for (int64_t j = 0; j < n; ++j) c.push_back(1.3 * m.lp.c[j] + 0.01);
  const LpProblem two = test::dense_lp(dense, b, c);
  SolverParams params;
  params.tolerance = 1e-6;
  params.initial_x.assign(2 * n, 0.25);
  params.initial_y.assign(2 * rows, 0.125);
  params.snapshot_seconds = 1e-9;
  std::vector<SolveSnapshot> seen;
  params.snapshot = [&](const SolveSnapshot& s) { seen.push_back(s); };
  const auto pdhg = make_solver("pdhg-cpu");
  const detail::JoinedSolve j = detail::solve_in_parts(two, params, *pdhg, nullptr, 0, params, true);
  REQUIRE(j.parts == 2);
  REQUIRE(j.r.status == LpStatus::Optimal);
  REQUIRE(seen.size() >= 2);
  // Block k of a snapshot's x equals `v`'s block k.
  auto block_is = [&](const std::vector<double>& s, int k, const std::vector<double>& v) {
    return std::equal(s.begin() + k * n, s.begin() + (k + 1) * n, v.begin() + k * n);
  };
  for (const SolveSnapshot& s : seen) {
    REQUIRE(s.x.size() == size_t(2 * n));
    REQUIRE(s.y.size() == size_t(2 * rows));
  }
  // The first: the part under way, the other as it starts; the last: the first part as it ended.
  const SolveSnapshot &first = seen.front(), &last = seen.back();
  CHECK(block_is(first.x, 0, params.initial_x) != block_is(first.x, 1, params.initial_x));  // one at its start
  const int later = block_is(first.x, 0, params.initial_x) ? 0 : 1;  // solved second
  CHECK(std::all_of(first.y.begin() + later * rows, first.y.begin() + (later + 1) * rows,
                    [](double v) { return v == 0.125; }));
  CHECK(block_is(last.x, 1 - later, j.r.x));
  CHECK_FALSE(block_is(last.x, later, params.initial_x));
  CHECK(std::equal(last.y.begin() + (1 - later) * rows, last.y.begin() + (2 - later) * rows,
                   j.r.y.begin() + (1 - later) * rows));
}

TEST_CASE("rounding: a part one solver gives up on goes to the other") {
  const Mesh x = shapes::octahedron();
  const Mesh y = test::deformed(x, [](const Eigen::Vector3d& p) { return Eigen::Vector3d(1.2 * p.x(), p.y(), 0.9 * p.z()); });
  const MatchingLp m = build_matching_lp(x, compute_geometry(x), y, compute_geometry(y));
  const LpResult exact = solve_lp(m.lp, "clp-dual");
  REQUIRE(exact.status == LpStatus::Optimal);
  SolverParams params;
  params.tolerance = 1e-6;
  GivingUp quitter;
  const auto pdhg = make_solver("pdhg-cpu");
  const auto clp = make_solver("clp-dual");
  const int64_t n = m.lp.cols();
  // The exact solver gives up on the (whole, small) LP: the first-order one solves it.
  const detail::JoinedSolve a = detail::solve_in_parts(m.lp, params, *pdhg, &quitter, n + 1, params, false);
  CHECK(quitter.calls == 1);
  CHECK(a.r.status == LpStatus::Optimal);
  CHECK(a.exact_parts == 0);
  CHECK(a.r.objective == doctest::Approx(exact.objective).epsilon(1e-4));
  // The first-order one gives up: the exact one takes a part up to 10× exact_below, not above.
  const detail::JoinedSolve b = detail::solve_in_parts(m.lp, params, quitter, clp.get(), n / 10 + 1, params, false);
  CHECK(quitter.calls == 2);
  CHECK(b.r.status == LpStatus::Optimal);
  CHECK(b.exact_parts == 1);
  CHECK(b.r.objective == doctest::Approx(exact.objective).epsilon(1e-9));
  const detail::JoinedSolve c = detail::solve_in_parts(m.lp, params, quitter, clp.get(), n / 20, params, false);
  CHECK(quitter.calls == 3);
  CHECK(c.r.status == LpStatus::NumericalTrouble);
  // Both give up: so does the join.
  GivingUp other;
  const detail::JoinedSolve d = detail::solve_in_parts(m.lp, params, quitter, &other, n + 1, params, false);
  CHECK(d.r.status == LpStatus::NumericalTrouble);
  CHECK(other.calls == 1);
  CHECK(quitter.calls == 4);
}

TEST_CASE("rounding: a part that reaches the exact solver's pivot cap goes to the first-order one") {
  const MatchingLp& m = dolphins_60();
  const LpResult exact = solve_lp(m.lp, "clp-dual");
  REQUIRE(exact.status == LpStatus::Optimal);
  REQUIRE(exact.iterations > 2);  // else a cap of one pivot would not bite
  SolverParams params;
  params.tolerance = 1e-6;
  const auto pdhg = make_solver("pdhg-cpu");
  const auto clp = make_solver("clp-dual");
  const int64_t n = m.lp.cols();
  // No cap: Clp solves the whole LP.
  const detail::JoinedSolve a = detail::solve_in_parts(m.lp, params, *pdhg, clp.get(), n + 1, params, false);
  CHECK(a.exact_parts == 1);
  CHECK(a.r.objective == doctest::Approx(exact.objective).epsilon(1e-9));
  // A cap Clp's solve stays under: still Clp's vertex.
  const double roomy = 2.0 * double(exact.iterations) / double(std::max<int64_t>(n, 1000));
  const detail::JoinedSolve b = detail::solve_in_parts(m.lp, params, *pdhg, clp.get(), n + 1, params, false, {roomy});
  CHECK(b.exact_parts == 1);
  CHECK(b.r.status == LpStatus::Optimal);
  CHECK(b.r.objective == doctest::Approx(exact.objective).epsilon(1e-9));
  // One pivot: Clp stops at its cap and PDHG solves the part to its tolerance instead.
  const double one = 1.0 / double(std::max<int64_t>(n, 1000));
  const detail::JoinedSolve c = detail::solve_in_parts(m.lp, params, *pdhg, clp.get(), n + 1, params, false, {one});
  CHECK(c.exact_parts == 0);
  CHECK(c.r.status == LpStatus::Optimal);
  CHECK(c.r.objective == doctest::Approx(exact.objective).epsilon(1e-4));
  CHECK(c.r.objective != exact.objective);  // not Clp's vertex
}

namespace {
// Clp, counting its solves.
class CountingClp final : public LpSolver {
public:
  std::string name() const override { return "counting-clp"; }
  LpResult solve(const LpProblem& lp, const SolverParams& params) override {
    ++calls;
    return clp->solve(lp, params);
  }
  std::unique_ptr<LpSolver> clp = make_solver("clp-dual");
  int calls = 0;
};
}  // namespace

TEST_CASE("rounding: a part solved exactly in one of the last rounds takes that result again") {
  // The dolphins at 30 faces: five exact solves of the 60-face LP took 124-166 s of this test's
  // time on an idle 2-core machine, over its 600 s timeout under load; the cache's logic is the same.
  const MatchingLp& m = dolphins_30();
  SolverParams params;
  params.tolerance = 1e-6;
  const auto pdhg = make_solver("pdhg-cpu");
  CountingClp clp;
  detail::ExactCache cache;
  const int64_t n = m.lp.cols();
  const detail::JoinedSolve a = detail::solve_in_parts(m.lp, params, *pdhg, &clp, n + 1, params, false, {}, &cache);
  REQUIRE(a.r.status == LpStatus::Optimal);
  CHECK(clp.calls == 1);
  // The same LP: no solve, the same result to the last bit.
  const detail::JoinedSolve b = detail::solve_in_parts(m.lp, params, *pdhg, &clp, n + 1, params, false, {}, &cache);
  CHECK(clp.calls == 1);
  CHECK(cache.reused == 1);
  CHECK(b.r.objective == a.r.objective);
  CHECK(b.r.x == a.r.x);
  CHECK(b.r.y == a.r.y);
  CHECK(b.exact_parts == 1);
  // One cost changed: solved again.
  LpProblem other = m.lp;
  other.c[0] += 1.0;
  const detail::JoinedSolve c = detail::solve_in_parts(other, params, *pdhg, &clp, n + 1, params, false, {}, &cache);
  CHECK(clp.calls == 2);
  CHECK(cache.reused == 1);
  // A call between that lacked it: still kept (FAUST_r 021-024 had such a round).
  const detail::JoinedSolve d = detail::solve_in_parts(m.lp, params, *pdhg, &clp, n + 1, params, false, {}, &cache);
  CHECK(clp.calls == 2);
  CHECK(cache.reused == 2);
  CHECK(d.r.x == a.r.x);
  // Another pivot cap (one Clp's solve stays under) is another solve.
  const double roomy = 2.0 * double(a.r.iterations) / double(std::max<int64_t>(n, 1000));
  REQUIRE(roomy * double(std::max<int64_t>(n, 1000)) < double(params.max_iterations));
  const detail::JoinedSolve e = detail::solve_in_parts(m.lp, params, *pdhg, &clp, n + 1, params, false, {roomy}, &cache);
  CHECK(clp.calls == 3);
  CHECK(e.r.objective == a.r.objective);
  // kKeepCalls calls in a row without it: dropped, solved again.
  for (int k = 0; k < detail::ExactCache::kKeepCalls; ++k)
    detail::solve_in_parts(other, params, *pdhg, &clp, n + 1, params, false, {}, &cache);
  CHECK(clp.calls == 3);  // `other` itself was kept
  detail::solve_in_parts(m.lp, params, *pdhg, &clp, n + 1, params, false, {}, &cache);
  CHECK(clp.calls == 4);
}

TEST_CASE("rounding: a part the exact solver failed on in one of the last rounds goes to the first-order one at once") {
  // The dolphins at 30 faces with a cap of one pivot: Clp stops at its cap and PDHG solves the
  // part. The same part again: PDHG at once, without Clp's attempt (before: Clp's cap reached
  // once more, which on a hard part of a full-resolution run cost 10 minutes a round).
  const MatchingLp& m = dolphins_30();
  const LpResult exact = solve_lp(m.lp, "clp-dual");
  REQUIRE(exact.status == LpStatus::Optimal);
  REQUIRE(exact.iterations > 2);  // else a cap of one pivot would not bite
  SolverParams params;
  params.tolerance = 1e-6;
  params.threads = 1;  // the same iterates both times
  const auto pdhg = make_solver("pdhg-cpu");
  CountingClp clp;
  detail::ExactCache cache;
  const int64_t n = m.lp.cols();
  const double one = 1.0 / double(std::max<int64_t>(n, 1000));
  const detail::JoinedSolve a = detail::solve_in_parts(m.lp, params, *pdhg, &clp, n + 1, params, false, {one}, &cache);
  CHECK(clp.calls == 1);
  CHECK(a.exact_parts == 0);
  REQUIRE(a.r.status == LpStatus::Optimal);
  CHECK(cache.capped_below == n);  // parts of its size go to PDHG from now on
  const detail::JoinedSolve b = detail::solve_in_parts(m.lp, params, *pdhg, &clp, n + 1, params, false, {one}, &cache);
  CHECK(clp.calls == 1);
  CHECK(b.exact_parts == 0);
  CHECK(b.r.status == LpStatus::Optimal);
  CHECK(b.r.objective == a.r.objective);
  // Without the cap it is another question: Clp solves it.
  detail::ExactCache fresh;
  const detail::JoinedSolve d = detail::solve_in_parts(m.lp, params, *pdhg, &clp, n + 1, params, false, {}, &fresh);
  CHECK(clp.calls == 2);
  CHECK(d.exact_parts == 1);
  CHECK(d.r.objective == doctest::Approx(exact.objective).epsilon(1e-9));
}

TEST_CASE("rounding: a part the exact solver was slow on is handed out as solved, once") {
  // Two independent parts (x0 + x1 = 1 and x2 + x3 = 1); `slow_part_seconds` 0 makes every exact
  // solve slow. Each part goes to the callback as the exact solver saw it; a part that takes its
  // result from the cache was not solved, so it is not handed out again. Above the threshold
  // nothing is.
  const LpProblem lp = test::dense_lp({{1, 1, 0, 0}, {0, 0, 1, 1}}, {1, 1}, {1, 2, 3, 1});
  SolverParams params;
  const auto pdhg = make_solver("pdhg-cpu");
  CountingClp clp;
  detail::ExactCache cache;
  std::vector<LpProblem> seen;
  const std::function<void(const LpProblem&)> keep = [&](const LpProblem& part) { seen.push_back(part); };
  const detail::JoinedSolve a =
      detail::solve_in_parts(lp, params, *pdhg, &clp, 10, params, true, {}, &cache, nullptr, keep, 0.0);
  REQUIRE(a.r.status == LpStatus::Optimal);
  CHECK(a.r.objective == doctest::Approx(2.0));
  CHECK(clp.calls == 2);
  REQUIRE(seen.size() == 2);
  for (const LpProblem& part : seen) {
    CHECK(part.rows() == 1);
    CHECK(part.cols() == 2);
  }
  CHECK(((seen[0].c == std::vector<double>{1, 2} && seen[1].c == std::vector<double>{3, 1}) ||
         (seen[0].c == std::vector<double>{3, 1} && seen[1].c == std::vector<double>{1, 2})));
  detail::solve_in_parts(lp, params, *pdhg, &clp, 10, params, true, {}, &cache, nullptr, keep, 0.0);
  CHECK(clp.calls == 2);  // both from the cache
  CHECK(seen.size() == 2);
  detail::ExactCache fresh;
  detail::solve_in_parts(lp, params, *pdhg, &clp, 10, params, true, {}, &fresh, nullptr, keep, 3600.0);
  CHECK(clp.calls == 4);
  CHECK(seen.size() == 2);
}

TEST_CASE("rounding: a release reaches further only where the same part fails again") {
  detail::ReleaseReach r;
  CHECK(r.first_depth({4, 5}) == 2);  // the first release
  r.released({5, 4, 5}, 2);
  CHECK(r.first_depth({6, 5}) == 4);  // shares column 5 with the last release's rows
  r.released({6, 5}, 8);              // (reached 8: nothing within 4 steps)
  CHECK(r.first_depth({6}) == 16);
  r.released({6}, 16);
  CHECK(r.first_depth({7, 9}) == 2);  // elsewhere: 2 again, however far the last one reached
  r.released({9, 7}, 2);
  CHECK(r.first_depth({6}) == 2);     // only the last release counts
  CHECK(r.first_depth({9}) == 4);
  r.released({9}, 64);
  CHECK(r.first_depth({9}) == 64);    // no further than 64 to start with
  CHECK(r.first_depth({}) == 2);
  CHECK(r.same_part({9, 1}));
  CHECK_FALSE(r.same_part({1}));
  // A release of the fixings a search's proofs rest on (depth 1): where the same part fails
  // again, the releases within 2, 4 … steps follow.
  r.released({3, 1}, 1);
  CHECK(r.same_part({1}));
  CHECK(r.first_depth({1}) == 2);
  r.released({1}, 2);
  CHECK(r.first_depth({1}) == 4);
  CHECK_FALSE(detail::ReleaseReach{}.same_part({1}));
}

TEST_CASE("rounding: fixings a proof blamed are remembered at the state they were made from") {
  // The memory behind remember_refuted. A state is the values of all variables: equal values
  // hash equal whatever led to them; one value changed anywhere (a tail shorter than a word
  // too) changes the hash.
  std::vector<int8_t> s(21, -1);
  s[3] = 1;
  s[4] = 0;
  const uint64_t h = detail::state_hash(s);
  std::vector<int8_t> same(21, -1);
  same[4] = 0;
  same[3] = 1;
  CHECK(detail::state_hash(same) == h);
  std::set<uint64_t> others{h};
  for (size_t k = 0; k < s.size(); ++k)
    for (int8_t v : {-1, 0, 1}) {
      if (v == s[k]) continue;
      std::vector<int8_t> t = s;
      t[k] = v;
      CHECK(others.insert(detail::state_hash(t)).second);
    }
  CHECK(detail::state_hash(std::vector<int8_t>(20, -1)) != detail::state_hash(std::vector<int8_t>(21, -1)));
  // Blamed from one state: recalled there, not at another, and what is blamed there later joins.
  detail::FailedFrom f;
  CHECK(f.empty());
  f.blamed(h, {});
  CHECK(f.empty());
  f.blamed(h, {10, 12});
  const uint64_t other = detail::state_hash(std::vector<int8_t>(21, 0));
  f.blamed(other, {7});
  std::vector<int64_t> back = f.recall(h);
  std::sort(back.begin(), back.end());
  CHECK(back == std::vector<int64_t>{10, 12});
  f.blamed(h, {12, 3});
  back = f.recall(h);
  std::sort(back.begin(), back.end());
  CHECK(back == std::vector<int64_t>{3, 10, 12});
  CHECK(f.recall(other) == std::vector<int64_t>{7});
  CHECK(f.recall(detail::state_hash(std::vector<int8_t>(21, 1))).empty());
}

TEST_CASE("rounding: trims in a row count only while the same part fails after each") {
  // The count behind release_after_trims: a failure continues the streak where it shares a row
  // with the failure just before it and that one trimmed the last fixing.
  detail::FailingAgain f;
  CHECK(f.failed({7, 3, 5}) == 0);  // the first failure
  f.trimmed();
  CHECK(f.failed({9, 5}) == 1);     // row 5 again, after one trim
  f.trimmed();
  CHECK(f.failed({9, 11}) == 2);    // row 9 again: two trims in a row before it
  f.trimmed();
  CHECK(f.failed({1, 2}) == 0);     // another part: a new streak
  // Not trimmed (undone whole, released, or gone on at a larger cap): the streak ends.
  CHECK(f.failed({1, 2}) == 0);
  f.trimmed();
  // A round that solved in between ends it too.
  f.solved();
  CHECK(f.failed({1, 2}) == 0);
  f.trimmed();
  CHECK(f.failed({2}) == 1);
  f.trimmed();
  CHECK(f.failed({}) == 0);  // nothing failed in parts: nothing to release around
}

namespace {

// Two causes of infeasibility in one part, each set off by a carried fixing to 1, and a third
// carried fixing that is innocent. A: a1 + a2 = a3 + a4 = 1 and a1 + … + a4 + cA = 2 (with
// cA = 1 the sums disagree; no row alone says so). B: the same over k pairs, b's sum + cB = k:
// its Farkas ray spreads over k + 1 rows, each under a tenth of A's, so the first proof names A's
// rows alone. A chain a4 + m1 = m1 + m2 = m2 + m3 = m3 + b_2k = 1 joins them into one part; c3
// sits on the chain's A end (c3 + m1 − m6 = 1), more than two steps from B. cA', cB', c3' are
// their alternatives (at `alternative_cost` each), and q1 + q2 = 1 (q1 costs 1) is a second part.
struct TwoCauses {
  LpProblem lp;
  std::vector<double> cost;
  int64_t ca, cb, c3;
};

TwoCauses two_causes(int k, double alternative_cost = 0.0) {
  const int n = 16 + 2 * k;
  const int a = 0, cA = 4, b = 6, cB = 6 + 2 * k, m = 8 + 2 * k, c3 = 11 + 2 * k, m6 = 13 + 2 * k, q = 14 + 2 * k;
  std::vector<std::vector<int>> rows;
  std::vector<double> rhs;
  auto row = [&](std::initializer_list<std::pair<int, int>> entries, double value) {
    rows.emplace_back(n, 0);
    for (const auto& [j, v] : entries) rows.back()[j] = v;
    rhs.push_back(value);
  };
  row({{a, 1}, {a + 1, 1}}, 1);
  row({{a + 2, 1}, {a + 3, 1}}, 1);
  row({{a, 1}, {a + 1, 1}, {a + 2, 1}, {a + 3, 1}, {cA, 1}}, 2);
  row({{cA, 1}, {cA + 1, 1}}, 1);
  for (int i = 0; i < k; ++i) row({{b + 2 * i, 1}, {b + 2 * i + 1, 1}}, 1);
  rows.emplace_back(n, 0);
  for (int j = b; j < b + 2 * k; ++j) rows.back()[j] = 1;
  rows.back()[cB] = 1;
  rhs.push_back(k);
  row({{cB, 1}, {cB + 1, 1}}, 1);
  row({{a + 3, 1}, {m, 1}}, 1);
  row({{m, 1}, {m + 1, 1}}, 1);
  row({{m + 1, 1}, {m + 2, 1}}, 1);
  row({{m + 2, 1}, {b + 2 * k - 1, 1}}, 1);
  row({{c3, 1}, {m, 1}, {m6, -1}}, 1);
  row({{c3, 1}, {c3 + 1, 1}}, 1);
  row({{q, 1}, {q + 1, 1}}, 1);
  TwoCauses t;
  t.cost.assign(n, 0.0);
  t.cost[q] = 1.0;
  t.cost[cA + 1] = t.cost[cB + 1] = t.cost[c3 + 1] = alternative_cost;
  t.lp = test::dense_lp(rows, rhs, t.cost);
  t.ca = cA;
  t.cb = cB;
  t.c3 = c3;
  return t;
}

// two_causes rounded on PDHG (its proofs name rows) with cA, cB and c3 carried.
RoundingResult round_two_causes(const TwoCauses& t) {
  const Mesh sphere = shapes::icosphere(2);
  const auto id = identity_matching(sphere);
  const ProductSpace space = ProductSpace::from_list(sphere, sphere, {id.begin(), id.begin() + t.lp.cols()});
  RoundingOptions options;
  options.solver = "pdhg-cpu";
  options.exact_below = 0;
  options.lp.threads = 1;  // the same iterates on any machine
  options.release_after_trims = 1;
  options.start_ones = {t.ca, t.cb, t.c3};
  return round_to_graph_surface(space, t.lp, t.cost, options);
}

}  // namespace

TEST_CASE("rounding: a part failing again after a trim releases the fixings around its proof, not around the whole part") {
  // two_causes with cA, cB and c3 carried, on PDHG (its proof names rows): round 1's proof names
  // A's three rows and trims cA; the part fails again, its proof on B's rows (41 of the part's
  // 50), and the release around those frees cB alone. Around the whole part it would free c3 too
  // (its row is one of the part's), which nothing blames.
  const TwoCauses t = two_causes(40);
  const RoundingResult r = round_two_causes(t);
  CHECK(satisfies_exactly(t.lp, r.gamma));
  CHECK(r.energy == 0.0);  // q2
  REQUIRE(r.rounds.size() >= 3);
  CHECK(r.rounds[0].status == LpStatus::Infeasible);
  CHECK(r.rounds[0].undone);
  CHECK(r.rounds[0].released == 0);  // a trim
  CHECK(r.rounds[1].status == LpStatus::Infeasible);
  CHECK(r.rounds[1].released == 1);  // cB; around the whole part: cB and c3
  CHECK(r.rounds[1].release_pool == 2);  // of cB and c3 (cA trimmed)
  CHECK(r.rounds[1].release_depth == 2);
  CHECK(r.rounds[0].release_depth == 0);  // (a trim releases nothing around)
  CHECK(r.rounds[1].fixed_to_one == -1);
  CHECK(r.rounds[2].status != LpStatus::Infeasible);
  auto in_gamma = [&](int64_t j) { return std::find(r.gamma.begin(), r.gamma.end(), j) != r.gamma.end(); };
  CHECK(!in_gamma(t.ca));
  CHECK(!in_gamma(t.cb));
  CHECK(in_gamma(t.c3));  // never released
}

TEST_CASE("rounding: a part proved infeasible by PDHG names its clash by a proof at zero cost, not by its ordinary duals") {
  // two_causes as above with the alternatives at cost 10. PDHG's proof of round 2 is a dual point:
  // its ordinary duals on A's rows (about 10) outweighed B's short ray, so it named A's 4 rows,
  // released c3 and left round 3 infeasible (measured before the proof at zero cost; the dual's
  // growth after the proof, PdhgOptions::ray_iterations, named B's rows here, but at full
  // resolution that growth was no ray). The same part at zero cost has no ordinary duals: its
  // proof names B's 41 rows, and the release frees cB alone.
  const TwoCauses t = two_causes(40, 10.0);
  const RoundingResult r = round_two_causes(t);
  CHECK(satisfies_exactly(t.lp, r.gamma));
  CHECK(r.energy == doctest::Approx(20.0));  // cA' and cB'
  REQUIRE(r.rounds.size() >= 3);
  CHECK(r.rounds[0].status == LpStatus::Infeasible);
  CHECK(r.rounds[1].status == LpStatus::Infeasible);
  CHECK(r.rounds[1].released == 1);
  CHECK(r.rounds[2].status != LpStatus::Infeasible);
  auto in_gamma = [&](int64_t j) { return std::find(r.gamma.begin(), r.gamma.end(), j) != r.gamma.end(); };
  CHECK(!in_gamma(t.ca));
  CHECK(!in_gamma(t.cb));
  CHECK(in_gamma(t.c3));  // never released
}

namespace {
// An LP infeasible beyond what propagation sees: a1 + a2 = 1, a3 + a4 = 1, a1 + … + a4 = 3 (no
// row alone says so), beside q1 + q2 = 1 at `q_cost` each, whose ordinary dual is that cost. With
// `feasible`, the third row asks for 2 instead.
LpProblem clash_beside_costs(double q_cost, bool feasible = false) {
  const std::vector<std::vector<int>> rows = {
      {1, 1, 0, 0, 0, 0}, {0, 0, 1, 1, 0, 0}, {1, 1, 1, 1, 0, 0}, {0, 0, 0, 0, 1, 1}};
  return test::dense_lp(rows, {1, 1, feasible ? 2.0 : 3.0, 1}, {0.5, 1, 0.25, 1, q_cost, q_cost});
}

RoundingResult round_clash(const LpProblem& lp, int64_t feasibility_iterations) {
  const Mesh sphere = shapes::icosphere(2);
  const auto id = identity_matching(sphere);
  const ProductSpace space = ProductSpace::from_list(sphere, sphere, {id.begin(), id.begin() + lp.cols()});
  RoundingOptions options;
  options.solver = "pdhg-cpu";
  options.lp.threads = 1;  // the same iterates on any machine
  options.lp.tolerance = 1e-6;
  options.feasibility_iterations = feasibility_iterations;
  return round_to_graph_surface(space, lp, lp.c, options);
}
}  // namespace

TEST_CASE("rounding: round 1's LP solved first at zero cost is proved infeasible there, by the clash's rows alone") {
  const LpProblem lp = clash_beside_costs(100.0);
  std::string what;
  std::vector<int64_t> rows;
  bool certified = false;
  auto failure = [&](int64_t iterations) {
    what.clear();
    rows.clear();
    try {
      round_clash(lp, iterations);
    } catch (const InfeasibleError& e) {
      what = e.what();
      rows = e.rows();
      certified = e.certified();
    }
  };
  failure(1000);
  CHECK(what.find("proved at zero cost") != std::string::npos);
  CHECK(certified);
  CHECK(rows == std::vector<int64_t>{0, 1, 2});
  // With its costs the proof is a dual point whose ordinary duals (q's row at 100) can outweigh a
  // ray still short: it names q's row too, where a widening would be wasted.
  failure(0);
  CHECK(!what.empty());
  CHECK(what.find("zero cost") == std::string::npos);
  CHECK(std::find(rows.begin(), rows.end(), 3) != rows.end());
  // A cap too short for a proof: the costed solve proves it as before.
  failure(1);
  CHECK(what.find("zero cost") == std::string::npos);
  CHECK(!rows.empty());
  // A feasible LP: the pre-test changes nothing.
  const LpProblem ok = clash_beside_costs(100.0, true);
  const RoundingResult plain = round_clash(ok, 0), tested = round_clash(ok, 1000);
  CHECK(tested.gamma == plain.gamma);
  CHECK(tested.energy == doctest::Approx(plain.energy));
  CHECK(tested.lower_bound == doctest::Approx(plain.lower_bound).epsilon(1e-5));
  // Its iterations are round 1's own, apart from the costed solve's.
  REQUIRE(!tested.rounds.empty());
  REQUIRE(!plain.rounds.empty());
  CHECK(plain.rounds[0].feasibility_iterations == 0);
  CHECK(tested.rounds[0].feasibility_iterations > 0);
  CHECK(tested.rounds[0].feasibility_iterations <= 1000);
  CHECK(tested.rounds[0].iterations == plain.rounds[0].iterations);
}

namespace {
// The first-order solver, noting for each solve whether it was at zero cost.
class ZeroCostNoting final : public LpSolver {
public:
  std::string name() const override { return "pdhg-cpu"; }
  LpResult solve(const LpProblem& lp, const SolverParams& params) override {
    zero.push_back(std::all_of(lp.c.begin(), lp.c.end(), [](double c) { return c == 0.0; }));
    tolerance.push_back(params.tolerance);
    warm.push_back(!params.initial_x.empty());
    cap.push_back(params.max_iterations);
    cols.push_back(lp.cols());
    LpResult r = inner->solve(lp, params);
    iterations.push_back(r.iterations);
    return r;
  }
  std::unique_ptr<LpSolver> inner = make_solver("pdhg-cpu");
  std::vector<bool> zero, warm;
  std::vector<double> tolerance;
  std::vector<int64_t> cap, cols, iterations;
};
}  // namespace

TEST_CASE("rounding: a later round's parts solved first at zero cost: a proof there ends the round's solve") {
  // Two parts: the clash (rows 0-2) and q's row, feasible.
  const LpProblem lp = clash_beside_costs(100.0);
  SolverParams params;
  params.tolerance = 1e-6;
  params.threads = 1;
  auto joined = [&](ZeroCostNoting& solver, int64_t feasibility_iterations) {
    return detail::solve_in_parts(lp, params, solver, nullptr, 0, params, true, {}, nullptr, nullptr, {}, 10.0,
                                  {feasibility_iterations});
  };
  ZeroCostNoting plain, tested;
  const detail::JoinedSolve a = joined(plain, 0), b = joined(tested, 1000);
  REQUIRE(a.parts == 2);
  CHECK(a.r.status == LpStatus::Infeasible);
  CHECK(b.r.status == LpStatus::Infeasible);
  CHECK(a.failed_rows == std::vector<int64_t>{0, 1, 2});
  CHECK(b.failed_rows == a.failed_rows);
  // The proof is the clash's alone either way (without the pre-test, proved again at zero cost).
  CHECK(b.proof[3] == 0.0);
  CHECK(std::abs(b.proof[2]) > 0.0);
  // Without it: the clash costed, then again at zero cost for its proof; q's part costed.
  CHECK(plain.zero == std::vector<bool>{false, true, false});
  // With it: both parts at zero cost, and no costed solve after the clash's proof there.
  CHECK(tested.zero == std::vector<bool>{true, true});
  // Their seconds are reported apart (only the pre-tests': the re-proof is the costed solve's).
  CHECK(a.pretest_seconds == 0.0);
  CHECK(b.pretest_seconds > 0.0);
  // A feasible LP: the same solution, the pre-test's iterations added.
  const LpProblem ok = clash_beside_costs(100.0, true);
  ZeroCostNoting plain_ok, tested_ok;
  const detail::JoinedSolve c = detail::solve_in_parts(ok, params, plain_ok, nullptr, 0, params, true),
                            d = detail::solve_in_parts(ok, params, tested_ok, nullptr, 0, params, true, {}, nullptr,
                                                       nullptr, {}, 10.0, {1000});
  REQUIRE(c.r.status == LpStatus::Optimal);
  REQUIRE(d.r.status == LpStatus::Optimal);
  CHECK(d.r.objective == doctest::Approx(c.r.objective).epsilon(1e-9));
  CHECK(d.r.x == c.r.x);
  CHECK(d.r.iterations > c.r.iterations);
  CHECK(c.pretest_seconds == 0.0);
  CHECK(d.pretest_seconds > 0.0);
  CHECK(tested_ok.zero == std::vector<bool>{true, true, false, false});
}

TEST_CASE("rounding: a later round's parts optimal within their first iterations skip the pre-test") {
  SolverParams params;
  params.tolerance = 1e-6;
  params.threads = 1;
  params.max_iterations = 100000;
  const auto joined = [&](const LpProblem& lp, ZeroCostNoting& solver, int64_t skip_below) {
    return detail::solve_in_parts(lp, params, solver, nullptr, 0, params, true, {}, nullptr, nullptr, {}, 10.0,
                                  {1000, 0.0, nullptr, skip_below});
  };
  // A feasible LP in two parts, each optimal well within 5 000 iterations: no zero-cost solve at
  // all, and the results of the solves without the pre-test, iterate for iterate.
  const LpProblem ok = clash_beside_costs(100.0, true);
  ZeroCostNoting none, tested, quick;
  const detail::JoinedSolve c = detail::solve_in_parts(ok, params, none, nullptr, 0, params, true);
  const detail::JoinedSolve d = joined(ok, quick, 5000);
  REQUIRE(c.r.status == LpStatus::Optimal);
  REQUIRE(d.r.status == LpStatus::Optimal);
  CHECK(quick.zero == std::vector<bool>{false, false});
  CHECK(quick.cap == std::vector<int64_t>{5000, 5000});
  CHECK(d.r.x == c.r.x);
  CHECK(d.r.iterations == c.r.iterations);
  CHECK(d.pretest_seconds == 0.0);
  // Optimal, but not within a residual bound of 1e-12: the clash rows' part ends at a point within
  // rounding error of exact, q's one-row part about 1e-7 away, so q's part alone is pre-tested,
  // and the first iterations' results stand.
  ZeroCostNoting strict;
  const detail::JoinedSolve g = detail::solve_in_parts(ok, params, strict, nullptr, 0, params, true, {}, nullptr,
                                                       nullptr, {}, 10.0, {1000, 0.0, nullptr, 5000, 1e-12});
  REQUIRE(g.r.status == LpStatus::Optimal);
  CHECK(strict.zero == std::vector<bool>{false, false, true});
  CHECK(strict.cols == std::vector<int64_t>{4, 2, 2});
  CHECK(g.r.x == c.r.x);
  CHECK(g.pretest_seconds > 0.0);
  // The same by the bound in a row alone (no relative bound): q's part, about 1e-7 off in its
  // row, is pre-tested under 1e-12 and not under 1e-3.
  ZeroCostNoting row_strict, row_loose;
  const detail::JoinedSolve rs = detail::solve_in_parts(ok, params, row_strict, nullptr, 0, params, true, {}, nullptr,
                                                       nullptr, {}, 10.0, {1000, 0.0, nullptr, 5000, 0.0, 1e-12});
  const detail::JoinedSolve rl = detail::solve_in_parts(ok, params, row_loose, nullptr, 0, params, true, {}, nullptr,
                                                       nullptr, {}, 10.0, {1000, 0.0, nullptr, 5000, 0.0, 1e-3});
  REQUIRE(rs.r.status == LpStatus::Optimal);
  REQUIRE(rl.r.status == LpStatus::Optimal);
  CHECK(row_strict.zero == std::vector<bool>{false, false, true});
  CHECK(row_strict.cols == std::vector<int64_t>{4, 2, 2});
  CHECK(row_loose.zero == std::vector<bool>{false, false});
  CHECK(rs.r.x == c.r.x);
  CHECK(rl.r.x == c.r.x);
  // Neither part optimal in its first 8 iterations: both pre-tested, then each costed solve goes
  // on from its first iterations' point (warm) for the rest of the cap, to the same optimum.
  const detail::JoinedSolve e = joined(ok, tested, 8);
  REQUIRE(e.r.status == LpStatus::Optimal);
  CHECK(tested.zero == std::vector<bool>{false, false, true, true, false, false});
  CHECK(tested.cap[0] == 8);
  CHECK(tested.cap[4] == params.max_iterations - 8);
  CHECK(tested.warm[4]);
  CHECK(e.r.objective == doctest::Approx(c.r.objective).epsilon(1e-5));
  // A part's iterations: its first ones, its pre-test's and the rest; the join's, the larger part's.
  REQUIRE(tested.iterations.size() == 6);
  const std::vector<int64_t>& its = tested.iterations;
  CHECK(e.r.iterations == std::max(its[0] + its[2] + its[4], its[1] + its[3] + its[5]));
  CHECK(e.pretest_seconds > 0.0);
  // An infeasible part not proved in its first iteration is still proved at zero cost, and
  // nothing runs after.
  const LpProblem clash = clash_beside_costs(100.0);
  ZeroCostNoting failing;
  const detail::JoinedSolve f = joined(clash, failing, 1);
  CHECK(f.r.status == LpStatus::Infeasible);
  CHECK(f.failed_rows == std::vector<int64_t>{0, 1, 2});
  CHECK(failing.zero == std::vector<bool>{false, false, true, true});
  // One its first 8 iterations prove infeasible (the clash's costs are small) skips its pre-test:
  // its costed proof stands, proved again at zero cost for the clash alone, and q's part, pre-tested,
  // goes on as before.
  ZeroCostNoting proved;
  const detail::JoinedSolve h = joined(clash, proved, 8);
  CHECK(h.r.status == LpStatus::Infeasible);
  CHECK(h.failed_rows == std::vector<int64_t>{0, 1, 2});
  CHECK(proved.zero == std::vector<bool>{false, false, true, true, false});
  CHECK(proved.cols == std::vector<int64_t>{4, 2, 2, 4, 2});
}

TEST_CASE("rounding: the later pre-test's own tolerance: a part within the LP's tolerance of feasible is proved "
          "infeasible under a tighter one") {
  // a1 + a2 = 1 and a1 + a2 = 1.01: infeasible, yet a point with both rows off by 0.005 has a
  // relative residual of 0.0029, under the LP's 0.01.
  const LpProblem lp = test::dense_lp({{1, 1}, {1, 1}}, {1.0, 1.01}, {1.0, 2.0});
  SolverParams params;
  params.tolerance = 1e-2;
  params.threads = 1;
  auto joined = [&](ZeroCostNoting& solver, double feasibility_tolerance) {
    return detail::solve_in_parts(lp, params, solver, nullptr, 0, params, true, {}, nullptr, nullptr, {}, 10.0,
                                  {2000, feasibility_tolerance});
  };
  ZeroCostNoting loose, tight;
  const detail::JoinedSolve a = joined(loose, 0.0), b = joined(tight, 1e-7);
  // At the LP's tolerance the pre-test passes the part and the costed solve calls it optimal.
  CHECK(a.r.status == LpStatus::Optimal);
  CHECK(loose.zero == std::vector<bool>{true, false});
  // Under 1e-7 the pre-test goes on to its proof, and no costed solve runs.
  CHECK(b.r.status == LpStatus::Infeasible);
  CHECK(tight.zero == std::vector<bool>{true});
  CHECK(b.failed_rows == std::vector<int64_t>{0, 1});
  // The certificate: the two rows against each other, bᵀy > 0.
  CHECK(b.proof[0] == doctest::Approx(-b.proof[1]).epsilon(1e-3));
  CHECK(b.proof[0] + 1.01 * b.proof[1] > 0.0);
  // Without the pre-test, the re-proof of a part the costed solve proved infeasible runs under
  // that tolerance too (clash_beside_costs: costed, at zero cost, costed).
  const LpProblem clash = clash_beside_costs(100.0);
  ZeroCostNoting reproved;
  const detail::JoinedSolve c = detail::solve_in_parts(clash, params, reproved, nullptr, 0, params, true, {}, nullptr,
                                                       nullptr, {}, 10.0, {0, 1e-7});
  CHECK(c.r.status == LpStatus::Infeasible);
  REQUIRE(reproved.zero == std::vector<bool>{false, true, false});
  CHECK(reproved.tolerance == std::vector<double>{1e-2, 1e-7, 1e-2});
}

TEST_CASE("rounding: a part unchanged since the later pre-test passed it is not tested again") {
  SolverParams params;
  params.tolerance = 1e-6;
  params.threads = 1;
  detail::PretestCache cache;
  auto joined = [&](const LpProblem& lp, ZeroCostNoting& solver) {
    return detail::solve_in_parts(lp, params, solver, nullptr, 0, params, true, {}, nullptr, nullptr, {}, 10.0,
                                  {1000, 0.0, &cache});
  };
  // Two feasible parts: both tested, then both solved with their costs.
  const LpProblem ok = clash_beside_costs(100.0, true);
  ZeroCostNoting first, again, changed;
  const detail::JoinedSolve a = joined(ok, first);
  CHECK(first.zero == std::vector<bool>{true, true, false, false});
  CHECK(cache.entries.size() == 2);
  // The same LP again: no pre-test, the same solution.
  const detail::JoinedSolve b = joined(ok, again);
  CHECK(again.zero == std::vector<bool>{false, false});
  CHECK(cache.reused == 2);
  REQUIRE(b.r.status == LpStatus::Optimal);
  CHECK(b.r.x == a.r.x);
  // q's right-hand side changed: only q's part is tested.
  LpProblem moved = ok;
  moved.b[3] = 0.5;
  const detail::JoinedSolve c = joined(moved, changed);
  CHECK(changed.zero == std::vector<bool>{true, false, false});
  CHECK(cache.reused == 3);
  CHECK(c.r.status == LpStatus::Optimal);
  CHECK(detail::constraint_fingerprint(moved) != detail::constraint_fingerprint(ok));
  // An infeasible part's verdict is not kept: the clash is proved again each time.
  const LpProblem clash = clash_beside_costs(100.0);
  ZeroCostNoting proved, proved_again;
  CHECK(joined(clash, proved).r.status == LpStatus::Infeasible);
  CHECK(joined(clash, proved_again).r.status == LpStatus::Infeasible);
  CHECK(proved_again.zero.front());
  // Solved whole from a warm start, the pre-test still starts cold (its kept verdicts rely on
  // it); the costed solve starts warm.
  SolverParams warm = params;
  warm.initial_x = a.r.x;
  warm.initial_y = a.r.y;
  ZeroCostNoting whole;
  detail::PretestCache fresh;
  const detail::JoinedSolve w =
      detail::solve_in_parts(ok, warm, whole, nullptr, 0, warm, false, {}, nullptr, nullptr, {}, 10.0, {1000, 0.0, &fresh});
  CHECK(w.r.status == LpStatus::Optimal);
  CHECK(whole.zero == std::vector<bool>{true, false});
  CHECK(whole.warm == std::vector<bool>{false, true});
}

namespace {
// The first-order solver, noting the primal weight each solve was asked to start from.
class WeightNoting final : public LpSolver {
public:
  std::string name() const override { return "pdhg-cpu"; }
  LpResult solve(const LpProblem& lp, const SolverParams& params) override {
    asked.push_back(params.initial_primal_weight);
    return inner->solve(lp, params);
  }
  std::unique_ptr<LpSolver> inner = make_solver("pdhg-cpu");
  std::vector<double> asked;
};

// Two copies of an LP side by side: two independent parts.
LpProblem twice(const LpProblem& p) {
  LpProblem q;
  q.a.rows = 2 * p.a.rows;
  q.a.cols = 2 * p.a.cols;
  q.a.row_ptr = p.a.row_ptr;
  q.a.entry = p.a.entry;
  for (int64_t i = 1; i <= p.a.rows; ++i) q.a.row_ptr.push_back(p.a.row_ptr.back() + p.a.row_ptr[i]);
  for (uint32_t e : p.a.entry) q.a.entry.push_back(e + static_cast<uint32_t>(p.a.cols));  // the sign bit stays
  q.at = transpose(q.a);
  q.b = p.b;
  q.b.insert(q.b.end(), p.b.begin(), p.b.end());
  q.c = p.c;
  q.c.insert(q.c.end(), p.c.begin(), p.c.end());
  q.objective_scale = p.objective_scale;
  q.check();
  return q;
}
}  // namespace

TEST_CASE("rounding: a later round's parts start from the primal weight their columns' last solve ended with") {
  const MatchingLp& m = dolphins_60();
  const LpProblem lp = twice(m.lp);
  const int64_t n = m.lp.cols();
  SolverParams params;
  params.tolerance = 1e-4;
  WeightNoting pdhg;
  // No weights given: every part starts from the solver's own; each part's columns get the ω its
  // solve ended with.
  const detail::JoinedSolve a = detail::solve_in_parts(lp, params, pdhg, nullptr, 0, params, true);
  REQUIRE(a.parts == 2);
  REQUIRE(pdhg.asked.size() == 2);
  CHECK(pdhg.asked[0] == 0.0);
  CHECK(pdhg.asked[1] == 0.0);
  REQUIRE(a.weight.size() == size_t(lp.cols()));
  CHECK(a.weight[0] > 0.0);
  CHECK(a.weight[0] != 1.0);  // it moved from the solver's start
  CHECK(a.weight[n - 1] == a.weight[0]);
  CHECK(a.weight[n] > 0.0);
  // Given per column: the first part's columns 2 and 8 (half each), zeros ignored; the second's 5.
  std::vector<double> w(lp.cols(), 0.0);
  for (int64_t j = 0; j < n; ++j) w[j] = j % 3 == 0 ? 0.0 : j % 3 == 1 ? 2.0 : 8.0;
  for (int64_t j = n; j < 2 * n; ++j) w[j] = 5.0;
  const int64_t ones = (n + 1) / 3, twos = n / 3;  // j % 3 == 1 and j % 3 == 2 below n
  pdhg.asked.clear();
  detail::solve_in_parts(lp, params, pdhg, nullptr, 0, params, true, {}, nullptr, &w);
  REQUIRE(pdhg.asked.size() == 2);
  CHECK(pdhg.asked[0] == doctest::Approx(std::exp((ones * std::log(2.0) + twos * std::log(8.0)) / double(ones + twos))));
  CHECK(pdhg.asked[1] == doctest::Approx(5.0));
  // The whole LP as one part (not split): the mean over all its columns.
  pdhg.asked.clear();
  std::vector<double> w1(n, 3.0);
  detail::solve_in_parts(m.lp, params, pdhg, nullptr, 0, params, false, {}, nullptr, &w1);
  REQUIRE(pdhg.asked.size() == 1);
  CHECK(pdhg.asked[0] == doctest::Approx(3.0));
}

TEST_CASE("rounding: later rounds carrying their parts' primal weights end in a verified graph surface") {
  // Every round on PDHG (as in the capped-rounds test), its parts started from the carried ω.
  const MatchingLp& m = dolphins_60();
  RoundingOptions o = every_round_on_pdhg();
  o.carry_weights = true;
  const RoundingResult r = round_to_graph_surface(m.space, m.lp, m.energy, o);
  REQUIRE(r.rounds.size() >= 2);
  CHECK(r.rounds[1].parts > 1);
  CHECK(satisfies_exactly(m.lp, r.gamma));
  CHECK(check_graph_surface(m.space, r.gamma).ok());
  // Round 2's parts hold only round 1's columns: each starts from round 1's final ω.
  CHECK(r.rounds[0].start_primal_weight == 0.0);
  REQUIRE(std::isfinite(r.rounds[0].primal_weight));
  CHECK(r.rounds[0].primal_weight != 1.0);
  CHECK(r.rounds[1].start_primal_weight == doctest::Approx(r.rounds[0].primal_weight));
  // Without it, the solver's own start.
  o.carry_weights = false;
  const RoundingResult u = round_to_graph_surface(m.space, m.lp, m.energy, o);
  REQUIRE(u.rounds.size() >= 2);
  CHECK(u.rounds[1].start_primal_weight == 0.0);
  CHECK(std::isfinite(u.rounds[1].primal_weight));
}

TEST_CASE("rounding: where no candidate of a big round stands away, one per undecided region is fixed, at most a share") {
  // x1 + … + x5 = 3 and x6 + … + x10 = 3 at equal costs: PDHG from 0 ends at 3/5 each, every
  // candidate undecided itself, the two rows two undecided regions. With a share of 0.99 one
  // candidate per region goes in (two; before, the largest nine of the ten, as far as they fit);
  // a share of 1 is the whole batch as far as it fits (three per row: done in one round); 0.1
  // of the ten fixes one; the default (0.125, two) one per region.
  const LpProblem lp = test::dense_lp({{1, 1, 1, 1, 1, 0, 0, 0, 0, 0}, {0, 0, 0, 0, 0, 1, 1, 1, 1, 1}}, {3, 3},
                                      std::vector<double>(10, 1.0));
  const ProductSpace space = stand_in_space(lp);
  const std::vector<double> cost(lp.cols(), 1.0);
  RoundingOptions options;
  options.solver = "pdhg-cpu";
  options.exact_below = 0;
  options.greedy_above = 0;
  options.alternative_thresholds = {};
  const RoundingResult by_default = round_to_graph_surface(space, lp, cost, options);
  REQUIRE(by_default.rounds.size() >= 2);
  CHECK(by_default.rounds[0].fixed_to_one == 2);
  options.greedy_fallback = 0.99;
  const RoundingResult regions = round_to_graph_surface(space, lp, cost, options);
  REQUIRE(regions.rounds.size() >= 2);
  CHECK(regions.rounds[0].fixed_to_one == 2);
  options.greedy_fallback = 1.0;
  const RoundingResult whole = round_to_graph_surface(space, lp, cost, options);
  REQUIRE(!whole.rounds.empty());
  CHECK(whole.rounds[0].fixed_to_one == 6);
  options.greedy_fallback = 0.1;
  const RoundingResult share = round_to_graph_surface(space, lp, cost, options);
  REQUIRE(share.rounds.size() >= 2);
  CHECK(share.rounds[0].fixed_to_one == 1);
  for (const RoundingResult* r : {&by_default, &regions, &whole, &share}) {
    CHECK(satisfies_exactly(lp, r->gamma));
    CHECK(r->gamma.size() == 6);
  }
}

namespace {
// Clp as if it took `seconds_per_column` per column of a part: past its time limit it stops
// there, as Clp does (status TimeLimit, its point so far); the column counts of its parts noted.
class ClockedClp final : public LpSolver {
public:
  explicit ClockedClp(double seconds_per_column) : per_column(seconds_per_column) {}
  std::string name() const override { return "clocked-clp"; }
  LpResult solve(const LpProblem& lp, const SolverParams& params) override {
    cols.push_back(lp.cols());
    const double takes = per_column * double(lp.cols());
    if (takes <= params.time_limit) return clp->solve(lp, params);
    LpResult r;
    r.solver = name();
    r.status = LpStatus::TimeLimit;
    r.seconds = params.time_limit;
    r.x.assign(lp.cols(), 0.0);
    r.y.assign(lp.rows(), 0.0);
    return r;
  }
  double per_column;
  std::vector<int64_t> cols;
  std::unique_ptr<LpSolver> clp = make_solver("clp-dual");
};
}  // namespace

TEST_CASE("rounding: a part that reaches the exact solver's time cap goes to the first-order one, and so do "
          "parts of its size from then on") {
  // Two parts: rows 0-2 on columns 0-3, row 3 on columns 4-5. At 10 s a column the first takes
  // Clp 40 s, the second 20 s; the cap is 30 s.
  const LpProblem lp = clash_beside_costs(1.0, true);
  const LpResult whole = solve_lp(lp, "clp-dual");
  REQUIRE(whole.status == LpStatus::Optimal);
  SolverParams params;
  params.tolerance = 1e-7;
  params.threads = 1;
  const auto pdhg = make_solver("pdhg-cpu");
  ClockedClp clp(10.0);
  detail::ExactCache cache;
  const detail::ExactCap cap{0.0, 30.0};
  const detail::JoinedSolve a = detail::solve_in_parts(lp, params, *pdhg, &clp, 10, params, true, cap, &cache);
  REQUIRE(a.parts == 2);
  CHECK(a.r.status == LpStatus::Optimal);
  CHECK(a.r.objective == doctest::Approx(whole.objective).epsilon(1e-5));
  CHECK(a.exact_parts == 1);  // the small part; the large one went to PDHG after Clp's 30 s
  CHECK(std::multiset<int64_t>(clp.cols.begin(), clp.cols.end()) == std::multiset<int64_t>{2, 4});
  CHECK(cache.capped_below == 4);
  // Both parts changed (no kept results): the large one goes to PDHG without Clp, the small one
  // to Clp as before.
  LpProblem other = lp;
  other.c[0] += 0.125;
  other.c[5] += 0.125;
  clp.cols.clear();
  const detail::JoinedSolve b = detail::solve_in_parts(other, params, *pdhg, &clp, 10, params, true, cap, &cache);
  CHECK(b.r.status == LpStatus::Optimal);
  CHECK(clp.cols == std::vector<int64_t>{2});
  CHECK(b.exact_parts == 1);
  // The LP's own time limit, under the cap, caps Clp the same way (Clp stopped short has no answer).
  detail::ExactCache fresh;
  SolverParams short_lp = params;
  short_lp.time_limit = 25.0;
  clp.cols.clear();
  const detail::JoinedSolve c = detail::solve_in_parts(lp, params, *pdhg, &clp, 10, short_lp, true, cap, &fresh);
  CHECK(c.r.status == LpStatus::Optimal);
  CHECK(c.exact_parts == 1);
  CHECK(fresh.capped_below == 4);
  // No cap: Clp's 40 s on the large part.
  fresh = {};
  clp.cols.clear();
  const detail::JoinedSolve d = detail::solve_in_parts(lp, params, *pdhg, &clp, 10, params, true, {}, &fresh);
  CHECK(d.exact_parts == 2);
  CHECK(d.r.objective == doctest::Approx(whole.objective).epsilon(1e-9));
}

TEST_CASE("rounding: the budget of undone fixings counts since the last round with fewer free variables than any before") {
  // Two disjoint copies of odd_cycle_behind_a (the second's a' at 20): each a = 1 leaves an odd
  // cycle, and the rounding undoes its way to a' = 1 in each. Its free variables by round: 10,
  // 6 (undone), 8, 6 (undone), 3 (undone), 5, 3 (undone). Counted over the whole rounding, a
  // budget of 3 or 4 undone fixings gave up (checked on the code before this rule); counted
  // since the last low, 3 suffices and 2 does not.
  std::vector<std::vector<int>> rows;
  const std::vector<std::vector<int>> one = {{1, 1, 0, 0, 0}, {0, 1, 1, 1, 0}, {0, 1, 0, 1, 1}, {0, 1, 1, 0, 1}};
  for (const auto& r : one) {
    std::vector<int> first = r, second(5, 0);
    first.resize(10, 0);
    second.insert(second.end(), r.begin(), r.end());
    rows.push_back(first);
    rows.push_back(second);
  }
  const std::vector<double> cost = {0, 10, 0, 0, 0, 0, 20, 0, 0, 0};
  const LpProblem lp = test::dense_lp(rows, std::vector<double>(8, 1.0), cost);
  const ProductSpace space = stand_in_space(lp);
  RoundingOptions options;
  options.solver = "clp-dual";  // vertices: the cycles at exactly 1/2
  options.max_backtracks = 3;
  const RoundingResult r = round_to_graph_surface(space, lp, cost, options);
  CHECK(r.gamma == std::vector<int64_t>{1, 6});
  CHECK(r.energy == 30.0);
  int undone = 0;
  for (const RoundingRound& k : r.rounds) undone += k.undone;
  CHECK(undone >= 4);
  options.max_backtracks = 2;
  CHECK_THROWS_AS(round_to_graph_surface(space, lp, cost, options), InfeasibleError);
}

namespace {

// `blocks` independent patches that each branch at a fractional vertex with both values viable,
// then a core with no binary solution, its columns last (ties in branching go to the lowest
// column, so the blocks are decided first). Block: x1 + x2 + e1 = 1, x2 + x3 + e2 = 1,
// x3 + x1 + e3 = 1, the e costing 1 (the LP's only optimum is x = 1/2). Core `pigeons` false: an
// odd cycle c1 + c2 = c2 + c3 = c3 + c1 = 1, each value of c1 refuted by propagation. True: c
// and two gadgets of three pigeons, two holes and two extra holes, whose capacity is 1 − c in
// the first and c in the second (the LP needs c = 1/2); either value of c closes one gadget's
// extra holes, which propagation sees, and leaves three pigeons in two holes, which only the LP
// does (Clp's ray).
LpProblem blocks_then_core(int blocks, bool pigeons) {
  std::vector<std::vector<std::pair<int, int>>> rows;  // (column, ±1)
  std::vector<double> b, c;
  const auto column = [&](double cost) {
    c.push_back(cost);
    return static_cast<int>(c.size()) - 1;
  };
  for (int k = 0; k < blocks; ++k) {
    const int x = column(0), y = column(0), z = column(0);
    const int e1 = column(1), e2 = column(1), e3 = column(1);
    rows.push_back({{x, 1}, {y, 1}, {e1, 1}});
    rows.push_back({{y, 1}, {z, 1}, {e2, 1}});
    rows.push_back({{z, 1}, {x, 1}, {e3, 1}});
    b.insert(b.end(), {1, 1, 1});
  }
  if (!pigeons) {
    const int c1 = column(0), c2 = column(0), c3 = column(0);
    rows.push_back({{c1, 1}, {c2, 1}});
    rows.push_back({{c2, 1}, {c3, 1}});
    rows.push_back({{c3, 1}, {c1, 1}});
    b.insert(b.end(), {1, 1, 1});
  } else {
    const int cc = column(0);
    for (int gadget = 0; gadget < 2; ++gadget) {
      int x[3][4];  // pigeon p in hole h (h1, h2, then the extra w1, w2)
      for (int p = 0; p < 3; ++p)
        for (int h = 0; h < 4; ++h)
          x[p][h] = column((p == 0 && h == 0) || (p == 1 && h == 1) ? 0.0 : p == 2 && h >= 2 ? 1.0 : 5.0);
      for (int p = 0; p < 3; ++p) {
        rows.push_back({{x[p][0], 1}, {x[p][1], 1}, {x[p][2], 1}, {x[p][3], 1}});
        b.push_back(1);
      }
      for (int h = 0; h < 4; ++h) {
        rows.push_back({{x[0][h], 1}, {x[1][h], 1}, {x[2][h], 1}, {column(0), 1}});
        if (h < 2) b.push_back(1);
        else if (gadget == 0) {
          rows.back().push_back({cc, 1});  // capacity 1 − c
          b.push_back(1);
        } else {
          rows.back().push_back({cc, -1});  // capacity c
          b.push_back(0);
        }
      }
    }
  }
  std::vector<std::vector<int>> dense(rows.size(), std::vector<int>(c.size(), 0));
  for (size_t i = 0; i < rows.size(); ++i)
    for (const auto& [j, v] : rows[i]) dense[i][j] = v;
  return test::dense_lp(dense, b, c);
}

}  // namespace

TEST_CASE("rounding: the search jumps back over decisions that its failures' proofs do not need") {
  constexpr int kBlocks = 6;
  for (const bool pigeons : {false, true}) {
    CAPTURE(pigeons);
    const LpProblem lp = blocks_then_core(kBlocks, pigeons);
    auto clp = make_solver("clp-dual");
    std::vector<int8_t> value;
    int64_t jumping = 0, stepping = 0;
    detail::SearchStats with, without;
    CHECK(detail::search_part(lp, *clp, {}, 100000, value, jumping, nullptr, true, &with) == detail::SearchEnd::none);
    CHECK(detail::search_part(lp, *clp, {}, 100000, value, stepping, nullptr, false, &without) ==
          detail::SearchEnd::none);
    MESSAGE("blocks then ", std::string(pigeons ? "pigeons" : "an odd cycle"), ": ", jumping, " nodes jumping back (",
            with.failures, " failures, ", with.short_nogoods, " short proofs, ", with.jumps, " jumps over ",
            with.levels_skipped, " levels), ", stepping, " nodes stepping back");
    // Jumping: the blocks are decided once, the core fails both ways, and its proofs need none of
    // them. Stepping back tries the core again under all 2^6 combinations of the blocks.
    CHECK(jumping <= kBlocks + 3);
    CHECK(with.short_nogoods == 2);
    CHECK(with.jumps == 1);
    CHECK(with.levels_skipped == kBlocks);
    CHECK(stepping >= (1 << kBlocks));
    CHECK(without.jumps == 0);
    CHECK(without.short_nogoods == 0);
  }
}

TEST_CASE("rounding: the search's verdicts, jumping back or not, match brute force") {
  // Random systems of three or four independent gadgets over shuffled columns: an odd cycle with
  // costly escapes (a fractional optimum, both values of a branch viable), an odd cycle without
  // (no binary solution), and small random blocks (mostly +1 entries as in a matching's rows,
  // some −1) with a planted binary solution or none. `found` must satisfy A x = b; the verdicts
  // must match the search that steps back one level at a time, and brute force where there are
  // at most 16 columns.
  std::mt19937 rng(81);
  auto clp = make_solver("clp-dual");
  int feasible = 0, infeasible = 0, brute = 0;
  int64_t nodes_with = 0, nodes_without = 0;
  detail::SearchStats stats;
  for (int trial = 0; trial < 600; ++trial) {
    std::vector<std::vector<std::pair<int, int>>> rows;  // gadget-local columns, in order of creation
    std::vector<double> b, cost;
    const auto column = [&](double c) {
      cost.push_back(c + 0.01 * static_cast<double>(rng() % 10));
      return static_cast<int>(cost.size()) - 1;
    };
    // Every other trial: one system of sparse rows over all its columns (3-5 entries each, as a
    // matching's rows are), planted or with one right-hand side off by one, where a decision's
    // effect reaches across the system (the gadgets are independent of each other).
    if (trial % 2) {
      const int n = trial % 4 == 1 ? 13 + static_cast<int>(rng() % 4) : 40, m = n * 2 / 3;
      std::vector<int> cols(n), planted(n);
      for (int j = 0; j < n; ++j) {
        cols[j] = column(static_cast<double>(rng() % 4));
        planted[j] = rng() % 3 == 0;
      }
      for (int r = 0; r < m; ++r) {
        std::vector<int> pick(cols);
        std::shuffle(pick.begin(), pick.end(), rng);
        pick.resize(3 + rng() % 3);
        std::vector<std::pair<int, int>> row;
        int sum = 0;
        for (int j : pick) {
          row.push_back({j, rng() % 10 == 0 ? -1 : 1});
          sum += row.back().second * planted[j];
        }
        rows.push_back(row);
        b.push_back(sum);
      }
      if (rng() % 2) b[rng() % m] += 1.0;
    }
    const int gadgets = trial % 2 ? 0 : 3 + static_cast<int>(rng() % 3);
    std::vector<int> escapes;  // a column of each odd cycle with escapes
    for (int g = 0; g < gadgets; ++g) {
      const unsigned kind = rng() % 10;
      if (kind < 4) {  // odd cycle with escapes
        const int x = column(0), y = column(0), z = column(0), e1 = column(1), e2 = column(1), e3 = column(1);
        rows.push_back({{x, 1}, {y, 1}, {e1, 1}});
        rows.push_back({{y, 1}, {z, 1}, {e2, 1}});
        rows.push_back({{z, 1}, {x, 1}, {e3, 1}});
        b.insert(b.end(), {1, 1, 1});
        escapes.push_back(x);
      } else if (kind < 6) {  // odd cycle, with an escape u set by earlier cycles' x where there are some
        const int x = column(0), y = column(0), z = column(0);
        rows.push_back({{x, 1}, {y, 1}});
        rows.push_back({{y, 1}, {z, 1}});
        rows.push_back({{z, 1}, {x, 1}});
        b.insert(b.end(), {1, 1, 1});
        if (escapes.size() >= 2 && rng() % 2) {  // u = 2 − x − x' (a propagation that needs both)
          const int u = column(0);
          rows[rows.size() - 3].push_back({u, 1});
          const size_t one = rng() % escapes.size(), other = (one + 1 + rng() % (escapes.size() - 1)) % escapes.size();
          rows.push_back({{u, 1}, {escapes[one], 1}, {escapes[other], 1}});
          b.push_back(2);
        } else if (!escapes.empty()) {
          const int u = column(0);
          rows[rows.size() - 3].push_back({u, 1});
          rows.push_back({{u, 1}, {escapes[rng() % escapes.size()], 1}});
          b.push_back(1);
        }
      } else {  // random, planted or not
        const bool plant = kind < 9;
        std::vector<int> cols, planted;
        for (int k = 0; k < 5; ++k) {
          cols.push_back(column(static_cast<double>(rng() % 4)));
          planted.push_back(static_cast<int>(rng() % 2));
        }
        for (int r = 0; r < 3; ++r) {
          std::vector<std::pair<int, int>> row;
          int sum = 0;
          for (int k = 0; k < 5; ++k) {
            const unsigned u = rng() % 10;
            if (u > 4) continue;
            row.push_back({cols[k], u == 0 ? -1 : 1});
            sum += row.back().second * planted[k];
          }
          rows.push_back(row);
          b.push_back(plant ? sum : 1.0);
        }
      }
    }
    const int n = static_cast<int>(cost.size()), m = static_cast<int>(rows.size());
    std::vector<int> where(n);  // shuffled: the branching order mixes the gadgets
    std::iota(where.begin(), where.end(), 0);
    std::shuffle(where.begin(), where.end(), rng);
    std::vector<std::vector<int>> a(m, std::vector<int>(n, 0));
    std::vector<double> c(n);
    for (int i = 0; i < m; ++i)
      for (const auto& [j, v] : rows[i]) a[i][where[j]] = v;
    for (int j = 0; j < n; ++j) c[where[j]] = cost[j];
    const LpProblem lp = test::dense_lp(a, b, c);
    CAPTURE(trial);
    std::vector<int8_t> value;
    detail::SearchEnd end[2];
    for (const bool backjump : {true, false}) {
      CAPTURE(backjump);
      int64_t nodes = 0;
      end[backjump] =
          detail::search_part(lp, *clp, {}, 100000, value, nodes, nullptr, backjump, backjump ? &stats : nullptr);
      (backjump ? nodes_with : nodes_without) += nodes;
      REQUIRE(end[backjump] != detail::SearchEnd::node_limit);
      if (end[backjump] == detail::SearchEnd::found) {
        REQUIRE(value.size() == size_t(n));
        for (int i = 0; i < m; ++i) {
          int s = 0;
          for (int j = 0; j < n; ++j) s += a[i][j] * value[j];
          CHECK(s == static_cast<int>(b[i]));
        }
      }
    }
    const bool found = end[1] == detail::SearchEnd::found;
    CHECK(found == (end[0] == detail::SearchEnd::found));
    (found ? feasible : infeasible) += 1;
    if (n <= 16) {
      ++brute;
      bool exists = false;
      for (uint32_t x = 0; x < (1u << n) && !exists; ++x) {
        bool ok = true;
        for (int i = 0; i < m && ok; ++i) {
          int s = 0;
          for (int j = 0; j < n; ++j) s += a[i][j] * static_cast<int>((x >> j) & 1u);
          ok = s == static_cast<int>(b[i]);
        }
        exists = ok;
      }
      CHECK(found == exists);
    }
  }
  MESSAGE(feasible, " with a binary solution, ", infeasible, " without, ", brute, " checked by brute force; nodes ",
          nodes_with, " jumping back (", stats.failures, " failures, ", stats.short_nogoods, " short proofs, ",
          stats.jumps, " jumps over ", stats.levels_skipped, " levels), ", nodes_without, " stepping back");
  CHECK(feasible >= 80);
  CHECK(infeasible >= 80);
  CHECK(brute >= 40);
  CHECK(stats.jumps >= 20);  // (the verdicts above are checked where jumps were made)
  CHECK(nodes_with < nodes_without);
}

TEST_CASE("rounding: the search checks a shorter proof on its decisions alone") {
  // u + p + q = 2, v = q (through h: q + h = v + h = 1), and two gadgets of three pigeons, two
  // holes and two extra holes of capacity u and v (the LP needs each at least 1/2; a binary
  // solution, 1). Costs p 1, q 2: the LP's optimum has p = q = 1/2, branched first, p before q.
  // p = 1, then q = 1 sets u = 0 (that needs both), and the first gadget's LP has no solution;
  // its ray weighs on what u = 0 closed, made at q's level, and on nothing of p's. Taken alone,
  // q = 1 leaves u free and the ray proves nothing: the failure needs p too. q = 0 then fails in
  // the second gadget, needing q alone. Going back over p on the strength of the short proof would
  // end in "none"; the only solution has p = 0, q = 1.
  std::vector<std::vector<std::pair<int, int>>> rows;
  std::vector<double> b, c;
  const auto column = [&](double cost) {
    c.push_back(cost);
    return static_cast<int>(c.size()) - 1;
  };
  const int p = column(1), q = column(2), u = column(0), h = column(0), v = column(0);
  rows.push_back({{u, 1}, {p, 1}, {q, 1}});
  b.push_back(2);
  rows.push_back({{q, 1}, {h, 1}});
  rows.push_back({{v, 1}, {h, 1}});
  b.insert(b.end(), {1, 1});
  for (const int capacity : {u, v}) {
    int x[3][4];
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 4; ++k) x[i][k] = column((i == 0 && k == 0) || (i == 1 && k == 1) ? 0.0 : i == 2 && k >= 2 ? 1.0 : 5.0);
    for (int i = 0; i < 3; ++i) {
      rows.push_back({{x[i][0], 1}, {x[i][1], 1}, {x[i][2], 1}, {x[i][3], 1}});
      b.push_back(1);
    }
    for (int k = 0; k < 4; ++k) {
      rows.push_back({{x[0][k], 1}, {x[1][k], 1}, {x[2][k], 1}, {column(0), 1}});
      if (k >= 2) rows.back().push_back({capacity, -1});
      b.push_back(k < 2 ? 1 : 0);
    }
  }
  std::vector<std::vector<int>> dense(rows.size(), std::vector<int>(c.size(), 0));
  for (size_t i = 0; i < rows.size(); ++i)
    for (const auto& [j, s] : rows[i]) dense[i][j] = s;
  const LpProblem lp = test::dense_lp(dense, b, c);
  auto clp = make_solver("clp-dual");
  for (const bool backjump : {true, false}) {
    CAPTURE(backjump);
    std::vector<int8_t> value;
    int64_t nodes = 0;
    detail::SearchStats stats;
    REQUIRE(detail::search_part(lp, *clp, {}, 1000, value, nodes, nullptr, backjump, &stats) ==
            detail::SearchEnd::found);
    CHECK(value[p] == 0);
    CHECK(value[q] == 1);
    CHECK(value[u] == 1);
    MESSAGE(nodes, " nodes, ", stats.failures, " failures, ", stats.short_nogoods, " short proofs, ", stats.jumps,
            " jumps");
    if (backjump) CHECK(stats.failures >= 2);
  }
}

TEST_CASE("rounding: a search's proofs release the fixings they rest on, not all near the part") {
  // odd_cycle_behind_a with b beside it: a + a' = 1, x_i + x_j + a' = 1 (a' costs 10), b + b' = 1
  // (b' costs 10) and a' + b + s + s2 = 2 (s, s2 cost 1). Round 1 fixes a, b and one of s, s2;
  // the x then form an odd cycle, which the search proves has no binary solution. Its proofs (the
  // rows where propagation stops) rest on a' = 0, which a's fixing set; without a, the fixing of
  // s (or s2) sets a' = 0 in turn (a' + s + s2 = 1 once b = 1), and the proofs weighed again
  // release it too. b lies within two LP steps of the cycle (through a') and carries nothing:
  // from the proofs, a and s go; from the neighbourhood, b as well.
  const LpProblem lp = test::dense_lp({{1, 1, 0, 0, 0, 0, 0, 0, 0},
                                       {0, 1, 1, 1, 0, 0, 0, 0, 0},
                                       {0, 1, 0, 1, 1, 0, 0, 0, 0},
                                       {0, 1, 1, 0, 1, 0, 0, 0, 0},
                                       {0, 0, 0, 0, 0, 1, 1, 0, 0},
                                       {0, 1, 0, 0, 0, 1, 0, 1, 1}},
                                      {1, 1, 1, 1, 1, 2}, {0, 10, 0, 0, 0, 0, 10, 1, 1});
  const Mesh m = shapes::icosphere(0);
  const auto id = identity_matching(m);
  REQUIRE(id.size() >= 9);
  const ProductSpace space = ProductSpace::from_list(m, m, {id.begin(), id.begin() + 9});
  RoundingOptions options = search_without_backtracking();
  int64_t released[2] = {0, 0}, by_proofs[2] = {0, 0};
  for (const bool proofs : {true, false}) {
    CAPTURE(proofs);
    options.search_proof_release = proofs;
    const RoundingResult r = round_to_graph_surface(space, lp, lp.c, options);
    CHECK(satisfies_exactly(lp, r.gamma));
    CHECK(r.energy == 10.0);  // a' (then b = 1, s = s2 = 0)
    REQUIRE(r.rounds.size() >= 2);
    CHECK(r.rounds[0].fixed_to_one >= 2);  // a and b
    CHECK(r.rounds[1].search);
    released[proofs] = r.rounds[1].released;
    by_proofs[proofs] = r.rounds[1].search_proof_released;
  }
  CHECK(released[1] == 2);
  CHECK(by_proofs[1] == 2);
  CHECK(released[0] == 3);
  CHECK(by_proofs[0] == 0);
}

TEST_CASE("rounding: with a release reach cap, the same part failing again is stuck, not released further") {
  // odd_cycle_behind_a with search only up to 3 variables and the release around parts (not by
  // proofs): round 2's search finds the odd cycle without a binary solution and releases a
  // within 2 steps; round 3's LP fixes a again and round 4's search finds the same cycle, whose
  // next release would reach 4 steps. With the cap at 2 that ends the rounding there, naming the
  // cycle's rows: an InfeasibleError, or a StuckError where stuck_after is set.
  const LpProblem lp = odd_cycle_behind_a();
  const ProductSpace space = five_variables();
  RoundingOptions options = search_without_backtracking();
  options.search_below = 3;
  options.search_proof_release = false;
  options.release_reach_cap = 2;
  options.stuck_after = 0.0;
  std::vector<RoundingRound> seen;
  try {
    round_to_graph_surface(space, lp, {0, 10, 0, 0, 0}, options, [&](const RoundingRound& r) { seen.push_back(r); });
    FAIL("no InfeasibleError");
  } catch (const StuckError&) {
    FAIL("a StuckError without stuck_after");
  } catch (const InfeasibleError& e) {
    CHECK(std::string(e.what()).find("release-reach-cap") != std::string::npos);
    CHECK(e.rows() == std::vector<int64_t>{1, 2, 3});
  }
  REQUIRE(seen.size() == 3);  // round 4 threw before reporting
  CHECK(seen[1].released == 1);
  options.stuck_after = 1e9;  // (no time-based rule fires)
  try {
    round_to_graph_surface(space, lp, {0, 10, 0, 0, 0}, options);
    FAIL("no StuckError");
  } catch (const StuckError& e) {
    CHECK(std::string(e.what()).find("release-reach-cap") != std::string::npos);
    CHECK(e.rows() == std::vector<int64_t>{1, 2, 3});
  }
  // Without the cap, the release reaches 4 steps (nothing more within reach: a again) and the
  // rounding goes on until max_releases.
  options.release_reach_cap = 0;
  options.stuck_after = 0.0;
  try {
    round_to_graph_surface(space, lp, {0, 10, 0, 0, 0}, options);
    FAIL("no InfeasibleError");
  } catch (const InfeasibleError& e) {
    CHECK(std::string(e.what()).find("releases of the fixings near it") != std::string::npos);
  }
}

TEST_CASE("rounding: a first LP stopped as diverging blames its stalled residual's rows too where asked") {
  // A divergence bound under the optimum stops round 1's LP at its second window (the watch's
  // bound stop: LpStatus::Diverging, an iterate short of feasible). Its rows are the dual growth's;
  // with blame_residual also the rows its iterate leaves furthest from b: a superset.
  const MatchingLp& m = dolphins_30();
  RoundingOptions o;
  o.solver = "pdhg-cpu";
  o.feasibility_iterations = 0;
  o.lp.tolerance = 1e-9;  // (not optimal before the stop)
  o.lp.stop_on_divergence = true;
  o.lp.divergence_bound = 0.0;
  const auto rows_blamed = [&](bool residual) {
    RoundingOptions b = o;
    b.blame_residual = residual;
    try {
      round_to_graph_surface(m.space, m.lp, m.energy, b);
    } catch (const InfeasibleError& e) {
      CHECK_FALSE(e.certified());
      std::vector<int64_t> rows = e.rows();
      std::sort(rows.begin(), rows.end());
      return rows;
    }
    FAIL("round 1's LP did not stop as diverging");
    return std::vector<int64_t>{};
  };
  const std::vector<int64_t> growth = rows_blamed(false), both = rows_blamed(true);
  MESSAGE("rows blamed: " << growth.size() << " by the dual growth, " << both.size() << " with the residual's");
  REQUIRE_FALSE(growth.empty());
  CHECK(both.size() > growth.size());
  CHECK(std::includes(both.begin(), both.end(), growth.begin(), growth.end()));  // (the growth's kept)
  CHECK(std::adjacent_find(both.begin(), both.end()) == both.end());  // (each once)
  CHECK(both.back() < m.lp.rows());
}

TEST_CASE("rounding: every row of the matching LP is placed on its face or on its product edge") {
  // The stalled rows' debug log names them by row_place: a π row's face must be the face every
  // one of its columns covers, and a closedness row's two product vertices an edge of every one
  // of its columns.
  const MatchingLp& m = dolphins_30();
  int64_t pi_x = 0, pi_y = 0, edges = 0;
  for (int64_t row = 0; row < m.lp.rows(); ++row) {
    const detail::RowPlace p = detail::row_place(m.space, m.lp, row);
    const uint32_t begin = m.lp.a.row_ptr[row], end = m.lp.a.row_ptr[row + 1];
    REQUIRE(end > begin);
    if (row < m.closedness_rows) {
      REQUIRE(p.kind == detail::RowPlace::closedness);
      if (end - begin < 2) continue;  // (one column: its three vertices are shared by it alone)
      REQUIRE(p.edge.size() == 2);
      ++edges;
      for (uint32_t k = begin; k < end; ++k) {
        const ProductTriangle t = m.space[col_of(m.lp.a.entry[k])];
        bool side = false;
        for (int i = 0; i < 3; ++i) {
          const std::set<std::pair<int, int>> e{{t.a[i], t.b[i]}, {t.a[(i + 1) % 3], t.b[(i + 1) % 3]}};
          side = side || e == std::set<std::pair<int, int>>(p.edge.begin(), p.edge.end());
        }
        CHECK(side);
      }
    } else {
      const bool x = row < m.closedness_rows + m.space.x().num_faces();
      REQUIRE(p.kind == (x ? detail::RowPlace::pi_x : detail::RowPlace::pi_y));
      ++(x ? pi_x : pi_y);
      for (uint32_t k = begin; k < end; ++k) {
        const ProductTriangle t = m.space[col_of(m.lp.a.entry[k])];
        CHECK((x ? t.fa : t.fb) == p.face);
      }
    }
  }
  CHECK(pi_x == m.space.x().num_faces());
  CHECK(pi_y == m.space.y().num_faces());
  CHECK(edges > m.closedness_rows / 2);
}

TEST_CASE("rounding: a local proof of infeasibility is found where the clash lies, as far out as it lies") {
  // A chain x_i + x_{i+1} = 1 (rows 0-10) is feasible; row 11, x5 + x6 = 0, clashes with row 5.
  // From row 2, the clash is three steps out (row 2 → x2..x3 → rows 1-3 → x1..x4 → rows 0-4 →
  // x0..x5 → rows 5 and 11).
  std::vector<std::vector<int>> a(12, std::vector<int>(12, 0));
  for (int i = 0; i < 11; ++i) a[i][i] = a[i][i + 1] = 1;
  a[11][5] = a[11][6] = 1;
  std::vector<double> b(12, 1.0);
  b[11] = 0.0;
  const LpProblem clash = test::dense_lp(a, b, std::vector<double>(12, 1.0));
  auto clp = make_solver("clp-dual");
  const detail::LocalProof p = detail::local_infeasibility(clash, {2}, 8, 1000, *clp);
  REQUIRE(p.proved);
  CHECK(p.depth == 3);
  CHECK(std::string(p.ended) == "proved");
  CHECK(p.support == std::vector<int64_t>{5, 11});
  // Its ray, zero elsewhere, proves the whole LP infeasible.
  std::vector<double> d(clash.rows(), 0.0);
  for (size_t k = 0; k < p.support.size(); ++k) d[p.support[k]] = p.ray[k];
  CHECK(farkas_rate(clash, d) > 0.0);
  // With PDHG at zero cost its dual is the ray (checked): it may lean on more rows, but not fewer.
  auto pdhg = make_solver("pdhg-cpu");
  const detail::LocalProof first_order = detail::local_infeasibility(clash, {2}, 8, 1000, *pdhg);
  REQUIRE(first_order.proved);
  CHECK(first_order.depth == 3);
  CHECK(std::binary_search(first_order.support.begin(), first_order.support.end(), int64_t{5}));
  CHECK(std::binary_search(first_order.support.begin(), first_order.support.end(), int64_t{11}));
  d.assign(clash.rows(), 0.0);
  for (size_t k = 0; k < first_order.support.size(); ++k) d[first_order.support[k]] = first_order.ray[k];
  CHECK(farkas_rate(clash, d) > 0.0);
  // The same LP as a reduced one whose row i is row 10 + 3i of a larger LP: seeds and support in
  // that numbering, a seed it lacks left out.
  std::vector<int64_t> rows(12);
  for (int i = 0; i < 12; ++i) rows[i] = 10 + 3 * i;
  const detail::LocalProof within = detail::local_infeasibility_within(clash, rows, {11, 16}, 8, 1000, *clp);
  REQUIRE(within.proved);
  CHECK(within.depth == 3);
  CHECK(within.support == std::vector<int64_t>{25, 43});
  CHECK_FALSE(detail::local_infeasibility_within(clash, rows, {11}, 8, 1000, *clp).proved);  // (no seed)
  // Capped at 5 columns: the relaxations of depths 0 and 1 (2 and 4 columns) alone, no proof.
  const detail::LocalProof capped = detail::local_infeasibility(clash, {2}, 8, 5, *clp);
  CHECK_FALSE(capped.proved);
  CHECK(std::string(capped.ended) == "column cap");
  CHECK(capped.depth == 1);
  CHECK(capped.cols == 4);
  CHECK(capped.capped_rows == 5);  // (depth 2's, rows 0-4 on x0..x5: not solved)
  CHECK(capped.capped_cols == 6);
  CHECK(p.capped_cols == 0);
  // Without row 11 the chain is feasible: no proof, however far out.
  a.pop_back();
  b.pop_back();
  const LpProblem chain = test::dense_lp(a, b, std::vector<double>(12, 1.0));
  const detail::LocalProof none = detail::local_infeasibility(chain, {2}, 20, 1000, *clp);
  CHECK_FALSE(none.proved);
  CHECK(std::string(none.ended) == "feasible");
  CHECK_FALSE(detail::local_infeasibility(chain, {2}, 20, 1000, *pdhg).proved);
  // Out of time before the first solve: said so.
  CHECK(std::string(detail::local_infeasibility(clash, {2}, 8, 1000, *clp, 0.0).ended) == "time limit");
  CHECK(none.rows == chain.rows());  // (it went out to the whole LP)
  // Nor on a feasible matching LP, from a π_Y row and a closedness row two steps out.
  const MatchingLp& m = dolphins_30();
  const detail::LocalProof matching =
      detail::local_infeasibility(m.lp, {0, m.lp.rows() - 1}, 2, 1'000'000, *clp);
  CHECK_FALSE(matching.proved);
  CHECK(matching.depth == 2);
  CHECK(matching.cols > 0);
}

TEST_CASE("rounding: a local proof certifies a matching LP's clash that propagation cannot see, and changes nothing on a feasible LP") {
  const MatchingLp& m = dolphins_30();
  RoundingOptions o;
  o.solver = "pdhg-cpu";
  o.feasibility_iterations = 0;
  o.lp.tolerance = 1e-9;
  o.lp.stop_on_divergence = true;
  o.lp.divergence_bound = 0.0;  // (stops round 1's LP as diverging at its second window: see above)
  const auto error_of = [&](int64_t columns) {
    RoundingOptions b = o;
    b.local_proof_columns = columns;
    try {
      round_to_graph_surface(m.space, m.lp, m.energy, b);
    } catch (const InfeasibleError& e) {
      std::vector<int64_t> rows = e.rows();
      std::sort(rows.begin(), rows.end());
      return std::make_pair(e.certified(), rows);
    }
    FAIL("round 1's LP did not stop");
    return std::make_pair(false, std::vector<int64_t>{});
  };
  // Feasible: no proof near the stalled rows, the same guess.
  const auto plain = error_of(0), tried = error_of(1'000'000);
  CHECK_FALSE(plain.first);
  CHECK_FALSE(tried.first);
  CHECK(tried.second == plain.second);
  // One closedness row asked for a net flux of 1: ∂∂ = 0 makes that impossible (a ray: a
  // potential 1 at one end of the product edge, on the edges there), while every row keeps two
  // free entries or more, so propagation sees nothing. (PDHG certifies this one itself within its
  // first window, so the rounding's own path to the proof is not reached here.)
  LpProblem clash = m.lp;
  clash.b[0] = 1.0;
  auto clp = make_solver("clp-dual");
  const detail::LocalProof p = detail::local_infeasibility(clash, {0}, 8, 1'000'000, *clp);
  REQUIRE(p.proved);
  MESSAGE("proved " << p.depth << " steps out, on " << p.rows << " rows and " << p.cols << " columns; the ray needs "
                    << p.support.size() << " rows");
  CHECK(p.rows < clash.rows());  // (local: the 30-face pair's relaxation has every column)
  CHECK(std::binary_search(p.support.begin(), p.support.end(), int64_t{0}));
  CHECK(p.support.back() < m.closedness_rows);  // (closedness rows alone)
  std::vector<double> d(clash.rows(), 0.0);
  for (size_t k = 0; k < p.support.size(); ++k) d[p.support[k]] = p.ray[k];
  CHECK(farkas_rate(clash, d) > 0.0);
  d.assign(m.lp.rows(), 0.0);  // (and it is no ray of the feasible LP)
  for (size_t k = 0; k < p.support.size(); ++k) d[p.support[k]] = p.ray[k];
  CHECK_FALSE(farkas_rate(m.lp, d) > 0.0);
}

TEST_CASE("rounding: a relaxation with face rows' far columns merged keeps a feasible point feasible") {
  // The identity matching of a mesh with itself is feasible; on any rows, its point restricted to
  // the columns kept, each slack the rest of its row, must satisfy the relaxation (a relaxation).
  static const Mesh x = decimate(shapes::dolphin(0, 5), 30);
  const MatchingLp m = build_matching_lp(x, compute_geometry(x), x, compute_geometry(x));
  std::vector<double> point(m.lp.cols(), 0.0);
  for (const ProductTriangle& t : identity_matching(x)) point[m.space.index_in_full(t)] = 1.0;
  std::vector<int64_t> all(m.lp.cols());
  std::iota(all.begin(), all.end(), int64_t{0});
  std::mt19937 rng(7);
  int64_t merged = 0;
  for (int trial = 0; trial < 12; ++trial) {
    CAPTURE(trial);
    std::vector<int64_t> keep;
    if (trial % 2 == 0) {
      keep = detail::rows_over_x_faces(m.space, m.lp, all, detail::faces_near(x, {trial}, 1 + trial % 3));
    } else {
      for (int64_t r = 0; r < m.lp.rows(); ++r)
        if (rng() % 10 == 0) keep.push_back(r);
    }
    const detail::Relaxation rel = detail::relaxation_on_rows(m.lp, keep, true);
    std::vector<double> p(rel.lp.cols(), 0.0);
    for (size_t k = 0; k < rel.cols.size(); ++k) p[k] = point[rel.cols[k]];
    std::vector<double> ax(rel.lp.rows(), 0.0);
    spmv(rel.lp.a, p.data(), ax.data());
    for (size_t s = 0; s < rel.slack_rows.size(); ++s) {  // (slack: what its row still needs)
      const int64_t i = rel.slack_rows[s];
      p[rel.cols.size() + s] = rel.lp.b[i] - ax[i];
      CHECK(p[rel.cols.size() + s] >= -1e-12);
      CHECK(p[rel.cols.size() + s] <= 1.0 + 1e-12);
    }
    spmv(rel.lp.a, p.data(), ax.data());
    for (int64_t i = 0; i < rel.lp.rows(); ++i) CHECK(ax[i] == doctest::Approx(rel.lp.b[i]));
    merged += static_cast<int64_t>(rel.slack_rows.size());
  }
  CHECK(merged > 0);  // (the merging was exercised)
}

TEST_CASE("rounding: a local proof over an X region certifies a matching LP's clash with its far columns merged") {
  // dolphins_30 with one closedness row's flux set to 1 (see above), proved over the X faces
  // around that row: a relaxation of fewer rows and columns than the plain growth's.
  const MatchingLp& m = dolphins_30();
  LpProblem clash = m.lp;
  clash.b[0] = 1.0;
  std::vector<int64_t> all(m.lp.cols());
  std::iota(all.begin(), all.end(), int64_t{0});
  const std::vector<int> seeds = detail::x_faces_of_rows(m.space, clash, all, {}, {0});
  REQUIRE_FALSE(seeds.empty());
  const auto region_rows = [&](int rings) {
    return detail::rows_over_x_faces(m.space, clash, all, detail::faces_near(m.space.x(), seeds, 1 + rings));
  };
  auto clp = make_solver("clp-dual");
  const detail::LocalProof p = detail::local_infeasibility_on(clash, region_rows, 8, 1'000'000, *clp, 600.0, true);
  REQUIRE(p.proved);
  MESSAGE("proved " << p.depth << " rings out, on " << p.rows << " rows and " << p.cols << " columns of "
                    << clash.rows() << " and " << clash.cols());
  CHECK(std::binary_search(p.support.begin(), p.support.end(), int64_t{0}));
  CHECK(p.cols < clash.cols());
  CHECK_FALSE(detail::relaxation_on_rows(clash, region_rows(p.depth), true).slack_rows.empty());  // (merged)
  // So too with PDHG's dual at zero cost as the ray.
  auto pdhg = make_solver("pdhg-cpu");
  CHECK(detail::local_infeasibility_on(clash, region_rows, 8, 1'000'000, *pdhg, 600.0, true).proved);
  // The feasible LP: no proof over the same regions.
  CHECK_FALSE(detail::local_infeasibility_on(m.lp, region_rows, 8, 1'000'000, *clp, 600.0, true).proved);
  // One region alone, as coarse to fine checks a proof's again (columns numbered as the space's:
  // no `cols`): the same rows and proof as at the depth found, none on the feasible LP or past its
  // column cap.
  CHECK(detail::rows_over_x_faces(m.space, clash, {}, detail::faces_near(m.space.x(), seeds, 1 + p.depth)) ==
        region_rows(p.depth));
  const detail::LocalProof again =
      detail::proof_over_x_region(m.space, clash, {}, seeds, p.depth, 1'000'000, *clp, 600.0);
  CHECK(again.proved);
  CHECK(again.rows == p.rows);
  CHECK(again.support == p.support);
  const detail::LocalProof feasible = detail::proof_over_x_region(m.space, m.lp, {}, seeds, p.depth, 1'000'000, *clp, 600.0);
  CHECK_FALSE(feasible.proved);
  CHECK(std::string(feasible.ended) == "feasible");
  const detail::LocalProof over = detail::proof_over_x_region(m.space, clash, {}, seeds, p.depth, 5, *clp, 600.0);
  CHECK(std::string(over.ended) == "column cap");
  CHECK(over.depth == -1);  // (nothing solved, so its size is the capped one's)
  CHECK(over.rows == 0);
  CHECK(over.capped_rows == p.rows);
  CHECK(over.capped_cols == p.cols);
}

TEST_CASE("rounding: the X faces of stalled rows: where their iterate lies, else all their columns'") {
  const MatchingLp& m = dolphins_30();
  std::vector<int64_t> all(m.lp.cols());
  std::iota(all.begin(), all.end(), int64_t{0});
  const int64_t pi_x = m.closedness_rows + 3, pi_y = m.closedness_rows + m.space.x().num_faces() + 5;
  std::vector<double> x(m.lp.cols(), 0.0);
  // A π_X row names its face, whatever the iterate.
  CHECK(detail::x_faces_of_rows(m.space, m.lp, all, x, {pi_x}) == std::vector<int>{3});
  // A π_Y row with nothing on it names the X faces of all its columns; with one column carrying
  // the iterate, that column's (a triangle's face, or the faces on a vertex or edge's vertices).
  const std::vector<int> every = detail::x_faces_of_rows(m.space, m.lp, all, x, {pi_y});
  CHECK(every.size() == size_t(m.space.x().num_faces()));  // (the full space covers Y face 5 from every X face)
  for (uint32_t k = m.lp.a.row_ptr[pi_y]; k < m.lp.a.row_ptr[pi_y + 1]; ++k) {
    const int64_t j = col_of(m.lp.a.entry[k]);
    const ProductTriangle t = m.space[j];
    x[j] = 1.0;
    const std::vector<int> one = detail::x_faces_of_rows(m.space, m.lp, all, x, {pi_y});
    x[j] = 0.0;
    if (t.fa >= 0) {
      CHECK(one == std::vector<int>{t.fa});
    } else {
      CHECK(one.size() > 1);
      for (int f : one) {
        const auto& face = m.space.x().faces[f];
        CHECK(std::find_first_of(face.begin(), face.end(), t.a.begin(), t.a.end()) != face.end());
      }
    }
  }
}
