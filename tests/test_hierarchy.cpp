#include "shapematch/hierarchy.hpp"
#include "shapematch/shapes.hpp"
#include "test_helpers.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <set>

using namespace shapematch;

namespace {
Mesh lumpy_sphere(int subdivisions, unsigned seed) { return test::lumpy_sphere(subdivisions, seed, 0.08); }
}  // namespace

TEST_CASE("hierarchy: face counts are geometric from the coarsest level to the input") {
  HierarchyOptions o;
  o.coarsest_faces = 250;
  const auto c = level_face_counts(10000, o);
  REQUIRE(c.size() == 4);  // 250·4³ = 16000 ≥ 10000: three steps of about 3.4×
  CHECK(c.front() == 250);
  CHECK(c.back() == 10000);
  for (size_t i = 1; i < c.size(); ++i) CHECK(double(c[i]) / c[i - 1] == doctest::Approx(std::cbrt(40.0)).epsilon(0.01));
  CHECK(level_face_counts(200, o) == std::vector<int>{200});
  o.levels = 2;
  CHECK(level_face_counts(1000, o) == std::vector<int>{250, 1000});
  CHECK(level_face_counts(100, o) == std::vector<int>{100, 100});  // padded: a pair shares a level count
  o.coarsest_faces = 2;
  CHECK_THROWS_AS(level_face_counts(1000, o), InvalidInputError);
}

TEST_CASE("hierarchy: a second level of given size sits above the coarsest, geometric from there") {
  HierarchyOptions o;
  o.coarsest_faces = 100;
  o.second_faces = 200;
  CHECK(level_face_counts(500, o) == std::vector<int>{100, 200, 500});
  CHECK(level_face_counts(2000, o) == std::vector<int>{100, 200, 632, 2000});
  CHECK(level_face_counts(200, o) == std::vector<int>{100, 200});   // the input is the second level
  CHECK(level_face_counts(150, o) == std::vector<int>{100, 150});   // smaller than the second level
  o.levels = 3;  // a pair's common count: one level for the coarsest, the rest above the second
  CHECK(level_face_counts(4000, o) == std::vector<int>{100, 200, 4000});
  o.levels = 4;
  CHECK(level_face_counts(150, o) == std::vector<int>{100, 114, 131, 150});  // no room: plain geometric
}

TEST_CASE("hierarchy: decimation keeps a subset of the input vertices and says which") {
  const Mesh m = lumpy_sphere(3, 1);
  std::vector<int> kept;
  const Mesh d = decimate(m, 300, &kept);
  REQUIRE(kept.size() == size_t(d.num_vertices()));
  CHECK(std::set<int>(kept.begin(), kept.end()).size() == kept.size());
  // Kept vertices stay where they were up to the decimator's area-preserving similarity.
  const double s = (d.vertices[1] - d.vertices[0]).norm() / (m.vertices[kept[1]] - m.vertices[kept[0]]).norm();
  CHECK(s == doctest::Approx(1.0).epsilon(0.1));
  for (int v = 2; v < d.num_vertices(); ++v) {
    const Eigen::Vector3d a = d.vertices[v] - d.vertices[0], b = m.vertices[kept[v]] - m.vertices[kept[0]];
    CHECK((a - s * b).norm() < 1e-9);
  }
  std::vector<int> same;
  decimate(m, m.num_faces(), &same);
  CHECK(same.size() == size_t(m.num_vertices()));
  CHECK(same.back() == m.num_vertices() - 1);
}

TEST_CASE("hierarchy: every level is a valid mesh, vertex ids nest and parents are near") {
  const Mesh m = lumpy_sphere(3, 2);  // 1280 faces
  const MeshHierarchy h = build_hierarchy(m, {80, 320, 1280});
  REQUIRE(h.size() == 3);
  CHECK(h.levels.back().mesh.vertices == m.vertices);
  CHECK(h.levels.front().parent_face.empty());
  for (int l = 0; l < h.size(); ++l) {
    const MeshLevel& level = h.levels[l];
    CAPTURE(l);
    CHECK_NOTHROW(validate_mesh(level.mesh));
    CHECK(std::abs(level.mesh.num_faces() - std::vector<int>{80, 320, 1280}[l]) <= 2);
    CHECK(level.geometry.face_area.size() == size_t(level.mesh.num_faces()));
    REQUIRE(level.input_vertex.size() == size_t(level.mesh.num_vertices()));
    if (l == 0) continue;
    // Coarser vertices are a subset of finer ones, in input indices.
    const std::set<int> finer(level.input_vertex.begin(), level.input_vertex.end());
    for (int v : h.levels[l - 1].input_vertex) CHECK(finer.count(v) == 1);
    // Every parent is close (a coarse edge here is about 0.5; a wrong map gives distances near 2).
    REQUIRE(level.parent_face.size() == size_t(level.mesh.num_faces()));
    const Mesh& coarse = h.levels[l - 1].mesh;
    std::vector<int> children(coarse.num_faces(), 0);
    for (int f = 0; f < level.mesh.num_faces(); ++f) {
      const int p = level.parent_face[f];
      REQUIRE(p >= 0);
      REQUIRE(p < coarse.num_faces());
      ++children[p];
      auto centroid = [](const Mesh& mm, int ff) {
        return Eigen::Vector3d((mm.vertices[mm.faces[ff][0]] + mm.vertices[mm.faces[ff][1]] + mm.vertices[mm.faces[ff][2]]) / 3);
      };
      CHECK((centroid(level.mesh, f) - centroid(coarse, p)).norm() < 1.0);
    }
    const int childless = static_cast<int>(std::count(children.begin(), children.end(), 0));
    CHECK(childless <= coarse.num_faces() / 10);
  }
}

TEST_CASE("hierarchy: rings grow from the element itself outwards") {
  const Mesh m = shapes::icosphere(1);  // 80 faces, valence 5 and 6
  const auto vf = vertex_face_table(m);
  const auto& f = m.faces[7];
  CHECK(ring_faces(m, vf, {f[0], f[1], f[2]}, 0) == std::vector<int>{7});
  CHECK(ring_faces(m, vf, {f[0], f[1], f[1]}, 0).size() == 2);          // an edge: its two faces
  CHECK(ring_faces(m, vf, {f[0], f[0], f[0]}, 0).size() == vf[f[0]].size());  // a vertex: its star
  const auto r1 = ring_faces(m, vf, {f[0], f[1], f[2]}, 1), r2 = ring_faces(m, vf, {f[0], f[1], f[2]}, 2);
  CHECK(r1.size() >= 12);
  CHECK(r1.size() <= 13);
  CHECK(r2.size() > r1.size());
  CHECK(std::includes(r2.begin(), r2.end(), r1.begin(), r1.end()));
}

TEST_CASE("hierarchy: point-to-triangle distance agrees with a dense sampling of the triangle") {
  const Eigen::Vector3d a(0.1, -0.2, 0.3), b(1.7, 0.4, -0.1), c(0.6, 1.1, 0.5);
  // Points around the triangle, so that every Voronoi region (corners, edges, interior) is hit.
  std::vector<Eigen::Vector3d> points;
  for (int i = -2; i <= 2; ++i)
    for (int j = -2; j <= 2; ++j)
      for (int k = -1; k <= 1; ++k) points.emplace_back(0.8 + 0.9 * i, 0.4 + 0.8 * j, 0.2 + 0.6 * k);
  const int n = 400;
  for (const Eigen::Vector3d& p : points) {
    double sampled = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        const Eigen::Vector3d q = a + (b - a) * (double(i) / n) + (c - a) * (double(j) / n);
        sampled = std::min(sampled, (p - q).squaredNorm());
      }
    CAPTURE(p.transpose());
    const double d = squared_distance_to_triangle(p, a, b, c);
    CHECK(d <= sampled + 1e-12);                            // never farther than a point of the triangle
    CHECK(std::sqrt(sampled) - std::sqrt(d) < 5e-3);        // and a sample is about as near
  }
  CHECK(squared_distance_to_triangle((a + b + c) / 3, a, b, c) == doctest::Approx(0).epsilon(1e-15));
}

TEST_CASE("hierarchy: a fine face's parent is the coarse face it lies on, not the one with the nearest centroid") {
  // A long coarse triangle and a small one beside its end; the fine face lies on the long one,
  // near the end, where the small triangle's centroid is much nearer than the long one's.
  Mesh coarse;
  coarse.vertices = {{0, 0, 0}, {10, 0, 0}, {5, 0.5, 0}, {-1, -1, 0}, {0, -1, 0}};
  coarse.faces = {{0, 1, 2}, {0, 3, 4}};
  Mesh fine;
  fine.vertices = {{0.8, 0.02, 0}, {1.2, 0.02, 0}, {1.0, 0.11, 0}};
  fine.faces = {{0, 1, 2}};
  CHECK(parent_faces(fine, coarse) == std::vector<int>{0});
  // Turned over, no coarse face points its way; the nearest of all is still the long one.
  fine.faces = {{0, 2, 1}};
  CHECK(parent_faces(fine, coarse) == std::vector<int>{0});
}

TEST_CASE("hierarchy: given the kept vertices, a parent comes from near on the surface, not across a gap") {
  // Two coarse faces facing the same way, B a little above A; the fine face starts at A's kept
  // corner and rises towards B (like a leg lying against a belly): nearest in space is B.
  Mesh coarse;
  coarse.vertices = {{0, 0, 0}, {4, 0, 0}, {0, 4, 0}, {-1, -1, 0.3}, {4, -1, 0.3}, {-1, 4, 0.3}};
  coarse.faces = {{0, 1, 2}, {3, 4, 5}};
  Mesh fine;
  fine.vertices = {{0, 0, 0}, {1, 0, 0.3}, {0, 1, 0.3}, {4, 0, 0}, {0, 4, 0}, {-1, -1, 0.3}, {4, -1, 0.3}, {-1, 4, 0.3}};
  fine.faces = {{0, 1, 2}};
  CHECK(parent_faces(fine, coarse) == std::vector<int>{1});
  // Coarse vertex v is fine vertex kept[v]; only fine vertex 0 (coarse 0, on A) is on the face's
  // side of the surface.
  const std::vector<int> kept{0, 3, 4, 5, 6, 7};
  CHECK(parent_faces(fine, coarse, kept) == std::vector<int>{0});
  CHECK_THROWS_AS(parent_faces(fine, coarse, {0, 3}), InvalidInputError);
}
