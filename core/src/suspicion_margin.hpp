#pragma once
// The X faces a suspicion's margin widens (CoarseToFineOptions::suspicion_rings and
// suspicion_margin_scope), kept apart from the level loop so that the choice is tested on its own.

#include "shapematch/coarse_to_fine.hpp"
#include "shapematch/hierarchy.hpp"

#include <vector>

namespace shapematch::detail {

// The faces within `rings` rings of the vertices flagged in `vertices` (one flag per vertex).
inline std::vector<int> faces_on(const Mesh& mesh, const std::vector<char>& vertices, int rings) {
  std::vector<int> seed;
  for (int v = 0; v < mesh.num_vertices(); ++v)
    if (vertices[v]) seed.push_back(v);
  if (seed.empty()) return {};
  return ring_faces(mesh, vertex_face_table(mesh), seed, rings);
}

// The faces within `rings` fine rings of the faces `seeds` (faces_on their vertices).
inline std::vector<int> faces_near(const Mesh& mesh, const std::vector<int>& seeds, int rings) {
  std::vector<char> on(mesh.num_vertices(), 0);
  for (int f : seeds)
    for (int v : mesh.faces[f]) on[v] = 1;
  return faces_on(mesh, on, rings);
}

// The margin's faces: near every face with extra rings at the level (MarginScope::widened), or
// near the faces the suspicion named alone (MarginScope::named).
inline std::vector<int> suspicion_margin_faces(const Mesh& x, const std::vector<int>& extra,
                                               const std::vector<int>& named,
                                               CoarseToFineOptions::MarginScope scope, int rings) {
  if (scope == CoarseToFineOptions::MarginScope::named) return faces_near(x, named, rings);
  std::vector<int> widened;
  for (int f = 0; f < x.num_faces() && f < int(extra.size()); ++f)
    if (extra[f] > 0) widened.push_back(f);
  return faces_near(x, widened, rings);
}

}  // namespace shapematch::detail
