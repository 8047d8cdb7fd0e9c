#pragma once
// The constraint system A x = b of DESIGN.md §4: A = [∂; π_X; π_Y], b = [0; 1; 1].
#include "shapematch/product_space.hpp"
#include "shapematch/sparse.hpp"

#include <cstdint>

namespace shapematch {

// A product edge (u1->u2 on X, w1->w2 on Y) in canonical orientation, encoded as one integer
// over the full product-edge space: [EE: 2|E_X||E_Y|][VE: |V_X||E_Y|][EV: |E_X||V_Y|].
struct ProductEdgeIndex {
  int64_t id = 0;
  int sign = +1;  // +1 if the triangle's boundary runs in the canonical direction
};

// The three boundary edges p1->p2, p2->p3, p3->p1 of a product triangle (eq. 7).
std::array<ProductEdgeIndex, 3> boundary_edges(const Mesh& x, const Mesh& y, const ProductTriangle& t);

// 2|E_X||E_Y| + |V_X||E_Y| + |E_X||V_Y|.
int64_t full_product_edge_count(const Mesh& x, const Mesh& y);

struct ConstraintSystem {
  SignedCsr a;        // rows: [closedness rows][|F_X| rows π_X][|F_Y| rows π_Y]
  SignedCsr at;       // the transpose, stored explicitly (gather-only SpMV on the GPU)
  std::vector<double> b;
  int64_t closedness_rows = 0;   // rows of ∂ actually used (untouched product edges dropped)
  std::vector<int64_t> row_edge; // product-edge id of each closedness row
};

// What an LP over one product triangle takes in memory, about: its assembly, A and Aᵀ, and a
// native PDHG solve's vectors. Measured with `lp --max-iter 1 --solver pdhg-cpu` on TOSCA_r
// horse0-horse5 decimated to 200 and 400 faces (0.88 M and 3.52 M variables): 148 and 558 MiB
// peak, 162 bytes per variable more.
inline constexpr uint64_t kLpBytesPerVariable = 160;

// Throws InvalidInputError naming both meshes where an LP of `variables` product triangles would
// need more than `available_bytes` (0: unknown, no check): a huge input gets a one-line error
// rather than the kernel's out-of-memory kill half way through.
void check_lp_memory(const Mesh& x, const Mesh& y, int64_t variables, uint64_t available_bytes);

// Assembles A, Aᵀ and b for the given product space. Multi-threaded over variables. Checks the
// memory first (check_lp_memory, against what the system has available now).
ConstraintSystem build_constraints(const ProductSpace& space);

}  // namespace shapematch
