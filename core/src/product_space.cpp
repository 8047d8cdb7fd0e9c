#include "shapematch/product_space.hpp"

#include "shapematch/errors.hpp"

#include <algorithm>

namespace shapematch {
namespace {

std::array<int, 3> rotated(const std::array<int, 3>& f, int r) {
  return {f[r % 3], f[(r + 1) % 3], f[(r + 2) % 3]};
}

// Rotation r with rotated(f, r) == t, or -1.
int rotation_of(const std::array<int, 3>& f, const std::array<int, 3>& t) {
  for (int r = 0; r < 3; ++r)
    if (rotated(f, r) == t) return r;
  return -1;
}

bool is_vertex(const std::array<int, 3>& t) { return t[0] == t[1] && t[1] == t[2]; }

}  // namespace

int64_t ProductSpace::full_size(const Mesh& x, const Mesh& y) {
  const int64_t fx = x.num_faces(), ex = x.num_edges(), vx = x.num_vertices();
  const int64_t fy = y.num_faces(), ey = y.num_edges(), vy = y.num_vertices();
  return 3 * fx * fy + vx * fy + 6 * ex * fy + fx * vy + 6 * fx * ey;
}

ProductSpace ProductSpace::full(const Mesh& x, const Mesh& y) {
  ProductSpace s;
  s.x_ = &x;
  s.y_ = &y;
  const int64_t fx = x.num_faces(), ex = x.num_edges(), vx = x.num_vertices();
  const int64_t fy = y.num_faces(), ey = y.num_edges(), vy = y.num_vertices();
  s.offsets_[0] = 0;
  s.offsets_[1] = s.offsets_[0] + 3 * fx * fy;  // TT
  s.offsets_[2] = s.offsets_[1] + vx * fy;      // VT
  s.offsets_[3] = s.offsets_[2] + 6 * ex * fy;  // ET
  s.offsets_[4] = s.offsets_[3] + fx * vy;      // TV
  s.offsets_[5] = s.offsets_[4] + 6 * fx * ey;  // TE
  s.size_ = s.offsets_[5];
  return s;
}

ProductSpace ProductSpace::from_list(const Mesh& x, const Mesh& y, std::vector<ProductTriangle> list) {
  ProductSpace s;
  s.x_ = &x;
  s.y_ = &y;
  s.size_ = static_cast<int64_t>(list.size());
  s.list_ = std::move(list);
  return s;
}

Block ProductSpace::block_of(int64_t j) const {
  const auto it = std::upper_bound(offsets_.begin() + 1, offsets_.end(), j);
  return static_cast<Block>(it - offsets_.begin() - 1);
}

ProductTriangle ProductSpace::operator[](int64_t j) const {
  if (!list_.empty()) return list_[static_cast<size_t>(j)];
  const Mesh& X = *x_;
  const Mesh& Y = *y_;
  const int64_t fy = Y.num_faces(), vy = Y.num_vertices(), dey = 2 * int64_t(Y.num_edges());
  ProductTriangle t;
  switch (block_of(j)) {
    case Block::TT: {
      const int64_t k = j - offsets_[0];
      t.fa = static_cast<int>(k / (3 * fy));
      const int r = static_cast<int>((k / fy) % 3);
      t.fb = static_cast<int>(k % fy);
      t.a = rotated(X.faces[t.fa], r);
      t.b = Y.faces[t.fb];
      break;
    }
    case Block::VT: {
      const int64_t k = j - offsets_[1];
      const int v = static_cast<int>(k / fy);
      t.fb = static_cast<int>(k % fy);
      t.a = {v, v, v};
      t.b = Y.faces[t.fb];
      break;
    }
    case Block::ET: {
      const int64_t k = j - offsets_[2];
      const auto e = X.directed_edge(static_cast<int>(k / (3 * fy)));
      const int r = static_cast<int>((k / fy) % 3);
      t.fb = static_cast<int>(k % fy);
      t.a = {e[0], e[1], e[1]};
      t.b = rotated(Y.faces[t.fb], r);
      break;
    }
    case Block::TV: {
      const int64_t k = j - offsets_[3];
      t.fa = static_cast<int>(k / vy);
      const int w = static_cast<int>(k % vy);
      t.a = X.faces[t.fa];
      t.b = {w, w, w};
      break;
    }
    case Block::TE: {
      const int64_t k = j - offsets_[4];
      t.fa = static_cast<int>(k / (3 * dey));
      const int r = static_cast<int>((k / dey) % 3);
      const auto e = Y.directed_edge(static_cast<int>(k % dey));
      t.a = rotated(X.faces[t.fa], r);
      t.b = {e[0], e[1], e[1]};
      break;
    }
  }
  return t;
}

int64_t ProductSpace::index_in_full(const ProductTriangle& t) const {
  const Mesh& X = *x_;
  const Mesh& Y = *y_;
  const int64_t fy = Y.num_faces(), vy = Y.num_vertices(), dey = 2 * int64_t(Y.num_edges());
  auto fail = [] [[noreturn]] () { throw InvalidInputError("product triangle is not in canonical form"); };
  if (t.fa >= 0 && t.fb >= 0) {
    const int r = rotation_of(X.faces[t.fa], t.a);
    if (r < 0 || t.b != Y.faces[t.fb]) fail();
    return offsets_[0] + (int64_t(t.fa) * 3 + r) * fy + t.fb;
  }
  if (t.fb >= 0) {
    if (is_vertex(t.a)) {
      if (t.b != Y.faces[t.fb]) fail();
      return offsets_[1] + int64_t(t.a[0]) * fy + t.fb;
    }
    if (t.a[1] != t.a[2]) fail();
    // ET: X tuple is (tail, head, head); the Y face may be rotated.
    const int d = X.directed_edge_index(t.a[0], t.a[1]);
    const int r = rotation_of(Y.faces[t.fb], t.b);
    if (d < 0 || r < 0) fail();
    return offsets_[2] + (int64_t(d) * 3 + r) * fy + t.fb;
  }
  if (t.fa >= 0) {
    if (is_vertex(t.b)) {
      if (t.a != X.faces[t.fa]) fail();
      return offsets_[3] + int64_t(t.fa) * vy + t.b[0];
    }
    const int r = rotation_of(X.faces[t.fa], t.a);
    const int d = Y.directed_edge_index(t.b[0], t.b[1]);
    if (r < 0 || d < 0 || t.b[1] != t.b[2]) fail();
    return offsets_[4] + (int64_t(t.fa) * 3 + r) * dey + d;
  }
  fail();
}

std::vector<ProductTriangle> identity_matching(const Mesh& mesh) {
  std::vector<ProductTriangle> gamma;
  gamma.reserve(mesh.faces.size());
  for (int f = 0; f < mesh.num_faces(); ++f)
    gamma.push_back({mesh.faces[f], mesh.faces[f], f, f});
  return gamma;
}

}  // namespace shapematch
