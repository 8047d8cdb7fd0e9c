#pragma once
// The product space X×Y of DESIGN.md §3: product triangles are the LP's variables.
#include "shapematch/mesh.hpp"

#include <cstdint>
#include <vector>

namespace shapematch {

// A product triangle: vertices p_i = (a[i], b[i]); it maps the X tuple a onto the Y tuple b.
// A degenerate tuple repeats a vertex: (v,v,v) or (u,w,w) for the directed edge u->w.
struct ProductTriangle {
  std::array<int, 3> a{};
  std::array<int, 3> b{};
  int fa = -1;  // face of X when the X part is a triangle, else -1
  int fb = -1;  // face of Y when the Y part is a triangle, else -1

  bool operator==(const ProductTriangle&) const = default;
};

// The five blocks of the canonical enumeration, in this order of variable indices.
enum class Block : int { TT = 0, VT = 1, ET = 2, TV = 3, TE = 4 };

// Either the full product space (decoded arithmetically, nothing stored) or an explicit list
// (the reduced spaces of coarse to fine). Holds references to both meshes: they must outlive it.
class ProductSpace {
public:
  // Every product triangle of X×Y, about 22·|F_X|·|F_Y| of them.
  static ProductSpace full(const Mesh& x, const Mesh& y);
  // An explicit subset (each entry must be a valid product triangle in canonical form).
  static ProductSpace from_list(const Mesh& x, const Mesh& y, std::vector<ProductTriangle> list);

  int64_t size() const { return size_; }
  bool is_full() const { return list_.empty() && size_ > 0; }
  ProductTriangle operator[](int64_t j) const;
  const Mesh& x() const { return *x_; }
  const Mesh& y() const { return *y_; }

  // Full space only: block offsets (offset(Block::TT) == 0, offset of one past TE == size()).
  int64_t block_offset(Block block) const { return offsets_[static_cast<int>(block)]; }
  Block block_of(int64_t j) const;

  // Index of a canonical product triangle in the full space (inverse of operator[]), for tests
  // and for looking up the identity matching.
  int64_t index_in_full(const ProductTriangle& t) const;

  // 3|F_X||F_Y| + |V_X||F_Y| + 6|E_X||F_Y| + |F_X||V_Y| + 6|F_X||E_Y|.
  static int64_t full_size(const Mesh& x, const Mesh& y);

private:
  const Mesh* x_ = nullptr;
  const Mesh* y_ = nullptr;
  int64_t size_ = 0;
  std::array<int64_t, 6> offsets_{};
  std::vector<ProductTriangle> list_;
};

// The identity matching of a mesh with itself: every face mapped onto itself, rotation 0.
std::vector<ProductTriangle> identity_matching(const Mesh& mesh);

}  // namespace shapematch
