#pragma once
// Coarse-to-fine mesh hierarchies (§5, DESIGN.md §7): successive quadric decimation with a
// child→parent face map between consecutive levels.
#include "shapematch/geometry.hpp"
#include "shapematch/mesh.hpp"

#include <vector>

namespace shapematch {

struct HierarchyOptions {
  int levels = 0;            // including the input itself; 0 = as many as `ratio` needs
  // Faces of the coarsest level (about). Measured (docs/results-log.md): at 100 the thin-shell
  // energy misses the global structure of some humans and animals, at 200 of others; the
  // defaults solve both and keep the better (CoarseToFineOptions::second_start).
  int coarsest_faces = 100;
  double ratio = 4.0;        // faces shrink by about this factor per level (when levels == 0)
  // > coarsest_faces: the level above the coarsest has about this many faces, and the levels
  // above it follow from there (coarse to fine's second start solves that level twice).
  int second_faces = 200;
  // Parents from around the kept vertices nearest on the fine surface (parent_faces with `kept`),
  // not the nearest coarse face in space, which can lie across a gap (measured on the
  // deformation-transfer cat 0001-0005 at full resolution: its level 4 widened 14 times, 1.7 M →
  // 6.3 M variables, and went on failing; with these parents 4 times, to 2.1 M, and solved). On
  // 8 FAUST_r pairs at 4 000 faces: 026-029 and 016-026 took 130 s and 145 s where nearest parents
  // widened by propagation 24 times, then everywhere (9-10 M variables; 508 s, gap 7.4 %, and
  // over 600 s); four pairs ended the same, 043-063 lower (17.71 against 18.18), 021-024 higher
  // (12.40 against 12.22). (In the thirteenth session, on FAUST_r 020-024 at full resolution,
  // it moved 31 parents and that run's level-6 rounding went on for 15 minutes without an end.)
  bool surface_parents = true;
};

struct MeshLevel {
  Mesh mesh;
  Geometry geometry;
  std::vector<int> input_vertex;  // each vertex's index in the input mesh (decimation keeps a subset)
  std::vector<int> parent_face;   // each face's parent in the next coarser level; empty at the coarsest
};

// levels[0] is the coarsest, levels.back() the input mesh itself (unchanged).
struct MeshHierarchy {
  std::vector<MeshLevel> levels;
  int size() const { return static_cast<int>(levels.size()); }
};

// Face counts from `coarsest_faces` up to `input_faces`, geometric, `levels` entries (the last
// is input_faces). With levels == 0 the count follows from the ratio.
std::vector<int> level_face_counts(int input_faces, const HierarchyOptions& options);

// Decimates level by level from the input (each level from the next finer one, so that vertex
// subsets nest) and links every face to a parent.
MeshHierarchy build_hierarchy(const Mesh& input, const std::vector<int>& face_counts, bool surface_parents = false);

// The parent of every fine face: the coarse face nearest to its centroid (point-to-triangle
// distance) among those whose normal does not point away from the fine face's (so thin parts do
// not take parents from the opposite side); the nearest of all if none qualifies. With `kept`
// (for every coarse vertex its fine vertex, as decimation gives it) only the coarse faces around
// the kept vertices nearest on the fine surface compete, so that no parent lies across a gap.
std::vector<int> parent_faces(const Mesh& fine, const Mesh& coarse, const std::vector<int>& kept = {});

// Squared distance from p to the triangle abc (closest point on its interior, edges or corners).
double squared_distance_to_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                    const Eigen::Vector3d& c);

// The faces within `ring` rings of an element given by its vertices: ring 0 gives the faces
// containing all of them (a face itself, an edge's two faces, a vertex's star), ring 1 the faces
// touching any of them, ring k the faces touching the vertices of ring k−1. `vertex_faces` is
// the vertex→incident-faces table.
std::vector<int> ring_faces(const Mesh& mesh, const std::vector<std::vector<int>>& vertex_faces,
                            const std::vector<int>& vertices, int ring);
std::vector<std::vector<int>> vertex_face_table(const Mesh& mesh);

}  // namespace shapematch
