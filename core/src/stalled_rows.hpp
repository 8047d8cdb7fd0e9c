#pragma once
// Where a row of the matching LP lies on the two meshes, for the debug log of a first LP that
// stalls short of feasible (rounding.cpp): kept apart so that its decoding is tested on its own.
#include "shapematch/lp.hpp"
#include "shapematch/product_space.hpp"
#include "shapematch/sparse.hpp"

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

}  // namespace shapematch::detail
