#include "shapematch/constraints.hpp"
#include "shapematch/shapes.hpp"
#include "shapematch/system.hpp"
#include "test_helpers.hpp"

#include "sorted_index.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <filesystem>
#include <numeric>

using namespace shapematch;

namespace {

// A x computed exactly in integers for a 0/1 vector given as a list of columns.
std::vector<int64_t> apply_integer(const ConstraintSystem& cs, const std::vector<int64_t>& columns) {
  std::vector<int64_t> ax(cs.a.rows, 0);
  for (int64_t j : columns)
    for (uint32_t k = cs.at.row_ptr[j]; k < cs.at.row_ptr[j + 1]; ++k)
      ax[col_of(cs.at.entry[k])] += is_negative(cs.at.entry[k]) ? -1 : 1;
  return ax;
}

bool satisfies(const ConstraintSystem& cs, const std::vector<int64_t>& columns) {
  const auto ax = apply_integer(cs, columns);
  for (int64_t i = 0; i < cs.a.rows; ++i)
    if (ax[i] != static_cast<int64_t>(cs.b[i])) return false;
  return true;
}

std::vector<Mesh> test_meshes() {
  std::vector<Mesh> ms{shapes::tetrahedron(), shapes::octahedron(), shapes::icosphere(1)};
  const std::string asset = std::string(SHAPEMATCH_ASSETS_DIR) + "/finger_straight.off";
  if (std::filesystem::exists(asset)) ms.push_back(decimate(load_mesh(asset), 60));
  return ms;
}

}  // namespace

TEST_CASE("constraints: row, column and nonzero counts match the formulas") {
  const auto meshes = test_meshes();
  REQUIRE(meshes.size() == 4);
  for (size_t i = 0; i < meshes.size(); ++i)
    for (size_t k = 0; k < meshes.size(); ++k) {
      const Mesh& x = meshes[i];
      const Mesh& y = meshes[k];
      if (x.num_faces() * y.num_faces() > 60 * 80) continue;
      const ProductSpace s = ProductSpace::full(x, y);
      const ConstraintSystem cs = build_constraints(s);
      const int64_t ex = x.num_edges(), ey = y.num_edges(), vx = x.num_vertices(), vy = y.num_vertices();
      CHECK(cs.closedness_rows == 2 * ex * ey + vx * ey + ex * vy);
      CHECK(cs.a.rows == cs.closedness_rows + x.num_faces() + y.num_faces());
      CHECK(cs.a.cols == s.size());
      // TT columns have two projection entries, the other blocks one.
      const int64_t tt = 3 * int64_t(x.num_faces()) * y.num_faces();
      CHECK(int64_t(cs.a.entry.size()) == 3 * s.size() + s.size() + tt);
      for (int64_t j = 0; j < s.size(); ++j) {
        int boundary = 0, projection = 0;
        for (uint32_t q = cs.at.row_ptr[j]; q < cs.at.row_ptr[j + 1]; ++q) {
          const uint32_t r = col_of(cs.at.entry[q]);
          if (r < cs.closedness_rows) {
            ++boundary;
          } else {
            ++projection;
            CHECK_FALSE(is_negative(cs.at.entry[q]));  // π entries are +1
          }
        }
        CHECK(boundary == 3);
        CHECK((projection == 1 || projection == 2));
      }
      for (int64_t r = 0; r < cs.a.rows; ++r) CHECK(cs.a.row_ptr[r + 1] > cs.a.row_ptr[r]);  // no empty rows
      CHECK(std::count(cs.b.begin(), cs.b.end(), 1.0) == x.num_faces() + y.num_faces());
    }
}

TEST_CASE("constraints: the identity matching is feasible, in integers") {
  for (const Mesh& m : test_meshes()) {
    if (m.num_faces() > 80) continue;
    const ProductSpace s = ProductSpace::full(m, m);
    const ConstraintSystem cs = build_constraints(s);
    std::vector<int64_t> cols;
    for (const auto& t : identity_matching(m)) cols.push_back(s.index_in_full(t));
    CHECK(satisfies(cs, cols));
    // Removing any single face of Γ breaks closedness and coverage.
    auto broken = cols;
    broken.erase(broken.begin() + broken.size() / 2);
    CHECK_FALSE(satisfies(cs, broken));
  }
}

TEST_CASE("constraints: an orientation-preserving symmetry of the octahedron is feasible") {
  const Mesh m = shapes::octahedron();
  // Rotation by 90° about z permutes the vertices; find the permutation from the positions.
  std::vector<int> sigma(m.num_vertices());
  for (int v = 0; v < m.num_vertices(); ++v) {
    const Eigen::Vector3d p = m.vertices[v];
    const Eigen::Vector3d q(-p.y(), p.x(), p.z());
    for (int w = 0; w < m.num_vertices(); ++w)
      if ((m.vertices[w] - q).norm() < 1e-9) sigma[v] = w;
  }
  const ProductSpace s = ProductSpace::full(m, m);
  const ConstraintSystem cs = build_constraints(s);
  std::vector<int64_t> cols;
  for (int f = 0; f < m.num_faces(); ++f) {
    const auto& a = m.faces[f];
    const std::array<int, 3> image{sigma[a[0]], sigma[a[1]], sigma[a[2]]};
    // The image is a face of Y up to rotation; canonical form keeps Y's face as stored.
    bool found = false;
    for (int g = 0; g < m.num_faces() && !found; ++g)
      for (int r = 0; r < 3 && !found; ++r) {
        const std::array<int, 3> ar{a[r], a[(r + 1) % 3], a[(r + 2) % 3]};
        if (std::array<int, 3>{sigma[ar[0]], sigma[ar[1]], sigma[ar[2]]} == m.faces[g]) {
          cols.push_back(s.index_in_full({ar, m.faces[g], f, g}));
          found = true;
        }
      }
    REQUIRE(found);
  }
  CHECK(satisfies(cs, cols));
}

TEST_CASE("constraints: a reduced space drops untouched closedness rows") {
  const Mesh m = shapes::octahedron();
  const auto id = identity_matching(m);
  const ProductSpace s = ProductSpace::from_list(m, m, id);
  const ConstraintSystem cs = build_constraints(s);
  // Each mesh edge u–v gives the one product edge (u→v, u→v), shared by its two faces.
  CHECK(cs.closedness_rows == m.num_edges());
  std::vector<int64_t> cols(id.size());
  std::iota(cols.begin(), cols.end(), 0);
  CHECK(satisfies(cs, cols));
}

TEST_CASE("constraints: the sorted index ranks every key as lower_bound does") {
  std::mt19937_64 rng(7);
  for (const int64_t n : {0, 1, 2, 17, 1000, 100000}) {
    for (const int64_t span : {int64_t(1), int64_t(3), int64_t(1) << 20, int64_t(1) << 40}) {
      // Distinct keys with gaps of 1..span, 0 among them when n > 0, some clustered at the top.
      std::vector<int64_t> keys;
      int64_t k = 0;
      for (int64_t i = 0; i < n; ++i) {
        keys.push_back(k);
        k += i > n - n / 8 ? 1 : 1 + int64_t(rng() % uint64_t(span));
      }
      const detail::SortedIndex index(keys);
      const int64_t top = keys.empty() ? 0 : keys.back();
      auto check = [&](int64_t q) {
        const int64_t want = std::lower_bound(keys.begin(), keys.end(), q) - keys.begin();
        if (index.rank(q) != want) FAIL_CHECK("n ", n, " span ", span, " key ", q, ": ", index.rank(q), " not ", want);
      };
      for (int64_t key : keys) check(key);
      for (int i = 0; i < 2000; ++i) check(int64_t(rng() % uint64_t(top + 2)));
      check(-1);
      check(top + 1);
      check(std::numeric_limits<int64_t>::max());
    }
  }
}

TEST_CASE("constraints: the key bitmap sorts, deduplicates and ranks as sort, unique and lower_bound do") {
  std::mt19937_64 rng(5);
  for (const int64_t universe : {int64_t(1), int64_t(63), int64_t(64), int64_t(65), int64_t(1000), int64_t(1) << 22}) {
    for (const int64_t n : {0, 1, 5, 1000, 50000}) {
      std::vector<int64_t> keys(n);
      for (int64_t& k : keys) k = int64_t(rng() % uint64_t(universe));
      if (n > 0) keys[0] = universe - 1;  // the last id in range
      const detail::KeyBitmap bitmap(keys, universe);
      std::vector<int64_t> want = keys;
      std::sort(want.begin(), want.end());
      want.erase(std::unique(want.begin(), want.end()), want.end());
      CHECK(bitmap.size() == int64_t(want.size()));
      CHECK(bitmap.sorted() == want);
      for (int64_t k : keys)
        if (bitmap.rank(k) != std::lower_bound(want.begin(), want.end(), k) - want.begin())
          FAIL_CHECK("universe ", universe, " n ", n, " key ", k);
    }
  }
}

TEST_CASE("constraints: a reduced space gives the same rows by the bitmap as by sorting") {
  // Both paths: a space of every third variable of the full one (bitmap: the universe is small
  // against it) and one of a few variables (sorting).
  const Mesh x = shapes::icosphere(1);
  const Mesh y = test::deformed(x, [](const Eigen::Vector3d& p) { return Eigen::Vector3d(1.2 * p.x(), p.y(), p.z()); });
  const ProductSpace full = ProductSpace::full(x, y);
  for (const int64_t stride : {int64_t(3), int64_t(997)}) {
    std::vector<ProductTriangle> some;
    for (int64_t j = 0; j < full.size(); j += stride) some.push_back(full[j]);
    const ConstraintSystem cs = build_constraints(ProductSpace::from_list(x, y, some));
    // Every closedness row is a product edge touched, in id order, and every entry of Aᵀ names
    // the row of its edge.
    CHECK(std::is_sorted(cs.row_edge.begin(), cs.row_edge.end()));
    CHECK(std::adjacent_find(cs.row_edge.begin(), cs.row_edge.end()) == cs.row_edge.end());
    const ConstraintSystem whole = build_constraints(full);
    for (int64_t j = 0; j < int64_t(some.size()); ++j) {
      const int64_t jf = j * stride;
      for (int i = 0; i < 3; ++i) {
        const uint32_t e = cs.at.entry[cs.at.row_ptr[j] + i], ef = whole.at.entry[whole.at.row_ptr[jf] + i];
        const int64_t row = col_of(e), row_full = col_of(ef);
        REQUIRE(row < cs.closedness_rows);
        CHECK(cs.row_edge[row] == whole.row_edge[row_full]);  // the same product edge
        CHECK(is_negative(e) == is_negative(ef));
      }
    }
    CHECK(cs.closedness_rows < whole.closedness_rows);
  }
}

TEST_CASE("constraints: an LP larger than the memory available is refused in one line naming the meshes") {
  const Mesh x = shapes::icosphere(1), y = shapes::octahedron();
  const int64_t n = ProductSpace::full_size(x, y);
  // Enough, or unknown (0): no check.
  CHECK_NOTHROW(check_lp_memory(x, y, n, n * kLpBytesPerVariable));
  CHECK_NOTHROW(check_lp_memory(x, y, n, 0));
  // One byte short.
  try {
    check_lp_memory(x, y, n, n * kLpBytesPerVariable - 1);
    FAIL("no exception");
  } catch (const InvalidInputError& e) {
    const std::string what = e.what();
    CAPTURE(what);
    CHECK(what.rfind(x.name + " × " + y.name + " (" + std::to_string(x.num_faces()) + " × " +
                         std::to_string(y.num_faces()) + " faces): the LP over " + std::to_string(n) +
                         " product triangles needs about",
                     0) == 0);
    CHECK(what.find("more than the") != std::string::npos);
    CHECK(what.find('\n') == std::string::npos);
  }
  // build_constraints checks against this machine's memory, which Linux reports.
  CHECK(available_memory_bytes() > 0);
  CHECK_NOTHROW(build_constraints(ProductSpace::full(x, y)));
}
