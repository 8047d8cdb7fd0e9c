#include "shapematch/hierarchy.hpp"

#include "parallel.hpp"
#include "shapematch/errors.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace shapematch {

std::vector<int> level_face_counts(int input_faces, const HierarchyOptions& o) {
  if (input_faces < 1) throw InvalidInputError("hierarchy: the mesh has no faces");
  if (o.coarsest_faces < 4) throw InvalidInputError("hierarchy: --coarsest-faces must be at least 4");
  if (o.levels < 0) throw InvalidInputError("hierarchy: --levels must not be negative");
  const int coarsest = std::min(o.coarsest_faces, input_faces);
  if (o.second_faces > coarsest && input_faces > o.second_faces && o.levels != 1) {
    HierarchyOptions above = o;
    above.coarsest_faces = o.second_faces;
    above.second_faces = 0;
    above.levels = o.levels > 0 ? o.levels - 1 : 0;
    std::vector<int> counts = level_face_counts(input_faces, above);
    counts.insert(counts.begin(), coarsest);
    return counts;
  }
  int levels = o.levels;
  if (levels == 0) {
    if (!(o.ratio > 1.0)) throw InvalidInputError("hierarchy: the level ratio must exceed 1");
    levels = 1 + static_cast<int>(std::ceil(std::log(double(input_faces) / coarsest) / std::log(o.ratio) - 1e-9));
    levels = std::max(levels, 1);
  }
  if (levels == 1) return {input_faces};
  // A shape already at the coarsest size repeats itself, so both shapes of a pair can share a
  // level count (decimating to its own size returns the mesh unchanged).
  if (coarsest == input_faces) return std::vector<int>(levels, input_faces);
  std::vector<int> counts(levels);
  for (int l = 0; l < levels; ++l)
    counts[l] = static_cast<int>(std::lround(coarsest * std::pow(double(input_faces) / coarsest, double(l) / (levels - 1))));
  counts.back() = input_faces;
  return counts;
}

std::vector<std::vector<int>> vertex_face_table(const Mesh& mesh) {
  std::vector<std::vector<int>> vf(mesh.num_vertices());
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int v : mesh.faces[f]) vf[v].push_back(f);
  return vf;
}

std::vector<int> ring_faces(const Mesh& mesh, const std::vector<std::vector<int>>& vertex_faces,
                            const std::vector<int>& vertices, int ring) {
  std::vector<int> verts(vertices);
  std::sort(verts.begin(), verts.end());
  verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
  std::vector<int> faces;
  if (ring <= 0) {
    // The faces containing every vertex of the set: a face itself, an edge's two faces, a
    // vertex's star.
    if (!verts.empty())
      for (int f : vertex_faces[verts.front()]) {
        const auto& t = mesh.faces[f];
        if (std::all_of(verts.begin(), verts.end(), [&](int u) { return std::find(t.begin(), t.end(), u) != t.end(); }))
          faces.push_back(f);
      }
  } else {
    for (int k = 0; k < ring; ++k) {
      faces.clear();
      for (int v : verts) faces.insert(faces.end(), vertex_faces[v].begin(), vertex_faces[v].end());
      std::sort(faces.begin(), faces.end());
      faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
      if (k + 1 == ring) break;
      for (int f : faces) verts.insert(verts.end(), mesh.faces[f].begin(), mesh.faces[f].end());
      std::sort(verts.begin(), verts.end());
      verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
    }
  }
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  return faces;
}

double squared_distance_to_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                   const Eigen::Vector3d& c) {
  // The closest point by the Voronoi region of p: a vertex, an edge or the interior.
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return ap.squaredNorm();
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return bp.squaredNorm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (ap - ab * (d1 / (d1 - d3))).squaredNorm();
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return cp.squaredNorm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (ap - ac * (d2 / (d2 - d6))).squaredNorm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) return (bp - (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))).squaredNorm();
  const double denom = va + vb + vc;
  if (!(denom > 0)) return std::min({ap.squaredNorm(), bp.squaredNorm(), cp.squaredNorm()});  // degenerate
  return (ap - ab * (vb / denom) - ac * (vc / denom)).squaredNorm();
}

std::vector<int> parent_faces(const Mesh& fine, const Mesh& coarse, const std::vector<int>& kept) {
  if (!kept.empty() && kept.size() != size_t(coarse.num_vertices()))
    throw InvalidInputError("parent faces: need one kept fine vertex per coarse vertex");
  auto centroid = [](const Mesh& m, int f) {
    const auto& t = m.faces[f];
    return Eigen::Vector3d((m.vertices[t[0]] + m.vertices[t[1]] + m.vertices[t[2]]) / 3.0);
  };
  auto normal = [](const Mesh& m, int f) {
    const auto& t = m.faces[f];
    return Eigen::Vector3d((m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]));
  };
  std::vector<Eigen::Vector3d> cn(coarse.num_faces());
  for (int g = 0; g < coarse.num_faces(); ++g) cn[g] = normal(coarse, g);
  // The coarse face nearest to the centroid, not the one with the nearest centroid: next to a
  // long coarse triangle the nearest centroid is often a neighbour's, and a wrong parent leaves
  // the reduced product space of the finer level without a surface there (measured on FAUST_r at
  // full resolution: local widenings at every level above 2 000 faces).
  auto nearest = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& n, auto&& candidates) {
    double best = std::numeric_limits<double>::infinity(), best_any = best;
    int arg = -1, arg_any = -1;
    candidates([&](int g) {
      const auto& t = coarse.faces[g];
      const double d = squared_distance_to_triangle(p, coarse.vertices[t[0]], coarse.vertices[t[1]], coarse.vertices[t[2]]);
      if (d < best_any) best_any = d, arg_any = g;
      if (d < best && cn[g].dot(n) > 0) best = d, arg = g;
    });
    return arg >= 0 ? arg : arg_any;
  };
  std::vector<int> parent(fine.num_faces());
  if (kept.empty()) {
    // Brute force: |F_fine|·|F_coarse| is at most a few times 10^7 between consecutive levels.
    detail::parallel_for(fine.num_faces(), 0, [&](int64_t f) {
      parent[f] = nearest(centroid(fine, int(f)), normal(fine, int(f)), [&](auto&& visit) {
        for (int g = 0; g < coarse.num_faces(); ++g) visit(g);
      });
    });
    return parent;
  }
  // Only coarse faces around the kept vertices nearest on the fine surface (breadth first, the
  // first ring of the fine mesh that holds one, and the ring after it): the nearest in space can
  // lie across a gap, on another part of the shape (measured on the deformation-transfer cat: a
  // leg's faces took parents on the belly, and the reduced space of the next level had no surface
  // there through a dozen widenings).
  std::vector<int> coarse_of(fine.num_vertices(), -1);
  for (int v = 0; v < coarse.num_vertices(); ++v) coarse_of[kept[v]] = v;
  const auto fine_vf = vertex_face_table(fine), coarse_vf = vertex_face_table(coarse);
  detail::parallel_for(fine.num_faces(), 0, [&](int64_t f) {
    std::vector<int> frontier(fine.faces[f].begin(), fine.faces[f].end()), seen = frontier, found, next;
    int extra = -1;  // rings still to take once a kept vertex is found
    while (!frontier.empty() && extra != 0) {
      if (extra > 0) --extra;
      for (int u : frontier)
        if (coarse_of[u] >= 0) found.push_back(coarse_of[u]);
      if (!found.empty() && extra < 0) extra = 1;
      next.clear();
      for (int u : frontier)
        for (int g : fine_vf[u])
          for (int w : fine.faces[g])
            if (std::find(seen.begin(), seen.end(), w) == seen.end()) seen.push_back(w), next.push_back(w);
      frontier.swap(next);
    }
    std::vector<int> faces;
    for (int v : found) faces.insert(faces.end(), coarse_vf[v].begin(), coarse_vf[v].end());
    std::sort(faces.begin(), faces.end());
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    const Eigen::Vector3d p = centroid(fine, int(f)), n = normal(fine, int(f));
    parent[f] = faces.empty() ? nearest(p, n, [&](auto&& visit) { for (int g = 0; g < coarse.num_faces(); ++g) visit(g); })
                              : nearest(p, n, [&](auto&& visit) { for (int g : faces) visit(g); });
  });
  return parent;
}

MeshHierarchy build_hierarchy(const Mesh& input, const std::vector<int>& face_counts, bool surface_parents) {
  if (face_counts.empty()) throw InvalidInputError("hierarchy: no levels");
  MeshHierarchy h;
  h.levels.resize(face_counts.size());
  MeshLevel& top = h.levels.back();
  top.mesh = input;
  top.input_vertex.resize(input.num_vertices());
  for (int v = 0; v < input.num_vertices(); ++v) top.input_vertex[v] = v;
  for (int l = static_cast<int>(face_counts.size()) - 2; l >= 0; --l) {
    MeshLevel& finer = h.levels[l + 1];
    MeshLevel& level = h.levels[l];
    std::vector<int> kept;
    level.mesh = decimate(finer.mesh, face_counts[l], &kept);
    level.input_vertex.resize(kept.size());
    for (size_t v = 0; v < kept.size(); ++v) level.input_vertex[v] = finer.input_vertex[kept[v]];
    finer.parent_face = parent_faces(finer.mesh, level.mesh, surface_parents ? kept : std::vector<int>{});
  }
  for (auto& level : h.levels) level.geometry = compute_geometry(level.mesh);
  return h;
}

}  // namespace shapematch
