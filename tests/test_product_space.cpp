#include "shapematch/product_space.hpp"
#include "shapematch/shapes.hpp"
#include "test_helpers.hpp"

#include <doctest/doctest.h>
#include <algorithm>
#include <set>
#include <tuple>

using namespace shapematch;

TEST_CASE("product space: variable count equals the closed-mesh formula") {
  const Mesh tet = shapes::tetrahedron(), oct = shapes::octahedron(), ico = shapes::icosphere(1);
  for (const Mesh* x : {&tet, &oct, &ico})
    for (const Mesh* y : {&tet, &oct, &ico}) {
      const ProductSpace s = ProductSpace::full(*x, *y);
      const int64_t fx = x->num_faces(), ex = x->num_edges(), vx = x->num_vertices();
      const int64_t fy = y->num_faces(), ey = y->num_edges(), vy = y->num_vertices();
      CHECK(s.size() == 3 * fx * fy + vx * fy + 6 * ex * fy + fx * vy + 6 * fx * ey);
      CHECK(s.block_offset(Block::VT) == 3 * fx * fy);
      CHECK(s.block_offset(Block::TE) == s.size() - 6 * fx * ey);
    }
  // Tetrahedron × tetrahedron by hand: F=4, E=6, V=4 → 48 + 16 + 144 + 16 + 144.
  CHECK(ProductSpace::full(tet, tet).size() == 368);
}

TEST_CASE("product space: decoding is canonical and inverts index_in_full") {
  const Mesh x = shapes::octahedron(), y = shapes::tetrahedron();
  const ProductSpace s = ProductSpace::full(x, y);
  std::set<std::pair<std::array<int, 3>, std::array<int, 3>>> seen;
  for (int64_t j = 0; j < s.size(); ++j) {
    const ProductTriangle t = s[j];
    REQUIRE(s.index_in_full(t) == j);
    CHECK((t.fa >= 0 || t.fb >= 0));  // at least one side is a real triangle
    if (t.fa >= 0) CHECK(std::is_permutation(t.a.begin(), t.a.end(), x.faces[t.fa].begin()));
    if (t.fb >= 0) CHECK(std::is_permutation(t.b.begin(), t.b.end(), y.faces[t.fb].begin()));
    // No two variables are the same product triangle up to a joint rotation.
    std::array<int, 3> a = t.a, b = t.b;
    int best = 0;
    for (int r = 1; r < 3; ++r) {
      std::array<int, 3> ar{t.a[r], t.a[(r + 1) % 3], t.a[(r + 2) % 3]}, br{t.b[r], t.b[(r + 1) % 3], t.b[(r + 2) % 3]};
      if (std::tie(ar, br) < std::tie(a, b)) a = ar, b = br, best = r;
    }
    (void)best;
    CHECK(seen.insert({a, b}).second);
  }
}

TEST_CASE("product space: explicit lists decode to themselves") {
  const Mesh m = shapes::icosphere(1);
  const auto id = identity_matching(m);
  const ProductSpace full = ProductSpace::full(m, m);
  const ProductSpace sub = ProductSpace::from_list(m, m, id);
  REQUIRE(sub.size() == m.num_faces());
  for (int64_t j = 0; j < sub.size(); ++j) {
    CHECK(sub[j] == id[j]);
    CHECK(full[full.index_in_full(id[j])] == id[j]);
  }
  CHECK_FALSE(sub.is_full());
  CHECK(full.is_full());
}
