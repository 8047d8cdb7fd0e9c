#pragma once
// Regions of a mesh made disc-like for a chart (point_map.cpp's untangling).
#include "shapematch/mesh.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace shapematch::detail {

// Adds to `faces` (sorted, unique on return) the star of every vertex where the region's rim
// touches itself: two rim arcs through one vertex make it no disc, and a rim that cannot be
// followed edge to edge hides the region's holes. The faces within a few rings of scattered
// points are often pinched so. Stops after `max_steps` rounds or once past twice the region's
// size; returns whether no rim vertex is pinched (where not, `faces` stays grown: the caller's
// disc test refuses it).
inline bool close_pinches(const Mesh& mesh, const std::vector<std::vector<int>>& vertex_faces, std::vector<int>& faces,
                          int max_steps = 4) {
  auto sort_unique = [&faces] {
    std::sort(faces.begin(), faces.end());
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  };
  sort_unique();
  const size_t limit = 2 * faces.size();
  const int64_t n = mesh.num_vertices();
  for (int step = 0;; ++step) {
    std::unordered_map<int64_t, int> directed;
    for (int f : faces)
      for (int i = 0; i < 3; ++i) ++directed[int64_t(mesh.faces[f][i]) * n + mesh.faces[f][(i + 1) % 3]];
    std::unordered_map<int, int> rim_out;  // rim edges leaving each vertex
    for (const auto& entry : directed) {
      const int u = static_cast<int>(entry.first / n), w = static_cast<int>(entry.first % n);
      if (!directed.count(int64_t(w) * n + u)) ++rim_out[u];
    }
    std::vector<int> pinched;
    for (const auto& [v, out] : rim_out)
      if (out > 1) pinched.push_back(v);
    if (pinched.empty()) return true;
    if (step == max_steps || faces.size() > limit) return false;
    for (int v : pinched) faces.insert(faces.end(), vertex_faces[v].begin(), vertex_faces[v].end());
    sort_unique();
  }
}

}  // namespace shapematch::detail
