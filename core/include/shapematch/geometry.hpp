#pragma once
// Per-vertex and per-face differential geometry (Meyer et al. 2002).
#include "shapematch/mesh.hpp"

#include <Eigen/Sparse>

namespace shapematch {

struct Geometry {
  std::vector<double> face_area;                   // |F|
  std::vector<std::array<double, 3>> corner_area;  // |F|: mixed Voronoi area of corner i inside face f
  std::vector<double> vertex_area;                 // |V|: sum of the corner areas (mixed Voronoi area)
  std::vector<Eigen::Vector3d> vertex_normal;      // |V|: area-weighted, unit length
  std::vector<double> mean_curvature;              // |V|: signed, H = 1/r on a sphere of radius r
  Eigen::SparseMatrix<double> cotan_laplacian;     // |V|x|V| positive semi-definite: L_ij = -(cot a + cot b)/2
  std::vector<int> halfedge_face;                  // |2E|: the face holding directed edge d (Mesh::directed_edge_index)
};

Geometry compute_geometry(const Mesh& mesh);

// The mean curvature averaged, weighted by vertex area, over the vertices within Euclidean distance
// `radius` of each vertex that are reached through edges staying within it (so that two fingers a
// radius apart stay apart). radius <= 0: g.mean_curvature itself. The per-vertex estimate is as
// noisy as the mesh is fine (FAUST_r at 10 000 faces: the median jump across an edge is half the
// median |H|); averaged over a fixed radius it is nearly the same quantity at every resolution.
std::vector<double> smoothed_mean_curvature(const Mesh& mesh, const Geometry& g, double radius);

// The orientation of the triangle (a, b, c) of y's vertices: +1 kept, -1 inverted, 0 degenerate
// (a repeated or collinear corner). A face of y is judged by y's own orientation (+1 in its
// cyclic order, -1 reversed), any other triangle against y's vertex normals at its corners. How
// a vertex map's image of a face is judged. (Vertex normals alone called a face of y inverted
// where y folds: 7-12 faces of each 500-vertex FAUST_r decimation, so even the identity map
// "flipped" faces.)
int image_orientation(const Mesh& y, const Geometry& gy, int a, int b, int c);

}  // namespace shapematch
