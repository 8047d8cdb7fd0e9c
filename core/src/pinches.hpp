#pragma once
// Regions of a mesh made disc-like for a chart (point_map.cpp's untangling).
#include "shapematch/mesh.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

namespace shapematch::detail {

// The boundary of a set of faces, as the chart path needs it three times over (pinch closing,
// hole filling, the disc test).
struct RegionRim {
  std::vector<std::pair<int, int>> edges;  // directed (tail, head) with no twin in the region, sorted
  int64_t inner_edges = 0;                 // undirected edges with both halves in the region
  bool repeated = false;                   // a directed edge in two faces: not an oriented patch
};

inline RegionRim region_rim(const Mesh& mesh, const std::vector<int>& faces) {
  std::unordered_map<int64_t, int> directed;  // directed edge -> faces holding it
  const int64_t n = mesh.num_vertices();
  for (int f : faces)
    for (int i = 0; i < 3; ++i) ++directed[int64_t(mesh.faces[f][i]) * n + mesh.faces[f][(i + 1) % 3]];
  RegionRim rim;
  for (const auto& [key, count] : directed) {
    const int u = static_cast<int>(key / n), w = static_cast<int>(key % n);
    if (count != 1) rim.repeated = true;
    if (!directed.count(int64_t(w) * n + u))
      rim.edges.emplace_back(u, w);
    else if (u < w)
      ++rim.inner_edges;
  }
  // Hash order would make where a rim walk starts (and so a chart's rotation) depend on the
  // standard library.
  std::sort(rim.edges.begin(), rim.edges.end());
  return rim;
}

// The rim as tail -> head, for walking it; false (and `next` partly filled) where a vertex has two
// rim edges leaving it: a pinched rim cannot be followed edge to edge.
inline bool rim_successors(const RegionRim& rim, std::unordered_map<int, int>& next) {
  next.clear();
  for (const auto& [u, w] : rim.edges)
    if (!next.emplace(u, w).second) return false;
  return true;
}

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
  for (int step = 0;; ++step) {
    // Sorted by tail: a pinched vertex is the tail of consecutive rim edges.
    const auto rim = region_rim(mesh, faces).edges;
    std::vector<int> pinched;
    for (size_t i = 1; i < rim.size(); ++i)
      if (rim[i].first == rim[i - 1].first && (pinched.empty() || pinched.back() != rim[i].first))
        pinched.push_back(rim[i].first);
    if (pinched.empty()) return true;
    if (step == max_steps || faces.size() > limit) return false;
    for (int v : pinched) faces.insert(faces.end(), vertex_faces[v].begin(), vertex_faces[v].end());
    sort_unique();
  }
}

}  // namespace shapematch::detail
