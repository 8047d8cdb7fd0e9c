#include "shapematch/constraints.hpp"

#include "parallel.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/system.hpp"
#include "sorted_index.hpp"

#include <spdlog/fmt/fmt.h>

#include <algorithm>
#include <cstdlib>
#include <string>

namespace shapematch {
namespace {

// The product edge (u1->u2, w1->w2), not both degenerate, in canonical orientation.
ProductEdgeIndex product_edge(const Mesh& x, const Mesh& y, int u1, int u2, int w1, int w2) {
  const int64_t ex = x.num_edges(), ey = y.num_edges(), vx = x.num_vertices(), vy = y.num_vertices();
  ProductEdgeIndex pe;
  if (u1 != u2) {
    if (u1 > u2) {  // canonical: the X part runs from the smaller index
      std::swap(u1, u2);
      std::swap(w1, w2);
      pe.sign = -1;
    }
    const int e = x.edge_index(u1, u2);
    if (e < 0) throw InvalidInputError("product triangle uses a non-edge of X");
    if (w1 == w2) {
      pe.id = 2 * ex * ey + vx * ey + int64_t(e) * vy + w1;  // EV
    } else {
      const int d = y.directed_edge_index(w1, w2);
      if (d < 0) throw InvalidInputError("product triangle uses a non-edge of Y");
      pe.id = int64_t(e) * 2 * ey + d;  // EE
    }
  } else {
    if (w1 == w2) throw InvalidInputError("product edge degenerate on both sides");
    pe.sign = w1 < w2 ? +1 : -1;
    const int e = y.edge_index(std::min(w1, w2), std::max(w1, w2));
    if (e < 0) throw InvalidInputError("product triangle uses a non-edge of Y");
    pe.id = 2 * ex * ey + int64_t(u1) * ey + e;  // VE
  }
  (void)vy;
  return pe;
}

}  // namespace

std::array<ProductEdgeIndex, 3> boundary_edges(const Mesh& x, const Mesh& y, const ProductTriangle& t) {
  std::array<ProductEdgeIndex, 3> out;
  for (int i = 0; i < 3; ++i) {
    const int k = (i + 1) % 3;
    out[i] = product_edge(x, y, t.a[i], t.a[k], t.b[i], t.b[k]);
  }
  return out;
}

int64_t full_product_edge_count(const Mesh& x, const Mesh& y) {
  const int64_t ex = x.num_edges(), ey = y.num_edges(), vx = x.num_vertices(), vy = y.num_vertices();
  return 2 * ex * ey + vx * ey + ex * vy;
}

void check_lp_memory(const Mesh& x, const Mesh& y, int64_t variables, uint64_t available_bytes) {
  const double needed = double(variables) * double(kLpBytesPerVariable);
  if (available_bytes == 0 || needed <= double(available_bytes)) return;
  throw InvalidInputError(fmt::format(
      "{} × {} ({} × {} faces): the LP over {} product triangles needs about {:.1f} GB, more than the {:.1f} GB "
      "this machine has available; decimate (--faces) or free memory (SHAPEMATCH_MEMORY_CHECK=0 skips this check)",
      x.name, y.name, x.num_faces(), y.num_faces(), variables, needed / 1e9, double(available_bytes) / 1e9));
}

ConstraintSystem build_constraints(const ProductSpace& space) {
  const Mesh& X = space.x();
  const Mesh& Y = space.y();
  const int64_t n = space.size();
  if (n >= (int64_t(1) << 31))
    throw InvalidInputError(fmt::format("{} × {} ({} × {} faces): product space too large: {} variables (at most 2³¹)",
                                        X.name, Y.name, X.num_faces(), Y.num_faces(), n));
  // SHAPEMATCH_MEMORY_CHECK=0 skips it (a machine whose swap should take the rest).
  const char* check = std::getenv("SHAPEMATCH_MEMORY_CHECK");
  if (!check || std::string(check) != "0") check_lp_memory(X, Y, n, available_memory_bytes());

  // Pass 1: boundary edges of every variable (ids and signs) and the π rows it touches.
  std::vector<int64_t> edge_id(3 * n);
  std::vector<int8_t> edge_sign(3 * n);
  std::vector<int> fa(n), fb(n);
  detail::parallel_for(n, 0, [&](int64_t j) {
    const ProductTriangle t = space[j];
    const auto be = boundary_edges(X, Y, t);
    for (int i = 0; i < 3; ++i) {
      edge_id[3 * j + i] = be[i].id;
      edge_sign[3 * j + i] = static_cast<int8_t>(be[i].sign);
    }
    fa[j] = t.fa;
    fb[j] = t.fb;
  });

  ConstraintSystem cs;
  // Closedness rows: in the full space every product edge is touched, so ids are row numbers;
  // otherwise keep only the touched ones, in id order.
  std::vector<uint32_t> edge_row(3 * n);
  const int64_t universe = full_product_edge_count(X, Y);
  if (space.is_full()) {
    cs.closedness_rows = universe;
    cs.row_edge.resize(cs.closedness_rows);
    for (int64_t r = 0; r < cs.closedness_rows; ++r) cs.row_edge[r] = r;
    for (int64_t k = 0; k < 3 * n; ++k) edge_row[k] = static_cast<uint32_t>(edge_id[k]);
  } else if (universe / 64 <= 3 * n) {  // a bitmap no larger than the list of ids
    const detail::KeyBitmap touched(edge_id, universe);
    cs.closedness_rows = touched.size();
    cs.row_edge = touched.sorted();
    detail::parallel_for(3 * n, 0, [&](int64_t k) { edge_row[k] = static_cast<uint32_t>(touched.rank(edge_id[k])); });
  } else {
    cs.row_edge = edge_id;
    detail::parallel_sort(cs.row_edge.data(), static_cast<int64_t>(cs.row_edge.size()));
    cs.row_edge.erase(std::unique(cs.row_edge.begin(), cs.row_edge.end()), cs.row_edge.end());
    cs.closedness_rows = static_cast<int64_t>(cs.row_edge.size());
    const detail::SortedIndex index(cs.row_edge);
    detail::parallel_for(3 * n, 0, [&](int64_t k) { edge_row[k] = static_cast<uint32_t>(index.rank(edge_id[k])); });
  }
  const int64_t m = cs.closedness_rows + X.num_faces() + Y.num_faces();
  if (m >= (int64_t(1) << 31)) throw InvalidInputError("too many constraints: " + std::to_string(m));
  std::vector<int64_t>().swap(edge_id);

  // Aᵀ: one row per variable with its 3 closedness entries and 1–2 projection entries.
  SignedCsr& at = cs.at;
  at.rows = n;
  at.cols = m;
  at.row_ptr.assign(n + 1, 0);
  int64_t nonzeros = 0;  // counted in 64 bits: up to 5n may exceed the 32-bit row pointers
  for (int64_t j = 0; j < n; ++j) {
    nonzeros += 3 + (fa[j] >= 0) + (fb[j] >= 0);
    if (nonzeros >= 0x7fffffff) throw InvalidInputError("constraint matrix too large: over 2^31 nonzeros");
    at.row_ptr[j + 1] = static_cast<uint32_t>(nonzeros);
  }
  at.entry.resize(at.row_ptr[n]);
  const uint32_t pix = static_cast<uint32_t>(cs.closedness_rows);
  const uint32_t piy = pix + static_cast<uint32_t>(X.num_faces());
  detail::parallel_for(n, 0, [&](int64_t j) {
    uint32_t* e = &at.entry[at.row_ptr[j]];
    int k = 0;
    for (int i = 0; i < 3; ++i)
      e[k++] = edge_row[3 * j + i] | (edge_sign[3 * j + i] < 0 ? SignedCsr::kNegative : 0u);
    if (fa[j] >= 0) e[k++] = pix + static_cast<uint32_t>(fa[j]);
    if (fb[j] >= 0) e[k++] = piy + static_cast<uint32_t>(fb[j]);
    std::sort(e, e + k, [](uint32_t p, uint32_t q) { return (p & ~SignedCsr::kNegative) < (q & ~SignedCsr::kNegative); });
  });
  cs.a = transpose(at);

  cs.b.assign(m, 0.0);
  std::fill(cs.b.begin() + cs.closedness_rows, cs.b.end(), 1.0);
  return cs;
}

}  // namespace shapematch
