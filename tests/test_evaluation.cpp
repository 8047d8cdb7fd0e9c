#include "shapematch/evaluation.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/geodesic.hpp"
#include "shapematch/json.hpp"
#include "shapematch/shapes.hpp"

#include "test_helpers.hpp"

#include <doctest/doctest.h>
#include <spdlog/fmt/fmt.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <sstream>
#include <numeric>
#include <random>
#include <sys/wait.h>

using namespace shapematch;
namespace fs = std::filesystem;

namespace {

// A fresh directory per test case: ctest runs the cases as parallel processes.
fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("shapematch_eval_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

fs::path write(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

std::vector<int> identity_map(int n) {
  std::vector<int> m(n);
  std::iota(m.begin(), m.end(), 0);
  return m;
}

// The vertex of `m` nearest to p (tests only: linear search).
int nearest(const Mesh& m, const Eigen::Vector3d& p) {
  int best = 0;
  for (int v = 1; v < m.num_vertices(); ++v)
    if ((m.vertices[v] - p).squaredNorm() < (m.vertices[best] - p).squaredNorm()) best = v;
  return best;
}

// The mirror image of a mesh in the plane x = 0, faces reversed so that they face outwards again.
Mesh mirrored(const Mesh& m) {
  std::vector<Eigen::Vector3d> v;
  for (const auto& p : m.vertices) v.emplace_back(-p.x(), p.y(), p.z());
  std::vector<std::array<int, 3>> f;
  for (const auto& t : m.faces) f.push_back({t[0], t[2], t[1]});
  return make_mesh(v, f, "mirrored");
}

template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

using Run = test::CliRun;
using test::json_number;
using test::run_cli;

int count_lines(const fs::path& p) {
  std::ifstream in(p);
  return static_cast<int>(std::count(std::istreambuf_iterator<char>(in), {}, '\n'));
}

}  // namespace

TEST_CASE("evaluation: the identity map has error 0, AUC 1 and no flips, also onto a rotated copy") {
  std::mt19937 rng(4);
  const Mesh x = shapes::bent_finger(10, 12, 8);
  const Mesh y = test::deformed(shapes::bent_finger(70, 12, 8), [&, r = test::random_rotation(rng)](const auto& p) {
    return Eigen::Vector3d(r * p);
  });
  const GeodesicErrors e = geodesic_errors(y, identity_map(x.num_vertices()),
                                           identity_ground_truth(x.num_vertices(), y.num_vertices()));
  CHECK(e.points == x.num_vertices());
  CHECK(e.mean == 0.0);
  CHECK(e.median == 0.0);
  CHECK(e.auc == 1.0);
  CHECK(e.geodesic_solves == 0);
  REQUIRE(e.pck.size() == 26);
  CHECK(e.pck.front()[0] == 0.0);
  CHECK(e.pck.back()[0] == 0.25);
  for (const auto& [t, fraction] : e.pck) CHECK(fraction == 1.0);
  const OrientationFlips f = count_orientation_flips(x, y, identity_map(x.num_vertices()));
  CHECK(f.faces == x.num_faces());
  CHECK(f.flips == 0);
  CHECK(f.degenerate == 0);
}

TEST_CASE("evaluation: the antipodal map on a sphere has error sqrt(pi)/2 and reverses every face") {
  // d(p, -p) = π r and area 4π r², so the normalised error is π r / √(4π r²) = √π / 2 for any r.
  const Mesh s = shapes::icosphere(4, 3.0);
  std::vector<int> antipode(s.num_vertices());
  for (int v = 0; v < s.num_vertices(); ++v) {
    antipode[v] = nearest(s, -s.vertices[v]);
    REQUIRE((s.vertices[antipode[v]] + s.vertices[v]).norm() < 1e-9);  // the icosphere is centrally symmetric
  }
  // Every 8th vertex. The antipode is the march's worst case (all geodesics meet there): measured
  // 1.2 % short at 2562 vertices (2.0 % at 642).
  GroundTruth some;
  for (int v = 0; v < s.num_vertices(); v += 8) some.push_back({v, v});
  EvaluationOptions two_threads;
  two_threads.threads = 2;
  const GeodesicErrors e = geodesic_errors(s, antipode, some, two_threads);
  const double expected = std::sqrt(std::numbers::pi) / 2;
  MESSAGE("antipodal map: mean " << e.mean << ", expected " << expected);
  CHECK(std::abs(e.mean - expected) < 0.02 * expected);
  CHECK(std::abs(e.median - expected) < 0.02 * expected);
  CHECK(e.auc == 0.0);
  CHECK(e.points == static_cast<int>(some.size()));
  CHECK(e.geodesic_solves == static_cast<int>(some.size()));
  // p ↦ -p reverses orientation on the sphere.
  const OrientationFlips f = count_orientation_flips(s, s, antipode);
  CHECK(f.flips == s.num_faces());
  CHECK(f.degenerate == 0);
}

TEST_CASE("evaluation: mirror maps flip (nearly) every face, a collapse is degenerate, not flipped") {
  // The finger has no mirror symmetry: its mirror image is another shape, matched vertex to vertex.
  const Mesh x = shapes::bent_finger(40, 12, 8);
  const OrientationFlips f = count_orientation_flips(x, mirrored(x), identity_map(x.num_vertices()));
  CHECK(f.flips == x.num_faces());
  CHECK(f.degenerate == 0);

  // A lopsided sphere reflected in z = 0 and snapped to its nearest vertex: not a symmetry, so
  // some faces collapse, and the rest are mirrored.
  const Mesh s = test::deformed(shapes::icosphere(3), [](const auto& p) {
    return Eigen::Vector3d(p.x() + 0.3 * p.y() * p.y(), p.y(), p.z() + 0.2 * p.z() * p.z());
  });
  std::vector<int> reflect(s.num_vertices());
  for (int v = 0; v < s.num_vertices(); ++v)
    reflect[v] = nearest(s, Eigen::Vector3d(s.vertices[v].x(), s.vertices[v].y(), -s.vertices[v].z()));
  const OrientationFlips g = count_orientation_flips(s, s, reflect);
  MESSAGE("snapped reflection: " << g.flips << " flipped, " << g.degenerate << " degenerate of " << g.faces);
  CHECK(g.flips + g.degenerate == s.num_faces());
  CHECK(g.flips > 0.8 * s.num_faces());

  const OrientationFlips c = count_orientation_flips(x, x, std::vector<int>(x.num_vertices(), 3));
  CHECK(c.flips == 0);
  CHECK(c.degenerate == x.num_faces());
  CHECK_THROWS_AS(count_orientation_flips(x, x, {0, 1}), InvalidInputError);
  CHECK_THROWS_AS(count_orientation_flips(x, s, std::vector<int>(x.num_vertices(), s.num_vertices())),
                  InvalidInputError);
}

TEST_CASE("evaluation: errors agree with direct geodesic distances, marched from either side") {
  const Mesh y = shapes::bent_finger(70, 10, 8);
  const int n = y.num_vertices();
  const GeodesicDistance geo(y);
  const double scale = 1 / std::sqrt(surface_area(y));
  std::mt19937 rng(9);

  // Few distinct predictions: marched from the predictions.
  std::vector<int> phi(n);
  for (int& p : phi) p = static_cast<int>(rng() % 3);
  const GroundTruth identity = identity_ground_truth(n, n);
  GeodesicErrors e = geodesic_errors(y, phi, identity);
  CHECK(e.geodesic_solves == 3);
  REQUIRE(e.errors.size() == static_cast<size_t>(n));
  for (int k = 0; k < n; ++k) CHECK(e.errors[k] == doctest::Approx(geo.from_vertex(phi[k])[k] * scale).epsilon(1e-12));

  // Few distinct true vertices: marched from them.
  GroundTruth few;
  for (int k = 0; k < n; ++k) few.push_back({k, 5 + k % 2});
  for (int& p : phi) p = static_cast<int>(rng() % n);
  e = geodesic_errors(y, phi, few);
  CHECK(e.geodesic_solves == 2);
  for (int k = 0; k < n; ++k) {
    const double expected = phi[k] == few[k].y ? 0.0 : geo.from_vertex(few[k].y)[phi[k]] * scale;
    CHECK(e.errors[k] == doctest::Approx(expected).epsilon(1e-12));
  }
  std::vector<double> sorted = e.errors;
  std::sort(sorted.begin(), sorted.end());
  const double median = n % 2 ? sorted[n / 2] : (sorted[n / 2 - 1] + sorted[n / 2]) / 2;
  CHECK(e.median == doctest::Approx(median));
  CHECK(e.mean == doctest::Approx(std::accumulate(sorted.begin(), sorted.end(), 0.0) / n));

  // X vertices without an image (decimated away) are left out; nothing left is an error.
  std::vector<int> partial(n, -1);
  partial[4] = 4;
  partial[7] = 9;
  e = geodesic_errors(y, partial, identity);
  CHECK(e.points == 2);
  CHECK(e.errors[0] == 0.0);
  CHECK(e.errors[1] > 0.0);
  CHECK(e.pair == std::vector<size_t>{4, 7});  // (each error's ground-truth pair)
  CHECK_THROWS_AS(geodesic_errors(y, std::vector<int>(n, -1), identity), InvalidInputError);
  CHECK_THROWS_AS(geodesic_errors(y, std::vector<int>(n, n), identity), InvalidInputError);
  CHECK_THROWS_AS(geodesic_errors(y, std::vector<int>(n - 1, 0), identity), InvalidInputError);
}

TEST_CASE("evaluation: error regions are connected parts above the threshold, mirrored where the symmetric truth fits") {
  // A torus of 24 rings of 6 vertices (vertex 6i + j on ring i), ground truth on the even rings
  // only, as after decimation. Rings 2 and 4 mapped 0.5 off but near their mirror image, rings 14
  // and 16 0.3 off and not, the other even rings 0.01 off.
  const Mesh x = shapes::torus(24, 6);
  GroundTruth truth;
  std::vector<double> err, sym;
  for (int i = 0; i < 24; i += 2)
    for (int j = 0; j < 6; ++j) {
      truth.push_back({6 * i + j, 6 * i + j});
      err.push_back(i == 2 || i == 4 ? 0.5 : i == 14 || i == 16 ? 0.3 : 0.01);
      sym.push_back(i == 2 || i == 4 ? 0.05 : 0.4);
    }
  truth.push_back({12, 12});  // a second pair on vertex 12 (ring 2)
  err.push_back(0.5);
  sym.push_back(0.05);
  truth.push_back({7, 7});  // a pair left out (ring 1: no image) changes nothing
  err.push_back(std::numeric_limits<double>::quiet_NaN());
  sym.push_back(std::numeric_limits<double>::quiet_NaN());
  const double total = 13 * 0.5 + 12 * 0.3 + 8 * 6 * 0.01;

  std::vector<ErrorRegion> r = error_regions(x, truth, err, sym, 0.1);
  // Ring 3 (no ground truth) takes its neighbours' verdict and joins rings 2 and 4; the rated rings
  // 6–12, below, keep the two parts apart (rings 5 and 13 borrow from 4 and 12, the lower-numbered
  // of their rated neighbours, but hold no points of their own).
  REQUIRE(r.size() == 2);
  std::vector<int> a, b;
  for (int j = 0; j < 6; ++j) a.push_back(12 + j), b.push_back(84 + j);
  for (int j = 0; j < 6; ++j) a.push_back(24 + j), b.push_back(96 + j);
  CHECK(r[0].x_vertices == a);
  CHECK(r[0].vertices == 12);
  CHECK(r[0].points == 13);
  CHECK(r[0].mean_error == doctest::Approx(0.5));
  CHECK(r[0].mean_symmetric_error == doctest::Approx(0.05));
  CHECK(r[0].mirrored);
  CHECK(r[0].error_share == doctest::Approx(13 * 0.5 / total));
  CHECK(r[1].x_vertices == b);
  CHECK(r[1].points == 12);
  CHECK(r[1].mean_error == doctest::Approx(0.3));
  CHECK_FALSE(r[1].mirrored);
  CHECK(r[1].error_share == doctest::Approx(12 * 0.3 / total));
  // Ring 15's vertices 0.05 off: rated below, they split the second part in two.
  for (int j = 0; j < 6; ++j) {
    truth.push_back({90 + j, 90 + j});
    err.push_back(0.05);
    sym.push_back(0.05);
  }
  r = error_regions(x, truth, err, sym, 0.1);
  REQUIRE(r.size() == 3);
  CHECK(r[1].vertices == 6);
  CHECK(r[2].vertices == 6);
  // A threshold above every vertex's mean: none; without the symmetric truth: never mirrored.
  CHECK(error_regions(x, truth, err, sym, 1.0).empty());
  r = error_regions(x, truth, err, {}, 0.1);
  REQUIRE(r.size() == 3);
  CHECK_FALSE(r[0].mirrored);
  CHECK(r[0].mean_symmetric_error == -1);
  CHECK_THROWS_AS(error_regions(x, truth, std::vector<double>(3, 0.0), {}, 0.1), InvalidInputError);
  std::vector<double> other = sym;  // NaN where the direct errors have none: not the same pairs
  other[0] = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_AS(error_regions(x, truth, err, other, 0.1), InvalidInputError);

  // A vertex without an error next to several rated ones takes the lowest-numbered one's verdict,
  // and that decides whether two parts join through it. Octahedron: vertex 0 unrated, its
  // neighbours 2, 3, 4, 5; 2 and 3 (opposite, apart) join through it where 2 is above the
  // threshold, 4 and 5 do not where 2 is below.
  const Mesh o = shapes::octahedron();
  const GroundTruth six = {{1, 1}, {2, 2}, {3, 3}, {4, 4}, {5, 5}};
  r = error_regions(o, six, {0.0, 0.5, 0.5, 0.0, 0.0}, {}, 0.1);
  REQUIRE(r.size() == 1);
  CHECK(r[0].x_vertices == std::vector<int>{2, 3});
  r = error_regions(o, six, {0.0, 0.0, 0.0, 0.5, 0.5}, {}, 0.1);
  REQUIRE(r.size() == 2);
  CHECK(r[0].vertices == 1);
  CHECK(r[1].vertices == 1);

  // Per vertex: the mean of its pairs, NaN without any.
  const std::vector<double> mean = vertex_mean_errors(x.num_vertices(), truth, err);
  CHECK(mean[12] == doctest::Approx(0.5));
  CHECK(std::isnan(mean[7]));
  CHECK(std::isnan(mean[18]));  // (ring 3)

  // Pair by pair: the pairs above the threshold whose symmetric error is under half theirs.
  CHECK(mirrored_error_share({0.4, 0.2, 0.05, std::nan("")}, {0.1, 0.15, 0.0, 0.0}, 0.1) == doctest::Approx(0.4 / 0.65));
  CHECK(mirrored_error_share({0.0, 0.0}, {0.0, 0.0}, 0.1) == 0.0);
  CHECK_THROWS_AS(mirrored_error_share({0.1}, {}, 0.1), InvalidInputError);

  // pair_errors spreads a GeodesicErrors over the pairs, NaN where X's vertex has no image.
  GeodesicErrors ge;
  ge.errors = {0.25, 0.5};
  ge.pair = {0, 2};
  const std::vector<double> spread = pair_errors(3, ge);
  REQUIRE(spread.size() == 3);
  CHECK(spread[0] == 0.25);
  CHECK(std::isnan(spread[1]));
  CHECK(spread[2] == 0.5);
  CHECK_THROWS_AS(pair_errors(2, ge), InvalidInputError);
  ge.pair = {0};
  CHECK_THROWS_AS(pair_errors(3, ge), InvalidInputError);
}

TEST_CASE("evaluation: PCK curve and its area") {
  const auto pck = pck_curve({0.0, 0.005, 0.045, 0.3}, 0.25, 0.01);
  REQUIRE(pck.size() == 26);
  CHECK(pck[0][1] == 0.25);
  CHECK(pck[1][1] == 0.5);
  CHECK(pck[4][1] == 0.5);
  CHECK(pck[5][1] == 0.75);
  CHECK(pck[25][1] == 0.75);
  // Trapezoids: 0.00375 + 3 · 0.005 + 0.00625 + 0.2 · 0.75 = 0.175 over a width of 0.25.
  CHECK(pck_auc(pck) == doctest::Approx(0.7));
  CHECK_THROWS_AS(pck_curve({0.1}, 0.25, 0.0), InvalidInputError);
}

TEST_CASE("evaluation: ground-truth readers parse the data set formats and reject malformed files") {
  const fs::path dir = scratch("readers");
  const std::string a = write(dir / "a.vts", "3\n1\r\n2\n\n").string();  // CRLF and a trailing blank line
  const std::string b = write(dir / "b.vts", "1\n2\n3\n").string();
  const GroundTruth vts = read_vts_ground_truth(a, b, 3, 5);
  REQUIRE(vts.size() == 3);
  CHECK(vts[0].x == 2);
  CHECK(vts[0].y == 0);
  CHECK(vts[2].x == 1);
  CHECK(vts[2].y == 2);

  // TOPKIDS layout: padded columns, X (kidXX) first, then Y (kid00).
  const std::string m = write(dir / "kid_ref.txt", "     1      3 \n     2      2 \n").string();
  const GroundTruth map = read_map_ground_truth(m, 2, 3);
  REQUIRE(map.size() == 2);
  CHECK(map[0].x == 0);
  CHECK(map[0].y == 2);
  CHECK(map[1].x == 1);
  CHECK(map[1].y == 1);
  // A header and comments, blank lines: skipped; a pair given twice is two samples.
  const GroundTruth commented =
      read_map_ground_truth(write(dir / "commented.txt", "# x y\n1 3\n\n  # again\n1 3 # twice\n2 2#\n").string(), 2, 3);
  REQUIRE(commented.size() == 3);
  CHECK(commented[0].x == 0);
  CHECK(commented[1].y == 2);
  CHECK(commented[2].y == 1);

  const std::vector<int> zero_based = read_vertex_list(write(dir / "ids.txt", "0\n4\n").string(), false, 5);
  CHECK(zero_based == std::vector<int>{0, 4});

  CHECK(identity_ground_truth(4, 4).size() == 4);
  CHECK_THROWS_AS(identity_ground_truth(4, 5), InvalidInputError);

  struct Bad {
    std::string name, text, expect;
  };
  const std::vector<Bad> bad_vts = {
      {"zero.vts", "1\n0\n2\n", "line 2: vertex 0 is not in 1..3"},
      {"big.vts", "1\n2\n4\n", "line 3: vertex 4 is not in 1..3"},
      {"word.vts", "1\nabc\n2\n", "line 2: 'abc' is not a vertex index"},
      {"two.vts", "1\n2 3\n1\n", "line 2: expected 1 vertex index, got 2"},
      {"gap.vts", "1\n\n2\n", "line 2: expected 1 vertex index, got 0"},
      {"neg.vts", "-1\n1\n1\n", "line 1: vertex -1 is not in 1..3"},
      {"huge.vts", "99999999999999999999\n1\n1\n", "is not a vertex index"},
      {"empty.vts", "\n\n", "empty file"},
      {"short.vts", "1\n2\n", "2 lines, but"},
  };
  for (const Bad& c : bad_vts) {
    CAPTURE(c.name);
    const std::string path = write(dir / c.name, c.text).string();
    // The malformed file is Y here, except for the line-count mismatch, which names Y too.
    const std::string what = error_of([&] { read_vts_ground_truth(b, path, 3, 3); });
    CHECK(what.rfind(path + ": ", 0) == 0);
    CHECK(what.find(c.expect) != std::string::npos);
    CHECK(what.find('\n') == std::string::npos);
    CHECK_THROWS_AS(read_vts_ground_truth(b, path, 3, 3), InvalidInputError);
  }
  const std::vector<Bad> bad_maps = {
      {"one.txt", "1 1\n2\n", "line 2: expected 2 vertex indices, got 1"},
      {"ycol.txt", "1 1\n2 4\n", "line 2: vertex 4 is not in 1..3"},
      {"xcol.txt", "3 1\n", "line 1: vertex 3 is not in 1..2"},
      {"later.txt", "# x y\n\n1 1\n1 x\n", "line 4: 'x' is not a vertex index"},  // (the file's line numbers)
      {"comments.txt", "# x y\n# nothing\n", "no vertex pairs (only comments)"},
  };
  for (const Bad& c : bad_maps) {
    CAPTURE(c.name);
    const std::string path = write(dir / c.name, c.text).string();
    const std::string what = error_of([&] { read_map_ground_truth(path, 2, 3); });
    CHECK(what.rfind(path + ": ", 0) == 0);
    CHECK(what.find(c.expect) != std::string::npos);
  }
  CHECK_THROWS_AS(read_vts_ground_truth((dir / "missing.vts").string(), b, 3, 3), IoError);
  CHECK(error_of([&] { read_vertex_list((dir / "missing.vts").string(), true, 3); }).find("missing.vts") !=
        std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("evaluation: shapematch eval reads a match directory through the vertex id files") {
  // A match directory made by hand: x.ply and y.ply hold the input vertices in a shuffled order,
  // as decimation would (a subset, renumbered), and the map is the true correspondence.
  const fs::path dir = scratch("cli_ids");
  const fs::path out = dir / "match";
  fs::create_directories(out);
  const Mesh x = shapes::bent_finger(10, 10, 8), y = shapes::bent_finger(70, 10, 8);
  const int n = x.num_vertices();
  save_mesh(x, (dir / "x_in.off").string());
  save_mesh(y, (dir / "y_in.off").string());
  std::mt19937 rng(2);
  auto shuffled = [&](const Mesh& m, std::vector<int>& ids, std::vector<int>& position) {
    ids = identity_map(n);
    std::shuffle(ids.begin(), ids.end(), rng);
    position.assign(n, 0);
    for (int v = 0; v < n; ++v) position[ids[v]] = v;
    std::vector<Eigen::Vector3d> vertices;
    for (int v = 0; v < n; ++v) vertices.push_back(m.vertices[ids[v]]);
    std::vector<std::array<int, 3>> faces;
    for (const auto& f : m.faces) faces.push_back({position[f[0]], position[f[1]], position[f[2]]});
    return make_mesh(vertices, faces);
  };
  std::vector<int> x_ids, x_pos, y_ids, y_pos;
  save_mesh(shuffled(x, x_ids, x_pos), (out / "x.ply").string());
  save_mesh(shuffled(y, y_ids, y_pos), (out / "y.ply").string());
  std::string map, xs, ys, vts;
  for (int v = 0; v < n; ++v) {
    map += std::to_string(y_pos[x_ids[v]]) + "\n";
    xs += std::to_string(x_ids[v]) + "\n";
    ys += std::to_string(y_ids[v]) + "\n";
    vts += std::to_string(v + 1) + "\n";
  }
  write(out / "map_x_to_y.txt", map);
  write(out / "x_vertex_ids.txt", xs);
  write(out / "y_vertex_ids.txt", ys);
  auto side = [&](const fs::path& file) {
    return Json::object().set("file", file.string()).set("vertices_input", n).set("vertices", n);
  };
  write(out / "report.json", Json::object()
                                 .set("x", side(dir / "x_in.off"))
                                 .set("y", side(dir / "y_in.off"))
                                 .set("options", Json::object().set("keep_scale", false))
                                 .dump());

  Run r = run_cli("eval " + out.string() + " --pck-csv " + (dir / "pck.csv").string(), dir);
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(json_number(r.out, "points") == n);
  CHECK(json_number(r.out, "mean_geodesic_error") == 0.0);
  CHECK(json_number(r.out, "auc") == 1.0);
  CHECK(json_number(r.out, "orientation_flips") == 0);
  CHECK(json_number(r.out, "degenerate_faces") == 0);
  CHECK(json_number(r.out, "faces") == x.num_faces());
  CHECK(json_number(r.out, "seconds") >= 0);
  CHECK(r.out.find("\"pck\": [") != std::string::npos);
  CHECK(count_lines(dir / "pck.csv") == 27);

  // The same through the .vts and two-column readers.
  write(dir / "a.vts", vts);
  r = run_cli("eval " + out.string() + " --gt-x " + (dir / "a.vts").string() + " --gt-y " + (dir / "a.vts").string(),
              dir);
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(json_number(r.out, "mean_geodesic_error") == 0.0);
  CHECK(r.out.find("symmetric") == std::string::npos);
  // A symmetric ground truth is scored as well, and the better of the two named.
  std::string reversed;
  for (int v = 0; v < n; ++v) reversed += std::to_string(n - v) + "\n";
  write(dir / "reversed.vts", reversed);
  r = run_cli("eval " + out.string() + " --gt-x " + (dir / "a.vts").string() + " --gt-y " + (dir / "a.vts").string() +
                  " --gt-y-sym " + (dir / "reversed.vts").string(),
              dir);
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(json_number(r.out, "mean_geodesic_error") == 0.0);
  CHECK(json_number(r.out, "symmetric_mean_geodesic_error") > 0.1);
  CHECK(json_number(r.out, "best_mean_geodesic_error") == 0.0);
  CHECK(r.out.find("\"best_ground_truth\": \"direct\"") != std::string::npos);
  CHECK(json_number(r.out, "mirrored_error_share") == 0.0);
  // A coarser level's map, as match writes it (0-based input vertices): every third vertex of X to
  // the same vertex of Y, which the reversed truth scores as mirrored.
  fs::create_directories(out / "levels");
  std::string level;
  for (int v = 0; v < n; v += 3) level += std::to_string(v) + " " + std::to_string(v) + "\n";
  write(out / "levels" / "level_1.txt", level);
  r = run_cli("eval " + out.string() + " --gt-x " + (dir / "a.vts").string() + " --gt-y " +
                  (dir / "reversed.vts").string() + " --gt-y-sym " + (dir / "a.vts").string() + " --errors-csv " +
                  (dir / "errors.csv").string(),
              dir);
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(json_number(r.out, "mean_geodesic_error") > 0.1);
  CHECK(json_number(r.out, "best_mean_geodesic_error") == 0.0);
  CHECK(r.out.find("\"best_ground_truth\": \"symmetric\"") != std::string::npos);
  {
    // The share of the error mirrored pair by pair: most of it, at the level as at the finest (the
    // last "mirrored_error_share" is the finest's, the levels' come first).
    const std::string levels = r.out.substr(r.out.find("\"levels\""));
    CHECK(json_number(levels, "points") == (n + 2) / 3);
    CHECK(json_number(levels, "mirrored_error_share") > 0.8);
    CHECK(json_number(levels, "mirrored_error_share") <= 1.0);
    const std::string finest = r.out.substr(r.out.rfind("\"mirrored_error_share\""));
    CHECK(json_number(finest, "mirrored_error_share") > 0.8);
    CHECK(json_number(finest, "mirrored_error_share") <= 1.0);
    CHECK(r.err.find("% of it mirrored") != std::string::npos);
  }
  fs::remove_all(out / "levels");
  // X's input mesh is found through report.json: the reversed part is a region, mirrored.
  CHECK(json_number(r.out, "error_regions_found") >= 1);
  CHECK(r.out.find("\"mirrored\": true") != std::string::npos);
  CHECK(r.out.find("\"mirrored\": false") == std::string::npos);
  CHECK(r.err.find("matched to its mirror image") != std::string::npos);
  {
    // Per pair: X's vertex, the reversed truth, the map's image (the identity) and both errors;
    // the errors' mean is the reported one.
    std::ifstream in(dir / "errors.csv");
    std::string line;
    std::getline(in, line);
    CHECK(line == "x,y_true,y_mapped,error,symmetric_error");
    int rows = 0;
    double sum = 0;
    while (std::getline(in, line)) {
      int xv = -1, yt = -1, ym = -1;
      double e = -1, es = -1;
      REQUIRE(std::sscanf(line.c_str(), "%d,%d,%d,%lf,%lf", &xv, &yt, &ym, &e, &es) == 5);
      CHECK(xv == rows);
      CHECK(yt == n - 1 - rows);
      CHECK(ym == rows);
      CHECK(es == 0.0);
      CHECK((e > 0) == (xv != yt));
      sum += e;
      ++rows;
    }
    CHECK(rows == n);
    CHECK(sum / n == doctest::Approx(json_number(r.out, "mean_geodesic_error")).epsilon(1e-9));
  }
  // X coloured by error: the mirrored vertices blue; with the true map, every vertex white.
  auto colours = [&](const fs::path& ply) {
    std::map<std::array<int, 3>, int> counts;
    std::ifstream in(ply);
    std::string line;
    while (std::getline(in, line) && line != "end_header") {}
    for (int v = 0; v < n && std::getline(in, line); ++v) {
      std::istringstream row(line);
      double c[3];
      std::array<int, 3> rgb{};
      row >> c[0] >> c[1] >> c[2] >> rgb[0] >> rgb[1] >> rgb[2];
      ++counts[rgb];
    }
    return counts;
  };
  r = run_cli("eval " + out.string() + " --gt-x " + (dir / "a.vts").string() + " --gt-y " +
                  (dir / "reversed.vts").string() + " --gt-y-sym " + (dir / "a.vts").string() + " --errors-ply " +
                  (dir / "errors.ply").string(),
              dir);
  REQUIRE_MESSAGE(r.code == 0, r.err);
  std::map<std::array<int, 3>, int> seen = colours(dir / "errors.ply");
  CHECK(seen[{60, 90, 230}] > n / 2);
  r = run_cli("eval " + out.string() + " --gt-x " + (dir / "a.vts").string() + " --gt-y " + (dir / "a.vts").string() +
                  " --errors-ply " + (dir / "errors.ply").string(),
              dir);
  REQUIRE_MESSAGE(r.code == 0, r.err);
  seen = colours(dir / "errors.ply");
  CHECK(seen.size() == 1);
  CHECK(seen[{255, 255, 255}] == n);
  // Without X's mesh the coloured file cannot be written: said before any work, nothing written.
  fs::remove(dir / "errors.ply");
  r = run_cli("eval " + out.string() + " --x-mesh " + (dir / "none.off").string() + " --errors-ply " +
                  (dir / "errors.ply").string(),
              dir);
  CHECK(r.code != 0);
  CHECK(r.err.find("none.off: cannot open") != std::string::npos);
  CHECK_FALSE(fs::exists(dir / "errors.ply"));
  std::string two_columns;
  for (int v = 0; v < n; v += 2) two_columns += std::to_string(v + 1) + " " + std::to_string(v + 1) + "\n";
  write(dir / "map.txt", two_columns);
  r = run_cli("eval " + out.string() + " --gt-map " + (dir / "map.txt").string(), dir);
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(json_number(r.out, "points") == (n + 1) / 2);
  CHECK(json_number(r.out, "mean_geodesic_error") == 0.0);

  // A PNG when Debian's matplotlib is there (a warning otherwise).
  if (std::system("/usr/bin/python3 -c 'import matplotlib' >/dev/null 2>&1") == 0) {
    r = run_cli("eval " + out.string() + " --pck-png " + (dir / "pck.png").string(), dir);
    REQUIRE_MESSAGE(r.code == 0, r.err);
    CHECK(fs::file_size(dir / "pck.png") > 5000);
  }

  // Options that contradict each other are refused.
  r = run_cli("eval " + out.string() + " --gt identity --gt-map " + (dir / "map.txt").string(), dir);
  CHECK(r.code != 0);
  r = run_cli("eval " + out.string() + " --gt-x " + (dir / "a.vts").string(), dir);
  CHECK(r.code != 0);
  r = run_cli("eval " + out.string() + " --gt-y-sym " + (dir / "a.vts").string(), dir);
  CHECK(r.code != 0);

  // Another mesh of as many vertices as Y (the finger bent the other way) named as Y: refused,
  // before anything is scored, rather than scored as if it were Y; as X too.
  for (const std::string& option : {"--y-mesh ", "--x-mesh "}) {
    const fs::path other = dir / (option == "--y-mesh " ? "x_in.off" : "y_in.off");
    r = run_cli("eval " + out.string() + " " + option + other.string(), dir);
    CHECK(r.code == 1);
    CHECK(r.err.find(other.string() + ": is not the " + (option == "--y-mesh " ? "Y" : "X") + " mesh the match read") !=
          std::string::npos);
    CHECK(r.out.empty());
  }
  // Y's own file scaled and moved is still Y (match's shift and scale are taken out).
  Mesh moved = y;
  for (auto& p : moved.vertices) p = 3.0 * p + Eigen::Vector3d(1, 2, 3);
  save_mesh(moved, (dir / "y_moved.off").string());
  r = run_cli("eval " + out.string() + " --y-mesh " + (dir / "y_moved.off").string(), dir);
  CHECK_MESSAGE(r.code == 0, r.err);

  // Malformed inputs: exit 1 and one line naming the file.
  write(dir / "bad.vts", "1\n2\nx\n");
  r = run_cli("eval " + out.string() + " --gt-x " + (dir / "a.vts").string() + " --gt-y " + (dir / "bad.vts").string(),
              dir);
  CHECK(r.code == 1);
  CHECK(r.err.find((dir / "bad.vts").string() + ": line 3") != std::string::npos);
  write(out / "y_vertex_ids.txt", "0\n");
  r = run_cli("eval " + out.string(), dir);
  CHECK(r.code == 1);
  CHECK(r.err.find("y_vertex_ids.txt: 1 lines, but y.ply has") != std::string::npos);

  // Without the id files the matched meshes are taken as the inputs themselves: here they are
  // shuffled, so the inputs are not what was matched: refused (it had been scored, as error).
  fs::remove(out / "x_vertex_ids.txt");
  fs::remove(out / "y_vertex_ids.txt");
  r = run_cli("eval " + out.string(), dir);
  CHECK(r.code == 1);
  CHECK(r.err.find("y_in.off: is not the Y mesh the match read") != std::string::npos);
  save_mesh(y, (out / "y.ply").string());  // (as an output from before the id files: the inputs themselves)
  save_mesh(x, (out / "x.ply").string());
  write(out / "map_x_to_y.txt", [&] {
    std::string identity;
    for (int v = 0; v < n; ++v) identity += std::to_string(v) + "\n";
    return identity;
  }());
  r = run_cli("eval " + out.string(), dir);
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(json_number(r.out, "mean_geodesic_error") == 0.0);

  write(out / "report.json", "{\"x\": {\"file\": 3}");
  r = run_cli("eval " + out.string(), dir);
  CHECK(r.code == 1);
  CHECK(r.err.find("report.json: not valid JSON") != std::string::npos);
  r = run_cli("eval " + (dir / "nothing").string(), dir);
  CHECK(r.code == 1);
  CHECK(r.err.find("not a directory") != std::string::npos);
  fs::remove_all(dir);
}

// An icosphere(1) with one face removed, written as OFF: an open input for --close-holes.
Mesh write_open_icosphere(const fs::path& path) {
  Mesh open = shapes::icosphere(1);
  open.faces.pop_back();
  std::string text = "OFF\n" + std::to_string(open.num_vertices()) + " " + std::to_string(open.num_faces()) + " 0\n";
  for (const auto& p : open.vertices) text += fmt::format("{} {} {}\n", p.x(), p.y(), p.z());
  for (const auto& f : open.faces) text += fmt::format("3 {} {} {}\n", f[0], f[1], f[2]);
  write(path, text);
  return open;
}

TEST_CASE("evaluation: shapematch eval closes Y's holes again when the match did") {
  // An open input (one face removed), matched as closed: the matched meshes have one vertex more.
  const fs::path dir = scratch("close_holes");
  const fs::path out = dir / "match";
  fs::create_directories(out);
  const Mesh open = write_open_icosphere(dir / "open.off");
  LoadOptions closing;
  closing.close_holes = true;
  const Mesh closed = load_mesh((dir / "open.off").string(), closing);
  const int n = closed.num_vertices();
  REQUIRE(n == open.num_vertices() + 1);
  save_mesh(closed, (out / "x.ply").string());
  save_mesh(closed, (out / "y.ply").string());
  std::string ids;
  for (int v = 0; v < n; ++v) ids += std::to_string(v) + "\n";
  write(out / "map_x_to_y.txt", ids);
  auto report = [&](bool close_holes) {
    auto side = Json::object().set("file", (dir / "open.off").string()).set("vertices_input", n).set("vertices", n);
    write(out / "report.json", Json::object()
                                   .set("x", side)
                                   .set("y", side)
                                   .set("options", Json::object().set("close_holes", close_holes))
                                   .dump());
  };
  report(true);
  Run r = run_cli("eval " + out.string(), dir);
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(json_number(r.out, "points") == n);
  CHECK(json_number(r.out, "mean_geodesic_error") == 0.0);
  report(false);  // Y read as it is: open, so not the mesh that was matched
  r = run_cli("eval " + out.string(), dir);
  CHECK(r.code == 1);
  CHECK(r.err.find("not closed") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("evaluation: shapematch eval on a real match output of a shared-connectivity pair") {
  // 60 faces, no decimation: with the paper's membrane the LP recovers the identity (a few
  // seconds on one core), so the evaluation must report zero error and no flips whether or not
  // match wrote vertex id files. (The compressive default lets two faces at the bend fold.)
  const fs::path dir = scratch("cli_match");
  save_mesh(shapes::bent_finger(10, 6, 5), (dir / "a.off").string());
  save_mesh(shapes::bent_finger(70, 6, 5), (dir / "b.off").string());
  const fs::path out = dir / "match";
  Run r = run_cli("match " + (dir / "a.off").string() + " " + (dir / "b.off").string() + " --backend cpu --membrane svk -o " +
                      out.string(),
                  dir);
  REQUIRE_MESSAGE(r.code == 0, r.err);
  r = run_cli("eval " + out.string(), dir);
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(json_number(r.out, "points") == 32);
  CHECK(json_number(r.out, "mean_geodesic_error") == 0.0);
  CHECK(json_number(r.out, "orientation_flips") == 0);
  CHECK(json_number(r.out, "degenerate_faces") == 0);

  // Decimated to 40 faces: the X vertices removed have no image, an empty error in the table and
  // grey in the coloured mesh; the rest are rated.
  const fs::path small = dir / "small";
  r = run_cli("match " + (dir / "a.off").string() + " " + (dir / "b.off").string() +
                  " --faces 40 --backend cpu --membrane svk -o " + small.string(),
              dir);
  REQUIRE_MESSAGE(r.code == 0, r.err);
  r = run_cli("eval " + small.string() + " --errors-csv " + (dir / "e.csv").string() + " --errors-ply " +
                  (dir / "e.ply").string(),
              dir);
  REQUIRE_MESSAGE(r.code == 0, r.err);
  const int kept = static_cast<int>(json_number(r.out, "points"));
  CHECK(kept < 32);
  int empty = 0, rows = 0;
  {
    std::ifstream in(dir / "e.csv");
    std::string line;
    std::getline(in, line);
    CHECK(line == "x,y_true,y_mapped,error");
    while (std::getline(in, line)) {
      ++rows;
      empty += line.back() == ',';
    }
  }
  CHECK(rows == 32);
  CHECK(empty == 32 - kept);
  int grey = 0;
  {
    std::ifstream in(dir / "e.ply");
    std::string line;
    while (std::getline(in, line) && line != "end_header") {}
    for (int v = 0; v < 32 && std::getline(in, line); ++v) grey += line.ends_with(" 160 160 160");
  }
  CHECK(grey == 32 - kept);

  // X's mesh is checked before any work, and a failed evaluation writes nothing: another X, a
  // missing one named, a coloured mesh not named .ply.
  fs::remove(dir / "e.csv");
  save_mesh(shapes::bent_finger(10, 8, 5), (dir / "other.off").string());
  r = run_cli("eval " + small.string() + " --x-mesh " + (dir / "other.off").string() + " --errors-csv " +
                  (dir / "e.csv").string(),
              dir);
  CHECK(r.code == 1);
  CHECK(r.err.find("other.off: 42 vertices, but X had 32 when it was matched") != std::string::npos);
  CHECK_FALSE(fs::exists(dir / "e.csv"));
  // Not asked for, X is optional: report.json's X replaced by another mesh, eval warns and goes on.
  fs::copy_file(dir / "a.off", dir / "a_saved.off");
  fs::copy_file(dir / "other.off", dir / "a.off", fs::copy_options::overwrite_existing);
  r = run_cli("eval " + small.string(), dir);
  CHECK_MESSAGE(r.code == 0, r.err);
  CHECK(r.err.find("no error regions") != std::string::npos);
  CHECK(r.out.find("error_regions") == std::string::npos);
  fs::copy_file(dir / "a_saved.off", dir / "a.off", fs::copy_options::overwrite_existing);
  r = run_cli("eval " + small.string() + " --x-mesh " + (dir / "none.off").string(), dir);
  CHECK(r.code != 0);
  CHECK(r.err.find("none.off: cannot open") != std::string::npos);
  r = run_cli("eval " + small.string() + " --errors-ply " + (dir / "e.off").string(), dir);
  CHECK(r.code == 1);
  CHECK(r.err.find("name it .ply") != std::string::npos);
  r = run_cli("eval " + small.string() + " --errors-ply " + (dir / "E.PLY").string(), dir);  // (any case)
  CHECK_MESSAGE(r.code == 0, r.err);
  CHECK(fs::exists(dir / "E.PLY"));
  r = run_cli("eval " + small.string() + " --region-threshold nan", dir);
  CHECK(r.code != 0);
  fs::remove_all(dir);
}

TEST_CASE("evaluation: a true map at the matched resolution takes the nearest ground truth on either side") {
  const Mesh m = shapes::icosphere(3);
  std::vector<int> ids;
  const Mesh coarse = decimate(m, 200, &ids);
  REQUIRE(coarse.num_vertices() < m.num_vertices());
  // The identity, dense: every kept vertex is its own nearest pair and image.
  const std::vector<int> same = truth_at(m, m, ids, ids, identity_ground_truth(m.num_vertices(), m.num_vertices()));
  REQUIRE(same.size() == ids.size());
  for (size_t v = 0; v < ids.size(); ++v) CHECK(same[v] == int(v));
  // Two pairs only, swapping two antipodes: each vertex takes the nearer pair's image, on the
  // matched Y the kept vertex nearest to it.
  int north = 0, south = 0;
  for (int v = 0; v < m.num_vertices(); ++v) {
    if (m.vertices[v].z() > m.vertices[north].z()) north = v;
    if (m.vertices[v].z() < m.vertices[south].z()) south = v;
  }
  const std::vector<int> swapped = truth_at(m, m, ids, ids, {{north, south}, {south, north}});
  auto nearest_distance = [&](int target) {  // over the kept vertices
    double best = 1e300;
    for (int id : ids) best = std::min(best, (m.vertices[id] - m.vertices[target]).squaredNorm());
    return best;
  };
  for (size_t v = 0; v < ids.size(); ++v) {
    const double z = m.vertices[ids[v]].z();
    if (std::abs(z) < 0.1) continue;  // near the equator either pair is about as near
    CAPTURE(z);
    const int target = z > 0 ? south : north;
    CHECK((m.vertices[ids[swapped[v]]] - m.vertices[target]).squaredNorm() ==
          doctest::Approx(nearest_distance(target)).epsilon(1e-12));
    CHECK(m.vertices[ids[swapped[v]]].z() * z < 0);
  }
  CHECK_THROWS_AS(truth_at(m, m, ids, ids, {}), InvalidInputError);
  CHECK_THROWS_AS(truth_at(m, m, ids, ids, {{m.num_vertices(), 0}}), InvalidInputError);
}

TEST_CASE("evaluation: shapematch eval checks its output files before scoring") {
  const fs::path dir = scratch("cli_outputs");
  const fs::path out = dir / "match";
  // Copies of the bundled pair: a failing check below would overwrite X.
  for (const char* name : {"dolphin_straight.off", "dolphin_swimming.off"})
    fs::copy_file(fs::path(SHAPEMATCH_ASSETS_DIR) / name, dir / name, fs::copy_options::overwrite_existing);
  REQUIRE(run_cli("match " + (dir / "dolphin_straight.off").string() + " " + (dir / "dolphin_swimming.off").string() +
                  " --faces 30 --backend cpu -o " + out.string())
              .code == 0);
  const std::string eval = "eval " + out.string() + " --gt identity ";
  fs::create_directories(dir / "folder");
  struct Case {
    std::string options, error;
  };
  const std::vector<Case> refused = {
      {"--errors-csv " + (dir / "same.csv").string() + " --pck-csv " + (dir / "same.csv").string(),
       (dir / "same.csv").string() + ": named by both --pck-csv and --errors-csv"},
      {"--pck-csv " + (out / "report.json").string(), (out / "report.json").string() + ": --pck-csv would overwrite a file eval reads"},
      {"--errors-csv " + (out / "map_x_to_y.txt").string(), "would overwrite a file eval reads"},
      {"--errors-csv " + (dir / "folder").string(), (dir / "folder").string() + ": is a directory, not a file"},
      {"--pck-png " + (dir / "missing" / "p.png").string(), "its folder " + (dir / "missing").string() + " does not exist"},
      {"--threads -1", "--threads: must not be negative"},
  };
  for (const auto& c : refused) {
    CAPTURE(c.options);
    const Run r = run_cli(eval + c.options);
    CHECK(r.code == 1);
    CHECK(r.out.empty());  // before any scoring: no JSON
    CHECK(r.err.find(c.error) != std::string::npos);
    CHECK(r.err.find("geodesic") == std::string::npos);  // (nothing solved)
  }
  CHECK(fs::exists(out / "report.json"));
  CHECK_FALSE(fs::exists(dir / "same.csv"));
  // A new file inside the match directory is fine, and so is writing it again.
  for (int again = 0; again < 2; ++again) {
    const Run ok = run_cli(eval + "--pck-csv " + (out / "pck.csv").string());
    CHECK(ok.code == 0);
    CHECK(fs::exists(out / "pck.csv"));
  }
  // The meshes report.json names (eval reads X's for its regions) are inputs too.
  const std::string x_file = [&] {
    std::ifstream in(out / "report.json");
    const std::string text((std::istreambuf_iterator<char>(in)), {});
    const size_t at = text.find("\"file\": \"") + 9;
    return text.substr(at, text.find('"', at) - at);
  }();
  REQUIRE(fs::path(x_file) == dir / "dolphin_straight.off");
  const Run mesh = run_cli(eval + "--errors-ply " + (dir / "x.ply").string() + " --pck-csv " + x_file);
  CHECK(mesh.code == 1);
  CHECK(mesh.err.find(x_file + ": --pck-csv would overwrite a file eval reads") != std::string::npos);
}

TEST_CASE("evaluation: a match with --close-holes keeps the file's vertices for ground truth and user features") {
  // One face removed from an icosphere: the file has 42 vertices, the matched mesh 43 (the fan's).
  const fs::path dir = scratch("close_holes_match");
  const Mesh open = write_open_icosphere(dir / "open.off");
  const int file = open.num_vertices();
  std::string features;  // one row per vertex of the file, as a user has them
  for (int v = 0; v < file; ++v) features += fmt::format("{} {}\n", open.vertices[v].x(), open.vertices[v].z());
  write(dir / "f.txt", features);
  const fs::path out = dir / "match";
  const std::string mesh = (dir / "open.off").string(), f = (dir / "f.txt").string();
  Run r = run_cli("match " + mesh + " " + mesh + " --close-holes --backend cpu --features-x " + f + " --features-y " + f +
                  " -o " + out.string());
  REQUIRE_MESSAGE(r.code == 0, r.err);
  std::ifstream in(out / "report.json");
  const std::string report((std::istreambuf_iterator<char>(in)), {});
  CHECK(json_number(report, "vertices_file") == file);
  CHECK(json_number(report, "vertices_input") == file + 1);
  // Scored over the file's vertices: the fan's vertex has no truth.
  r = run_cli("eval " + out.string() + " --gt identity");
  REQUIRE_MESSAGE(r.code == 0, r.err);
  CHECK(json_number(r.out, "ground_truth_pairs") == file);
  CHECK(json_number(r.out, "points") == file);
  // A ground-truth file that names the fan's vertex is refused, as for the open file itself.
  std::string vts;
  for (int v = 1; v <= file + 1; ++v) vts += std::to_string(v) + "\n";
  write(dir / "all.vts", vts);
  r = run_cli("eval " + out.string() + " --gt-x " + (dir / "all.vts").string() + " --gt-y " + (dir / "all.vts").string());
  CHECK(r.code == 1);
  CHECK(r.err.find(fmt::format("vertex {} is not in 1..{}", file + 1, file)) != std::string::npos);
  fs::remove_all(dir);
}
