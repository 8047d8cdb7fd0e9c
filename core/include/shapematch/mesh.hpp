#pragma once
// Triangle meshes: loading through OpenMesh, validation, scaling, decimation, saving.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace shapematch {

// A closed, oriented, 2-manifold triangle mesh with the edge structure the product space needs.
// Faces are counter-clockwise seen from outside. Edges are undirected, stored as (u, v) with
// u < v and sorted lexicographically; the directed edge u->v has index 2*e + (u > v ? 1 : 0).
struct Mesh {
  std::string name;  // the file it came from (or a descriptive name); used in error messages
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<int, 3>> faces;
  std::vector<std::array<int, 2>> edges;  // derived by build_edges()
  // Derived by build_edges(): the edges (u, ·) are edges[edge_begin[u] … edge_begin[u + 1]), so
  // that edge_index reads a vertex's few edges instead of searching all of them.
  std::vector<int> edge_begin;

  int num_vertices() const { return static_cast<int>(vertices.size()); }
  int num_faces() const { return static_cast<int>(faces.size()); }
  int num_edges() const { return static_cast<int>(edges.size()); }

  // Index of the undirected edge {u, v}, or -1 if there is none: O(degree) after build_edges(),
  // O(log |E|) where `edges` was filled otherwise.
  int edge_index(int u, int v) const;
  // Index of the directed edge u->v in [0, 2|E|), or -1.
  int directed_edge_index(int u, int v) const {
    const int e = edge_index(u, v);
    return e < 0 ? -1 : 2 * e + (u > v ? 1 : 0);
  }
  // The directed edge with index d as (tail, head).
  std::array<int, 2> directed_edge(int d) const {
    const auto& e = edges[d / 2];
    return (d & 1) ? std::array<int, 2>{e[1], e[0]} : e;
  }
  // Fills `edges` from `faces`.
  void build_edges();
};

struct MeshReport {
  int genus = 0;
  int triangulated_faces = 0;  // polygons split into triangles while loading
  int closed_holes = 0;        // boundary loops closed (LoadOptions::close_holes)
};

struct LoadOptions {
  bool normalize_area = true;  // scale to unit total area (DESIGN.md §5 "Scale")
  bool allow_polygons = true;  // triangulate polygons with a warning instead of failing
  // Close each boundary loop with a fan around a new vertex at its centroid (appended after the
  // file's vertices, so vertex indices of the file keep their meaning), instead of failing.
  bool close_holes = false;
};

// Reads OFF, OBJ, PLY or STL (OFF and OBJ in double precision, PLY and STL through OpenMesh in
// single precision), validates (throws InvalidInputError/IoError naming the file) and
// optionally normalises the area. A consistently inside-out mesh (negative enclosed volume) has
// its faces reversed with a warning. The returned mesh has its edges built.
Mesh load_mesh(const std::string& path, const LoadOptions& options = {}, MeshReport* report = nullptr);

// Builds a mesh from arrays (tests, generators); validates it like load_mesh.
Mesh make_mesh(std::vector<Eigen::Vector3d> vertices, std::vector<std::array<int, 3>> faces,
               std::string name = "<memory>");

// Checks everything DESIGN.md §1 requires of an input: finite coordinates, at least one face,
// valid indices, 2-manifold, closed, one component, consistently oriented, no zero-area faces.
// Throws InvalidInputError("<name>: <problem>"). Returns the genus.
int validate_mesh(const Mesh& mesh);

double surface_area(const Mesh& mesh);
// Enclosed volume, positive when the faces are counter-clockwise seen from outside.
double signed_volume(const Mesh& mesh);
// Scales about the area-weighted centroid so that the total area is `target_area`.
void normalize_area(Mesh& mesh, double target_area = 1.0);

// Quadric edge-collapse decimation (OpenMesh) to about `target_faces` faces, keeping the mesh
// closed, manifold and consistently oriented. Returns the mesh unchanged if already smaller.
// Collapses keep surviving vertices where they are (up to the area-preserving rescale), so the
// result's vertices are a subset of the input's: `kept_vertices`, if given, receives for every
// output vertex its index in `mesh` (ground truth and user features are indexed that way).
Mesh decimate(const Mesh& mesh, int target_faces, std::vector<int>* kept_vertices = nullptr);

// Writes OFF, OBJ, PLY or binary STL (by extension) through a temporary file renamed into place.
// STL stores single-precision coordinates; the other formats round-trip doubles exactly.
void save_mesh(const Mesh& mesh, const std::string& path);
// Writes a PLY file with one RGB colour per vertex.
void save_mesh(const Mesh& mesh, const std::string& path,
               const std::vector<std::array<uint8_t, 3>>& vertex_colors);

}  // namespace shapematch
