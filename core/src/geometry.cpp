#include "shapematch/geometry.hpp"

#include <Eigen/Sparse>

namespace shapematch {

Geometry compute_geometry(const Mesh& mesh) {
  const int nv = mesh.num_vertices();
  const int nf = mesh.num_faces();
  Geometry g;
  g.face_area.resize(nf);
  g.corner_area.resize(nf);
  g.vertex_area.assign(nv, 0.0);
  g.vertex_normal.assign(nv, Eigen::Vector3d::Zero());
  g.mean_curvature.assign(nv, 0.0);

  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(12 * static_cast<size_t>(nf));
  for (int f = 0; f < nf; ++f) {
    const auto& t = mesh.faces[f];
    const Eigen::Vector3d p[3] = {mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]};
    const Eigen::Vector3d cross = (p[1] - p[0]).cross(p[2] - p[0]);
    const double double_area = cross.norm();
    const double area = 0.5 * double_area;
    g.face_area[f] = area;

    // cot of the angle at corner i = (e1 . e2) / |e1 x e2|, with |e1 x e2| = twice the area.
    double cot[3];
    bool obtuse_at[3];
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d e1 = p[(i + 1) % 3] - p[i], e2 = p[(i + 2) % 3] - p[i];
      const double dot = e1.dot(e2);
      cot[i] = dot / double_area;
      obtuse_at[i] = dot < 0;
    }

    // Mixed Voronoi areas (Meyer et al. 2002, Fig. 4): the Voronoi region leaves an obtuse
    // triangle, so there the obtuse corner gets half the area and the others a quarter each.
    const int obtuse = obtuse_at[0] ? 0 : obtuse_at[1] ? 1 : obtuse_at[2] ? 2 : -1;
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3, k = (i + 2) % 3;
      double a;
      if (obtuse < 0)
        a = ((p[i] - p[j]).squaredNorm() * cot[k] + (p[i] - p[k]).squaredNorm() * cot[j]) / 8.0;
      else
        a = i == obtuse ? area / 2.0 : area / 4.0;
      g.corner_area[f][i] = a;
      g.vertex_area[t[i]] += a;
      g.vertex_normal[t[i]] += cross;  // |cross| = 2 * area: area weighting
    }

    // The edge opposite corner i gets half its cot; summed over both faces: (cot a + cot b) / 2.
    for (int i = 0; i < 3; ++i) {
      const int u = t[(i + 1) % 3], v = t[(i + 2) % 3];
      const double w = cot[i] / 2.0;
      triplets.emplace_back(u, v, -w);
      triplets.emplace_back(v, u, -w);
      triplets.emplace_back(u, u, w);
      triplets.emplace_back(v, v, w);
    }
  }
  for (auto& n : g.vertex_normal) n.normalize();
  g.halfedge_face.assign(2 * static_cast<size_t>(mesh.num_edges()), -1);
  for (int f = 0; f < nf; ++f)
    for (int i = 0; i < 3; ++i) {
      const int d = mesh.directed_edge_index(mesh.faces[f][i], mesh.faces[f][(i + 1) % 3]);
      if (d >= 0) g.halfedge_face[d] = f;  // -1 where the mesh's edges are not built
    }

  g.cotan_laplacian.resize(nv, nv);
  g.cotan_laplacian.setFromTriplets(triplets.begin(), triplets.end());

  // L x approximates -Δx * area = 2 H n * area with outward n (Δx = -2 H n; H = 1/r on a sphere).
  Eigen::MatrixXd x(nv, 3);
  for (int v = 0; v < nv; ++v) x.row(v) = mesh.vertices[v].transpose();
  const Eigen::MatrixXd lx = g.cotan_laplacian * x;
  for (int v = 0; v < nv; ++v)
    g.mean_curvature[v] = lx.row(v).dot(g.vertex_normal[v].transpose()) / (2.0 * g.vertex_area[v]);
  return g;
}

std::vector<double> smoothed_mean_curvature(const Mesh& mesh, const Geometry& g, double radius) {
  if (radius <= 0.0) return g.mean_curvature;
  const int nv = mesh.num_vertices();
  std::vector<std::vector<int>> next(nv);
  for (const auto& f : mesh.faces)
    for (int i = 0; i < 3; ++i) next[f[i]].push_back(f[(i + 1) % 3]);  // each edge both ways on a closed mesh
  std::vector<double> h(nv, 0.0);
  std::vector<int> seen(nv, -1), queue;
  const double r2 = radius * radius;
  for (int v = 0; v < nv; ++v) {
    double sum = 0.0, weight = 0.0;
    queue.assign(1, v);
    seen[v] = v;
    for (size_t q = 0; q < queue.size(); ++q) {
      const int u = queue[q];
      sum += g.vertex_area[u] * g.mean_curvature[u];
      weight += g.vertex_area[u];
      for (int w : next[u])
        if (seen[w] != v && (mesh.vertices[w] - mesh.vertices[v]).squaredNorm() <= r2) {
          seen[w] = v;
          queue.push_back(w);
        }
    }
    h[v] = weight > 0.0 ? sum / weight : g.mean_curvature[v];
  }
  return h;
}

int image_orientation(const Mesh& y, const Geometry& gy, int a, int b, int c) {
  const Eigen::Vector3d ab = y.vertices[b] - y.vertices[a], ac = y.vertices[c] - y.vertices[a];
  const Eigen::Vector3d normal = ab.cross(ac);
  if (a == b || b == c || c == a || normal.norm() <= 1e-12 * (ab.squaredNorm() + ac.squaredNorm())) return 0;
  // The face on the left of a->b (right of b->a) has c as its third corner: (a, b, c) is that face.
  auto third_is_c = [&](int u, int v) {
    const int d = y.directed_edge_index(u, v);
    if (d < 0 || static_cast<size_t>(d) >= gy.halfedge_face.size() || gy.halfedge_face[d] < 0) return false;
    const auto& f = y.faces[gy.halfedge_face[d]];
    return f[0] == c || f[1] == c || f[2] == c;
  };
  if (third_is_c(a, b)) return 1;
  if (third_is_c(b, a)) return -1;
  return normal.dot(gy.vertex_normal[a] + gy.vertex_normal[b] + gy.vertex_normal[c]) < 0 ? -1 : 1;
}

}  // namespace shapematch
