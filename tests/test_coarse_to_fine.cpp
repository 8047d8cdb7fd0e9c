#include "divergence_watch.hpp"
#include "divergence_rule.hpp"
#include "key_set.hpp"
#include "recurring_conflicts.hpp"
#include "suspicion_margin.hpp"
#include "shapematch/coarse_to_fine.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/evaluation.hpp"
#include "shapematch/point_map.hpp"
#include "shapematch/shapes.hpp"
#include "test_helpers.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <memory>
#include <numeric>
#include <optional>
#include <set>

using namespace shapematch;

namespace {
Mesh lumpy_sphere(int subdivisions, unsigned seed) { return test::lumpy_sphere(subdivisions, seed, 0.1); }

// Two levels on the native solver, for the bent finger pair below.
CoarseToFineOptions two_levels(int coarsest_faces) {
  CoarseToFineOptions o;
  o.hierarchy.levels = 2;
  o.hierarchy.coarsest_faces = coarsest_faces;
  o.rounding.solver = "pdhg-cpu";
  return o;
}

// Levels of 12, 24, ~38 … faces up to the shapes' own (four or five on the test pairs), CPU PDHG.
CoarseToFineOptions small_levels() {
  CoarseToFineOptions o;
  o.hierarchy.coarsest_faces = 12;
  o.hierarchy.second_faces = 24;
  o.hierarchy.ratio = 1.6;
  o.rounding.solver = "pdhg-cpu";
  return o;
}

// Two dolphins whose lookahead chains still differ at the second level (five levels under
// small_levels(); on the finger pair both chains find the same Γ there and go on as one).
Mesh lookahead_dolphin_x() { return decimate(shapes::dolphin(20, 0), 80); }
Mesh lookahead_dolphin_y() { return decimate(shapes::dolphin(-20, 40), 90); }

// small_levels() with both chains refined to level 4's decision and both rounded there (the
// second chain's LP bound there is above the first chain's energy: lookahead_bound_drop would
// stop it after its first LP).
CoarseToFineOptions both_chains_to_level_4() {
  CoarseToFineOptions o = small_levels();
  o.lookahead_levels = 2;
  o.lookahead_bound_drop = false;
  return o;
}

// The finger straight and bent, decimated to different triangulations.
CoarseToFineMatcher finger_matcher(const CoarseToFineOptions& o) {
  return CoarseToFineMatcher(decimate(shapes::bent_finger(10, 8, 8), 80), decimate(shapes::bent_finger(60, 8, 8), 90), o);
}

// The same pair a little finer (120 and 130 faces), built once, and options under which its
// finest rounding is slow: ring 0, and few fixings per round (every round greedy, a wide margin).
const std::pair<Mesh, Mesh>& fine_fingers() {
  static const std::pair<Mesh, Mesh> p{decimate(shapes::bent_finger(10, 8, 8), 120),
                                       decimate(shapes::bent_finger(60, 8, 8), 130)};
  return p;
}
CoarseToFineOptions slow_finest_rounding() {
  CoarseToFineOptions o = two_levels(24);
  o.ring = 0;
  o.rounding.greedy_above = 0;
  o.rounding.greedy_margin = 2;
  return o;
}

std::set<int64_t> full_indices(const ProductSpace& full, const std::vector<ProductTriangle>& list) {
  std::set<int64_t> s;
  for (const auto& t : list) s.insert(full.index_in_full(t));
  return s;
}
// The finger pair at two levels (`coarse` and `fine` faces per shape), the coarse level matched,
// and the LP of the fine level's ring-1 space with `extra` rings on some X faces.
struct FingerLevels {
  FingerLevels(int coarse_faces, int fine_faces)
      : hx(build_hierarchy(decimate(shapes::bent_finger(10, 8, 8), fine_faces), {coarse_faces, fine_faces})),
        hy(build_hierarchy(decimate(shapes::bent_finger(60, 8, 8), fine_faces), {coarse_faces, fine_faces})),
        gx(compute_geometry(x())), gy(compute_geometry(y())), model(x(), gx, y(), gy) {
    const Mesh& xc = hx.levels[0].mesh;
    const Mesh& yc = hy.levels[0].mesh;
    const MatchingLp coarse = build_matching_lp(xc, compute_geometry(xc), yc, compute_geometry(yc));
    const RoundingResult cr = round_to_graph_surface(coarse.space, coarse.lp, coarse.energy);
    for (int64_t j : cr.gamma) gamma.push_back(coarse.space[j]);
  }
  const Mesh& x() const { return hx.levels[1].mesh; }
  const Mesh& y() const { return hy.levels[1].mesh; }
  MatchingLp lp_at(const std::vector<int>& extra) const {
    return build_matching_lp(ProductSpace::from_list(x(), y(), reduced_product_space(hx.levels[1], hy.levels[1],
                                                                                     hx.levels[0].mesh, hy.levels[0].mesh,
                                                                                     gamma, 1, Neighbourhood::Fine, extra)),
                             model);
  }

  MeshHierarchy hx, hy;
  Geometry gx, gy;  // the model refers to them
  EnergyModel model;
  std::vector<ProductTriangle> gamma;
};
}  // namespace

TEST_CASE("coarse to fine: the reduced space is a duplicate-free subset that grows with the ring") {
  const Mesh m = lumpy_sphere(2, 3);  // 320 faces
  const MeshHierarchy h = build_hierarchy(m, {20, 80});
  const MeshLevel& fine = h.levels[1];
  const Mesh& coarse = h.levels[0].mesh;
  const ProductSpace full = ProductSpace::full(fine.mesh, fine.mesh);
  std::vector<std::set<int64_t>> spaces;
  for (int ring : {0, 1, 2}) {
    const auto list = reduced_product_space(fine, fine, coarse, coarse, identity_matching(coarse), ring, Neighbourhood::Coarse);
    const auto s = full_indices(full, list);  // throws if any entry is not canonical
    CHECK(s.size() == list.size());
    if (ring < 2) CHECK(int64_t(list.size()) < full.size());
    if (!spaces.empty()) CHECK(std::includes(s.begin(), s.end(), spaces.back().begin(), spaces.back().end()));
    spaces.push_back(s);
  }
  CHECK(spaces[0].size() < spaces[1].size());
  // A coarse Γ that is everything gives the full space.
  std::vector<ProductTriangle> everything;
  const ProductSpace coarse_full = ProductSpace::full(coarse, coarse);
  for (int64_t j = 0; j < coarse_full.size(); ++j) everything.push_back(coarse_full[j]);
  CHECK(int64_t(reduced_product_space(fine, fine, coarse, coarse, everything, 0, Neighbourhood::Coarse).size()) == full.size());
}

TEST_CASE("coarse to fine: the fine identity survives the reduction of a coarse identity") {
  const Mesh m = lumpy_sphere(2, 4);
  const MeshHierarchy h = build_hierarchy(m, {20, 80, 320});
  for (int l = 1; l < h.size(); ++l) {
    const auto list = reduced_product_space(h.levels[l], h.levels[l], h.levels[l - 1].mesh, h.levels[l - 1].mesh,
                                            identity_matching(h.levels[l - 1].mesh), 0, Neighbourhood::Coarse);
    const ProductSpace full = ProductSpace::full(h.levels[l].mesh, h.levels[l].mesh);
    const auto s = full_indices(full, list);
    for (const auto& t : identity_matching(h.levels[l].mesh)) CHECK(s.count(full.index_in_full(t)) == 1);
  }
}

TEST_CASE("coarse to fine: the fine neighbourhood is smaller than eq. (17)'s, grows with the ring, keeps the identity") {
  const Mesh m = lumpy_sphere(3, 6);  // 1280 faces
  const MeshHierarchy h = build_hierarchy(m, {80, 320, 1280});
  for (int l = 1; l < h.size(); ++l) {
    const MeshLevel& fine = h.levels[l];
    const Mesh& coarse = h.levels[l - 1].mesh;
    const ProductSpace full = ProductSpace::full(fine.mesh, fine.mesh);
    const auto id = identity_matching(coarse);
    CAPTURE(l);
    // Ring 0 is eq. (17) at ring 0 in both.
    CHECK(reduced_product_space(fine, fine, coarse, coarse, id, 0, Neighbourhood::Fine) ==
          reduced_product_space(fine, fine, coarse, coarse, id, 0, Neighbourhood::Coarse));
    std::set<int64_t> previous;
    for (int ring : {0, 1, 2, 3}) {
      CAPTURE(ring);
      const auto list = reduced_product_space(fine, fine, coarse, coarse, id, ring, Neighbourhood::Fine);
      const auto s = full_indices(full, list);
      CHECK(s.size() == list.size());
      CHECK(std::includes(s.begin(), s.end(), previous.begin(), previous.end()));
      if (ring > 0) CHECK(s.size() > previous.size());
      if (ring == 1)
        CHECK(s.size() < reduced_product_space(fine, fine, coarse, coarse, id, 1, Neighbourhood::Coarse).size());
      for (const auto& t : identity_matching(fine.mesh)) CHECK(s.count(full.index_in_full(t)) == 1);
      previous = s;
    }
  }
}

TEST_CASE("coarse to fine: a face keeps its reach on Y where the ring grows") {
  // Every face with the same extra rings, so that the whole space shows one face's reach: the
  // space after the ring step holds the space before it, for faces below max_ring and past it.
  const Mesh m = lumpy_sphere(2, 4);
  const MeshHierarchy h = build_hierarchy(m, {80, 320});
  const MeshLevel& fine = h.levels[1];
  const Mesh& coarse = h.levels[0].mesh;
  const ProductSpace full = ProductSpace::full(fine.mesh, fine.mesh);
  const auto id = identity_matching(coarse);
  const int max_ring = 3;
  for (int y_margin : {0, 1})
    for (int ring : {1, 2, 3})
      for (int extra : {0, 1, 2, 3, 5}) {
        CAPTURE(y_margin);
        CAPTURE(ring);
        CAPTURE(extra);
        const int after = extra_rings_after_ring_step(extra, ring, max_ring, Neighbourhood::Fine, y_margin);
        CHECK(after >= 0);
        CHECK(after <= extra);
        const auto space = [&](int r, int e) {
          return full_indices(full, reduced_product_space(fine, fine, coarse, coarse, id, r, Neighbourhood::Fine,
                                                          std::vector<int>(fine.mesh.num_faces(), e), y_margin));
        };
        const auto before = space(ring - 1, extra), now = space(ring, after);
        CHECK(std::includes(now.begin(), now.end(), before.begin(), before.end()));
      }
  // On the coarse neighbourhood the ring is a coarse one: the extra rings past max_ring all kept.
  CHECK(extra_rings_after_ring_step(5, 2, max_ring, Neighbourhood::Coarse) == 5);
  CHECK(extra_rings_after_ring_step(2, 2, max_ring, Neighbourhood::Coarse) == 2);
  CHECK(extra_rings_after_ring_step(1, 2, max_ring, Neighbourhood::Coarse) == 1);
}

TEST_CASE("coarse to fine: a shape against itself is matched to the identity at every level") {
  const Mesh m = lumpy_sphere(2, 5);
  CoarseToFineOptions o;
  o.hierarchy.levels = 3;
  o.hierarchy.coarsest_faces = 20;
  o.ring = 0;
  o.rounding.solver = "clp-dual";
  const CoarseToFineMatcher matcher(m, m, o);
  REQUIRE(matcher.x_levels().size() == 3);
  const CoarseToFineResult r = matcher.run();
  REQUIRE(r.levels.size() == 3);
  for (const auto& l : r.levels) {
    CAPTURE(l.level);
    CHECK(l.energy == doctest::Approx(0.0).epsilon(1e-9));
    CHECK(l.variables <= l.full_variables);
  }
  CHECK(r.levels[2].variables < r.levels[2].full_variables / 4);
  const VertexMaps maps = vertex_maps(r.finest.space, r.rounding.gamma);
  for (int v = 0; v < m.num_vertices(); ++v) CHECK(maps.x_to_y[v] == v);
  CHECK(check_graph_surface(r.finest.space, r.rounding.gamma).ok());
}

TEST_CASE("coarse to fine: every level's first LP can be written out and solved again on its own") {
  const Mesh m = lumpy_sphere(2, 5);
  CoarseToFineOptions o;
  o.hierarchy.levels = 2;
  o.hierarchy.coarsest_faces = 20;
  o.ring = 0;
  o.second_start = false;
  o.rounding.solver = "clp-dual";
  o.rounding.alternative_thresholds = {};
  o.price_widenings = 0;
  const test::TempDir dir;
  o.dump_first_lps = dir.path.string();
  const CoarseToFineResult r = CoarseToFineMatcher(m, m, o).run();
  REQUIRE(r.levels.size() == 2);
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(dir.path)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  REQUIRE(names.size() == 2);  // one first LP per level: nothing widened
  CHECK(names[0] == "level1-000.smlp");
  CHECK(names[1] == "level2-001.smlp");
  for (int l = 0; l < 2; ++l) {
    CAPTURE(l);
    const LpProblem lp = read_lp((dir.path / names[l]).string());
    CHECK(lp.cols() > 0);
    CHECK(lp.cols() <= r.levels[l].variables);  // what propagation left free
    const LpResult again = solve_lp(lp, "clp-dual");
    REQUIRE(again.status == LpStatus::Optimal);
    CHECK(again.objective == doctest::Approx(0.0).epsilon(1e-9));  // a shape against itself
  }
}

TEST_CASE("coarse to fine: the later rounds' parts Clp was slow on can be written out and solved again") {
  // slow_part_seconds 0: every part Clp solves in a later round counts as slow. Each file is
  // named after its level and solves again to an optimum or a proof, as in the run.
  const Mesh x = shapes::bent_finger(10, 8, 8), y = shapes::bent_finger(60, 8, 8);
  CoarseToFineOptions o;
  o.hierarchy.levels = 2;
  o.hierarchy.coarsest_faces = 16;
  o.rounding.solver = "pdhg-cpu";
  o.rounding.slow_part_seconds = 0.0;
  const test::TempDir dir;
  o.dump_slow_parts = dir.path.string();
  const CoarseToFineResult r = CoarseToFineMatcher(decimate(x, 50), decimate(y, 60), o).run();
  REQUIRE(r.levels.size() == 2);
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(dir.path)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  REQUIRE(!names.empty());
  for (size_t k = 0; k < names.size(); ++k) {
    CAPTURE(names[k]);
    CHECK((names[k].rfind("level1-slow-", 0) == 0 || names[k].rfind("level2-slow-", 0) == 0));
    const LpProblem lp = read_lp((dir.path / names[k]).string());
    CHECK(lp.cols() > 0);
    const LpResult again = solve_lp(lp, "clp-dual");
    CHECK((again.status == LpStatus::Optimal || again.status == LpStatus::Infeasible));
  }
  // Numbered over the run: no two files share a number.
  std::set<std::string> numbers;
  for (const std::string& n : names) numbers.insert(n.substr(n.size() - 9));
  CHECK(numbers.size() == names.size());
}

TEST_CASE("coarse to fine: a deformed pair with different triangulations ends verified") {
  const Mesh x = shapes::bent_finger(10, 8, 8), y = shapes::bent_finger(60, 8, 8);
  CoarseToFineOptions o;
  o.hierarchy.levels = 2;
  o.hierarchy.coarsest_faces = 16;
  o.matching.energy.membrane = MembraneModel::Compressive;
  o.rounding.solver = "pdhg-cpu";
  int flips_untangled = 0, flips_first = 0;
  for (const Neighbourhood n : {Neighbourhood::Coarse, Neighbourhood::Fine}) {
    CAPTURE(static_cast<int>(n));
    o.neighbourhood = n;
    const CoarseToFineMatcher matcher(decimate(x, 50), decimate(y, 60), o);
    const CoarseToFineResult r = matcher.run();
    REQUIRE(r.levels.size() == 2);
    const GraphSurfaceCheck c = check_graph_surface(r.finest.space, r.rounding.gamma);
    CHECK(c.covers_x);
    CHECK(c.covers_y);
    CHECK(c.orientation);
    CHECK(c.continuous);
    CHECK(satisfies_exactly(r.finest.lp, r.rounding.gamma));
    // Within each fibre, the vertex maps pick partners that invert fewer faces than the first
    // partner found (measured: 1 inverted face left of 5 in the first pass, summed over both
    // directions and both neighbourhoods).
    const Mesh &fx = r.finest.space.x(), &fy = r.finest.space.y();
    const VertexMaps maps = vertex_maps(r.finest.space, r.rounding.gamma);
    const VertexMaps plain = vertex_maps(r.finest.space, r.rounding.gamma, false);
    const int untangled_x = count_orientation_flips(fx, fy, maps.x_to_y).flips;
    const int untangled_y = count_orientation_flips(fy, fx, maps.y_to_x).flips;
    const int first_x = count_orientation_flips(fx, fy, plain.x_to_y).flips;
    const int first_y = count_orientation_flips(fy, fx, plain.y_to_x).flips;
    const int untangled = untangled_x + untangled_y, first = first_x + first_y;
    MESSAGE("inverted faces: ", untangled, " untangled, ", first, " first partners");
    CHECK(untangled_x <= first_x);  // never worse, in either direction
    CHECK(untangled_y <= first_y);
    // Points never invert more than the vertex maps they start from.
    const PointMaps points = point_maps(r.finest.space, r.rounding.gamma, maps);
    CHECK(count_orientation_flips(fx, fy, points.x_to_y).flips <= untangled_x);
    CHECK(count_orientation_flips(fy, fx, points.y_to_x).flips <= untangled_y);
    flips_untangled += untangled;
    flips_first += first;
    for (const auto& l : r.levels) {
      CHECK(l.lower_bound <= l.energy + 1e-9);
      CHECK(l.rounds >= 1);
    }
  }
  CHECK(flips_untangled < flips_first);
}

TEST_CASE("coarse to fine: shapes of different sizes share the level count and end at their inputs") {
  const Mesh small = lumpy_sphere(0, 7), large = lumpy_sphere(1, 8);  // 20 and 80 faces
  CoarseToFineOptions o;
  o.hierarchy.coarsest_faces = 20;
  o.rounding.solver = "pdhg-cpu";
  // Measured: eq. (17)'s neighbourhood keeps this pair continuous; the fine one tears one vertex
  // (a reduced space can force a tear; match reports it).
  o.neighbourhood = Neighbourhood::Coarse;
  o.matching.energy.bending_weight = 1.0;  // the weight it was measured with (at 0.1 one vertex tears)
  for (const bool swap : {false, true}) {
    CAPTURE(swap);
    const CoarseToFineMatcher matcher(swap ? large : small, swap ? small : large, o);
    REQUIRE(matcher.x_levels().size() == 2);
    REQUIRE(matcher.y_levels().size() == 2);
    CHECK(matcher.x_levels().levels.back().mesh.num_faces() == (swap ? 80 : 20));
    CHECK(matcher.y_levels().levels.back().mesh.num_faces() == (swap ? 20 : 80));
    const CoarseToFineResult r = matcher.run();
    CHECK(&r.finest.space.x() == &matcher.x_levels().levels.back().mesh);
    CHECK(&r.finest.space.y() == &matcher.y_levels().levels.back().mesh);
    const GraphSurfaceCheck c = check_graph_surface(r.finest.space, r.rounding.gamma);
    CHECK(c.covers_x);
    CHECK(c.covers_y);
    CHECK(c.orientation);
    CHECK(c.continuous);
  }
}

TEST_CASE("coarse to fine: features must have one row per input vertex") {
  const Mesh m = lumpy_sphere(1, 6);
  CoarseToFineMatcher matcher(m, m, {});
  CHECK_THROWS_AS(matcher.set_features(Eigen::MatrixXd::Zero(3, 2), Eigen::MatrixXd::Zero(3, 2)), InvalidInputError);
  CHECK_NOTHROW(matcher.set_features(Eigen::MatrixXd::Zero(m.num_vertices(), 2), Eigen::MatrixXd::Zero(m.num_vertices(), 2)));
}

TEST_CASE("coarse to fine: extra rings grow only the chosen faces' candidates, a margin on Y every face's") {
  const Mesh m = lumpy_sphere(2, 11);  // 320 faces
  const MeshHierarchy h = build_hierarchy(m, {80, 320});
  const MeshLevel& fine = h.levels[1];
  const Mesh& coarse = h.levels[0].mesh;
  const ProductSpace full = ProductSpace::full(fine.mesh, fine.mesh);
  const auto id = identity_matching(coarse);
  const auto plain = full_indices(full, reduced_product_space(fine, fine, coarse, coarse, id, 1, Neighbourhood::Fine));
  const int chosen = 17;
  std::vector<int> extra(fine.mesh.num_faces(), 0);
  extra[chosen] = 1;
  const auto list = reduced_product_space(fine, fine, coarse, coarse, id, 1, Neighbourhood::Fine, extra);
  const auto grown = full_indices(full, list);
  CHECK(grown.size() == list.size());
  CHECK(std::includes(grown.begin(), grown.end(), plain.begin(), plain.end()));
  CHECK(grown.size() > plain.size());
  // Every new product triangle has the chosen face, one of its edges or one of its vertices on X.
  const auto& f = fine.mesh.faces[chosen];
  auto on_chosen = [&](int v) { return v == f[0] || v == f[1] || v == f[2]; };
  for (const auto& t : list) {
    if (plain.count(full.index_in_full(t))) continue;
    CHECK((t.fa == chosen || (t.fa < 0 && on_chosen(t.a[0]) && on_chosen(t.a[1]) && on_chosen(t.a[2]))));
  }
  // A list of the wrong size is an error, not a silent partial widening.
  CHECK_THROWS_AS(reduced_product_space(fine, fine, coarse, coarse, id, 1, Neighbourhood::Fine, {1, 2}),
                  InvalidInputError);

  // A margin on Y is one more fine ring for every face, at every ring.
  const std::vector<int> everywhere(fine.mesh.num_faces(), 1);
  // Ring 1 with a margin of 1 = ring 1 with every face widened locally by one ring.
  const auto margin = full_indices(full, reduced_product_space(fine, fine, coarse, coarse, id, 1, Neighbourhood::Fine, {}, 1));
  const auto widened = full_indices(full, reduced_product_space(fine, fine, coarse, coarse, id, 1, Neighbourhood::Fine, everywhere));
  CHECK(margin == widened);
  CHECK(margin.size() > plain.size());
  // At ring 2 it adds to the ring's own fine rings on Y as well.
  const auto ring2 = full_indices(full, reduced_product_space(fine, fine, coarse, coarse, id, 2, Neighbourhood::Fine));
  const auto ring2m = full_indices(full, reduced_product_space(fine, fine, coarse, coarse, id, 2, Neighbourhood::Fine, {}, 1));
  CHECK(std::includes(ring2m.begin(), ring2m.end(), ring2.begin(), ring2.end()));
  CHECK(ring2m.size() > ring2.size());
}

TEST_CASE("coarse to fine: a coarse face no fine face took as parent still has a candidate") {
  const Mesh m = lumpy_sphere(2, 12);
  const MeshHierarchy h = build_hierarchy(m, {80, 320});
  MeshLevel fine_y = h.levels[1];
  const Mesh& coarse = h.levels[0].mesh;
  // Hand coarse face 0's children to another parent: face 0 is now childless on Y.
  const int other = coarse.num_faces() - 1;
  int moved = 0;
  for (int& p : fine_y.parent_face)
    if (p == 0) p = other, ++moved;
  REQUIRE(moved > 0);
  const auto list = reduced_product_space(h.levels[1], fine_y, coarse, coarse, identity_matching(coarse), 0,
                                          Neighbourhood::Fine);
  std::vector<int> candidates(h.levels[1].mesh.num_faces(), 0);
  for (const auto& t : list)
    if (t.fa >= 0) ++candidates[t.fa];
  for (int f = 0; f < h.levels[1].mesh.num_faces(); ++f) {
    CAPTURE(f);
    CHECK(candidates[f] > 0);  // before: the children of coarse face 0 had none
  }
}

TEST_CASE("coarse to fine: an infeasible reduced LP is widened near the proof, not everywhere") {
  // Measured: at ring 0 this pair's finest reduced LP is infeasible; propagation names the
  // places, and widening 17 of 80 faces makes it feasible (the global ring 1 keeps 1.8x as many
  // variables).
  CoarseToFineOptions o = two_levels(16);
  o.ring = 0;
  o.max_ring = 2;
  o.widen_margin = 0;
  o.price_widenings = 0;  // (they are local widenings too)
  int64_t variables[2] = {0, 0};
  for (const bool local : {true, false}) {
    CAPTURE(local);
    o.local_widening = local;
    const CoarseToFineMatcher matcher = finger_matcher(o);  // the result refers to its meshes
    const CoarseToFineResult r = matcher.run();
    const LevelReport& l = r.levels.back();
    CHECK(check_graph_surface(r.finest.space, r.rounding.gamma).ok());
    CHECK(satisfies_exactly(r.finest.lp, r.rounding.gamma));
    if (local) {
      CHECK(l.local_widenings >= 1);
      CHECK(l.propagation_widenings == l.local_widenings);  // all found by propagation
      CHECK(l.recurring_widenings == 0);                    // none came back
      CHECK(l.widenings == 0);
      CHECK(l.widened_faces > 0);
      CHECK(l.widened_faces < l.faces_x);
    } else {
      CHECK(l.local_widenings == 0);
      CHECK(l.widenings == 1);
    }
    variables[local ? 0 : 1] = l.variables;
  }
  CHECK(variables[0] < variables[1]);
  {
    // Where none comes back, widening wider where one does changes nothing: the same space
    // without it.
    o.local_widening = true;
    o.recurring_margin = 0;
    const CoarseToFineMatcher off = finger_matcher(o);
    CHECK(off.run().levels.back().variables == variables[0]);
    o.recurring_margin = CoarseToFineOptions{}.recurring_margin;
  }
  // Propagation's widenings have a budget of their own: the same without any of the other kind.
  o.local_widening = true;
  o.max_local_widenings = 0;
  const CoarseToFineMatcher matcher = finger_matcher(o);
  const CoarseToFineResult r = matcher.run();
  CHECK(r.levels.back().widenings == 0);
  CHECK(r.levels.back().variables == variables[0]);
  // And with that budget at 0 as well, the ring widens everywhere as without local widening.
  o.max_propagation_widenings = 0;
  const CoarseToFineMatcher global = finger_matcher(o);
  CHECK(global.run().levels.back().widenings == 1);
}

TEST_CASE("coarse to fine: faces whose parent was widened start widened where asked") {
  // Four levels at ring 0, where the third level's reduced LP is infeasible (as above) and
  // widens locally.
  CoarseToFineOptions o = two_levels(16);
  o.hierarchy.levels = 4;
  o.ring = 0;
  o.max_ring = 2;
  o.price_widenings = 0;
  o.second_start = false;
  o.rounding.alternative_thresholds = {};  // the coarsest Γ these widenings were measured on
  o.coarse_ring_faces = 0;                 // ring 0 at every level, as measured
  int widenings[2][4] = {};
  for (const int inherit : {0, 1}) {
    CAPTURE(inherit);
    o.inherit_widening = inherit;
    const CoarseToFineMatcher matcher = finger_matcher(o);
    const CoarseToFineResult r = matcher.run();
    for (int l = 0; l < 4 && l < int(r.levels.size()); ++l) widenings[inherit][l] = r.levels[l].local_widenings;
    REQUIRE(r.levels.size() == 4);
    CHECK(check_graph_surface(r.finest.space, r.rounding.gamma).ok());
    CHECK(satisfies_exactly(r.finest.lp, r.rounding.gamma));
    CHECK(r.levels[0].inherited_faces == 0);  // the full space
    CHECK(r.levels[1].inherited_faces == 0);  // its parent level was the full space
    REQUIRE(r.levels[1].local_widenings > 0);
    if (inherit == 0) {
      CHECK(r.levels[2].inherited_faces == 0);
    } else {
      // At least the children of the faces widened at level 2, at most every face.
      CHECK(r.levels[2].inherited_faces > 0);
      CHECK(r.levels[2].inherited_faces < r.levels[2].faces_x);
    }
  }
  // Measured: level 2 widens the same either way (10 faces); levels 3 and 4 then start where they
  // needed 1 and 2 widenings without (12, then 28 and 13 faces) and need none.
  CHECK(widenings[1][1] == widenings[0][1]);
  CHECK(widenings[0][2] + widenings[0][3] > 0);
  CHECK(widenings[1][2] + widenings[1][3] < widenings[0][2] + widenings[0][3]);
}

TEST_CASE("coarse to fine: an iterate carried to a wider space keeps its values by identity and starts near the optimum") {
  // The finger pair's two levels; the fine LP over ring 1 solved, its iterate carried to the LP
  // of a space widened on some faces.
  const FingerLevels f(40, 320);
  const Mesh& x = f.x();
  const Mesh& y = f.y();
  auto lp_at = [&](const std::vector<int>& extra) { return f.lp_at(extra); };
  // As a local widening does: one more ring on a few faces (every tenth).
  std::vector<int> extra(x.num_faces(), 0);
  for (int f = 0; f < x.num_faces(); f += 10) extra[f] = 1;
  const MatchingLp narrow = lp_at({}), wide = lp_at(extra);
  REQUIRE(narrow.lp.cols() < wide.lp.cols());
  SolverParams params;
  params.tolerance = 1e-4;
  const LpResult a = solve_lp(narrow.lp, "pdhg-cpu", params);
  REQUIRE(a.status == LpStatus::Optimal);
  CarriedIterate carried;
  CHECK(carried.empty());
  carried.keep(narrow, a.x, a.y);
  CHECK(!carried.empty());
  SolverParams warm = params;
  carried.apply(wide, warm);
  REQUIRE(warm.initial_x.size() == size_t(wide.lp.cols()));
  REQUIRE(warm.initial_y.size() == size_t(wide.lp.rows()));
  // Every variable by identity: the narrow space's values where it has them, 0 elsewhere.
  std::map<std::array<int, 6>, double> value;
  for (int64_t j = 0; j < narrow.lp.cols(); ++j) {
    const ProductTriangle t = narrow.space[j];
    value[{t.a[0], t.a[1], t.a[2], t.b[0], t.b[1], t.b[2]}] = a.x[j];
  }
  int64_t found = 0;
  for (int64_t j = 0; j < wide.lp.cols(); ++j) {
    const ProductTriangle t = wide.space[j];
    const auto it = value.find({t.a[0], t.a[1], t.a[2], t.b[0], t.b[1], t.b[2]});
    const double expected = it == value.end() || it->second <= 1e-9 ? 0.0 : it->second;
    found += it != value.end();
    CHECK(warm.initial_x[j] == expected);
  }
  CHECK(found == narrow.lp.cols());
  // A face's row keeps its dual, in the wide LP's cost scale.
  const double ratio = narrow.lp.objective_scale / wide.lp.objective_scale;
  for (int64_t f = 0; f < x.num_faces() + y.num_faces(); ++f)
    CHECK(warm.initial_y[wide.closedness_rows + f] == doctest::Approx(ratio * a.y[narrow.closedness_rows + f]));
  // From there the wide LP converges in fewer iterations than from zero, to the same optimum.
  const LpResult cold = solve_lp(wide.lp, "pdhg-cpu", params);
  const LpResult hot = solve_lp(wide.lp, "pdhg-cpu", warm);
  REQUIRE(cold.status == LpStatus::Optimal);
  REQUIRE(hot.status == LpStatus::Optimal);
  MESSAGE("wide LP ", wide.lp.cols(), " variables: ", cold.iterations, " iterations cold, ", hot.iterations, " warm");
  CHECK(hot.iterations < cold.iterations);
  CHECK(hot.objective == doctest::Approx(cold.objective).epsilon(1e-2));

  // The new rows' duals by coordinate ascent: the rows that had none, only those, and a
  // Lagrangian bound that only rises with the sweeps and stays below the wide LP's optimum.
  // (The optimum from PDHG to 1e-4: Clp takes minutes on this LP.)
  const double optimum = cold.objective * (1.0 + 1e-3);
  double bound = certified_lower_bound(wide.lp, warm.initial_y);
  CHECK(bound < optimum);
  for (const int sweeps : {1, 2, 4}) {
    CAPTURE(sweeps);
    SolverParams ascended = params;
    carried.apply(wide, ascended);
    const int64_t fresh = carried.ascend_new_rows(wide, ascended.initial_y, sweeps);
    CHECK(fresh > 0);
    CHECK(fresh == wide.closedness_rows - narrow.closedness_rows);  // ring 1 ⊂ the widened space
    CHECK(ascended.initial_x == warm.initial_x);
    int64_t changed = 0;
    for (int64_t i = 0; i < wide.lp.rows(); ++i) changed += ascended.initial_y[i] != warm.initial_y[i];
    CHECK(changed > 0);
    CHECK(changed <= fresh);
    const double b = certified_lower_bound(wide.lp, ascended.initial_y);
    MESSAGE("new rows ", fresh, ", ", sweeps, " sweeps: bound ", b, " (at 0: ",
            certified_lower_bound(wide.lp, warm.initial_y), ", optimum ", cold.objective, ")");
    CHECK(b >= bound - 1e-9);
    CHECK(b <= optimum);
    bound = b;
    if (sweeps == 4) {
      const LpResult ascended_hot = solve_lp(wide.lp, "pdhg-cpu", ascended);
      REQUIRE(ascended_hot.status == LpStatus::Optimal);
      MESSAGE("warm with ascended duals: ", ascended_hot.iterations, " iterations");
      CHECK(ascended_hot.objective == doctest::Approx(cold.objective).epsilon(1e-2));
    }
  }
}

TEST_CASE("coarse to fine: the tolerance below the finest level is its own, looser or tighter") {
  // The coarsest level's first LP (round 1): what its tolerance decides (the level's later rounds
  // depend on where that LP stopped, in either direction).
  auto first_lp_iterations = [](const CoarseToFineMatcher& matcher, CoarseToFineResult& result) {
    int64_t iterations = -1;
    result = matcher.run([&](const LevelReport& level, const RoundingRound& round) {
      if (level.level == 0 && round.round == 1) iterations = round.iterations;
    });
    return iterations;
  };
  CoarseToFineOptions o = two_levels(40);
  o.coarse_tolerance = 0.0;
  const CoarseToFineMatcher tight = finger_matcher(o);  // the results refer to their meshes
  o.coarse_tolerance = 1e-2;
  const CoarseToFineMatcher loose = finger_matcher(o);
  CoarseToFineResult a, b;
  const int64_t ia = first_lp_iterations(tight, a), ib = first_lp_iterations(loose, b);
  MESSAGE("coarsest level's first LP: ", ia, " iterations at 1e-4, ", ib, " at 1e-2");
  CHECK(ib < ia);
  CHECK(check_graph_surface(b.finest.space, b.rounding.gamma).ok());
  CHECK(b.levels[1].lower_bound <= b.levels[1].energy + 1e-9);
  // Also tighter than a loose finest level (at full resolution 3e-3 below it made rounding thrash).
  o.rounding.lp.tolerance = 1e-2;
  o.coarse_tolerance = 0.0;  // 1e-2 everywhere
  const CoarseToFineMatcher all_loose = finger_matcher(o);
  o.coarse_tolerance = 1e-4;
  const CoarseToFineMatcher tight_below = finger_matcher(o);
  CoarseToFineResult c, d;
  const int64_t ic = first_lp_iterations(all_loose, c), id = first_lp_iterations(tight_below, d);
  CHECK(id > ic);
  CHECK(id == ia);  // 1e-4 below the finest, as in `tight`
  CHECK(d.levels[0].iterations == a.levels[0].iterations);
}

TEST_CASE("coarse to fine: the small levels below the finest start at their own ring, the finest at --ring") {
  CoarseToFineOptions o;
  o.hierarchy.levels = 3;
  o.hierarchy.coarsest_faces = 16;
  o.rounding.solver = "pdhg-cpu";
  o.coarse_ring_faces = 1000000;  // every level below the finest, whatever its size
  CoarseToFineResult r[2];
  std::vector<std::unique_ptr<CoarseToFineMatcher>> keep;  // the results refer to their meshes
  for (int k : {1, 2}) {
    o.coarse_ring = k;
    keep.push_back(std::make_unique<CoarseToFineMatcher>(finger_matcher(o)));
    r[k - 1] = keep.back()->run();
    REQUIRE(r[k - 1].levels.size() == 3);
    CHECK(r[k - 1].levels[1].ring >= k);
    CHECK(check_graph_surface(r[k - 1].finest.space, r[k - 1].rounding.gamma).ok());
  }
  // Both refine the same coarsest Γ (the full space's): the middle level's space at ring 2 holds
  // the one at ring 1, so its LP is no higher (bounds within the coarse tolerance of the optimum).
  CHECK(r[0].levels[0].energy == doctest::Approx(r[1].levels[0].energy).epsilon(1e-12));
  CHECK(r[1].levels[1].variables > r[0].levels[1].variables);
  CHECK(r[1].levels[1].lower_bound <= r[0].levels[1].lower_bound + 1e-2 * std::abs(r[0].levels[1].lower_bound));
  CHECK(r[1].levels[1].lower_bound <= r[0].levels[1].energy + 1e-9);
  // The finest level starts at --ring either way.
  CHECK(r[0].levels[2].ring == o.ring);
  CHECK(r[1].levels[2].ring == o.ring);
  // Above the size limit a level keeps --ring.
  o.coarse_ring_faces = 10;
  const CoarseToFineMatcher none = finger_matcher(o);
  CHECK(none.run().levels[1].ring == o.ring);
  // A coarse ring beyond max_ring is refused.
  o.coarse_ring_faces = 1000;
  o.coarse_ring = o.max_ring + 1;
  CHECK_THROWS_AS(finger_matcher(o), InvalidInputError);
}

TEST_CASE("coarse to fine: the second start solves the second level twice and keeps the lower energy") {
  CoarseToFineOptions o;
  o.hierarchy.coarsest_faces = 12;
  o.hierarchy.second_faces = 24;
  o.rounding.solver = "pdhg-cpu";
  o.second_start = false;
  const CoarseToFineMatcher plain_matcher = finger_matcher(o);  // the results refer to their meshes
  REQUIRE(plain_matcher.x_levels().size() == 3);
  const CoarseToFineResult plain = plain_matcher.run();
  CHECK(std::isnan(plain.levels[1].second_start_energy));
  o.second_start = true;
  const CoarseToFineMatcher matcher = finger_matcher(o);
  const CoarseToFineResult r = matcher.run();
  const LevelReport& l = r.levels[1];
  REQUIRE(std::isfinite(l.second_start_energy));
  MESSAGE("level 2: refined ", plain.levels[1].energy, ", second start ", l.second_start_energy);
  // The same refined solve as without the second start, then the lower of the two goes on.
  CHECK(l.energy == doctest::Approx(std::min(plain.levels[1].energy, l.second_start_energy)).epsilon(1e-12));
  CHECK(l.second_start_kept == (l.second_start_energy < plain.levels[1].energy));
  if (l.second_start_kept) CHECK(l.ring == -1);
  CHECK(std::isnan(r.levels[0].second_start_energy));
  CHECK(std::isnan(r.levels[2].second_start_energy));
  CHECK(check_graph_surface(r.finest.space, r.rounding.gamma).ok());
  CHECK(satisfies_exactly(r.finest.lp, r.rounding.gamma));
}

TEST_CASE("coarse to fine: lookahead refines both Γ of the second level and keeps the lower energy further up") {
  // Two dolphins, whose chains still differ at the second level (on the finger pair both found
  // the same Γ there and went on as one).
  const Mesh dx = lookahead_dolphin_x(), dy = lookahead_dolphin_y();
  auto dolphin_matcher = [&](const CoarseToFineOptions& options) { return CoarseToFineMatcher(dx, dy, options); };
  CoarseToFineOptions o = small_levels();
  o.lookahead_levels = 0;
  const CoarseToFineMatcher plain_matcher = dolphin_matcher(o);  // decided at the second level
  REQUIRE(plain_matcher.x_levels().size() == 5);
  const CoarseToFineResult plain = plain_matcher.run();
  o.second_start = false;
  const CoarseToFineMatcher refined_matcher = dolphin_matcher(o);  // the refined chain alone
  const CoarseToFineResult refined = refined_matcher.run();
  o.second_start = true;
  o.lookahead_levels = 2;
  o.lookahead_bound_drop = false;  // (level 4's second chain, bound above the first's energy, rounds too)
  const CoarseToFineMatcher matcher = dolphin_matcher(o);
  const CoarseToFineResult r = matcher.run();
  REQUIRE(r.levels.size() == 5);
  CHECK(check_graph_surface(r.finest.space, r.rounding.gamma).ok());
  CHECK(satisfies_exactly(r.finest.lp, r.rounding.gamma));
  // Compared at level 4 (two levels past the second, below the finest), and only there.
  for (int l : {0, 1, 2, 4}) CHECK(std::isnan(r.levels[l].lookahead_other_energy));
  const LevelReport& d = r.levels[3];
  REQUIRE(std::isfinite(d.lookahead_other_energy));
  CHECK(d.energy <= d.lookahead_other_energy);
  MESSAGE("level 2: second start ", plain.levels[1].second_start_energy, ", refined ", refined.levels[1].energy,
          "; level 4: kept ", d.energy, ", other ", d.lookahead_other_energy, ", switched ", d.lookahead_switched);
  // Levels 1-2 solve the same LPs as without lookahead; the chain leading at level 2 is the one
  // the plain run kept, and the other one, where it is the refined chain, the run without second start.
  CHECK(r.levels[0].energy == plain.levels[0].energy);
  CHECK(r.levels[1].second_start_energy == plain.levels[1].second_start_energy);
  const double lead = d.lookahead_switched ? d.lookahead_other_energy : d.energy;
  const double other = d.lookahead_switched ? d.energy : d.lookahead_other_energy;
  CHECK(lead == doctest::Approx(plain.levels[3].energy).epsilon(1e-12));
  if (plain.levels[1].second_start_kept) CHECK(other == doctest::Approx(refined.levels[3].energy).epsilon(1e-12));
  // The reports below the decision are the kept chain's: it started at the full space iff
  // second_start_kept, and if it is the leading chain, they are the plain run's.
  CHECK(r.levels[1].second_start_kept == (plain.levels[1].second_start_kept != d.lookahead_switched));
  if (!d.lookahead_switched)
    for (int l : {1, 2}) CHECK(r.levels[l].energy == doctest::Approx(plain.levels[l].energy).epsilon(1e-12));
}

TEST_CASE("coarse to fine: at the deciding level a second chain whose first LP cannot win drops out after it") {
  // The dolphins of the lookahead test: at level 4, where lookahead decides, the first chain's
  // energy is below the second chain's first LP bound. A checkpoint after every round.
  const Mesh dx = lookahead_dolphin_x(), dy = lookahead_dolphin_y();
  CoarseToFineOptions o = both_chains_to_level_4();
  o.rounding.alternative_thresholds = {};  // (with them a level's rounding is not saved)
  o.rounding_checkpoint_seconds = 0.0;
  const CoarseToFineMatcher both(dx, dy, o);
  std::vector<LevelCheckpoint> inside;  // inside the second chain's rounding of level 4
  const CoarseToFineResult whole = both.run({}, nullptr, [&](const LevelCheckpoint& c) {
    if (c.done() == 3 && c.first_chain_ahead() && !c.in_progress().rounding.empty()) inside.push_back(c);
  });
  const LevelReport& d = whole.levels[3];
  REQUIRE(std::isfinite(d.lookahead_other_energy));
  REQUIRE_FALSE(d.lookahead_switched);
  REQUIRE_FALSE(inside.empty());

  o.lookahead_bound_drop = true;
  const CoarseToFineMatcher dropping(dx, dy, o);
  std::optional<LevelCheckpoint> after;  // after level 4
  const CoarseToFineResult r = dropping.run({}, nullptr, [&](const LevelCheckpoint& c) {
    if (c.done() == 4 && c.in_progress().empty()) after = c;
  });
  REQUIRE(r.levels.size() == whole.levels.size());
  const LevelReport& k = r.levels[3];
  REQUIRE(std::isfinite(k.lookahead_other_bound));
  CHECK(std::isnan(k.lookahead_other_energy));
  CHECK(k.lookahead_other_bound >= k.energy);
  // The bound held: rounded on, that chain's Γ was no lower, and the same chain went on.
  CHECK(d.lookahead_other_energy >= k.lookahead_other_bound * (1 - 1e-9));
  MESSAGE("level 4: first chain ", k.energy, ", second chain's bound ", k.lookahead_other_bound, ", its energy ",
          d.lookahead_other_energy);
  for (size_t l = 0; l < r.levels.size(); ++l) {
    CHECK(r.levels[l].gamma == whole.levels[l].gamma);
    CHECK(r.levels[l].energy == doctest::Approx(whole.levels[l].energy).epsilon(1e-12));
    if (l != 3) CHECK(std::isnan(r.levels[l].lookahead_other_bound));
  }
  CHECK(r.rounding.energy == doctest::Approx(whole.rounding.energy).epsilon(1e-12));

  // Gone on from inside that chain's rounding: it drops out at once, on the saved bound.
  const LevelCheckpoint& c = inside.back();
  const double saved = c.chains[1].attempt.rounding.lower_bound;
  const CoarseToFineResult g = dropping.run({}, &c);
  CHECK(g.levels[3].lookahead_other_bound == saved);
  CHECK(g.levels[3].gamma == whole.levels[3].gamma);
  CHECK(g.rounding.energy == doctest::Approx(whole.rounding.energy).epsilon(1e-12));

  // With less lookahead, decided at level 3, where the second chain's Γ is the lower: its LP's
  // bound is below the first chain's energy, and it rounds and wins.
  o.lookahead_levels = 1;
  const CoarseToFineMatcher shorter(dx, dy, o);
  const CoarseToFineResult e = shorter.run();
  CHECK(std::isfinite(e.levels[2].lookahead_other_energy));
  CHECK(std::isnan(e.levels[2].lookahead_other_bound));
  CHECK(e.levels[2].lookahead_switched);
  CHECK(e.levels[2].energy < e.levels[2].lookahead_other_energy);

  // Kept by a checkpoint (version 7), not by a version-6 one.
  REQUIRE(after);
  REQUIRE(after->levels.size() == 4);
  test::TempDir tmp;
  const std::string file = (tmp.path / "bound.ckpt").string();
  save_checkpoint(file, *after);
  CHECK(load_checkpoint(file).levels[3].lookahead_other_bound == k.lookahead_other_bound);
  detail::save_checkpoint_as(file, *after, 6);
  CHECK(std::isnan(load_checkpoint(file).levels[3].lookahead_other_bound));
}

TEST_CASE("coarse to fine: two lookahead chains that reach the same Γ go on as one, with the same result") {
  // A shape against itself: the second start and the refined chain both find the identity at the
  // second level, so lookahead has nothing to compare there or above.
  CoarseToFineOptions o = small_levels();
  const Mesh finger = decimate(shapes::bent_finger(30, 8, 8), 80);
  o.lookahead_levels = 0;
  const CoarseToFineMatcher plain_matcher(finger, finger, o);
  const CoarseToFineResult plain = plain_matcher.run();
  o.lookahead_levels = 2;
  const CoarseToFineMatcher matcher(finger, finger, o);
  const CoarseToFineResult r = matcher.run();
  REQUIRE(r.levels.size() == plain.levels.size());
  REQUIRE(r.levels.size() >= 4);
  // Merged where they met: at the second level, the other chain's energy recorded there only.
  CHECK(r.levels[1].lookahead_other_energy == doctest::Approx(r.levels[1].energy).epsilon(1e-12));
  for (size_t l = 0; l < r.levels.size(); ++l) {
    if (l != 1) CHECK(std::isnan(r.levels[l].lookahead_other_energy));
    CHECK(!r.levels[l].lookahead_switched);
    CHECK(r.levels[l].energy == doctest::Approx(plain.levels[l].energy).epsilon(1e-12));
    CHECK(r.levels[l].variables == plain.levels[l].variables);
  }
  CHECK(check_graph_surface(r.finest.space, r.rounding.gamma).ok());
}

TEST_CASE("coarse to fine: a run gone on from a checkpoint inside lookahead ends as the whole run") {
  // The dolphins of the lookahead test: both chains go on from level 2 to level 4's decision.
  const Mesh dx = lookahead_dolphin_x(), dy = lookahead_dolphin_y();
  CoarseToFineOptions o = both_chains_to_level_4();
  const CoarseToFineMatcher matcher(dx, dy, o);
  REQUIRE(matcher.x_levels().size() == 5);
  std::vector<LevelCheckpoint> saved;
  const CoarseToFineResult whole = matcher.run({}, nullptr, [&](const LevelCheckpoint& c) {
    if (c.in_progress().empty() && !c.first_chain_ahead()) saved.push_back(c);
  });
  // After levels 1 to 4: one chain, two (levels 2 and 3, before the decision at 4), then one.
  REQUIRE(saved.size() == 4);
  for (size_t k = 0; k < saved.size(); ++k) {
    CHECK(saved[k].done() == int(k + 1));
    CHECK(saved[k].chains.size() == (k == 1 || k == 2 ? 2u : 0u));
  }
  for (size_t k : {size_t(1), size_t(2)}) {
    CHECK(saved[k].levels.size() == 1);  // the levels before the split
    CHECK(saved[k].chains[0].leading);
    CHECK_FALSE(saved[k].chains[1].leading);
    for (const LevelCheckpoint::Chain& chain : saved[k].chains) CHECK(chain.pending.size() == k);
    // One of the two is the chain that went on.
    const bool first = saved[k].chains[0].pending.back().gamma == whole.levels[k].gamma;
    const bool second = saved[k].chains[1].pending.back().gamma == whole.levels[k].gamma;
    CHECK(first != second);
  }
  const LevelReport& d = whole.levels[3];
  REQUIRE(std::isfinite(d.lookahead_other_energy));

  test::TempDir tmp;
  const std::string file = (tmp.path / "lookahead.ckpt").string();
  for (size_t k : {size_t(1), size_t(2)}) {
    save_checkpoint(file, saved[k]);
    const LevelCheckpoint loaded = load_checkpoint(file);
    REQUIRE(loaded.chains.size() == 2);
    for (int i = 0; i < 2; ++i) {
      CHECK(loaded.chains[i].leading == saved[k].chains[i].leading);
      CHECK(loaded.chains[i].widened == saved[k].chains[i].widened);
      REQUIRE(loaded.chains[i].pending.size() == saved[k].chains[i].pending.size());
      CHECK(loaded.chains[i].pending.back().gamma == saved[k].chains[i].pending.back().gamma);
      CHECK(loaded.chains[i].pending.back().energy == saved[k].chains[i].pending.back().energy);
    }
    int called = 0;
    const CoarseToFineResult r =
        matcher.run({}, &loaded, [&](const LevelCheckpoint& c) { called += c.in_progress().empty() && !c.first_chain_ahead(); });
    CHECK(called == 3 - int(k));  // the levels after it but the finest
    REQUIRE(r.levels.size() == whole.levels.size());
    for (size_t l = 0; l < r.levels.size(); ++l) {
      CHECK(r.levels[l].energy == doctest::Approx(whole.levels[l].energy).epsilon(1e-12));
      CHECK(r.levels[l].gamma == whole.levels[l].gamma);
      CHECK(r.levels[l].second_start_kept == whole.levels[l].second_start_kept);
      CHECK(r.levels[l].lookahead_switched == whole.levels[l].lookahead_switched);
    }
    CHECK(r.levels[3].lookahead_other_energy == doctest::Approx(d.lookahead_other_energy).epsilon(1e-12));
    CHECK(r.rounding.energy == doctest::Approx(whole.rounding.energy).epsilon(1e-12));
    CHECK(check_graph_surface(r.finest.space, r.rounding.gamma).ok());
  }

  // With less lookahead, a checkpoint past the decision is decided at once: at level 3, by
  // energy there.
  o.lookahead_levels = 1;
  const CoarseToFineMatcher shorter(dx, dy, o);
  REQUIRE(shorter.fingerprint() == matcher.fingerprint());
  const CoarseToFineResult r = shorter.run({}, &saved[2]);
  REQUIRE(r.levels.size() == whole.levels.size());
  const auto& chains = saved[2].chains;
  const double e0 = chains[0].pending.back().energy, e1 = chains[1].pending.back().energy;
  CHECK(r.levels[2].energy == std::min(e0, e1));
  CHECK(r.levels[2].lookahead_other_energy == std::max(e0, e1));
  CHECK(r.levels[2].gamma == chains[e1 < e0 ? 1 : 0].pending.back().gamma);
  CHECK(std::isnan(r.levels[3].lookahead_other_energy));
  CHECK(check_graph_surface(r.finest.space, r.rounding.gamma).ok());

  // Chains of different lengths, beside an attempt, or a version-4 file (which drops them).
  LevelCheckpoint uneven = saved[2];
  uneven.chains[1].pending.pop_back();
  CHECK_THROWS_AS(matcher.run({}, &uneven), InvalidInputError);
  LevelCheckpoint beside = saved[2];
  beside.attempt.ring = 1;
  beside.attempt.extra.assign(matcher.x_levels().levels[3].mesh.num_faces(), 0);
  beside.attempt.report.level = 3;
  CHECK_THROWS_AS(matcher.run({}, &beside), InvalidInputError);
  detail::save_checkpoint_as(file, saved[2], 4);
  const LevelCheckpoint v4 = load_checkpoint(file);
  CHECK(v4.chains.empty());
  CHECK(v4.done() == 1);
}

TEST_CASE("coarse to fine: a run gone on from inside a level of lookahead goes on in the chain that was at it") {
  // The dolphins of the lookahead test, with a checkpoint after every round of every rounding.
  const Mesh dx = lookahead_dolphin_x(), dy = lookahead_dolphin_y();
  CoarseToFineOptions o = both_chains_to_level_4();
  o.rounding.alternative_thresholds = {};  // (with them a level's rounding is not saved)
  o.rounding_checkpoint_seconds = 0.0;
  const CoarseToFineMatcher matcher(dx, dy, o);
  std::vector<LevelCheckpoint> inside, ends;  // inside a level of lookahead; after level 3
  const CoarseToFineResult whole = matcher.run({}, nullptr, [&](const LevelCheckpoint& c) {
    if (!c.chains.empty() && (!c.in_progress().empty() || c.first_chain_ahead())) inside.push_back(c);
    if (!c.chains.empty() && c.in_progress().empty() && !c.first_chain_ahead()) ends.push_back(c);
  });
  // At levels 3 and 4 (below the decision at 4), each chain in turn: the first at the level, then
  // (a checkpoint when it has done it) the second with the first's report of it.
  enum class At { none, attempt, rounding };
  auto find = [&](int done, bool ahead, At at) -> const LevelCheckpoint* {
    for (const LevelCheckpoint& c : inside) {
      const LevelAttempt& a = c.in_progress();
      const At kind = a.empty() ? At::none : a.rounding.empty() ? At::attempt : At::rounding;
      if (c.done() == done && c.first_chain_ahead() == ahead && kind == at) return &c;
    }
    return nullptr;
  };
  for (const LevelCheckpoint& c : inside) {
    REQUIRE(c.chains.size() == 2);
    CHECK((c.done() == 2 || c.done() == 3));
    // The chain at the level holds the attempt: the first, or the second once the first is done.
    CHECK(c.chains[0].attempt.empty() == c.first_chain_ahead());
    CHECK((c.chains[1].attempt.empty() || c.first_chain_ahead()));
    if (!c.in_progress().empty()) CHECK(c.in_progress().report.level == c.done());
    CHECK(c.chains[0].pending.size() == c.chains[1].pending.size() + (c.first_chain_ahead() ? 1 : 0));
    if (c.first_chain_ahead()) CHECK(c.chains[0].pending.back().seconds > 0);  // its own time so far
  }

  test::TempDir tmp;
  const std::string file = (tmp.path / "inside.ckpt").string();
  for (const LevelCheckpoint* c : {find(2, false, At::attempt), find(2, true, At::attempt), find(3, true, At::rounding)}) {
    REQUIRE(c != nullptr);
    save_checkpoint(file, *c);
    const LevelCheckpoint loaded = load_checkpoint(file);
    REQUIRE(loaded.chains.size() == 2);
    CHECK(loaded.done() == c->done());
    CHECK(loaded.first_chain_ahead() == c->first_chain_ahead());
    for (int i = 0; i < 2; ++i) {
      const LevelAttempt &a = loaded.chains[i].attempt, &b = c->chains[i].attempt;
      CHECK(a.ring == b.ring);
      CHECK(a.extra == b.extra);
      CHECK(a.report.widened_faces == b.report.widened_faces);
      CHECK(a.rounding.ones == b.rounding.ones);
      CHECK(a.rounding.rounds == b.rounding.rounds);
    }
    // Gone on from it: the first chain's report of the level, where it had done it, is kept as
    // it was, and the chain at the level does not start it again (no attempt before its widened one).
    const int level = c->done();
    bool first_end = true;
    int earlier_attempts = 0;
    const CoarseToFineResult r = matcher.run({}, &loaded, [&](const LevelCheckpoint& k) {
      const LevelAttempt& a = k.in_progress();
      if (!a.empty() && a.report.level == level && a.widenings() < c->in_progress().widenings()) ++earlier_attempts;
      if (!a.empty() || k.first_chain_ahead() || !first_end) return;
      first_end = false;  // after the level gone on in
      CHECK(k.done() == level + 1);
      CHECK(k.chains.size() == (level == 3 ? 0u : 2u));  // (decided at level 4)
      if (c->first_chain_ahead() && level == 2) {
        CHECK(k.chains[0].pending.back().gamma == c->chains[0].pending.back().gamma);
        CHECK(k.chains[0].pending.back().energy == c->chains[0].pending.back().energy);
        CHECK(k.chains[0].pending.back().seconds > c->chains[0].pending.back().seconds);  // this run's added
      }
    });
    if (c->first_chain_ahead() && level == 3 && !r.levels[3].lookahead_switched) {  // the first chain won
      CHECK(r.levels[3].gamma == c->chains[0].pending.back().gamma);
      CHECK(r.levels[3].energy == c->chains[0].pending.back().energy);
    }
    CHECK(earlier_attempts == 0);
    CHECK_FALSE(first_end);
    REQUIRE(r.levels.size() == whole.levels.size());
    CHECK(r.levels[0].gamma == whole.levels[0].gamma);
    CHECK(r.levels[1].energy == whole.levels[1].energy);
    CHECK(std::isfinite(r.levels[3].lookahead_other_energy));  // decided at level 4, as the whole run
    CHECK(check_graph_surface(r.finest.space, r.rounding.gamma).ok());
    CHECK(satisfies_exactly(r.finest.lp, r.rounding.gamma));
    // Before its rounding, the attempt is the whole run's: so is every level.
    if (c->in_progress().rounding.empty())
      for (size_t l = 0; l < r.levels.size(); ++l) {
        CHECK(r.levels[l].energy == doctest::Approx(whole.levels[l].energy).epsilon(1e-12));
        CHECK(r.levels[l].gamma == whole.levels[l].gamma);
      }
  }

  // Without lookahead past the split, a run gone on from the first chain's end of level 3
  // decides there, between its report and the second chain's, solved now as in the whole run.
  const LevelCheckpoint* first_done = find(2, true, At::none);
  REQUIRE(first_done != nullptr);
  REQUIRE(first_done->chains[1].attempt.empty());
  const LevelCheckpoint* after = nullptr;
  for (const LevelCheckpoint& c : ends)
    if (c.done() == 3) after = &c;
  REQUIRE(after != nullptr);
  CoarseToFineOptions none = o;
  none.lookahead_levels = 0;
  const CoarseToFineMatcher deciding(dx, dy, none);
  REQUIRE(deciding.fingerprint() == matcher.fingerprint());
  const CoarseToFineResult decided = deciding.run({}, first_done);
  const double e0 = first_done->chains[0].pending.back().energy, e1 = after->chains[1].pending.back().energy;
  CHECK(after->chains[0].pending.back().energy == e0);
  REQUIRE(decided.levels.size() == whole.levels.size());
  CHECK(decided.levels[2].energy == doctest::Approx(std::min(e0, e1)).epsilon(1e-12));
  CHECK(decided.levels[2].lookahead_other_energy == doctest::Approx(std::max(e0, e1)).epsilon(1e-12));
  CHECK(std::isnan(decided.levels[3].lookahead_other_energy));
  CHECK(check_graph_surface(decided.finest.space, decided.rounding.gamma).ok());

  // An attempt on a chain that is not at the level in progress, a second chain ahead, or chains
  // that reach the finest level are refused.
  const LevelCheckpoint& at_second = *find(2, true, At::attempt);
  LevelCheckpoint wrong = at_second;
  wrong.chains[0].attempt = wrong.chains[1].attempt;
  CHECK_THROWS_AS(matcher.check(wrong), InvalidInputError);
  wrong = *find(2, false, At::attempt);
  wrong.chains[1].attempt = find(2, false, At::attempt)->chains[0].attempt;
  CHECK_THROWS_AS(matcher.check(wrong), InvalidInputError);
  wrong = at_second;
  std::swap(wrong.chains[0], wrong.chains[1]);
  CHECK_THROWS_AS(matcher.check(wrong), InvalidInputError);
  wrong = *find(3, true, At::rounding);
  wrong.chains[0].pending.push_back(whole.levels[4]);
  wrong.chains[1].pending.push_back(whole.levels[3]);
  wrong.chains[1].attempt = {};
  CHECK_THROWS_AS(matcher.check(wrong), InvalidInputError);
  // A version-5 file keeps the chains' levels but not their attempts.
  detail::save_checkpoint_as(file, at_second, 5);
  const LevelCheckpoint v5 = load_checkpoint(file);
  CHECK(v5.first_chain_ahead());
  CHECK(v5.in_progress().empty());
  CHECK_NOTHROW(matcher.check(v5));
}

TEST_CASE("coarse to fine: a stuck rounding widens around its failed parts and goes on from its fixings") {
  // Measured: with max_total_rounds 3 and a wide greedy margin (few fixings per round), this pair's
  // finest rounding (ring 0) runs out of rounds with a few faces open. Stuck (stuck_after), it
  // widens there and solves the level again: afresh, or (stuck_carry) from the fixings to 1
  // elsewhere, the widened LP then solved again for a certified bound. Off, running out of
  // rounds widens too, as an infeasible LP (not counted as stuck).
  CoarseToFineOptions o = slow_finest_rounding();
  o.rounding.max_total_rounds = 3;
  // Measured with the whole batch fixed where no candidate stands away: with only an eighth of
  // it (the default since the fifty-second session) none of the stuck rounding's fixings to 1 lies
  // where the widened space keeps it (0 of 69 carried).
  o.rounding.greedy_fallback = 1.0;
  o.price_widenings = 0;  // pricing widens this ring-0 space before rounding, which then is not stuck
  const auto& [x, y] = fine_fingers();
  for (const int mode : {0, 1, 2}) {  // off, afresh, carried
    CAPTURE(mode);
    o.stuck_after = mode == 0 ? 0.0 : 1e-12;
    o.stuck_carry = mode == 2;
    const CoarseToFineMatcher matcher(x, y, o);
    const CoarseToFineResult r = matcher.run();
    const LevelReport& l = r.levels.back();
    CHECK(l.stuck_widenings == (mode > 0 ? 1 : 0));
    CHECK((l.carried_fixings > 0) == (mode == 2));  // the fixings did go on
    CHECK((l.iterations_bound > 0) == (mode == 2));
    CHECK(check_graph_surface(r.finest.space, r.rounding.gamma).ok());
    CHECK(satisfies_exactly(r.finest.lp, r.rounding.gamma));
    CHECK(std::isfinite(l.lower_bound));
    CHECK(l.lower_bound <= l.energy + 1e-9);
    MESSAGE("mode ", mode, ": bound ", l.lower_bound, " energy ", l.energy, " gap ", l.gap, " widened faces ",
            l.widened_faces, " variables ", l.variables);
  }
  // With pricing (the default), the same ring-0 space widens where its columns one ring out price
  // below zero, and the rounding ends without getting stuck (measured: energy 8.95 against 6.93
  // where the stuck rounding widened around its failed parts: two pricings widened 4 faces
  // here, the stuck widening more; pricing only ever adds to a space).
  o.stuck_after = 1e-12;
  o.stuck_carry = false;
  const CoarseToFineMatcher off(x, y, o);
  const CoarseToFineResult without = off.run();
  o.price_widenings = CoarseToFineOptions{}.price_widenings;
  REQUIRE(o.price_widenings > 0);
  const CoarseToFineMatcher on(x, y, o);
  const CoarseToFineResult priced = on.run();
  const LevelReport& l = priced.levels.back();
  CHECK(l.price_widenings > 0);
  CHECK(l.stuck_widenings == 0);
  CHECK(check_graph_surface(priced.finest.space, priced.rounding.gamma).ok());
  CHECK(l.gap < 0.01);
  MESSAGE("priced ", l.price_widenings, " times: energy ", l.energy, " (without ", without.levels.back().energy,
          "), gap ", l.gap, ", variables ", l.variables);
  // The re-solves from duals ascended on the new rows (the second pricing then prices against
  // another dual): a verified Γ.
  o.price_dual_sweeps = 4;
  const CoarseToFineMatcher ascended(x, y, o);
  const CoarseToFineResult a = ascended.run();
  const LevelReport& la = a.levels.back();
  CHECK(la.price_widenings > 0);
  CHECK(check_graph_surface(a.finest.space, a.rounding.gamma).ok());
  CHECK(satisfies_exactly(a.finest.lp, a.rounding.gamma));
  CHECK(la.gap < 0.01);
  MESSAGE("ascended: energy ", la.energy, ", gap ", la.gap, ", iterations ", la.iterations, " (", l.iterations, ")");
}

TEST_CASE("coarse to fine: a stuck rounding's carried fixings leave a margin around the widened faces") {
  // Measured on the pair above: carried right up to the widened faces, the attempt keeps the
  // narrow space's choices next to them (energy 7.146 against 6.926 afresh); one ring of margin
  // drops all but 2 of the 32 carried fixings and ends at the fresh attempt's energy, two or more
  // drop them all (the widening took 68 of 120 faces here; at full resolution 243 of 9 996).
  CoarseToFineOptions o = slow_finest_rounding();
  o.rounding.max_total_rounds = 3;
  o.rounding.greedy_fallback = 1.0;  // (as in the test above)
  o.price_widenings = 0;
  o.stuck_after = 1e-12;
  const auto& [x, y] = fine_fingers();
  const CoarseToFineMatcher afresh(x, y, o);  // (a result refers to its matcher's meshes)
  const CoarseToFineResult fresh = afresh.run();
  o.stuck_carry = true;
  int64_t carried_before = std::numeric_limits<int64_t>::max();
  std::map<int, LevelReport> at;
  for (const int margin : {0, 1, 2}) {
    CAPTURE(margin);
    o.stuck_carry_margin = margin;
    const CoarseToFineMatcher matcher(x, y, o);
    const CoarseToFineResult r = matcher.run();
    const LevelReport& l = r.levels.back();
    CHECK(l.stuck_widenings == 1);
    CHECK(l.variables == fresh.levels.back().variables);  // the same widened space
    CHECK(l.carried_fixings <= carried_before);          // a wider margin drops more
    carried_before = l.carried_fixings;
    CHECK(check_graph_surface(r.finest.space, r.rounding.gamma).ok());
    CHECK(satisfies_exactly(r.finest.lp, r.rounding.gamma));
    CHECK(l.lower_bound <= l.energy + 1e-9);
    at[margin] = l;
    MESSAGE("margin ", margin, ": carried ", l.carried_fixings, ", energy ", l.energy, " (afresh ",
            fresh.levels.back().energy, "), rounds ", l.rounds, ", iterations ", l.iterations, " + ",
            l.iterations_bound, " for the bound");
  }
  CHECK(at[0].carried_fixings > at[1].carried_fixings);
  CHECK(at[1].energy < at[0].energy - 1e-3);  // what the margin is for
  CHECK(at[1].energy <= fresh.levels.back().energy * (1.0 + 1e-6));
  // Where the margin leaves no fixing, the attempt is a fresh one: its own first LP's bound, no
  // bound solve, the fresh run's Γ.
  CHECK(at[2].carried_fixings == 0);
  CHECK(at[2].iterations_bound == 0);
  CHECK(at[2].energy == doctest::Approx(fresh.levels.back().energy));
}

TEST_CASE("coarse to fine: a stuck rounding gone on from its checkpoint still goes on from its fixings") {
  // At full resolution a level's end game spans sittings: the rounding that gets stuck was gone on
  // from a checkpoint, without the first LP's iterate. Its fixings still carry to the widened
  // space (before the eighty-second session they did not: it started afresh); the widened LP's
  // bound is then solved for cold.
  CoarseToFineOptions o = slow_finest_rounding();
  o.rounding.max_total_rounds = 3;
  o.rounding.greedy_fallback = 1.0;  // (as in the test above: fixings that the widened space keeps)
  o.rounding.alternative_thresholds = {};  // (with them a level's rounding is not saved)
  o.rounding_checkpoint_seconds = 0.0;     // after every round
  o.price_widenings = 0;
  o.lookahead_levels = 0;
  o.stuck_after = 1e-12;
  o.stuck_carry = true;
  const auto& [x, y] = fine_fingers();
  const CoarseToFineMatcher matcher(x, y, o);
  const int levels = matcher.x_levels().size();
  std::optional<LevelCheckpoint> after_one;  // the finest level's first rounding, after its round 1
  const CoarseToFineResult whole = matcher.run({}, nullptr, [&](const LevelCheckpoint& c) {
    if (!after_one && int(c.levels.size()) == levels - 1 && c.attempt.rounding.rounds == 1)
      after_one = c;
  });
  REQUIRE(after_one);
  const LevelReport& w = whole.levels.back();
  REQUIRE(w.stuck_widenings == 1);
  REQUIRE(w.carried_fixings > 0);
  // (A rounding gone on from a checkpoint counts its rounds afresh: two more, as the whole run had.)
  o.rounding.max_total_rounds = 2;
  const CoarseToFineMatcher again(x, y, o);
  std::optional<LevelCheckpoint> carried;  // the carried start's rounding, after its round 1
  const CoarseToFineResult r = again.run({}, &*after_one, [&](const LevelCheckpoint& c) {
    if (!carried && int(c.levels.size()) == levels - 1 && c.attempt.report.stuck_widenings == 1 &&
        c.attempt.rounding.rounds >= 1)
      carried = c;
  });
  const LevelReport& l = r.levels.back();
  CHECK(l.stuck_widenings == 1);
  CHECK(l.carried_fixings > 0);     // on from the stuck rounding's fixings, not afresh
  CHECK(l.iterations_bound > 0);    // the widened LP solved for its bound
  CHECK(l.variables == w.variables);  // the same widened space
  CHECK(check_graph_surface(r.finest.space, r.rounding.gamma).ok());
  CHECK(satisfies_exactly(r.finest.lp, r.rounding.gamma));
  CHECK(std::isfinite(l.lower_bound));
  CHECK(l.lower_bound <= l.energy + 1e-9);
  // A bound of the widened LP, not of what the carried fixings leave (round 1's: 7.1 here, above
  // the widened LP's optimum of 6.93 that the whole run's bound certifies).
  CHECK(l.lower_bound <= w.lower_bound + 1e-3 * std::abs(w.lower_bound));
  CHECK(l.gap < 0.05);
  MESSAGE("gone on: carried ", l.carried_fixings, " (whole run ", w.carried_fixings, "), bound ", l.lower_bound,
          " (whole run ", w.lower_bound, "), energy ", l.energy, " (whole run ", w.energy, "), bound iterations ",
          l.iterations_bound, " (whole run ", w.iterations_bound, ")");
  // The carried start is saved as it goes, without a bound of the space (its round 1 bounds only
  // what the carried fixings leave); gone on from there, the widened LP's bound is solved for at
  // the end, as in one run.
  REQUIRE(carried);
  CHECK(std::isnan(carried->attempt.rounding.lower_bound));
  CHECK(carried->attempt.rounding.columns == l.variables);
  const CoarseToFineResult c = again.run({}, &*carried);
  const LevelReport& lc = c.levels.back();
  CHECK(lc.variables == l.variables);
  CHECK(lc.carried_fixings == l.carried_fixings);  // (the attempt's count, kept with it)
  CHECK(lc.iterations_bound > 0);
  CHECK(check_graph_surface(c.finest.space, c.rounding.gamma).ok());
  CHECK(satisfies_exactly(c.finest.lp, c.rounding.gamma));
  CHECK(std::isfinite(lc.lower_bound));
  CHECK(lc.lower_bound <= lc.energy + 1e-9);
  CHECK(lc.lower_bound == doctest::Approx(l.lower_bound).epsilon(1e-3));
  CHECK(lc.lower_bound <= w.lower_bound + 1e-3 * std::abs(w.lower_bound));
  CHECK(lc.gap < 0.05);
  MESSAGE("gone on from the carried start: bound ", lc.lower_bound, ", energy ", lc.energy, ", rounds ", lc.rounds);
}

TEST_CASE("coarse to fine: a stuck rounding starts again from its fixings in the same space before widening") {
  // The pair of the test above, stuck after its 3 rounds: with stuck_restarts, its rounding starts
  // again from its fixings to 1 in the same LP (saved as a checkpoint would be), keeps round 1's
  // bound and counts its rounds on; stuck again with no restart left, it widens as before.
  // Measured: it finishes one round after the restart, in the ring-0 space it was stuck in, at
  // energy 11.86 against 6.93 after the widening (which is why it is off by default).
  CoarseToFineOptions o = slow_finest_rounding();
  o.rounding.max_total_rounds = 3;
  o.price_widenings = 0;
  o.stuck_after = 1e-12;
  o.rounding.alternative_thresholds = {};  // (with them a rounding is neither saved nor restarted)
  o.rounding_checkpoint_seconds = 0.0;
  const auto& [x, y] = fine_fingers();
  const CoarseToFineMatcher matcher(x, y, o);
  const int levels = matcher.x_levels().size();
  LevelAttempt stuck;  // the finest rounding's last checkpoint before it was stuck
  const CoarseToFineResult plain = matcher.run({}, nullptr, [&](const LevelCheckpoint& c) {
    if (int(c.levels.size()) == levels - 1 && c.attempt.report.stuck_widenings == 0 && !c.attempt.rounding.empty())
      stuck = c.attempt;
  });
  REQUIRE(plain.levels.back().stuck_widenings == 1);
  REQUIRE(stuck.rounding.rounds >= 3);
  REQUIRE(plain.levels.back().stuck_restarts == 0);
  for (const int restarts : {1, 2}) {
    CAPTURE(restarts);
    o.stuck_restarts = restarts;
    const CoarseToFineMatcher again(x, y, o);
    std::vector<LevelAttempt> saved;  // the finest level's attempts that start from a restart
    const CoarseToFineResult r = again.run({}, nullptr, [&](const LevelCheckpoint& c) {
      if (int(c.levels.size()) == levels - 1 && c.attempt.report.stuck_restarts > int(saved.size()))
        saved.push_back(c.attempt);
    });
    const LevelReport& l = r.levels.back();
    MESSAGE("restarts ", l.stuck_restarts, ", stuck widenings ", l.stuck_widenings, ", rounds ", l.rounds,
            ", energy ", l.energy, " (without ", plain.levels.back().energy, "), gap ", l.gap);
    CHECK(l.stuck_restarts >= 1);
    CHECK(l.stuck_restarts <= restarts);
    REQUIRE(int(saved.size()) == l.stuck_restarts);
    // Started again from where it was stuck.
    const LevelAttempt::Rounding& g = saved.front().rounding;
    CHECK(g.rounds == stuck.rounding.rounds);
    CHECK(g.iterations == stuck.rounding.iterations);
    CHECK(g.ones == stuck.rounding.ones);
    CHECK(g.steps == stuck.rounding.steps);  // in their undo steps, as a checkpoint keeps them
    CHECK(g.step_count() > 1);
    CHECK(g.columns == stuck.rounding.columns);
    CHECK(g.lower_bound == stuck.rounding.lower_bound);
    CHECK(saved.front().extra == stuck.extra);
    CHECK(saved.front().report.stuck_widenings == 0);
    CHECK(check_graph_surface(r.finest.space, r.rounding.gamma).ok());
    CHECK(satisfies_exactly(r.finest.lp, r.rounding.gamma));
    CHECK(l.lower_bound <= l.energy + 1e-9);
    // The same without a checkpoint to save to: it restarts all the same.
    const CoarseToFineResult quiet = again.run();
    CHECK(quiet.levels.back().stuck_restarts == l.stuck_restarts);
    CHECK(quiet.levels.back().rounds == l.rounds);
    CHECK(quiet.levels.back().energy == doctest::Approx(l.energy).epsilon(1e-12));
    if (l.stuck_widenings == 0) {  // finished in the space it was stuck in
      const LevelAttempt::Rounding& last = saved.back().rounding;
      CHECK(l.variables == last.columns);
      CHECK(l.lower_bound == last.lower_bound);
      CHECK(l.rounds == last.rounds + int(r.rounding.rounds.size()));
      for (int64_t j : last.ones) CHECK(std::binary_search(r.rounding.gamma.begin(), r.rounding.gamma.end(), j));
    }
  }
}

TEST_CASE("coarse to fine: after pricing, the later rounds' caps scale with the cold first LP, not the warm re-solve") {
  // Pricing's re-solve starts warm and takes a fraction of the cold solve's iterations; the later
  // rounds' caps (later_round_iterations times round 1's) must not shrink with it. Here the caps
  // are round 1's count exactly and every later round is solved by PDHG. (Measured: 3 264
  // iterations cold, 320 warm, and round 2 took 384.)
  CoarseToFineOptions o = slow_finest_rounding();
  o.rounding.later_round_iterations = 1.0;
  o.rounding.later_round_min_iterations = 1;
  o.rounding.exact_below = 0;
  o.rounding.max_rounds = 200;
  const auto& [x, y] = fine_fingers();
  struct Seen {
    int level;
    RoundingRound round;
  };
  std::vector<Seen> seen;
  const CoarseToFineMatcher matcher(x, y, o);
  const CoarseToFineResult r = matcher.run([&](const LevelReport& l, const RoundingRound& round) {
    seen.push_back({l.level, round});
  });
  const int finest = static_cast<int>(r.levels.size()) - 1;
  REQUIRE(r.levels.back().price_widenings > 0);
  std::vector<int64_t> firsts;       // the finest level's round-1 iterations, attempt by attempt
  std::vector<RoundingRound> later;  // the last attempt's later rounds
  for (const Seen& s : seen) {
    if (s.level != finest) continue;
    if (s.round.round == 1) {
      firsts.push_back(s.round.iterations);
      later.clear();
    } else {
      later.push_back(s.round);
    }
  }
  REQUIRE(firsts.size() >= 2);
  const int64_t cold = firsts.front(), warm = firsts.back();
  REQUIRE(warm < cold);  // else this pair shows nothing
  // A later round that needs more than the warm re-solve's count: the old cap would have stopped it.
  int64_t longest = 0;
  for (const RoundingRound& round : later) {
    longest = std::max(longest, round.iterations);
    if (round.status == LpStatus::IterationLimit) CHECK(round.iterations >= cold);  // never the warm count
  }
  CHECK(longest > warm);
  CHECK(satisfies_exactly(r.finest.lp, r.rounding.gamma));
}

TEST_CASE("coarse to fine: pricing a wider space against an exact dual says whether it lowers the optimum") {
  // The finger pair's fine level at ring 1 (narrow) and with one more ring on every X face
  // (wide), both solved exactly by Clp: the narrow dual prices the wide columns.
  const FingerLevels f(16, 48);
  const Mesh& x = f.x();
  auto lp_at = [&](const std::vector<int>& extra) { return f.lp_at(extra); };
  const MatchingLp narrow = lp_at({}), wide = lp_at(std::vector<int>(x.num_faces(), 1));
  REQUIRE(narrow.lp.cols() < wide.lp.cols());
  const LpResult a = solve_lp(narrow.lp, "clp-dual"), b = solve_lp(wide.lp, "clp-dual");
  REQUIRE(a.status == LpStatus::Optimal);
  REQUIRE(b.status == LpStatus::Optimal);
  // Against itself an optimal dual prices nothing below zero (the sign convention).
  const std::vector<double> own = reduced_costs(narrow, a.y, narrow);
  CHECK(*std::min_element(own.begin(), own.end()) > -1e-7);
  const std::vector<double> rc = reduced_costs(narrow, a.y, wide);
  REQUIRE(rc.size() == size_t(wide.lp.cols()));
  const double lowest = *std::min_element(rc.begin(), rc.end());
  MESSAGE("narrow ", narrow.lp.cols(), " columns, optimum ", a.objective, "; wide ", wide.lp.cols(), ", optimum ",
          b.objective, "; lowest reduced cost ", lowest);
  // The wider space lowers the optimum here, so some column must price below zero (if none did,
  // the mapped dual would prove the narrow optimum optimal for the wide LP too).
  REQUIRE(b.objective < a.objective - 1e-6);
  CHECK(lowest < -1e-6);
  // And the Lagrangian bound of the mapped dual over the wide LP is a bound: below its optimum.
  double bound = 0.0;
  {
    SolverParams mapped;
    CarriedIterate dual;
    dual.keep(narrow, {}, a.y);
    dual.apply(wide, mapped);
    bound = certified_lower_bound(wide.lp, mapped.initial_y);
  }
  CHECK(bound <= b.objective + 1e-6);
  // Widening only the X faces of the columns priced lowest (under a quarter of the lowest) lowers
  // the optimum with fewer columns than widening everywhere.
  std::vector<int> extra(x.num_faces(), 0);
  for (int64_t j = 0; j < wide.lp.cols(); ++j)
    if (rc[j] < 0.25 * lowest && wide.space[j].fa >= 0) extra[wide.space[j].fa] = 1;
  const MatchingLp priced = lp_at(extra);
  const LpResult c = solve_lp(priced.lp, "clp-dual");
  REQUIRE(c.status == LpStatus::Optimal);
  MESSAGE("widened on ", std::count(extra.begin(), extra.end(), 1), " of ", x.num_faces(), " faces: ", priced.lp.cols(),
          " columns, optimum ", c.objective);
  CHECK(c.objective < a.objective - 1e-6);
  CHECK(c.objective >= b.objective - 1e-6);
  CHECK(priced.lp.cols() < wide.lp.cols());
}

TEST_CASE("KeySet: exactly the keys it was given, 0 and colliding slots included") {
  std::mt19937_64 rng(17);
  std::vector<uint64_t> keys;
  for (int i = 0; i < 5000; ++i) keys.push_back(rng());
  for (uint64_t k = 0; k < 64; ++k) keys.push_back(k << 40);  // one slot for all: long probe runs
  keys.push_back(keys[10]);                                     // a duplicate
  const detail::KeySet set(keys);
  for (uint64_t k : keys) CHECK(set.contains(k));
  const std::set<uint64_t> given(keys.begin(), keys.end());
  int absent = 0;
  for (int i = 0; i < 20000; ++i) {
    const uint64_t k = i < 64 ? (uint64_t(i) << 40) + 1 : rng();
    if (given.count(k)) continue;
    ++absent;
    CHECK_FALSE(set.contains(k));
  }
  CHECK(absent > 19000);
  CHECK_FALSE(detail::KeySet({1, 2, 3}).contains(0));
  CHECK(detail::KeySet({}).contains(5) == false);
}

TEST_CASE("coarse to fine: a contradiction counts as back only in the π row of the same face") {
  detail::RecurringConflicts r;
  std::vector<int64_t> back;
  CHECK(r.record({7, 3}, back) == 0);
  CHECK(back.empty());
  CHECK(r.record({3, 3, 9}, back) == 1);  // 3 again (once, though listed twice); 9 new
  CHECK(back == std::vector<int64_t>{3});
  CHECK(r.record({9, 3}, back) == 2);  // 3 a third time, 9 a second
  CHECK(back == std::vector<int64_t>{3, 9});
  CHECK(r.record({}, back) == 0);
  CHECK(back.empty());
}

TEST_CASE("coarse to fine: a recurring widening is too wide by the faces it would still grow") {
  using detail::recurring_too_wide;
  // 100 faces at ring 2; faces 0-9 already have 4 extra rings (ring 6 = the cap), 10-19 have 1.
  std::vector<int> extra(100, 0);
  for (int f = 0; f < 10; ++f) extra[f] = 4;
  for (int f = 10; f < 20; ++f) extra[f] = 1;
  std::vector<int> faces;
  for (int f = 0; f < 30; ++f) faces.push_back(f);
  int64_t growing = -1;
  // 30 faces, but the 10 at the cap do not grow: 20 of 100.
  CHECK_FALSE(recurring_too_wide(faces, extra, 2, 6, 0.2, 100, &growing));
  CHECK(growing == 20);
  CHECK(recurring_too_wide(faces, extra, 2, 6, 0.19, 100, &growing));
  // A lower cap: faces 10-19 (ring 3) reach it too.
  CHECK_FALSE(recurring_too_wide(faces, extra, 2, 3, 0.1, 100, &growing));
  CHECK(growing == 10);
  // Faces past the end of `extra` have no extra rings; share 0 is never too wide.
  CHECK(recurring_too_wide({150, 151, 152}, extra, 2, 6, 0.01, 200, &growing));
  CHECK(growing == 3);
  CHECK_FALSE(recurring_too_wide(faces, extra, 2, 6, 0.0, 100));
  CHECK_FALSE(recurring_too_wide({}, extra, 2, 6, 0.1, 100));
}

TEST_CASE("coarse to fine: the divergence watch stops first LPs with widenings left, not the re-solve after pricing") {
  using detail::FirstLpState;
  using detail::watch_divergence;
  const FirstLpState first{.refined = true, .widenings_left = true, .trusted = true};
  CHECK(watch_divergence(first));
  FirstLpState s = first;
  s.refined = false;  // the coarsest level is the full space: nothing to widen
  CHECK_FALSE(watch_divergence(s));
  s = first;
  s.widenings_left = false;  // the last attempts wait for a proof
  CHECK_FALSE(watch_divergence(s));
  s = first;
  s.trusted = false;  // a suspicion came to nothing at this level
  CHECK_FALSE(watch_divergence(s));
  s = first;
  s.warm_resolve = true;  // its space contains one whose LP ended optimal
  CHECK_FALSE(watch_divergence(s));
  s.watch_resolve = true;  // the rule before the twenty-sixth session
  CHECK(watch_divergence(s));
  s.trusted = false;
  CHECK_FALSE(watch_divergence(s));
}

TEST_CASE("coarse to fine: where the watch is no longer trusted or out of local widenings, the first LPs are watched patiently") {
  using detail::FirstLpState;
  using detail::watch_patiently;
  const FirstLpState untrusted{.refined = true, .widenings_left = true, .trusted = false};
  CHECK(watch_patiently(untrusted));
  FirstLpState s = untrusted;
  s.trusted = true;  // watched as before, not patiently
  CHECK_FALSE(watch_patiently(s));
  CHECK(detail::watch_divergence(s));
  s = untrusted;
  s.widenings_left = false;  // nothing left to widen at all: it waits for a proof or an optimum
  CHECK_FALSE(watch_patiently(s));
  s.ring_left = true;  // out of local widenings, a ring left: its stop widens by the ring
  CHECK(watch_patiently(s));
  s.trusted = true;  // so too where no suspicion came before (the quick watch needs widenings left)
  CHECK(watch_patiently(s));
  CHECK_FALSE(detail::watch_divergence(s));
  s.ring_left = false;
  CHECK_FALSE(watch_patiently(s));
  s = untrusted;
  s.refined = false;
  CHECK_FALSE(watch_patiently(s));
  s.ring_left = true;  // the coarsest level is the full space
  CHECK_FALSE(watch_patiently(s));
  s = untrusted;
  s.warm_resolve = true;
  CHECK_FALSE(watch_patiently(s));
  s.widenings_left = false;
  s.ring_left = true;
  CHECK_FALSE(watch_patiently(s));
  s.watch_resolve = true;
  CHECK(watch_patiently(s));
  // Never both watches: one LP, one rule.
  for (int bits = 0; bits < 64; ++bits) {
    const FirstLpState t{.refined = bool(bits & 1),
                         .widenings_left = bool(bits & 2),
                         .ring_left = bool(bits & 4),
                         .trusted = bool(bits & 8),
                         .warm_resolve = bool(bits & 16),
                         .watch_resolve = bool(bits & 32)};
    CHECK_FALSE((watch_patiently(t) && detail::watch_divergence(t)));
  }
}

TEST_CASE("coarse to fine: after N suspicions in a row the watch is off until a proof") {
  detail::SuspicionCount s(3);
  CHECK(s.trusted());
  CHECK_FALSE(s.suspicion());
  CHECK_FALSE(s.suspicion());
  CHECK(s.trusted());
  CHECK(s.suspicion());  // the third ends the trust, and says so once
  CHECK_FALSE(s.trusted());
  CHECK_FALSE(s.suspicion());
  CHECK_FALSE(s.trusted());
  CHECK(s.count() == 4);
  s.proof();  // a proof: trusted again, counted afresh
  CHECK(s.trusted());
  CHECK(s.count() == 0);
  CHECK_FALSE(s.suspicion());
  CHECK_FALSE(s.suspicion());
  s.proof();  // not in a row: two, a proof, two more keep the trust
  CHECK_FALSE(s.suspicion());
  CHECK_FALSE(s.suspicion());
  CHECK(s.trusted());
  s.distrust();  // nothing left to widen on a suspicion
  CHECK_FALSE(s.trusted());

  detail::SuspicionCount one(1);  // the default: the first suspicion ends the trust
  CHECK(one.suspicion());
  CHECK_FALSE(one.trusted());
  one.proof();
  CHECK(one.trusted());
  CHECK(one.suspicion());  // and so again after a proof
  CHECK_FALSE(one.trusted());
  CHECK(CoarseToFineOptions{}.max_suspected_widenings == 1);

  detail::SuspicionCount unlimited(0);
  for (int i = 0; i < 50; ++i) CHECK_FALSE(unlimited.suspicion());
  CHECK(unlimited.trusted());
}

TEST_CASE("coarse to fine: the suspicion's margin at most suspicion_margins times per ring") {
  using detail::margin_left;
  const int limit = CoarseToFineOptions{}.suspicion_margins;
  CHECK(limit == 1);  // the default: once per ring
  CHECK(margin_left(0, limit));
  CHECK_FALSE(margin_left(1, limit));
  CHECK(margin_left(2, 3));
  CHECK_FALSE(margin_left(3, 3));
  CHECK(margin_left(0, 0));  // 0: no limit, a margin at every suspicion that ends the trust
  CHECK(margin_left(100, 0));
}

TEST_CASE("coarse to fine: the suspicion's margin around every widening or around the suspicion's places") {
  using Scope = CoarseToFineOptions::MarginScope;
  CHECK(CoarseToFineOptions{}.suspicion_margin_scope == Scope::widened);  // the default, as before
  const Mesh x = shapes::icosphere(3);                                    // 1 280 faces
  // Two widenings at opposite poles (the faces touching the vertex furthest up and down); the
  // suspicion named the top one.
  int top = 0, bottom = 0;
  for (int v = 0; v < x.num_vertices(); ++v) {
    if (x.vertices[v].z() > x.vertices[top].z()) top = v;
    if (x.vertices[v].z() < x.vertices[bottom].z()) bottom = v;
  }
  std::vector<int> extra(x.num_faces(), 0), named;
  for (int f = 0; f < x.num_faces(); ++f) {
    const auto& t = x.faces[f];
    const bool at_top = t[0] == top || t[1] == top || t[2] == top;
    const bool at_bottom = t[0] == bottom || t[1] == bottom || t[2] == bottom;
    if (at_top || at_bottom) extra[f] = 1;
    if (at_top) named.push_back(f);
  }
  REQUIRE(named.size() >= 5);  // (a vertex star)
  auto height = [&](int f) {
    double z = 0.0;
    for (int v : x.faces[f]) z += x.vertices[v].z() / 3.0;
    return z;
  };
  const int rings = 2;
  const std::vector<int> all = detail::suspicion_margin_faces(x, extra, named, Scope::widened, rings);
  const std::vector<int> here = detail::suspicion_margin_faces(x, extra, named, Scope::named, rings);
  // Every face within the rings of a widened face, at both poles; only the top's with `named`.
  CHECK(all == detail::faces_near(x, [&] {
          std::vector<int> w;
          for (int f = 0; f < x.num_faces(); ++f)
            if (extra[f] > 0) w.push_back(f);
          return w;
        }(), rings));
  CHECK(here == detail::faces_near(x, named, rings));
  CHECK(std::count_if(all.begin(), all.end(), [&](int f) { return height(f) < 0.0; }) > 0);
  CHECK(std::count_if(here.begin(), here.end(), [&](int f) { return height(f) < 0.0; }) == 0);
  CHECK(here.size() * 2 == all.size());  // (the icosphere is point-symmetric: the poles are alike)
  for (int f : named) CHECK(std::find(here.begin(), here.end(), f) != here.end());
  // Two rings out from a pole's star: the faces on its star's vertices and on theirs.
  CHECK(here.size() > named.size());
  CHECK(detail::faces_near(x, named, 0).size() < here.size());
  // Nothing widened, nothing named: no margin (the caller then gives none).
  CHECK(detail::suspicion_margin_faces(x, std::vector<int>(x.num_faces(), 0), named, Scope::widened, rings).empty());
  CHECK(detail::suspicion_margin_faces(x, extra, {}, Scope::named, rings).empty());
}

TEST_CASE("coarse to fine: a run gone on from a level's checkpoint ends as the whole run") {
  CoarseToFineOptions o = small_levels();
  o.lookahead_levels = 0;  // (one chain throughout; inside lookahead: the test case above)
  o.inherit_widening = 2;  // so that the extra rings a level widened by carry over too
  const CoarseToFineMatcher matcher = finger_matcher(o);
  const int levels = matcher.x_levels().size();
  REQUIRE(levels >= 4);
  std::vector<LevelCheckpoint> saved;
  const CoarseToFineResult whole = matcher.run({}, nullptr, [&](const LevelCheckpoint& c) {
    if (c.attempt.empty()) saved.push_back(c);  // (attempts: the next test case)
  });
  // One after every level but the finest, each holding the levels so far and their Γ.
  REQUIRE(saved.size() == size_t(levels - 1));
  for (size_t k = 0; k < saved.size(); ++k) {
    CHECK(saved[k].hierarchy == matcher.fingerprint());
    REQUIRE(saved[k].levels.size() == k + 1);
    CHECK(saved[k].levels.back().gamma == whole.levels[k].gamma);
  }
  // (The test carries extra rings: the last checkpoint's faces were widened.)
  CHECK(std::count_if(saved.back().widened.begin(), saved.back().widened.end(), [](int e) { return e > 0; }) > 0);

  test::TempDir tmp;
  const std::string file = (tmp.path / "after.ckpt").string();
  for (const size_t k : {size_t(0), saved.size() - 1}) {  // after the coarsest (the second start still to come), and last
    save_checkpoint(file, saved[k]);
    const LevelCheckpoint loaded = load_checkpoint(file);
    CHECK(loaded.hierarchy == saved[k].hierarchy);
    CHECK(loaded.widened == saved[k].widened);
    REQUIRE(loaded.levels.size() == saved[k].levels.size());
    CHECK(loaded.levels.back().energy == saved[k].levels.back().energy);
    CHECK(loaded.levels.back().second_start_kept == saved[k].levels.back().second_start_kept);
    CHECK(loaded.levels.back().gamma == saved[k].levels.back().gamma);
    int called = 0;
    const CoarseToFineResult r = matcher.run({}, &loaded, [&](const LevelCheckpoint& c) { called += c.attempt.empty(); });
    CHECK(called == levels - 1 - int(k + 1));
    REQUIRE(r.levels.size() == whole.levels.size());
    for (int l = 0; l < levels; ++l) {
      CHECK(r.levels[l].energy == doctest::Approx(whole.levels[l].energy).epsilon(1e-12));
      CHECK(r.levels[l].gamma == whole.levels[l].gamma);
      CHECK(r.levels[l].inherited_faces == whole.levels[l].inherited_faces);
    }
    CHECK(r.rounding.energy == doctest::Approx(whole.rounding.energy).epsilon(1e-12));
    CHECK(check_graph_surface(r.finest.space, r.rounding.gamma).ok());
  }

  // Another pair's checkpoint, one that holds every level, and broken files are refused.
  const CoarseToFineMatcher other(decimate(shapes::bent_finger(10, 8, 8), 80), decimate(shapes::bent_finger(40, 8, 8), 90), o);
  CHECK_THROWS_AS(other.run({}, &saved[0]), InvalidInputError);
  LevelCheckpoint damaged = saved[0];  // (its fingerprint intact)
  damaged.levels[0].gamma[0].a[0] = 1 << 20;
  CHECK_THROWS_AS(matcher.run({}, &damaged), InvalidInputError);
  LevelCheckpoint all = saved.back();
  all.levels = whole.levels;
  CHECK_THROWS_AS(matcher.run({}, &all), InvalidInputError);
  save_checkpoint(file, saved[0]);
  const auto size = std::filesystem::file_size(file);
  std::filesystem::resize_file(file, size - 3);
  CHECK_THROWS_AS(load_checkpoint(file), IoError);
  std::ofstream(file) << "OFF\n3 1 0\n";
  CHECK_THROWS_AS(load_checkpoint(file), IoError);
  CHECK_THROWS_AS(load_checkpoint((tmp.path / "missing.ckpt").string()), IoError);
}

TEST_CASE("coarse to fine: a run gone on from an attempt of a level in progress starts in its widened space") {
  CoarseToFineOptions o = small_levels();
  o.lookahead_levels = 0;
  o.inherit_widening = 2;
  o.ring = 0;  // so that the finest level widens
  o.price_widenings = 0;  // (after a pricing the next LP starts warm, which a checkpoint does not keep)
  const CoarseToFineMatcher matcher = finger_matcher(o);
  const int levels = matcher.x_levels().size();
  std::vector<LevelCheckpoint> attempts;
  const CoarseToFineResult whole = matcher.run({}, nullptr, [&](const LevelCheckpoint& c) {
    if (!c.attempt.empty()) attempts.push_back(c);
  });
  REQUIRE_FALSE(attempts.empty());
  // The last attempt of the finest level, where it widened: every level below it done.
  const LevelCheckpoint& last = attempts.back();
  REQUIRE(last.levels.size() == size_t(levels - 1));
  const LevelAttempt& a = last.attempt;
  CHECK(a.report.level == levels - 1);
  CHECK(a.report.local_widenings + a.report.widenings > 0);
  CHECK(std::count_if(a.extra.begin(), a.extra.end(), [](int e) { return e > 0; }) > 0);

  test::TempDir tmp;
  const std::string file = (tmp.path / "attempt.ckpt").string();
  save_checkpoint(file, last);
  const LevelCheckpoint loaded = load_checkpoint(file);
  CHECK(loaded.attempt.ring == a.ring);
  CHECK(loaded.attempt.extra == a.extra);
  CHECK(loaded.attempt.local == a.local);
  CHECK(loaded.attempt.propagated == a.propagated);
  CHECK(loaded.attempt.report.widened_faces == a.report.widened_faces);
  CHECK(loaded.attempt.zero_cost_margin_given == a.zero_cost_margin_given);
  CHECK(loaded.attempt.suspicion_margins == a.suspicion_margins);
  {  // (The margin's flag through a checkpoint, version 9, not through a version-8 one.)
    LevelCheckpoint given = last;
    given.attempt.zero_cost_margin_given = true;
    const std::string other = (tmp.path / "given.ckpt").string();
    save_checkpoint(other, given);
    CHECK(load_checkpoint(other).attempt.zero_cost_margin_given);
    CHECK(load_checkpoint(other).attempt.extra == a.extra);
    detail::save_checkpoint_as(other, given, 8);
    CHECK_FALSE(load_checkpoint(other).attempt.zero_cost_margin_given);
    CHECK(load_checkpoint(other).attempt.extra == a.extra);
  }
  {  // (The suspicion margins given at the ring through a checkpoint, version 11, not version 10.)
    LevelCheckpoint given = last;
    given.attempt.suspicion_margins = 2;
    given.attempt.zero_cost_margin_given = true;
    const std::string other = (tmp.path / "margins.ckpt").string();
    save_checkpoint(other, given);
    CHECK(load_checkpoint(other).attempt.suspicion_margins == 2);
    CHECK(load_checkpoint(other).attempt.zero_cost_margin_given);
    CHECK(load_checkpoint(other).attempt.extra == a.extra);
    detail::save_checkpoint_as(other, given, 10);
    CHECK(load_checkpoint(other).attempt.suspicion_margins == 0);
    CHECK(load_checkpoint(other).attempt.zero_cost_margin_given);
    CHECK(load_checkpoint(other).attempt.extra == a.extra);
  }
  {  // (A local proof's region to check again, and the checks made, version 17, not version 16.)
    LevelCheckpoint given = last;
    given.attempt.proof_faces = {3, 1, 4};
    given.attempt.proof_rings = 2;
    given.attempt.report.proof_rechecks = 5;
    const std::string other = (tmp.path / "region.ckpt").string();
    save_checkpoint(other, given);
    const LevelCheckpoint back = load_checkpoint(other);
    CHECK(back.attempt.proof_faces == given.attempt.proof_faces);
    CHECK(back.attempt.proof_rings == 2);
    CHECK(back.attempt.proof_rows == -1);  // (not rechecked yet)
    CHECK(back.attempt.report.proof_rechecks == 5);
    CHECK(back.attempt.extra == a.extra);
    given.attempt.proof_rows = 1'488'311;  // (its size at its last recheck, version 20, not 19)
    given.attempt.proof_cols = 5'198'111;
    save_checkpoint(other, given);
    CHECK(load_checkpoint(other).attempt.proof_rows == 1'488'311);
    CHECK(load_checkpoint(other).attempt.proof_cols == 5'198'111);
    CHECK(load_checkpoint(other).attempt.proof_faces == given.attempt.proof_faces);
    detail::save_checkpoint_as(other, given, 19);
    CHECK(load_checkpoint(other).attempt.proof_rows == -1);
    CHECK(load_checkpoint(other).attempt.proof_cols == -1);
    CHECK(load_checkpoint(other).attempt.proof_faces == given.attempt.proof_faces);
    given.attempt.proof_cols = -1;  // (one without the other: refused)
    save_checkpoint(other, given);
    CHECK_THROWS_AS(load_checkpoint(other), IoError);
    given.attempt.proof_rows = given.attempt.proof_cols = -1;
    given.attempt.proof_rings = 65;  // (more than a proof grows: refused, as a negative face is)
    save_checkpoint(other, given);
    CHECK_THROWS_AS(load_checkpoint(other), IoError);
    given.attempt.proof_rings = 2;
    given.attempt.proof_faces = {3, -1};
    save_checkpoint(other, given);
    CHECK_THROWS_AS(load_checkpoint(other), IoError);
    given.attempt.proof_faces = {3, 1, 4};
    detail::save_checkpoint_as(other, given, 16);
    CHECK(load_checkpoint(other).attempt.proof_faces.empty());
    CHECK(load_checkpoint(other).attempt.report.proof_rechecks == 0);
    CHECK(load_checkpoint(other).attempt.extra == a.extra);
  }
  int more = 0;
  const CoarseToFineResult r = matcher.run({}, &loaded, [&](const LevelCheckpoint& c) { more += !c.attempt.empty(); });
  CHECK(more == 0);  // the whole run's last attempt was the one that finished
  REQUIRE(r.levels.size() == whole.levels.size());
  const LevelReport& finest = r.levels.back();
  CHECK(finest.variables == whole.levels.back().variables);  // straight into the widened space
  CHECK(finest.local_widenings == whole.levels.back().local_widenings);
  CHECK(finest.widened_faces == whole.levels.back().widened_faces);
  CHECK(finest.energy == doctest::Approx(whole.levels.back().energy).epsilon(1e-12));
  CHECK(finest.gamma == whole.levels.back().gamma);
  CHECK(check_graph_surface(r.finest.space, r.rounding.gamma).ok());

  // With a local proof's region to check again (feasible in this LP: a relaxation of it), the
  // check is made once and the run goes on as without it; with local proofs off, it is not
  // proved either (no relaxation fits a cap of 0 columns). Faces past the level's: none made.
  {
    CoarseToFineOptions po = o;
    po.rounding.local_proof_columns = 1'000'000;
    const CoarseToFineMatcher proving = finger_matcher(po);
    LevelCheckpoint region = last;
    region.attempt.proof_faces = {0, 1};
    region.attempt.proof_rings = 1;
    const CoarseToFineResult checked = proving.run({}, &region);
    REQUIRE(checked.levels.size() == whole.levels.size());
    CHECK(checked.levels.back().proof_rechecks == 1);
    CHECK(checked.levels.back().local_widenings == finest.local_widenings);
    CHECK(checked.levels.back().gamma == finest.gamma);
    const CoarseToFineResult off = matcher.run({}, &region);
    CHECK(off.levels.back().proof_rechecks == 0);
    CHECK(off.levels.back().gamma == finest.gamma);
    region.attempt.proof_faces = {0, proving.x_levels().levels.back().mesh.num_faces()};
    CHECK(proving.run({}, &region).levels.back().proof_rechecks == 0);

    // The finest level's first attempt, whose LP propagation proves infeasible, with propagation's
    // widenings spent: its region (every X face) proved infeasible again before the LP, widened
    // there (every face one ring), checked again until it is not, and only then solved.
    po.max_propagation_widenings = 0;
    const CoarseToFineMatcher spent = finger_matcher(po);
    const auto first = std::find_if(attempts.begin(), attempts.end(), [&](const LevelCheckpoint& c) {
      return c.levels.size() == size_t(levels - 1);
    });
    REQUIRE(first != attempts.end());
    LevelCheckpoint all = *first;
    REQUIRE(all.attempt.local == 0);  // (after a propagation widening: the first attempt is not saved)
    const LevelReport& before = all.attempt.report;
    const int faces = spent.x_levels().levels.back().mesh.num_faces();
    all.attempt.proof_faces.resize(faces);
    std::iota(all.attempt.proof_faces.begin(), all.attempt.proof_faces.end(), 0);
    const CoarseToFineResult rechecked = spent.run({}, &all);
    const LevelReport& fin = rechecked.levels.back();
    MESSAGE("rechecks " << fin.proof_rechecks << ", local widenings " << fin.local_widenings << ", widened faces "
                        << fin.widened_faces << ", energy " << fin.energy << " (" << finest.energy << ")");
    CHECK(fin.proof_rechecks >= 2);
    CHECK(fin.local_widenings - before.local_widenings == fin.proof_rechecks - 1);
    CHECK(fin.widened_faces - before.widened_faces == int64_t(faces) * (fin.proof_rechecks - 1));
    CHECK(fin.propagation_widenings == before.propagation_widenings);
    CHECK(check_graph_surface(rechecked.finest.space, rechecked.rounding.gamma).ok());

    // With the local widenings spent too, the region still infeasible is widened by the regional
    // widening (around every earlier widening) and checked again before that attempt's LP: it
    // used to be dropped there, and the LP solved unchecked.
    po.max_local_widenings = 0;
    const CoarseToFineMatcher none_left = finger_matcher(po);
    const CoarseToFineResult regional = none_left.run({}, &all);
    const LevelReport& reg = regional.levels.back();
    MESSAGE("rechecks " << reg.proof_rechecks << ", local widenings " << reg.local_widenings << ", margins "
                        << reg.margin_widenings << ", ring widenings " << reg.widenings);
    CHECK(reg.proof_rechecks == 2);
    CHECK(reg.local_widenings == before.local_widenings + 1);  // (the regional one)
    CHECK(reg.margin_widenings == before.margin_widenings + 1);
    CHECK(reg.widenings == before.widenings);
    CHECK(check_graph_surface(regional.finest.space, regional.rounding.gamma).ok());

    // With the regional widening given already, the ring widens: the region is kept for that
    // attempt's recheck too, and a face widened past --max-ring keeps its rings (it used to drop
    // to --max-ring, where a proved region's faces are infeasible again).
    LevelCheckpoint ringed = all;
    ringed.attempt.regional_done = true;
    ringed.attempt.extra.resize(faces, 0);
    REQUIRE(ringed.attempt.ring == 0);
    ringed.attempt.extra[0] = po.max_ring + 2;
    std::vector<LevelAttempt> seen;
    const CoarseToFineResult ring_up = none_left.run({}, &ringed, [&](const LevelCheckpoint& c) {
      if (!c.attempt.empty()) seen.push_back(c.attempt);
    });
    const LevelReport& up = ring_up.levels.back();
    CHECK(up.proof_rechecks == 2);
    CHECK(up.widenings == before.widenings + 1);
    REQUIRE_FALSE(seen.empty());
    CHECK(seen.front().ring == 1);
    CHECK(seen.front().extra[0] == po.max_ring + 1);  // (ring 1 + extra: the same max_ring + 2 rings)
    CHECK(seen.front().proof_faces == all.attempt.proof_faces);
    CHECK(check_graph_surface(ring_up.finest.space, ring_up.rounding.gamma).ok());
  }

  // Without its attempt, the same checkpoint widens again from the coarser Γ.
  LevelCheckpoint before = last;
  before.attempt = {};
  const CoarseToFineResult again = matcher.run({}, &before);
  CHECK(again.levels.back().energy == doctest::Approx(whole.levels.back().energy).epsilon(1e-12));

  // An attempt that does not fit its level is refused.
  LevelCheckpoint wrong = last;
  wrong.attempt.extra.pop_back();
  CHECK_THROWS_AS(matcher.run({}, &wrong), InvalidInputError);
  wrong = last;
  wrong.attempt.report.level = 0;
  CHECK_THROWS_AS(matcher.run({}, &wrong), InvalidInputError);
  // Files of earlier versions still load: the first (no attempt), the second (an attempt, no
  // rounding), the third (no stuck_restarts), the fourth (no lookahead chains).
  LevelCheckpoint marked = last;
  marked.attempt.report.stuck_restarts = 2;
  for (LevelReport& rep : marked.levels) rep.stuck_restarts = 1;
  save_checkpoint(file, marked);
  const LevelCheckpoint current = load_checkpoint(file);
  CHECK(current.attempt.report.stuck_restarts == 2);
  CHECK(current.levels.front().stuck_restarts == 1);
  detail::save_checkpoint_as(file, marked, 4);
  const LevelCheckpoint v4 = load_checkpoint(file);
  CHECK(v4.attempt.report.stuck_restarts == 2);
  CHECK(v4.levels.front().stuck_restarts == 1);
  CHECK(v4.attempt.rounding.ones == marked.attempt.rounding.ones);
  // The ninth (no steps of the rounding's fixings: one step), on a rounding made up for it.
  LevelCheckpoint stepped = marked;
  stepped.attempt.rounding = {.columns = 100, .rows = 50, .ones = {3, 7, 9}, .steps = {0, 0, 1}, .rounds = 2};
  detail::save_checkpoint_as(file, stepped, 9);
  const LevelCheckpoint v9 = load_checkpoint(file);
  CHECK(v9.attempt.rounding.ones == stepped.attempt.rounding.ones);
  CHECK(v9.attempt.rounding.steps.empty());
  CHECK(v9.attempt.rounding.step_count() == 1);
  save_checkpoint(file, stepped);
  CHECK(load_checkpoint(file).attempt.rounding.steps == stepped.attempt.rounding.steps);
  CHECK(load_checkpoint(file).attempt.rounding.step_count() == 2);
  // The twelfth keeps the later rounds' cap multiple; the eleventh has none (1).
  stepped.attempt.rounding.cap_scale = 4.0;
  save_checkpoint(file, stepped);
  CHECK(load_checkpoint(file).attempt.rounding.cap_scale == 4.0);
  detail::save_checkpoint_as(file, stepped, 11);
  CHECK(load_checkpoint(file).attempt.rounding.cap_scale == 1.0);
  CHECK(load_checkpoint(file).attempt.rounding.steps == stepped.attempt.rounding.steps);
  stepped.attempt.rounding.cap_scale = 0.5;  // no rounding's: refused
  save_checkpoint(file, stepped);
  CHECK_THROWS_AS(load_checkpoint(file), IoError);
  save_checkpoint(file, marked);
  std::string bytes;
  {
    std::ifstream in(file, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const size_t at = std::string("shapematch level checkpoint\n").size();
  REQUIRE(bytes[at] == 20);
  {  // The checksum (version 18 on): any byte changed, or the file cut short, is refused as damaged.
    auto refused = [&](const std::string& damaged) {
      std::ofstream(file, std::ios::binary) << damaged;
      std::string what;
      try {
        load_checkpoint(file);
      } catch (const IoError& e) {
        what = e.what();
      }
      return what;
    };
    for (size_t i : {at + 4, bytes.size() / 3, bytes.size() / 2, bytes.size() - 9, bytes.size() - 1}) {
      std::string damaged = bytes;
      damaged[i] = char(damaged[i] ^ 0x10);
      CHECK_MESSAGE(refused(damaged).find("checksum does not match") != std::string::npos, "byte " << i);
    }
    CHECK(refused(bytes.substr(0, bytes.size() - 1)).find("checksum") != std::string::npos);
    CHECK(refused(bytes.substr(0, bytes.size() - 8)).find("checksum") != std::string::npos);
    CHECK(refused(bytes.substr(0, at + 6)).find("cut short") != std::string::npos);
    // Its version field damaged (to an earlier version, which has no checksum, or a later one):
    // refused as damaged too, not as a file of that version.
    for (char version : {char(16), char(17), char(18), char(50)}) {
      std::string damaged = bytes;
      damaged[at] = version;
      CHECK_MESSAGE(refused(damaged).find("checksum does not match") != std::string::npos, int(version));
    }
    // Two words swapped (same bytes, other order) differ too.
    std::string swapped = bytes;
    const size_t mid = (bytes.size() / 16) * 8;
    std::swap_ranges(swapped.begin() + mid - 8, swapped.begin() + mid, swapped.begin() + mid);
    REQUIRE(swapped != bytes);
    CHECK(refused(swapped).find("checksum") != std::string::npos);
    CHECK(refused(bytes).empty());  // (and the file as written loads)
    // Version 17 has no checksum: read as it is, its last byte no checksum's.
    detail::save_checkpoint_as(file, marked, 17);
    CHECK(load_checkpoint(file).levels.back().gamma == marked.levels.back().gamma);
  }
  bytes[at] = 21;  // a later version than this build's
  std::ofstream(file, std::ios::binary) << bytes;
  CHECK_THROWS_AS(load_checkpoint(file), IoError);
  {  // The fifteenth: a carried start's rounding without a bound (NaN); the fourteenth has 15's layout.
    LevelCheckpoint carried = marked;
    carried.attempt.rounding = {.columns = 100, .rows = 50, .ones = {3, 7}, .steps = {0, 1}, .rounds = 1};
    carried.attempt.rounding.lower_bound = std::numeric_limits<double>::quiet_NaN();
    save_checkpoint(file, carried);
    CHECK(std::isnan(load_checkpoint(file).attempt.rounding.lower_bound));
    carried.attempt.rounding.lower_bound = 2.5;
    detail::save_checkpoint_as(file, carried, 14);
    CHECK(load_checkpoint(file).attempt.rounding.lower_bound == 2.5);
    CHECK(load_checkpoint(file).attempt.rounding.steps == carried.attempt.rounding.steps);
  }
  detail::save_checkpoint_as(file, marked, 1);
  const LevelCheckpoint v1 = load_checkpoint(file);
  CHECK(v1.attempt.empty());
  CHECK(v1.levels.size() == before.levels.size());
  CHECK(v1.levels.back().energy == last.levels.back().energy);
  CHECK(v1.levels.back().gamma == last.levels.back().gamma);
  CHECK(v1.levels.front().stuck_restarts == 0);
  detail::save_checkpoint_as(file, marked, 2);
  const LevelCheckpoint v2 = load_checkpoint(file);
  CHECK(v2.attempt.extra == a.extra);
  CHECK(v2.attempt.rounding.empty());
  detail::save_checkpoint_as(file, marked, 3);
  const LevelCheckpoint v3 = load_checkpoint(file);
  CHECK(v3.attempt.extra == a.extra);
  CHECK(v3.attempt.report.widened_faces == a.report.widened_faces);
  CHECK(v3.attempt.report.stuck_restarts == 0);
  CHECK(v3.levels.back().gamma == last.levels.back().gamma);
  CHECK_THROWS_AS(detail::save_checkpoint_as(file, marked, 21), InvalidInputError);
}

// The saves of a run made inside the first LP of level `level` (lp_checkpoint_seconds).
void matcher_run_saves(const CoarseToFineMatcher& matcher, int level, std::vector<LevelCheckpoint>& saves) {
  matcher.run({}, nullptr, [&](const LevelCheckpoint& c) {
    if (!c.attempt.empty() && !c.attempt.solving.empty() && c.attempt.report.level == level) saves.push_back(c);
  });
}

TEST_CASE("coarse to fine: a run gone on from inside a refined level's first LP starts that LP where it was") {
  // lp_checkpoint_seconds: the attempt is saved with its first LP's iterate and whole state as it
  // goes (here at every residual check); a run gone on from the last such save makes the rest of
  // that LP's iterations, exactly as the whole run did, and ends with its Γ (version 19); from the
  // iterate alone (version 18), the rest of it, not all of it, to a verified Γ of about the same
  // energy.
  CoarseToFineOptions o = small_levels();
  o.lookahead_levels = 0;
  o.price_widenings = 0;  // (one first LP at the finest level: the one saved)
  o.rounding.greedy_above = 0;  // (a few fixings a round: later rounds, which save nothing)
  o.rounding.greedy_margin = 2;
  o.lp_checkpoint_seconds = 1e-9;
  REQUIRE(CoarseToFineOptions{}.lp_checkpoint_seconds > 0.0);  // on by default
  const CoarseToFineMatcher matcher = finger_matcher(o);
  const int finest = static_cast<int>(matcher.x_levels().size()) - 1;
  std::vector<LevelCheckpoint> solving;
  std::vector<int64_t> firsts;  // the finest level's round-1 iterations, attempt by attempt
  int rounds_seen = 0;          // the finest level's rounds reported so far
  auto at_finest = [&](std::vector<int64_t>& into) {
    return [&, finest](const LevelReport& l, const RoundingRound& r) {
      if (l.level == finest && r.round == 1) into.push_back(r.iterations);
      if (l.level == finest) ++rounds_seen;
    };
  };
  const CoarseToFineResult whole = matcher.run(at_finest(firsts), nullptr, [&](const LevelCheckpoint& c) {
    if (!c.attempt.empty() && !c.attempt.solving.empty() && c.attempt.report.level == finest) {
      CHECK(rounds_seen == 0);  // saved inside round 1's LP only: not its pre-test, not a later round
      solving.push_back(c);
    }
  });
  REQUIRE(firsts.size() == 1);
  REQUIRE(solving.size() >= 3);
  CHECK(rounds_seen >= 1);  // (later rounds, where there are any, save none: test_rounding)
  const LevelCheckpoint& late = solving.back();
  const int64_t done = late.attempt.solving_iterations;
  CHECK_FALSE(late.attempt.solving_resolve);
  CHECK(done > 0);
  CHECK(done <= firsts[0]);
  CHECK(late.attempt.rounding.empty());
  // Through a file, and on from it.
  test::TempDir tmp;
  const std::string file = (tmp.path / "solving.ckpt").string();
  save_checkpoint(file, late);
  const LevelCheckpoint loaded = load_checkpoint(file);
  REQUIRE_FALSE(loaded.attempt.solving.empty());
  CHECK(loaded.attempt.solving_iterations == done);
  CHECK(loaded.attempt.solving_seconds == late.attempt.solving_seconds);
  CHECK(loaded.attempt.solving_seconds > 0.0);
  CHECK(loaded.attempt.solving_watched == late.attempt.solving_watched);
  {  // (the watch flag both ways)
    LevelCheckpoint unwatched = late;
    unwatched.attempt.solving_watched = !late.attempt.solving_watched;
    const std::string other = (tmp.path / "unwatched.ckpt").string();
    save_checkpoint(other, unwatched);
    CHECK(load_checkpoint(other).attempt.solving_watched == !late.attempt.solving_watched);
  }
  CHECK(loaded.attempt.solving.parts().y == late.attempt.solving.parts().y);
  // Its divergence watch as it stood (version 16), which the LP gone on from it watches on from.
  CHECK(loaded.attempt.solving_watch == late.attempt.solving_watch);
  // Its whole state (version 19), as it was, bit for bit.
  REQUIRE(late.attempt.solving_state != nullptr);
  REQUIRE(loaded.attempt.solving_state != nullptr);
  CHECK(*loaded.attempt.solving_state == *late.attempt.solving_state);
  CHECK(late.attempt.solving_state->iterations == done);
  {  // A state whose vectors disagree in size, or hold a value that is not finite: refused.
    for (int fault = 0; fault < 3; ++fault) {
      CAPTURE(fault);
      LevelCheckpoint broken = late;
      auto state = std::make_shared<SolverState>(*late.attempt.solving_state);
      if (fault == 0) state->y0.pop_back();
      if (fault == 1) state->x.back() = std::numeric_limits<double>::quiet_NaN();
      if (fault == 2) state->since_restart = -1;
      broken.attempt.solving_state = state;
      const std::string other = (tmp.path / "broken_state.ckpt").string();
      save_checkpoint(other, broken);
      CHECK_THROWS_WITH_AS(load_checkpoint(other), doctest::Contains("an LP state"), IoError);
    }
  }
  {  // A save after the watch's first window holds what that window saw (a fresh watch before).
    CoarseToFineOptions longer = o;
    longer.rounding.lp.tolerance = 1e-7;  // (a first LP past 512 iterations)
    std::vector<LevelCheckpoint> saves;
    matcher_run_saves(finger_matcher(longer), finest, saves);
    REQUIRE_FALSE(saves.empty());
    REQUIRE(saves.back().attempt.solving_watched);
    for (const LevelCheckpoint& c : saves) {
      const DivergenceWatchState& w = c.attempt.solving_watch;
      CHECK(w.windows == c.attempt.solving_iterations / detail::DivergenceWatch::kWindow);
      if (w.windows == 0) CHECK(w == DivergenceWatchState{});
    }
    CHECK(saves.back().attempt.solving_watch.windows >= 1);
    CHECK(saves.back().attempt.solving_watch.bound != 0.0);
  }
  {
    LevelCheckpoint near_stop = late;  // (a made-up state: every field is kept)
    DivergenceWatchState& w = near_stop.attempt.solving_watch;
    w = {.windows = 4, .creeping = 3, .climbing = 3, .primal = 0.0, .gap = 0.0, .bound = -1e9, .excess = {0.5, 1.5}};
    const std::string other = (tmp.path / "near_stop.ckpt").string();
    save_checkpoint(other, near_stop);
    CHECK(load_checkpoint(other).attempt.solving_watch == w);
    detail::save_checkpoint_as(other, near_stop, 15);  // (before 16: a fresh watch)
    CHECK(load_checkpoint(other).attempt.solving_watch == DivergenceWatchState{});
    w.climbing = 5;  // (more windows in a row than seen: refused)
    save_checkpoint(other, near_stop);
    CHECK_THROWS_AS(load_checkpoint(other), IoError);
  }
  // From the last save and from one halfway, through a file: exactly the whole run's rest.
  const LevelCheckpoint& halfway = solving[solving.size() / 2];
  for (const LevelCheckpoint* save : {&late, &halfway}) {
    const int64_t before = save->attempt.solving_iterations;
    CAPTURE(before);
    save_checkpoint(file, *save);
    std::vector<int64_t> rest;
    const LevelCheckpoint from = load_checkpoint(file);
    const CoarseToFineResult r = matcher.run(at_finest(rest), &from);  // (no checkpointing: no saves)
    REQUIRE(rest.size() == 1);
    // (Round 1 is reported with the iterations before the save: the LP's whole count.)
    MESSAGE("first LP: ", firsts[0], " iterations whole, ", before, " before the save and ", rest[0] - before,
            " after it");
    CHECK(rest[0] == firsts[0]);  // the rest of it, exactly
    const LevelReport& f = r.levels.back();
    CHECK(f.iterations == whole.levels.back().iterations);  // the report counts those before the save too
    CHECK(check_graph_surface(r.finest.space, r.rounding.gamma).ok());
    CHECK(f.energy == whole.levels.back().energy);
    CHECK(r.rounding.gamma == whole.rounding.gamma);
    // From the iterate alone (version 18 kept no state): the rest of it, not all of it.
    detail::save_checkpoint_as(file, *save, 18);
    const LevelCheckpoint v18 = load_checkpoint(file);
    CHECK(v18.attempt.solving_state == nullptr);
    std::vector<int64_t> rest18;
    const CoarseToFineResult r18 = matcher.run(at_finest(rest18), &v18);
    REQUIRE(rest18.size() == 1);
    const int64_t after18 = rest18[0] - before;  // (reported with those before the save)
    MESSAGE("from the iterate alone: ", after18, " iterations after it");
    CHECK(after18 < firsts[0]);
    CHECK(after18 <= firsts[0] - before / 2);  // (it goes on, not from zero)
    CHECK(r18.levels.back().iterations >= rest18[0]);
    CHECK(check_graph_surface(r18.finest.space, r18.rounding.gamma).ok());
    CHECK(r18.levels.back().energy == doctest::Approx(whole.levels.back().energy).epsilon(0.05));
  }
  {  // A longer first LP (past 512 iterations, restarts between the saves): from the state it ends
     // as in the whole run; from the iterate alone, at another point.
    CoarseToFineOptions longer = o;
    longer.rounding.lp.tolerance = 1e-7;
    const CoarseToFineMatcher lm = finger_matcher(longer);
    std::vector<int64_t> lfirst;
    std::vector<LevelCheckpoint> lsaves;
    const CoarseToFineResult lwhole = lm.run(at_finest(lfirst), nullptr, [&](const LevelCheckpoint& c) {
      if (!c.attempt.empty() && !c.attempt.solving.empty() && c.attempt.report.level == finest) lsaves.push_back(c);
    });
    REQUIRE(lfirst.size() == 1);
    REQUIRE(lsaves.size() >= 4);
    const LevelCheckpoint& mid = lsaves[lsaves.size() / 2];
    REQUIRE(mid.attempt.solving_state != nullptr);
    std::vector<int64_t> exact_rest, plain_rest;
    const CoarseToFineResult re = lm.run(at_finest(exact_rest), &mid);
    LevelCheckpoint bare = mid;
    bare.attempt.solving_state = nullptr;
    const CoarseToFineResult rp = lm.run(at_finest(plain_rest), &bare);
    REQUIRE(exact_rest.size() == 1);
    REQUIRE(plain_rest.size() == 1);
    MESSAGE("longer first LP: ", lfirst[0], " iterations whole, ", mid.attempt.solving_iterations,
            " before the save, in all ", exact_rest[0], " from its state, ", plain_rest[0], " from its iterate");
    CHECK(exact_rest[0] == lfirst[0]);  // (those before the save and the rest, exactly)
    CHECK(re.rounding.gamma == lwhole.rounding.gamma);
    CHECK(re.levels.back().energy == lwhole.levels.back().energy);
    CHECK(re.levels.back().lower_bound == lwhole.levels.back().lower_bound);  // (its LP's bound, bit for bit)
    // (What the state is for: from the iterate alone the LP ends at another point, its bound another.)
    CHECK(rp.levels.back().lower_bound != lwhole.levels.back().lower_bound);
    CHECK(check_graph_surface(rp.finest.space, rp.rounding.gamma).ok());
  }
  // Version 13 kept the iterate but neither its seconds nor its watch flag; 12 no iterate: the
  // same attempt from zero.
  detail::save_checkpoint_as(file, late, 13);
  CHECK(load_checkpoint(file).attempt.solving_iterations == done);
  CHECK(load_checkpoint(file).attempt.solving_seconds == 0.0);
  CHECK(load_checkpoint(file).attempt.solving_watched);
  detail::save_checkpoint_as(file, late, 12);
  CHECK(load_checkpoint(file).attempt.solving.empty());
  // Cut short inside the iterate: an error naming the file. (Version 17, without a checksum: the
  // reader's own length checks; from 18 on the checksum refuses it first.)
  for (uint32_t version : {17u, 18u}) {
    detail::save_checkpoint_as(file, late, version);
    std::ifstream in(file, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    in.close();
    std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes.substr(0, bytes.size() - 64);
    CHECK_THROWS_WITH_AS(load_checkpoint(file), doctest::Contains(file.c_str()), IoError);
    CHECK_THROWS_WITH_AS(load_checkpoint(file), doctest::Contains(version == 17 ? "cut short" : "checksum"), IoError);
  }
  // An LP under way at a negative count is refused.
  LevelCheckpoint broken = late;
  broken.attempt.solving_iterations = -1;
  save_checkpoint(file, broken);
  CHECK_THROWS_AS(load_checkpoint(file), IoError);
}

TEST_CASE("coarse to fine: a run gone on from the attempt after a pricing starts its re-solve warm, as the whole run") {
  // The attempt checkpointed right after a pricing widened the space keeps the priced LP's
  // iterate (version 13): a run gone on from it re-solves warm, capped at the cold solve's
  // iterations, exactly as the uninterrupted run did; from a version-12 file it solves cold.
  CoarseToFineOptions o = small_levels();
  o.lookahead_levels = 0;
  o.ring = 0;  // (the finest level's ring-0 space prices below zero one ring out)
  REQUIRE(o.price_widenings > 0);
  const CoarseToFineMatcher matcher = finger_matcher(o);
  std::vector<LevelCheckpoint> priced;
  const CoarseToFineResult whole = matcher.run({}, nullptr, [&](const LevelCheckpoint& c) {
    if (!c.attempt.empty() && !c.attempt.priced_from.empty()) priced.push_back(c);
  });
  REQUIRE_FALSE(priced.empty());
  const LevelCheckpoint& after = priced.back();
  const LevelAttempt& a = after.attempt;
  CHECK(a.report.price_widenings > 0);
  CHECK(a.cold_iterations > 0);
  CHECK(a.rounding.empty());

  test::TempDir tmp;
  const std::string file = (tmp.path / "priced.ckpt").string();
  save_checkpoint(file, after);
  const LevelCheckpoint loaded = load_checkpoint(file);
  REQUIRE_FALSE(loaded.attempt.priced_from.empty());
  CHECK(loaded.attempt.cold_iterations == a.cold_iterations);
  CHECK(loaded.attempt.cold_seconds == a.cold_seconds);
  {  // the same iterate back, part by part
    const CarriedIterate::Parts p = a.priced_from.parts(), q = loaded.attempt.priced_from.parts();
    CHECK_FALSE(p.keys.empty());
    CHECK(q.keys == p.keys);
    CHECK(q.values == p.values);
    CHECK(q.row_edge == p.row_edge);
    CHECK(q.y == p.y);
    CHECK(q.scale == p.scale);
  }
  const CoarseToFineResult r = matcher.run({}, &loaded);
  REQUIRE(r.levels.size() == whole.levels.size());
  const LevelReport& f = r.levels.back();
  const LevelReport& w = whole.levels.back();
  CHECK(f.variables == w.variables);
  CHECK(f.price_widenings == w.price_widenings);
  CHECK(f.iterations == w.iterations);  // the re-solve's as warm as it was
  CHECK(f.rounds == w.rounds);
  CHECK(f.energy == doctest::Approx(w.energy).epsilon(1e-12));
  CHECK(f.gamma == w.gamma);
  CHECK(check_graph_surface(r.finest.space, r.rounding.gamma).ok());

  // Version 12 kept no iterate: the same attempt, its re-solve cold (another iteration count).
  detail::save_checkpoint_as(file, after, 12);
  const LevelCheckpoint v12 = load_checkpoint(file);
  CHECK(v12.attempt.priced_from.empty());
  CHECK(v12.attempt.extra == a.extra);
  const CoarseToFineResult cold = matcher.run({}, &v12);
  CHECK(cold.levels.back().variables == w.variables);
  CHECK(check_graph_surface(cold.finest.space, cold.rounding.gamma).ok());

  // Parts that do not fit together are refused, in memory and in a file.
  CarriedIterate::Parts bad = a.priced_from.parts();
  bad.values.pop_back();
  CHECK_THROWS_AS(CarriedIterate::from_parts(bad), InvalidInputError);
  bad = a.priced_from.parts();
  bad.y.assign(bad.y.size(), std::numeric_limits<double>::quiet_NaN());
  CHECK_THROWS_AS(CarriedIterate::from_parts(bad), InvalidInputError);
  LevelCheckpoint broken = after;
  bad = a.priced_from.parts();
  std::swap(bad.row_edge.front(), bad.row_edge.back());
  REQUIRE(bad.row_edge.front() != bad.row_edge.back());
  CHECK_THROWS_AS(CarriedIterate::from_parts(bad), InvalidInputError);
  broken.attempt.cold_iterations = 0;
  save_checkpoint(file, broken);
  CHECK_THROWS_AS(load_checkpoint(file), IoError);

  // Saved inside that re-solve (lp_checkpoint_seconds), a run gone on from it goes on with the
  // re-solve's rules: from that iterate, capped at what is left of the cold solve's iterations.
  o.lp_checkpoint_seconds = 1e-9;
  const CoarseToFineMatcher saving = finger_matcher(o);
  std::vector<LevelCheckpoint> inside;
  const CoarseToFineResult again = saving.run({}, nullptr, [&](const LevelCheckpoint& c) {
    if (!c.attempt.empty() && c.attempt.solving_resolve) inside.push_back(c);
  });
  CHECK(again.levels.back().energy == doctest::Approx(w.energy).epsilon(1e-12));  // the saves change nothing
  REQUIRE_FALSE(inside.empty());
  const LevelAttempt& at = inside.back().attempt;
  CHECK(at.cold_iterations > 0);
  CHECK(at.priced_from.empty());  // (the re-solve had started from it)
  save_checkpoint(file, inside.back());
  const LevelCheckpoint inside_loaded = load_checkpoint(file);
  CHECK(inside_loaded.attempt.solving_resolve);
  const CoarseToFineResult on = saving.run({}, &inside_loaded);
  CHECK(check_graph_surface(on.finest.space, on.rounding.gamma).ok());
  CHECK(on.levels.back().energy == doctest::Approx(w.energy).epsilon(0.05));
  CHECK(on.levels.back().iterations <= w.iterations + 64);  // (not the re-solve again from zero)
}

TEST_CASE("coarse to fine: a run gone on from a checkpoint inside a rounding fixes its decisions and keeps its bound") {
  CoarseToFineOptions o = slow_finest_rounding();  // (a finest rounding of several rounds)
  o.lookahead_levels = 0;
  o.rounding.alternative_thresholds = {};  // (with them a level's rounding is not saved)
  o.rounding_checkpoint_seconds = 0.0;     // after every round
  const CoarseToFineMatcher matcher(fine_fingers().first, fine_fingers().second, o);
  const int levels = matcher.x_levels().size();
  std::vector<LevelCheckpoint> inside;
  const CoarseToFineResult whole = matcher.run({}, nullptr, [&](const LevelCheckpoint& c) {
    if (!c.attempt.rounding.empty() && int(c.levels.size()) == levels - 1) inside.push_back(c);
  });
  REQUIRE_FALSE(inside.empty());
  const LevelReport& finest = whole.levels.back();
  // The finest level's last attempt (the one that finished): a checkpoint after each of its rounds.
  std::vector<LevelCheckpoint> last;
  for (const LevelCheckpoint& c : inside)
    if (c.attempt.widenings() == inside.back().attempt.widenings()) last.push_back(c);
  REQUIRE(int(last.size()) == finest.rounds);
  REQUIRE(finest.rounds >= 2);
  for (size_t k = 0; k < last.size(); ++k) {
    const LevelAttempt::Rounding& g = last[k].attempt.rounding;
    CHECK(g.rounds == int(k) + 1);
    CHECK(g.columns == finest.variables);
    CHECK(g.rows == finest.constraints);
    CHECK(g.lower_bound == finest.lower_bound);
    CHECK(std::is_sorted(g.ones.begin(), g.ones.end()));
    CHECK(g.steps.size() == g.ones.size());
    if (k > 0) CHECK(g.iterations > last[k - 1].attempt.rounding.iterations);
  }
  CHECK(last.back().attempt.rounding.iterations == finest.iterations);

  // Gone on from after round 1: the same LP and bound, a Γ that keeps Theorem 1, with every
  // decision of round 1 in it, and the rounds counted on.
  test::TempDir tmp;
  const std::string file = (tmp.path / "rounding.ckpt").string();
  save_checkpoint(file, last.front());
  const LevelCheckpoint loaded = load_checkpoint(file);
  const LevelAttempt::Rounding& g = loaded.attempt.rounding;
  CHECK(g.ones == last.front().attempt.rounding.ones);
  CHECK(g.steps == last.front().attempt.rounding.steps);
  CHECK(g.rounds == 1);
  CHECK(g.columns == finest.variables);
  CHECK(g.lower_bound == finest.lower_bound);
  CHECK(g.iterations == last.front().attempt.rounding.iterations);
  CHECK(g.reference_iterations == last.front().attempt.rounding.reference_iterations);
  REQUIRE_FALSE(g.ones.empty());
  // The next round's warm start goes with it (lp_checkpoint_seconds, on by default), every time.
  REQUIRE_FALSE(g.warm.empty());
  for (const LevelCheckpoint& c : last) CHECK_FALSE(c.attempt.rounding.warm.empty());
  {
    const CarriedIterate::Parts p = last.front().attempt.rounding.warm.parts(), q = g.warm.parts();
    CHECK(q.keys == p.keys);
    CHECK(q.values == p.values);
    CHECK(q.row_edge == p.row_edge);
    CHECK(q.y == p.y);
  }
  {  // (Version 13 had none; nor the LP under way's seconds and watch flag.)
    detail::save_checkpoint_as(file, last.front(), 13);
    const LevelCheckpoint v13 = load_checkpoint(file);
    CHECK(v13.attempt.rounding.warm.empty());
    CHECK(v13.attempt.rounding.ones == g.ones);
    save_checkpoint(file, last.front());
  }
  int saved_again = 0;
  const CoarseToFineResult r = matcher.run({}, &loaded, [&](const LevelCheckpoint& c) {
    if (!c.attempt.rounding.empty()) {
      ++saved_again;
      CHECK(c.attempt.rounding.rounds >= 2);  // counted on from the checkpoint's
    }
  });
  REQUIRE(r.levels.size() == whole.levels.size());
  const LevelReport& on = r.levels.back();
  CHECK(on.variables == finest.variables);
  CHECK(on.lower_bound == finest.lower_bound);
  CHECK(on.rounds > 1);
  CHECK(on.rounds == 1 + int(r.rounding.rounds.size()));
  CHECK(saved_again == int(r.rounding.rounds.size()));
  CHECK(on.energy >= finest.lower_bound);
  CHECK(on.gap == doctest::Approx(relative_gap(on.energy, finest.lower_bound)));
  CHECK(check_graph_surface(r.finest.space, r.rounding.gamma).ok());
  CHECK(satisfies_exactly(r.finest.lp, r.rounding.gamma));
  for (int64_t j : g.ones) CHECK(std::binary_search(r.rounding.gamma.begin(), r.rounding.gamma.end(), j));
  {  // Without the warm start (a version-12 file) its round 1 starts cold: no fewer iterations.
    detail::save_checkpoint_as(file, last.front(), 12);
    const LevelCheckpoint v12 = load_checkpoint(file);
    CHECK(v12.attempt.rounding.warm.empty());
    CHECK(v12.attempt.rounding.ones == g.ones);
    // (Every part on PDHG, whose iterations a warm start saves; the LP is the same.)
    CoarseToFineOptions first_order = o;
    first_order.rounding.exact_below = 0;
    const CoarseToFineMatcher pdhg(fine_fingers().first, fine_fingers().second, first_order);
    const CoarseToFineResult cold = pdhg.run({}, &v12), warm = pdhg.run({}, &loaded);
    REQUIRE_FALSE(cold.rounding.rounds.empty());
    REQUIRE_FALSE(warm.rounding.rounds.empty());
    {  // The warm start is the one the next round had: gone on from this run's own checkpoint after
       // round 1, its round 1 does what the uninterrupted run's round 2 did.
      std::vector<LevelCheckpoint> own;
      const CoarseToFineResult whole_pdhg = pdhg.run({}, nullptr, [&](const LevelCheckpoint& c) {
        if (!c.attempt.rounding.empty() && int(c.levels.size()) == levels - 1) own.push_back(c);
      });
      REQUIRE(whole_pdhg.rounding.rounds.size() >= 2);
      REQUIRE_FALSE(own.empty());
      REQUIRE(own.front().attempt.rounding.rounds == 1);
      REQUIRE(own.front().attempt.widenings() == own.back().attempt.widenings());  // (the attempt that finished)
      const CoarseToFineResult on_pdhg = pdhg.run({}, &own.front());
      REQUIRE_FALSE(on_pdhg.rounding.rounds.empty());
      CHECK(on_pdhg.rounding.rounds.front().iterations == whole_pdhg.rounding.rounds[1].iterations);
      CHECK(on_pdhg.rounding.rounds.front().fixed_to_one == whole_pdhg.rounding.rounds[1].fixed_to_one);
    }
    MESSAGE("gone on from round 1: its first round ", cold.rounding.rounds.front().iterations, " iterations cold, ",
            warm.rounding.rounds.front().iterations, " warm");
    CHECK(warm.rounding.rounds.front().iterations < cold.rounding.rounds.front().iterations);
    CHECK(check_graph_surface(cold.finest.space, cold.rounding.gamma).ok());
    CHECK(check_graph_surface(warm.finest.space, warm.rounding.gamma).ok());
  }
  // The later rounds' cap multiple goes on where the saved rounding had got, and is saved again.
  LevelCheckpoint scaled = loaded;
  scaled.attempt.rounding.cap_scale = 4.0;
  int scaled_saves = 0;
  const CoarseToFineResult rs = matcher.run({}, &scaled, [&](const LevelCheckpoint& c) {
    if (c.attempt.rounding.empty()) return;
    ++scaled_saves;
    CHECK(c.attempt.rounding.cap_scale >= 4.0);
  });
  CHECK(scaled_saves > 0);
  REQUIRE_FALSE(rs.rounding.rounds.empty());
  CHECK(rs.rounding.rounds.front().cap_scale >= 4.0);
  CHECK(check_graph_surface(rs.finest.space, rs.rounding.gamma).ok());

  // A rounding of another LP (another build, say) is dropped: the attempt rounds afresh, as the
  // whole run's did.
  LevelCheckpoint other = last.front();
  other.attempt.rounding.rows += 1;
  const CoarseToFineResult afresh = matcher.run({}, &other);
  CHECK(afresh.levels.back().energy == doctest::Approx(finest.energy).epsilon(1e-12));
  CHECK(afresh.levels.back().gamma == finest.gamma);
  CHECK(afresh.levels.back().rounds == finest.rounds);
  // Decisions that name no column are refused, and steps that do not fit them.
  LevelCheckpoint wrong = last.front();
  wrong.attempt.rounding.ones.push_back(g.columns);
  CHECK_THROWS_AS(matcher.run({}, &wrong), InvalidInputError);
  wrong = last.front();
  wrong.attempt.rounding.steps.push_back(0);
  CHECK_THROWS_AS(matcher.run({}, &wrong), InvalidInputError);
}

TEST_CASE("coarse to fine: with lookahead_drop_stuck a chain stuck inside lookahead drops out and the other goes on") {
  // The dolphins of the lookahead test, gone on from after level 3 (both chains, decided at 4)
  // with one round per level: there the second chain's rounding cannot finish (stuck: out of
  // rounds) and, without dropping, widens and solves level 4 again; the first's finishes.
  const Mesh dx = lookahead_dolphin_x(), dy = lookahead_dolphin_y();
  CoarseToFineOptions o = both_chains_to_level_4();
  const CoarseToFineMatcher matcher(dx, dy, o);
  std::vector<LevelCheckpoint> saved;
  matcher.run({}, nullptr, [&](const LevelCheckpoint& c) {
    if (c.in_progress().empty() && !c.first_chain_ahead() && c.done() == 3) saved.push_back(c);
  });
  REQUIRE(saved.size() == 1);
  REQUIRE(saved[0].chains.size() == 2);
  o.rounding.max_total_rounds = 1;
  const CoarseToFineMatcher once(dx, dy, o);
  const CoarseToFineResult plain = once.run({}, &saved[0]);
  REQUIRE(plain.levels.size() == 5);
  const LevelReport& d = plain.levels[3];
  REQUIRE(std::isfinite(d.lookahead_other_energy));  // both chains found a Γ at level 4
  REQUIRE_FALSE(d.lookahead_switched);               // the first chain's, round once
  CHECK(d.stuck_widenings == 0);

  o.lookahead_drop_stuck = true;
  const CoarseToFineMatcher dropping(dx, dy, o);
  // The second chain drops out at level 4: the first goes on alone, with the same Γ.
  const CoarseToFineResult r = dropping.run({}, &saved[0]);
  REQUIRE(r.levels.size() == 5);
  CHECK(std::isnan(r.levels[3].lookahead_other_energy));
  CHECK(r.levels[3].lookahead_other_stuck);
  CHECK_FALSE(plain.levels[3].lookahead_other_stuck);
  CHECK_FALSE(r.levels[3].lookahead_switched);
  for (int l : {3, 4}) {
    CHECK(r.levels[l].gamma == plain.levels[l].gamma);
    CHECK(r.levels[l].energy == doctest::Approx(plain.levels[l].energy).epsilon(1e-12));
  }
  CHECK(check_graph_surface(r.finest.space, r.rounding.gamma).ok());
  CHECK(satisfies_exactly(r.finest.lp, r.rounding.gamma));

  // The stuck chain first: it drops out and the other goes on, as above.
  LevelCheckpoint swapped = saved[0];
  std::swap(swapped.chains[0], swapped.chains[1]);
  const CoarseToFineResult s = dropping.run({}, &swapped);
  REQUIRE(s.levels.size() == 5);
  CHECK(std::isnan(s.levels[3].lookahead_other_energy));
  CHECK(s.levels[3].lookahead_other_stuck);
  CHECK(s.levels[3].gamma == plain.levels[3].gamma);
  CHECK(s.rounding.energy == doctest::Approx(plain.rounding.energy).epsilon(1e-12));

  // Where the other chain then finds no Γ (a Γ of one product triangle leaves no surface near
  // it at any ring), the stuck chain solves level 4 again without dropping: widened, as without
  // lookahead_drop_stuck, to the Γ that was the other energy above.
  // (Stopped after level 4: the finest level, rounded once per LP, then widens for a minute.)
  // Each chain, alone at level 4 once the other has dropped out, saves its attempts as the only
  // chain.
  LevelCheckpoint broken = swapped;
  broken.chains[1].pending.back().gamma.resize(1);
  struct Stop {};
  std::optional<LevelCheckpoint> after;
  std::vector<LevelCheckpoint> alone;
  CHECK_THROWS_AS(dropping.run({}, &broken,
                               [&](const LevelCheckpoint& c) {
                                 if (c.done() == 3 && !c.in_progress().empty()) alone.push_back(c);
                                 if (c.done() < 4 || !c.in_progress().empty()) return;
                                 after = c;
                                 throw Stop{};
                               }),
                  Stop);
  REQUIRE(after);
  REQUIRE(after->levels.size() == 4);
  const LevelReport& a = after->levels[3];
  CHECK(a.stuck_widenings > 0);
  CHECK(a.energy == doctest::Approx(d.lookahead_other_energy).epsilon(1e-12));
  CHECK(a.lookahead_switched);  // the chain that did not lead at level 2
  CHECK(std::isnan(a.lookahead_other_energy));
  CHECK_FALSE(a.lookahead_other_stuck);  // (it was the one stuck; the other found no Γ)
  // (The first chain's attempts before it dropped out: both chains, the attempt on the first.)
  const auto single = std::find_if(alone.begin(), alone.end(), [](const LevelCheckpoint& c) { return c.chains.empty(); });
  REQUIRE(single != alone.end());
  for (auto c = alone.begin(); c != single; ++c) CHECK_FALSE(c->chains[0].attempt.empty());
  for (auto c = single; c != alone.end(); ++c) {
    CHECK(c->chains.empty());
    CHECK(c->levels.size() == 3);
    CHECK(c->attempt.report.level == 3);
  }
  // The last: the stuck chain's widened attempt, gone on from, ends level 4 as above.
  CHECK(alone.back().levels[2].gamma == swapped.chains[0].pending.back().gamma);
  std::optional<LevelCheckpoint> again;
  CHECK_THROWS_AS(dropping.run({}, &alone.back(),
                               [&](const LevelCheckpoint& c) {
                                 if (c.done() < 4 || !c.in_progress().empty()) return;
                                 again = c;
                                 throw Stop{};
                               }),
                  Stop);
  REQUIRE(again);
  CHECK(again->levels[3].gamma == a.gamma);
  CHECK(again->levels[3].energy == doctest::Approx(a.energy).epsilon(1e-12));
}

TEST_CASE("coarse to fine: the truth space is the identity at 0 rings and grows with them to the full space") {
  const Mesh m = lumpy_sphere(1, 3);
  std::vector<int> identity(m.num_vertices());
  std::iota(identity.begin(), identity.end(), 0);
  const ProductSpace full = ProductSpace::full(m, m);
  auto indices = [&](const std::vector<ProductTriangle>& list) {
    std::set<int64_t> s;
    for (const ProductTriangle& t : list) s.insert(full.index_in_full(t));
    CHECK(s.size() == list.size());  // no duplicates
    return s;
  };
  std::set<int64_t> expected;
  for (const ProductTriangle& t : identity_matching(m)) expected.insert(full.index_in_full(t));
  std::set<int64_t> last = indices(truth_space(m, m, identity, 0));
  CHECK(last == expected);
  for (int rings = 1; rings <= 4; ++rings) {
    CAPTURE(rings);
    const std::set<int64_t> now = indices(truth_space(m, m, identity, rings));
    CHECK(now.size() > last.size());
    CHECK(std::includes(now.begin(), now.end(), last.begin(), last.end()));
    last = now;
  }
  // Every corner within reach of its image (the mesh's diameter in edges is under 16), or no image.
  CHECK(int64_t(truth_space(m, m, identity, 16).size()) == full.size());
  CHECK(int64_t(truth_space(m, m, std::vector<int>(m.num_vertices(), -1), 0).size()) == full.size());
  // One vertex constrained: the full space less the product triangles that put it elsewhere.
  std::vector<int> one(m.num_vertices(), -1);
  one[0] = 0;
  int64_t off = 0;
  for (int64_t j = 0; j < full.size(); ++j) {
    const ProductTriangle t = full[j];
    for (int i = 0; i < 3; ++i)
      if (t.a[i] == 0 && t.b[i] != 0) {
        ++off;
        break;
      }
  }
  CHECK(int64_t(truth_space(m, m, one, 0).size()) == full.size() - off);
  CHECK_THROWS_AS(truth_space(m, m, {0, 1}, 1), InvalidInputError);
}

TEST_CASE("coarse to fine: a true map restricts the coarsest level, and there is no second start beside it") {
  const Mesh m = lumpy_sphere(2, 5);
  CoarseToFineOptions o;
  o.hierarchy.levels = 3;
  o.hierarchy.coarsest_faces = 20;
  o.hierarchy.second_faces = 40;
  o.ring = 0;
  o.rounding.solver = "clp-dual";
  o.truth.resize(m.num_vertices());
  std::iota(o.truth.begin(), o.truth.end(), 0);
  o.truth_rings = 0;
  const CoarseToFineMatcher matcher(m, m, o);
  REQUIRE(matcher.x_levels().size() == 3);
  REQUIRE(matcher.x_levels().levels[1].mesh.num_faces() == 40);
  const CoarseToFineResult r = matcher.run();
  // At 0 rings around the identity the coarsest space is the identity itself.
  CHECK(r.levels[0].variables == matcher.x_levels().levels[0].mesh.num_faces());
  for (const auto& l : r.levels) {
    CAPTURE(l.level);
    CHECK(l.energy == doctest::Approx(0.0).epsilon(1e-9));
    CHECK(std::isnan(l.second_start_energy));
  }
  const VertexMaps maps = vertex_maps(r.finest.space, r.rounding.gamma);
  for (int v = 0; v < m.num_vertices(); ++v) CHECK(maps.x_to_y[v] == v);
  CHECK_THROWS_AS(matcher.run({}, nullptr, [](const LevelCheckpoint&) {}), InvalidInputError);

  // A true map that sends every vertex to one vertex of Y leaves no closed matching at 0 rings.
  std::fill(o.truth.begin(), o.truth.end(), 0);
  const CoarseToFineMatcher collapsed(m, m, o);
  CHECK_THROWS_WITH_AS(collapsed.run(), doctest::Contains("within 0 rings of the true map"), InfeasibleError);
  o.truth.pop_back();
  CHECK_THROWS_AS(CoarseToFineMatcher(m, m, o), InvalidInputError);
  // (Options out of range are refused up front too: a recurring widening's ring past the cap.)
  CoarseToFineOptions beyond;
  for (int n : {0, 4}) {
    beyond.recurring_beyond = n;
    CHECK_THROWS_AS(CoarseToFineMatcher(m, m, beyond), InvalidInputError);
  }
  beyond.recurring_beyond = 1;
  CHECK_NOTHROW(CoarseToFineMatcher(m, m, beyond));
  for (int n : {0, 13}) {  // (a proof's own faces: up to 12)
    beyond.proof_beyond = n;
    CHECK_THROWS_AS(CoarseToFineMatcher(m, m, beyond), InvalidInputError);
  }
  beyond.proof_beyond = 12;
  CHECK_NOTHROW(CoarseToFineMatcher(m, m, beyond));
  CoarseToFineOptions scope;
  scope.suspicion_margin_scope = static_cast<CoarseToFineOptions::MarginScope>(7);
  CHECK_THROWS_AS(CoarseToFineMatcher(m, m, scope), InvalidInputError);
}

TEST_CASE("image split: an LP half the identity and half a rotation splits the images the rotation moves") {
  const Mesh m = shapes::octahedron();
  // Rotation by 180° about z: ±x and ±y swap signs, ±z stay.
  std::vector<int> turn(m.num_vertices(), -1), identity(m.num_vertices());
  std::iota(identity.begin(), identity.end(), 0);
  for (int v = 0; v < m.num_vertices(); ++v) {
    const Eigen::Vector3d p = m.vertices[v], q(-p.x(), -p.y(), p.z());
    for (int w = 0; w < m.num_vertices(); ++w)
      if ((m.vertices[w] - q).norm() < 1e-9) turn[v] = w;
  }
  REQUIRE(std::count(turn.begin(), turn.end(), -1) == 0);
  std::vector<ProductTriangle> list = truth_space(m, m, identity, 0), rotated = truth_space(m, m, turn, 0);
  REQUIRE(list.size() == size_t(m.num_faces()));
  REQUIRE(rotated.size() == size_t(m.num_faces()));
  list.insert(list.end(), rotated.begin(), rotated.end());
  const ProductSpace space = ProductSpace::from_list(m, m, list);
  const std::vector<double> half(list.size(), 0.5);
  std::vector<char> moved(m.num_vertices(), 0);
  for (int v = 0; v < m.num_vertices(); ++v) moved[v] = turn[v] != v;
  const int first_moved = int(std::find(moved.begin(), moved.end(), 1) - moved.begin());

  // At 0 rings each place is one vertex: a moved vertex's image is half at itself, half at its turn.
  const ImageSplit s = most_split_image(space, half, 0);
  CHECK(s.vertex == first_moved);  // (four tie; the lowest index)
  CHECK(s.split == doctest::Approx(0.5));
  REQUIRE(s.first.size() == size_t(m.num_vertices()));
  REQUIRE(s.second.size() == size_t(m.num_vertices()));
  CHECK(std::count(s.first.begin(), s.first.end(), 1) == 1);
  CHECK(s.first[s.vertex] + s.second[s.vertex] == 1);  // one place is itself, the other its turn
  CHECK(s.first[turn[s.vertex]] + s.second[turn[s.vertex]] == 1);
  // At 1 ring a vertex's ball holds all but its antipode, which is its turn: the same split.
  CHECK(most_split_image(space, half, 1).split == doctest::Approx(0.5));
  // At 2 rings one ball is the whole octahedron: no second place.
  const ImageSplit whole = most_split_image(space, half, 2);
  CHECK(whole.split == 0.0);
  CHECK(whole.second.empty());
  // The moved vertices skipped, the rest are not split.
  const ImageSplit rest = most_split_image(space, half, 0, moved);
  CHECK(rest.vertex >= 0);
  CHECK_FALSE(moved[rest.vertex]);
  CHECK(rest.split == 0.0);
  // Only the identity's values: nothing split.
  std::vector<double> one(list.size(), 0.0);
  std::fill(one.begin(), one.begin() + m.num_faces(), 1.0);
  CHECK(most_split_image(space, one, 0).split == 0.0);
  CHECK(most_split_image(space, std::vector<double>(list.size(), 0.0), 0).vertex == -1);
  CHECK_THROWS_AS(most_split_image(space, {0.5}, 0), InvalidInputError);

  // Kept at its own place, the vertex keeps the identity's triangles and loses the rotation's
  // through it; at its turn's, the other way round.
  const int v = s.vertex;
  std::vector<char> at_self(m.num_vertices(), 0), at_turn(m.num_vertices(), 0);
  at_self[v] = 1;
  at_turn[turn[v]] = 1;
  int through = 0;
  for (const std::array<int, 3>& f : m.faces) through += std::count(f.begin(), f.end(), v);
  for (const std::vector<char>* place : {&at_self, &at_turn}) {
    const std::vector<ProductTriangle> kept = keep_images(space, v, *place);
    CHECK(kept.size() == list.size() - through);
    for (const ProductTriangle& t : kept)
      for (int i = 0; i < 3; ++i)
        if (t.a[i] == v) CHECK((*place)[t.b[i]]);
  }
  CHECK(keep_images(space, v, std::vector<char>(m.num_vertices(), 1)).size() == list.size());
}

TEST_CASE("coarse to fine: the coarsest dive keeps its bound and ends below a fractional LP's plain rounding") {
  // A single level (the coarsest is the finest: its LP and rounding are the result's), on a pair
  // whose LP is fractional there: the plain rounding ends 9 % above the bound.
  CoarseToFineOptions o;
  o.hierarchy.levels = 1;
  o.rounding.solver = "pdhg-cpu";
  o.branch_gap = 0.0;
  o.branch_min_split = 1e-6;
  const Mesh x = decimate(shapes::dolphin(20, 0), 40), y = decimate(shapes::dolphin(-20, 40), 44);
  const CoarseToFineResult plain = CoarseToFineMatcher(x, y, o).run();
  o.branch_depth = 2;
  const CoarseToFineMatcher diving(x, y, o);  // (r.finest points into its levels)
  const CoarseToFineResult r = diving.run();
  const LevelReport& p = plain.levels[0];
  const LevelReport& b = r.levels[0];
  MESSAGE("plain ", p.energy, " (bound ", p.lower_bound, "), dive ", b.energy, ", ", b.branch_roundings,
          " sides rounded, least ", b.branch_energy);
  CHECK(p.branch_roundings == 0);
  CHECK(std::isnan(p.branch_energy));
  CHECK_FALSE(p.branch_kept);
  REQUIRE(p.gap > 0.05);
  CHECK(b.lower_bound == p.lower_bound);  // the full space's
  CHECK(b.variables == p.variables);
  CHECK(b.branch_roundings >= 1);
  CHECK(b.branch_kept);
  CHECK(b.energy < p.energy);
  CHECK(b.energy == b.branch_energy);
  CHECK(b.gap == doctest::Approx(relative_gap(b.energy, b.lower_bound)));
  CHECK(check_graph_surface(r.finest.space, r.rounding.gamma).ok());
  CHECK(r.rounding.energy == doctest::Approx(b.energy).epsilon(1e-12));
  CHECK(r.rounding.lower_bound == p.lower_bound);
  double sum = 0.0;
  for (int64_t j : r.rounding.gamma) sum += r.finest.energy[j];
  CHECK(sum == doctest::Approx(b.energy).epsilon(1e-9));
  // The branch numbers go through a checkpoint (version 8), not through a version-7 one.
  test::TempDir tmp;
  const std::string file = (tmp.path / "branch.ckpt").string();
  LevelCheckpoint c;
  c.levels = r.levels;
  save_checkpoint(file, c);
  const LevelReport loaded = load_checkpoint(file).levels[0];
  CHECK(loaded.branch_roundings == b.branch_roundings);
  CHECK(loaded.branch_energy == b.branch_energy);
  CHECK(loaded.branch_kept);
  detail::save_checkpoint_as(file, c, 7);
  CHECK(std::isnan(load_checkpoint(file).levels[0].branch_energy));
  // Where the plain Γ is within branch_gap of its bound there is no dive.
  o.branch_gap = 1.0;
  const CoarseToFineResult none = CoarseToFineMatcher(x, y, o).run();
  CHECK(none.levels[0].branch_roundings == 0);
  CHECK(none.levels[0].gamma == p.gamma);
}

TEST_CASE("coarse to fine: the divergence bound is the factor times the coarser energy while a ring is left") {
  using detail::divergence_bound;
  const detail::FirstLpState ring_left{.refined = true, .ring_left = true};
  CHECK(divergence_bound(ring_left, 2.0, 3.0) == 6.0);
  CHECK(std::isinf(divergence_bound(ring_left, 0.0, 3.0)));  // off
  CHECK(std::isinf(divergence_bound(ring_left, 2.0, std::nan(""))));  // no coarser level
  CHECK(std::isinf(divergence_bound(ring_left, 2.0, 0.0)));  // (nothing to scale)
  detail::FirstLpState last = ring_left;
  last.ring_left = false;  // at the last ring a stop could end the level: none
  last.widenings_left = true;
  CHECK(std::isinf(divergence_bound(last, 2.0, 3.0)));
  CHECK(CoarseToFineOptions{}.divergence_bound_factor == 2.0);
  CoarseToFineOptions o;
  o.divergence_bound_factor = -1.0;
  CHECK_THROWS_AS(CoarseToFineMatcher(shapes::octahedron(), shapes::octahedron(), o), InvalidInputError);
}

TEST_CASE("coarse to fine: watched first LPs stop where their bound passes the factor; the run still ends") {
  // Under a factor of 10⁻⁶ every watched first LP whose certified bound turns positive stops at
  // its window's end, feasible or not: the levels widen more, and still end with a Γ (at the
  // last ring no bound applies). At the default the finger pair's LPs stay far below it.
  auto run = [](double factor) {
    CoarseToFineOptions o = small_levels();
    o.divergence_bound_factor = factor;
    const CoarseToFineMatcher matcher = finger_matcher(o);
    const CoarseToFineResult r = matcher.run();
    CHECK(check_graph_surface(r.finest.space, r.rounding.gamma).ok());
    int widenings = 0;
    for (const LevelReport& l : r.levels) widenings += l.widenings + l.local_widenings;
    return std::pair{widenings, r.levels.back().energy};
  };
  const auto [off_widenings, off_energy] = run(0.0);
  const auto [tiny_widenings, tiny_energy] = run(1e-6);
  const auto [default_widenings, default_energy] = run(CoarseToFineOptions{}.divergence_bound_factor);
  MESSAGE("widenings: off " << off_widenings << ", factor 1e-6 " << tiny_widenings << ", default "
                            << default_widenings);
  CHECK(tiny_widenings > off_widenings);
  CHECK(std::isfinite(tiny_energy));
  CHECK(default_widenings == off_widenings);
  CHECK(default_energy == off_energy);
}

TEST_CASE("coarse to fine: a rounding's round under way is saved as its warm start, and a run goes on from there") {
  // lp_checkpoint_seconds (here at every residual check): besides the checkpoint after round k,
  // saves inside round k + 1 with the same decisions and that round's iterate so far as the warm
  // start; a run gone on from the last of them redoes less of round k + 1 than from round k's.
  CoarseToFineOptions o = slow_finest_rounding();
  o.lookahead_levels = 0;
  o.rounding.alternative_thresholds = {};
  o.rounding_checkpoint_seconds = 0.0;
  o.rounding.later_feasibility_iterations = 0;  // (the costed solves alone: what a save shortens)
  o.rounding.exact_below = 0;                   // (every round on PDHG, which saves)
  o.rounding.search_below = 0;
  o.lp_checkpoint_seconds = 1e-9;
  const CoarseToFineMatcher matcher(fine_fingers().first, fine_fingers().second, o);
  const int levels = matcher.x_levels().size();
  std::vector<LevelCheckpoint> inside;  // the finest level's rounding checkpoints, in order
  const CoarseToFineResult whole = matcher.run({}, nullptr, [&](const LevelCheckpoint& c) {
    if (!c.attempt.rounding.empty() && int(c.levels.size()) == levels - 1) inside.push_back(c);
  });
  REQUIRE_FALSE(inside.empty());
  // The last round k with saves inside round k + 1: the first save of k is after it, the last inside.
  const LevelCheckpoint *after = nullptr, *under_way = nullptr;
  for (size_t i = 1; i < inside.size(); ++i) {
    const auto &a = inside[i - 1].attempt, &b = inside[i].attempt;
    if (a.widenings() != b.widenings() || a.rounding.rounds != b.rounding.rounds) continue;
    CHECK(b.rounding.ones == a.rounding.ones);  // the same decisions
    CHECK(b.rounding.iterations == a.rounding.iterations);
    CHECK_FALSE(b.rounding.warm.empty());
    CHECK(b.rounding.warm.primal_weight() > 0.0);  // the part under way's ω
    under_way = &inside[i];
    size_t first = i - 1;
    while (first > 0 && inside[first - 1].attempt.rounding.rounds == a.rounding.rounds &&
           inside[first - 1].attempt.widenings() == a.widenings())
      --first;
    after = &inside[first];
  }
  REQUIRE(under_way != nullptr);
  auto first_round = [&](const LevelCheckpoint& from, int64_t& iterations) {
    test::TempDir tmp;
    const std::string file = (tmp.path / "c.ckpt").string();
    save_checkpoint(file, from);
    const LevelCheckpoint loaded = load_checkpoint(file);
    REQUIRE_FALSE(loaded.attempt.rounding.warm.empty());
    iterations = -1;
    int first_shown = -1;
    const CoarseToFineResult r = matcher.run([&](const LevelReport& l, const RoundingRound& q) {
      if (l.level == levels - 1 && iterations < 0) iterations = q.iterations, first_shown = q.round;
    }, &loaded);
    // Its rounds are reported as the level's: on from the checkpoint's, not from 1 again.
    CHECK(first_shown == from.attempt.rounding.rounds + 1);
    // (Theorem 1's conditions; on this pair at ring 0 with every round on PDHG the whole run's Γ
    // is not continuous either.)
    CHECK(satisfies_exactly(r.finest.lp, r.rounding.gamma));
    const GraphSurfaceCheck g = check_graph_surface(r.finest.space, r.rounding.gamma);
    CHECK(g.covers_x);
    CHECK(g.covers_y);
    CHECK(g.orientation);
    for (int64_t j : from.attempt.rounding.ones)
      CHECK(std::binary_search(r.rounding.gamma.begin(), r.rounding.gamma.end(), j));
  };
  int64_t from_after = 0, from_inside = 0;
  first_round(*after, from_after);
  first_round(*under_way, from_inside);
  MESSAGE("round " << after->attempt.rounding.rounds + 1 << " gone on from the checkpoint after round "
                   << after->attempt.rounding.rounds << ": " << from_after << " iterations; from its last save inside: "
                   << from_inside);
  CHECK(from_inside < from_after);
  // At the default cadence (600 s) a test-sized rounding saves only after its rounds.
  CHECK(CoarseToFineOptions{}.lp_checkpoint_seconds == 600.0);
}
