#pragma once
// Where a row of the matching LP lies on the two meshes, for the debug log of a first LP that
// stalls short of feasible (rounding.cpp): kept apart so that its decoding is tested on its own.
#include "shapematch/lp.hpp"
#include "shapematch/product_space.hpp"
#include "shapematch/sparse.hpp"
#include "suspicion_margin.hpp"

#include <cstdint>
#include <iterator>
#include <set>
#include <utility>
#include <vector>

namespace shapematch::detail {

struct RowPlace {
  enum Kind { closedness, pi_x, pi_y } kind = closedness;
  int face = -1;  // π rows: the X (π_X) or Y (π_Y) face
  // Closedness rows: the product vertices (X vertex, Y vertex) all its columns share, the product
  // edge (two of them; more only where the row has a single column).
  std::vector<std::pair<int, int>> edge;
};

// Row `row` of `lp`, a matching LP over `space` (rows: closedness, then π_X, then π_Y).
inline RowPlace row_place(const ProductSpace& space, const LpProblem& lp, int64_t row) {
  RowPlace p;
  const int64_t fx = space.x().num_faces(), fy = space.y().num_faces();
  const int64_t first_pi = lp.rows() - fx - fy;
  if (row >= first_pi + fx) {
    p.kind = RowPlace::pi_y;
    p.face = static_cast<int>(row - first_pi - fx);
    return p;
  }
  if (row >= first_pi) {
    p.kind = RowPlace::pi_x;
    p.face = static_cast<int>(row - first_pi);
    return p;
  }
  std::set<std::pair<int, int>> common;
  for (uint32_t k = lp.a.row_ptr[row]; k < lp.a.row_ptr[row + 1]; ++k) {
    const ProductTriangle t = space[col_of(lp.a.entry[k])];
    std::set<std::pair<int, int>> here;
    for (int v = 0; v < 3; ++v) here.emplace(t.a[v], t.b[v]);
    if (k == lp.a.row_ptr[row]) common = std::move(here);
    else
      for (auto it = common.begin(); it != common.end();) it = here.count(*it) ? std::next(it) : common.erase(it);
  }
  p.edge.assign(common.begin(), common.end());
  return p;
}

// The X faces where the rows `rows` of `lp` lie: those of the columns of each row that carry at
// least `at_least` of `x`, or of all its columns where none does (or `x` is not given); columns
// j of `lp` are space[cols[j]], and a column whose X part is an edge or a vertex names the faces
// on its vertices.
inline std::vector<int> x_faces_of_rows(const ProductSpace& space, const LpProblem& lp, const std::vector<int64_t>& cols,
                                        const std::vector<double>& x, const std::vector<int64_t>& rows,
                                        double at_least = 0.01) {
  const Mesh& X = space.x();
  std::vector<std::vector<int>> around;  // faces per X vertex, built where first needed
  std::set<int> faces;
  const auto add = [&](const ProductTriangle& t) {
    if (t.fa >= 0) {
      faces.insert(t.fa);
      return;
    }
    if (around.empty()) {
      around.resize(X.num_vertices());
      for (int f = 0; f < X.num_faces(); ++f)
        for (int v : X.faces[f]) around[v].push_back(f);
    }
    for (int v : t.a) faces.insert(around[v].begin(), around[v].end());
  };
  const bool given = x.size() == cols.size();
  for (int64_t r : rows) {
    bool any = false;
    for (uint32_t k = lp.a.row_ptr[r]; k < lp.a.row_ptr[r + 1]; ++k) {
      const uint32_t j = col_of(lp.a.entry[k]);
      if (given && x[j] < at_least) continue;
      add(space[cols[j]]);
      any = true;
    }
    if (!any)
      for (uint32_t k = lp.a.row_ptr[r]; k < lp.a.row_ptr[r + 1]; ++k) add(space[cols[col_of(lp.a.entry[k])]]);
  }
  return {faces.begin(), faces.end()};
}

// The rows of `lp` that a column over the X faces `faces` has (its X part a face of them, or an
// edge or vertex of one), increasing: an X region's rows, for a local proof (local_proof.hpp) that
// grows with the region rather than with every column its rows reach. `cols`: lp's columns in
// `space` (empty: the same numbering).
inline std::vector<int64_t> rows_over_x_faces(const ProductSpace& space, const LpProblem& lp,
                                              const std::vector<int64_t>& cols, const std::vector<int>& faces) {
  const Mesh& X = space.x();
  std::vector<char> face_in(X.num_faces(), 0), vertex_in(X.num_vertices(), 0);
  for (int f : faces) {
    face_in[f] = 1;
    for (int v : X.faces[f]) vertex_in[v] = 1;
  }
  std::vector<char> in(lp.rows(), 0);
  for (int64_t j = 0; j < lp.cols(); ++j) {
    const ProductTriangle t = space[cols.empty() ? j : cols[j]];
    const bool over = t.fa >= 0 ? face_in[t.fa] != 0 : vertex_in[t.a[0]] && vertex_in[t.a[1]] && vertex_in[t.a[2]];
    if (!over) continue;
    for (uint32_t k = lp.at.row_ptr[j]; k < lp.at.row_ptr[j + 1]; ++k) in[col_of(lp.at.entry[k])] = 1;
  }
  std::vector<int64_t> out;
  for (int64_t r = 0; r < lp.rows(); ++r)
    if (in[r]) out.push_back(r);
  return out;
}

// rows_over_x_faces over the X faces within `rings` rings of `faces` (none where `faces` is
// empty): the region a local proof solves over, the same in the rounding and in its re-check.
inline std::vector<int64_t> x_region_rows(const ProductSpace& space, const LpProblem& lp,
                                          const std::vector<int64_t>& cols, const std::vector<int>& faces, int rings) {
  if (faces.empty()) return {};
  return rows_over_x_faces(space, lp, cols, faces_near(space.x(), faces, 1 + rings));
}

}  // namespace shapematch::detail
