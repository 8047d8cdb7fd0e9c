#pragma once
// Point maps read off Γ: every vertex of one shape to a point on the other (a face and
// barycentric coordinates), not just to a vertex. Γ relates a vertex to a whole set of the other
// shape where it blows the vertex up (a face) or stretches an edge (an edge); one partner vertex
// cannot follow that and inverts faces around it, a point inside the set, or next to it, can.
#include "shapematch/geometry.hpp"
#include "shapematch/mesh.hpp"
#include "shapematch/product_space.hpp"
#include "shapematch/rounding.hpp"

#include <array>
#include <string>
#include <vector>

namespace shapematch {

// A point on a mesh: barycentric coordinates (non-negative, summing to 1) in one of its faces.
struct SurfacePoint {
  int face = -1;
  std::array<double, 3> bary{};
};

// The point at vertex v (in the first face of `vertex_faces[v]`).
SurfacePoint vertex_point(const Mesh& mesh, const std::vector<std::vector<int>>& vertex_faces, int v);
// The vertex a point sits on, or -1 where it is inside an edge or a face.
int point_vertex(const Mesh& mesh, const SurfacePoint& p);
Eigen::Vector3d point_position(const Mesh& mesh, const SurfacePoint& p);

// The orientation of the triangle of three points on y: +1 kept, -1 inverted, 0 degenerate. Three
// vertices are judged as image_orientation does; three points in one face of y in that face's
// plane; any other triangle against y's vertex normals interpolated at its corners.
int image_orientation(const Mesh& y, const Geometry& gy, const SurfacePoint& a, const SurfacePoint& b,
                      const SurfacePoint& c);

struct PointMapOptions {
  // Where a vertex's faces still map to inverted triangles from every point of its fibre, it may
  // move to points of the faces within this many rings of its fibre.
  int max_ring = 5;
  // Interior points tried per face: barycentric (i, j, k) / samples with i, j, k >= 1.
  int samples = 8;
  int max_sweeps = 20;
  // Where single moves leave an image inverted (Γ folds there, so one vertex cannot move without
  // inverting another face), the discs of 1..this many rings around it are laid out again
  // (untangle_point_map). 0: off. (A fold in a slit of Γ needs a disc that reaches past the slit:
  // 8-13 rings on the TOSCA_r results, where 4 left faces inverted.)
  int untangle_rings = 24;
  // The most one disc may move the points, summed, divided by √area(to) and by the vertices of
  // `from`: about what one disc may add to the mean geodesic error (each disc kept must unfold a
  // face, so they are few).
  double untangle_max_shift = 1e-3;
};

struct PointMaps {
  std::vector<SurfacePoint> x_to_y;  // one point of Y per vertex of X
  std::vector<SurfacePoint> y_to_x;  // one point of X per vertex of Y
};

// Starts from `start` (vertex_maps' partners) and moves, one vertex at a time while that inverts
// fewer faces (then leaves fewer degenerate), first within the vertex's fibre (its partner
// vertices, points of the edges it is stretched along, points of the faces it is blown up over),
// then, for faces still inverted, to points of faces up to PointMapOptions::max_ring rings around
// the fibre, then, for degenerate images, up to two rings; then re-embeds discs around what is
// still inverted (untangle_point_map). Never inverts more faces than `start`.
PointMaps point_maps(const ProductSpace& space, const std::vector<int64_t>& gamma, const VertexMaps& start,
                     const PointMapOptions& options = {});

// For each face of `from` whose image under `map` is inverted, for r = 1, 2, ..., `max_rings`
// while it stays inverted: the disc of r vertex rings around its corners is laid out again. The
// rim's points stay; the inside goes to Tutte's embedding (mean-value weights of `from`) of the
// rim's points in a chart of `to` (the faces around the points, if they form a disc, embedded by
// Tutte onto a circle); then inside vertices whose star is still inverted move one at a time (back,
// into their star's kernel in the chart, or nearby); then every inside vertex moves back towards
// its old point (all the way, or a half, quarter or eighth of it in the chart) where its star
// inverts no more faces than before the move, first letting degenerate images return, then not.
// The disc is kept if it leaves fewer of its faces inverted and none more degenerate (or, up to 4
// rings, as many inverted and fewer degenerate) and moves the points by at most
// `max_shift` · √area(to) · |V(from)| summed (per disc); else it is undone. A convex rim cannot
// fold in the chart (Floater 2003), but orientation is judged on `to` (image_orientation) and rims
// need not be convex, hence the check. A disc that holds the whole of f's component (no rim) is
// never laid out. Every inverted face gets its 1-ring disc, then every face still inverted its
// 2-ring disc, and so on; up to three such passes, and no new disc once max(4 000 · |V(from)|,
// 20 M) faces have been judged. `map` must have one point per vertex of `from` on a face of `to`; `max_shift`
// >= 0. Returns the number of discs kept.
int untangle_point_map(const Mesh& from, const Mesh& to, std::vector<SurfacePoint>& map, int max_rings = 24,
                       double max_shift = 1e-3);

// `face b0 b1 b2` per line (0-based face of the target mesh).
std::string point_map_text(const std::vector<SurfacePoint>& map);
// Reads point_map_text's format; each line's face must be a face of `target` and its
// coordinates finite, >= -1e-9 and summing to 1 within 1e-6. Throws IoError /
// InvalidInputError "<path>: line N: <problem>".
std::vector<SurfacePoint> read_point_map(const std::string& path, const Mesh& target);

}  // namespace shapematch
