#include "shapematch/point_map.hpp"

#include "shapematch/errors.hpp"
#include "shapematch/files.hpp"
#include "shapematch/hierarchy.hpp"

#include "pinches.hpp"
#include "untangle_layout.hpp"

#include <Eigen/SparseLU>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <unordered_map>

namespace shapematch {

SurfacePoint vertex_point(const Mesh& mesh, const std::vector<std::vector<int>>& vertex_faces, int v) {
  SurfacePoint p;
  p.face = vertex_faces[v].front();
  for (int i = 0; i < 3; ++i)
    if (mesh.faces[p.face][i] == v) p.bary[i] = 1.0;
  return p;
}

int point_vertex(const Mesh& mesh, const SurfacePoint& p) {
  for (int i = 0; i < 3; ++i)
    if (p.bary[i] >= 1.0) return mesh.faces[p.face][i];
  return -1;
}

Eigen::Vector3d point_position(const Mesh& mesh, const SurfacePoint& p) {
  const auto& f = mesh.faces[p.face];
  return p.bary[0] * mesh.vertices[f[0]] + p.bary[1] * mesh.vertices[f[1]] + p.bary[2] * mesh.vertices[f[2]];
}

namespace {

// The vertices whose weight in p is not zero.
int support(const Mesh& mesh, const SurfacePoint& p, std::array<int, 3>& out) {
  int n = 0;
  for (int i = 0; i < 3; ++i)
    if (p.bary[i] > 0) out[n++] = mesh.faces[p.face][i];
  return n;
}

// The face of y with exactly the vertices u, v, w (any order), or -1.
int face_with(const Mesh& y, const Geometry& gy, int u, int v, int w) {
  for (int d : {y.directed_edge_index(u, v), y.directed_edge_index(v, u)}) {
    if (d < 0 || gy.halfedge_face[d] < 0) continue;
    const auto& f = y.faces[gy.halfedge_face[d]];
    if (f[0] == w || f[1] == w || f[2] == w) return gy.halfedge_face[d];
  }
  return -1;
}

Eigen::Vector3d point_normal(const Mesh& y, const Geometry& gy, const SurfacePoint& p) {
  const auto& f = y.faces[p.face];
  return p.bary[0] * gy.vertex_normal[f[0]] + p.bary[1] * gy.vertex_normal[f[1]] + p.bary[2] * gy.vertex_normal[f[2]];
}

}  // namespace

int image_orientation(const Mesh& y, const Geometry& gy, const SurfacePoint& a, const SurfacePoint& b,
                      const SurfacePoint& c) {
  const int va = point_vertex(y, a), vb = point_vertex(y, b), vc = point_vertex(y, c);
  if (va >= 0 && vb >= 0 && vc >= 0) return image_orientation(y, gy, va, vb, vc);
  const Eigen::Vector3d pa = point_position(y, a), ab = point_position(y, b) - pa, ac = point_position(y, c) - pa;
  const Eigen::Vector3d normal = ab.cross(ac);
  const double scale = ab.squaredNorm() + ac.squaredNorm();
  if (normal.norm() <= 1e-12 * scale) return 0;
  // All three in one face (their supports together are at most its three corners): its plane.
  std::array<int, 9> all{};
  std::array<int, 3> s{};
  int n = 0;
  for (const SurfacePoint* p : {&a, &b, &c}) {
    const int k = support(y, *p, s);
    for (int i = 0; i < k; ++i)
      if (std::find(all.begin(), all.begin() + n, s[i]) == all.begin() + n) all[n++] = s[i];
  }
  if (n == 3) {
    const int f = face_with(y, gy, all[0], all[1], all[2]);
    if (f >= 0) {
      const auto& t = y.faces[f];
      const Eigen::Vector3d fn = (y.vertices[t[1]] - y.vertices[t[0]]).cross(y.vertices[t[2]] - y.vertices[t[0]]);
      const double side = normal.dot(fn.normalized());
      if (std::abs(side) <= 1e-9 * normal.norm()) return 0;
      return side < 0 ? -1 : 1;
    }
  }
  return normal.dot(point_normal(y, gy, a) + point_normal(y, gy, b) + point_normal(y, gy, c)) < 0 ? -1 : 1;
}

namespace {

// Γ's relation of one shape's vertices to the other shape, by dimension.
struct Fibres {
  std::vector<std::vector<int>> vertices;
  std::vector<std::vector<std::array<int, 2>>> edges;  // stretched along (sorted ends)
  std::vector<std::vector<int>> faces;                 // blown up over
};

template <class T>
void sort_unique(std::vector<T>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

// `from_a`: the fibres of X's vertices (a tuples), else of Y's (b tuples).
Fibres fibres(const ProductSpace& space, const std::vector<int64_t>& gamma, bool from_a) {
  const int n = from_a ? space.x().num_vertices() : space.y().num_vertices();
  Fibres fb;
  fb.vertices.resize(n);
  fb.edges.resize(n);
  fb.faces.resize(n);
  for (int64_t j : gamma) {
    const ProductTriangle t = space[j];
    const auto& a = from_a ? t.a : t.b;
    const auto& b = from_a ? t.b : t.a;
    const int other_face = from_a ? t.fb : t.fa;
    for (int i = 0; i < 3; ++i) fb.vertices[a[i]].push_back(b[i]);
    if (a[0] == a[1] && a[1] == a[2]) {
      if (other_face >= 0) fb.faces[a[0]].push_back(other_face);
      continue;
    }
    for (int i = 0; i < 3; ++i)
      for (int k = i + 1; k < 3; ++k)
        if (a[i] == a[k] && b[i] != b[k]) fb.edges[a[i]].push_back({std::min(b[i], b[k]), std::max(b[i], b[k])});
  }
  for (int v = 0; v < n; ++v) {
    sort_unique(fb.vertices[v]);
    sort_unique(fb.edges[v]);
    sort_unique(fb.faces[v]);
  }
  return fb;
}

// How many of `faces` of `from` have inverted, and how many degenerate, images under p.
std::pair<int, int> image_tally(const Mesh& from, const Mesh& to, const Geometry& g, const std::vector<SurfacePoint>& p,
                                const std::vector<int>& faces) {
  std::pair<int, int> c{0, 0};
  for (int f : faces) {
    const auto& t = from.faces[f];
    const int o = image_orientation(to, g, p[t[0]], p[t[1]], p[t[2]]);
    c.first += o < 0 ? 1 : 0;
    c.second += o == 0 ? 1 : 0;
  }
  return c;
}

// Lays discs of `from` out again around inverted images (untangle_point_map).
class Untangler {
public:
  Untangler(const Mesh& from, const Mesh& to, const Geometry& gt, const std::vector<std::vector<int>>& from_faces,
            const std::vector<std::vector<int>>& to_faces, std::vector<SurfacePoint>& p, double max_shift)
      : from_(from), to_(to), g_(gt), from_faces_(from_faces), to_faces_(to_faces), p_(p) {
    double area = 0;
    for (const double a : gt.face_area) area += a;
    shift_budget_ = max_shift * std::sqrt(area) * from.num_vertices();
  }

  // Small discs for every face first, then larger ones: the work of a disc grows with its area,
  // and where no disc helps (a map mirrored as a whole) the budget runs out on the large ones.
  int run(int max_rings) {
    int kept = 0;
    std::vector<char> whole(from_.num_faces(), 0);  // r rings held the face's whole component
    // A disc is kept when it inverts fewer faces in all, which may invert one seen before: again.
    for (int pass = 0; pass < 3; ++pass) {
      const int before = kept;
      for (int r = 1; r <= max_rings; ++r)
        for (int f = 0; f < from_.num_faces(); ++f) {
          if (whole[f] || orientation(f) >= 0) continue;
          if (work_ > std::max(kWorkPerVertex * from_.num_vertices(), kMinWork)) return kept;
          const Disc d = embed_disc(f, r);
          kept += d == Disc::kept ? 1 : 0;
          whole[f] = d == Disc::no_rim;
        }
      if (kept == before) break;
    }
    return kept;
  }

private:
  int orientation(int f) const {
    const auto& t = from_.faces[f];
    return image_orientation(to_, g_, p_[t[0]], p_[t[1]], p_[t[2]]);
  }
  // Inverted, then degenerate images among `faces` (compared in that order).
  std::pair<int, int> cost(const std::vector<int>& faces) {
    work_ += static_cast<int64_t>(faces.size());
    return image_tally(from_, to_, g_, p_, faces);
  }

  std::pair<int, int> star_cost(int v) { return cost(from_faces_[v]); }
  // Sample points of the faces of `to` within kRepairRings rings of q's support (3: on the saved
  // TOSCA_r Γ, 1 and 2 left one more face inverted).
  void near_points(const SurfacePoint& q, std::vector<SurfacePoint>& out) const {
    constexpr int kSamples = 6;
    std::array<int, 3> s{};
    const int k = support(to_, q, s);
    for (int f : ring_faces(to_, to_faces_, std::vector<int>(s.begin(), s.begin() + k), kRepairRings))
      for (int i = 1; i < kSamples; ++i)
        for (int j = 1; i + j < kSamples; ++j)
          out.push_back({f, {double(i) / kSamples, double(j) / kSamples, double(kSamples - i - j) / kSamples}});
  }

  // The point of the chart deepest inside all of v's star's half-planes (where every face of the
  // star keeps its orientation), searched on a grid over the star's box; false if outside `to`.
  template <class InChart, class ChartOf, class Locate>
  bool kernel_point(int v, const InChart& in_chart, const ChartOf& chart_of, const Locate& locate,
                    SurfacePoint& out) const {
    std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> edges;  // (j, k): v must lie left of j->k
    Eigen::Vector2d lo(std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity());
    Eigen::Vector2d hi = -lo;
    for (int f : from_faces_[v]) {
      const auto& t = from_.faces[f];
      const int c = t[0] == v ? 0 : t[1] == v ? 1 : 2;
      const SurfacePoint &pj = p_[t[(c + 1) % 3]], &pk = p_[t[(c + 2) % 3]];
      if (!in_chart(pj) || !in_chart(pk)) return false;
      const Eigen::Vector2d j = chart_of(pj), k = chart_of(pk);
      edges.push_back({j, k});
      lo = lo.cwiseMin(j).cwiseMin(k);
      hi = hi.cwiseMax(j).cwiseMax(k);
    }
    if (edges.empty()) return false;
    constexpr int kGrid = 24;
    double best = -std::numeric_limits<double>::infinity();
    Eigen::Vector2d at = lo;
    for (int gx = 0; gx <= kGrid; ++gx)
      for (int gy = 0; gy <= kGrid; ++gy) {
        const Eigen::Vector2d q = lo + Eigen::Vector2d(gx, gy).cwiseProduct(hi - lo) / kGrid;
        double worst = std::numeric_limits<double>::infinity();
        for (const auto& [j, k] : edges) {
          const double len = (k - j).norm();
          worst = std::min(worst, len > 0 ? cross2(k - j, q - j) / len : 0.0);
        }
        if (worst > best) best = worst, at = q;
      }
    return best > 0 && locate(at, out);
  }

  enum class Disc { kept, rejected, no_rim };

  Disc embed_disc(int f0, int rings) {
    // Vertex rings around f0's corners: inside (ring < rings) moves, the rim (ring == rings) stays.
    std::unordered_map<int, int> ring;
    std::vector<int> order(from_.faces[f0].begin(), from_.faces[f0].end());
    for (int v : order) ring[v] = 0;
    for (size_t k = 0; k < order.size(); ++k) {
      const int v = order[k], d = ring[v];
      if (d == rings) continue;
      for (int f : from_faces_[v])
        for (int w : from_.faces[f])
          if (ring.emplace(w, d + 1).second) order.push_back(w);
    }
    std::vector<int> inside, faces;
    std::unordered_map<int, int> index;  // inside vertex -> unknown
    for (int v : order)
      if (ring[v] < rings) {
        index[v] = static_cast<int>(inside.size());
        inside.push_back(v);
        faces.insert(faces.end(), from_faces_[v].begin(), from_faces_[v].end());
      }
    sort_unique(faces);
    {
      // Tutte needs a rim that spans something: at least three distinct points.
      std::vector<std::pair<int, std::array<double, 3>>> rim_points;
      for (int v : order)
        if (ring[v] == rings) rim_points.push_back({p_[v].face, p_[v].bary});
      if (rim_points.empty()) return Disc::no_rim;
      sort_unique(rim_points);
      if (rim_points.size() < 3) return Disc::rejected;
    }
    const std::pair<int, int> before = cost(faces);

    // The chart: the faces of `to` within two rings of the images, pinches closed and holes
    // filled, if they form a disc, laid out by Tutte's embedding of its rim onto a circle (an
    // embedding: it cannot fold). (One ring where two wrap around a thin part.) Unclosed pinches
    // left TOSCA_r michael0-michael10's point map with a face inverted at every ring up to 24.
    std::vector<int> supports;
    std::array<int, 3> s{};
    for (int v : order)
      for (int i = 0, k = support(to_, p_[v], s); i < k; ++i) supports.push_back(s[i]);
    std::vector<int> region;
    std::unordered_map<int, Eigen::Vector2d> chart;
    bool laid_out = false;
    for (int grow = 2; grow >= 1 && !laid_out; --grow) {
      region = ring_faces(to_, to_faces_, supports, grow);
      detail::close_pinches(to_, to_faces_, region);
      fill_holes(region);
      std::vector<int> near;
      for (int f : region) near.insert(near.end(), to_.faces[f].begin(), to_.faces[f].end());
      sort_unique(near);
      chart.clear();
      laid_out = lay_out_disc(region, near, chart);
    }
    if (!laid_out) return Disc::rejected;
    auto in_chart = [&](const SurfacePoint& q) {
      const auto& t = to_.faces[q.face];
      return chart.count(t[0]) && chart.count(t[1]) && chart.count(t[2]);
    };
    auto chart_of = [&](const SurfacePoint& q) {
      const auto& t = to_.faces[q.face];
      return Eigen::Vector2d(q.bary[0] * chart.at(t[0]) + q.bary[1] * chart.at(t[1]) + q.bary[2] * chart.at(t[2]));
    };

    for (int v : order)
      if (ring[v] == rings && !in_chart(p_[v])) return Disc::rejected;
    // Tutte's embedding of the disc of `from` with its mean-value weights (positive whatever the
    // angles), the rim where its images are.
    const int m = static_cast<int>(inside.size());
    std::vector<Eigen::Triplet<double>> entries;
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(m, 2);
    for (int i = 0; i < m; ++i) {
      const int v = inside[i];
      for (const auto& [w, weight] : mean_value_weights(from_, from_faces_, v)) {
        entries.emplace_back(i, i, weight);
        const auto at = index.find(w);
        if (at != index.end()) {
          entries.emplace_back(i, at->second, -weight);
        } else {
          rhs.row(i) += weight * chart_of(p_[w]).transpose();
        }
      }
    }
    Eigen::SparseMatrix<double> a(m, m);
    a.setFromTriplets(entries.begin(), entries.end());
    Eigen::SparseLU<Eigen::SparseMatrix<double>> lu(a);
    if (lu.info() != Eigen::Success) return Disc::rejected;
    Eigen::MatrixXd u = lu.solve(rhs);
    if (lu.info() != Eigen::Success || !u.allFinite()) return Disc::rejected;

    // Back onto `to` through the chart's faces: the one q is deepest inside (ties at shared edges).
    // The chart lies in the unit disc; a grid of its faces' boxes keeps this local.
    const int cells = std::max(1, static_cast<int>(std::sqrt(double(region.size()))));
    std::vector<std::vector<int>> grid(size_t(cells) * cells);
    auto cell = [cells](double c) { return std::clamp(static_cast<int>((c + 1) * 0.5 * cells), 0, cells - 1); };
    for (int f : region) {
      const auto& t = to_.faces[f];
      Eigen::Vector2d lo = chart.at(t[0]), hi = lo;
      for (int i = 1; i < 3; ++i) lo = lo.cwiseMin(chart.at(t[i])), hi = hi.cwiseMax(chart.at(t[i]));
      for (int gx = cell(lo.x() - 4e-9); gx <= cell(hi.x() + 4e-9); ++gx)
        for (int gy = cell(lo.y() - 4e-9); gy <= cell(hi.y() + 4e-9); ++gy) grid[size_t(gx) * cells + gy].push_back(f);
    }
    auto locate = [&](const Eigen::Vector2d& q, SurfacePoint& out) {
      double best = -std::numeric_limits<double>::infinity();
      for (int f : grid[size_t(cell(q.x())) * cells + cell(q.y())]) {
        const auto& t = to_.faces[f];
        const Eigen::Vector2d p0 = chart.at(t[0]), p1 = chart.at(t[1]), p2 = chart.at(t[2]);
        const double area = cross2(p1 - p0, p2 - p0);
        if (area <= 0) continue;
        std::array<double, 3> b{cross2(p1 - q, p2 - q) / area, cross2(p2 - q, p0 - q) / area, 0.0};
        b[2] = 1 - b[0] - b[1];
        const double worst = std::min({b[0], b[1], b[2]});
        if (worst <= best) continue;
        best = worst;
        for (double& x : b) x = std::max(x, 0.0);
        const double sum = b[0] + b[1] + b[2];
        for (double& x : b) x /= sum;
        out = SurfacePoint{f, b};
      }
      return best >= -1e-9;
    };
    std::vector<SurfacePoint> saved(m);
    for (int i = 0; i < m; ++i) saved[i] = p_[inside[i]];
    // Tutte's layout first; where that is refused and folds in the chart, unfolded (unfold).
    auto settle = [&](const Eigen::MatrixXd& layout) {
      std::vector<SurfacePoint> placed(m);
      for (int i = 0; i < m; ++i)
        if (!locate(layout.row(i).transpose(), placed[i])) return Disc::rejected;
      auto put = [&](const std::vector<SurfacePoint>& points) {
        for (int i = 0; i < m; ++i) p_[inside[i]] = points[i];
      };
      put(placed);
      // Where the rim is concave, a face with two rim corners can fold over it: move the inside
      // corners of inverted stars (back where they were, into their star's kernel in the chart, or
      // nearby) while that unfolds their stars.
      for (int sweep = 0; sweep < 5; ++sweep) {
        bool changed = false;
        for (int i = 0; i < m; ++i) {
          const int v = inside[i];
          std::pair<int, int> best = star_cost(v);
          if (best.first == 0) continue;
          std::vector<SurfacePoint> candidates{saved[i]};
          near_points(p_[v], candidates);
          if (SurfacePoint k; kernel_point(v, in_chart, chart_of, locate, k)) candidates.push_back(k);
          const SurfacePoint current = p_[v];
          SurfacePoint choice = current;
          for (const SurfacePoint& q : candidates) {
            p_[v] = q;
            const std::pair<int, int> c = star_cost(v);
            if (c < best) best = c, choice = q;
          }
          p_[v] = choice;
          changed = changed || choice.face != current.face || choice.bary != current.bary;
        }
        if (!changed) break;
      }
      // Kept: fewer inverted and no more degenerate, or as many inverted and fewer degenerate (so a
      // disc collapsed onto a curve never pays for an unfolded face).
      // (Fewer degenerate alone counts only for small discs: a large one would move hundreds of
      // points far from Γ for it.)
      auto better = [&before, rings](const std::pair<int, int>& after) {
        return (after.first < before.first && after.second <= before.second) ||
               (rings <= 4 && after.first == before.first && after.second < before.second);
      };
      // A disc may move the points only so far in all: where Γ collapsed a whole part (a hand onto a
      // curve), unfolding one face re-spreads hundreds of points far from their truth.
      auto shift_ok = [&] {
        double moved = 0;
        for (int i = 0; i < m; ++i) moved += (point_position(to_, p_[inside[i]]) - point_position(to_, saved[i])).norm();
        return moved <= shift_budget_;
      };
      if (!better(cost(faces))) {
        put(saved);
        return Disc::rejected;
      }
      // Tutte's layout is needed only near the fold; elsewhere it moves points off where Γ put them
      // (on FAUST_r, 24 rings of it nearly doubled the point map's error). So the inside goes back
      // towards its old points wherever that inverts no more faces: first letting degenerate images
      // come back too (Γ collapses faces where X is compressed), then, if that loses the disc, only
      // where they do not.
      std::vector<SurfacePoint> laid(m);
      for (int i = 0; i < m; ++i) laid[i] = p_[inside[i]];
      for (const bool strict : {false, true}) {
        pull_back(inside, saved, strict, in_chart, chart_of, locate);
        if (better(cost(faces)) && shift_ok()) return Disc::kept;
        put(laid);
      }
      if (shift_ok()) return Disc::kept;
      put(saved);
      return Disc::rejected;
    };
    if (settle(u) == Disc::kept) return Disc::kept;
    return unfold(faces, inside, index, chart_of, u) ? settle(u) : Disc::rejected;
  }

  // Tutte's layout `u` of the disc's inside folds where the rim's images are not convex (the
  // forty-sixth and forty-ninth sessions' FAUST_r 016-020 and cat 0001-0005 flips): unfolded in
  // the chart, the rim held.
  template <class ChartOf>
  bool unfold(const std::vector<int>& faces, const std::vector<int>& inside, const std::unordered_map<int, int>& index,
              const ChartOf& chart_of, Eigen::MatrixXd& u) {
    std::vector<Eigen::Vector2d> layout;
    std::vector<Eigen::Vector3d> rest;
    std::vector<char> free;
    for (size_t i = 0; i < inside.size(); ++i) {
      layout.push_back(u.row(static_cast<Eigen::Index>(i)).transpose());
      rest.push_back(from_.vertices[inside[i]]);
      free.push_back(1);
    }
    std::unordered_map<int, int> rim;  // rim vertex -> its place after the inside's
    auto local = [&](int v) {
      if (const auto at = index.find(v); at != index.end()) return at->second;
      const auto [at, added] = rim.emplace(v, static_cast<int>(layout.size()));
      if (added) {
        layout.push_back(chart_of(p_[v]));
        rest.push_back(from_.vertices[v]);
        free.push_back(0);
      }
      return at->second;
    };
    std::vector<std::array<int, 3>> triangles;
    for (int f : faces) {
      const auto& t = from_.faces[f];
      triangles.push_back({local(t[0]), local(t[1]), local(t[2])});
    }
    detail::UntangleLayoutOptions options;
    options.max_work = kUnfoldWorkPerFace * static_cast<int64_t>(faces.size());
    const detail::UntangleLayoutResult r = detail::untangle_layout(triangles, rest, free, layout, options);
    work_ += r.work / kUnfoldWorkPerJudged;
    if (r.inverted_after >= r.inverted_before) return false;
    for (size_t i = 0; i < inside.size(); ++i) u.row(static_cast<Eigen::Index>(i)) = layout[i].transpose();
    return true;
  }

  // Moves each vertex of `inside` to its old point, or a half, quarter or eighth of the way there
  // in the chart, where its star inverts no more faces than now (and, if `strict`, has no more
  // degenerate images); sweeps while anything moves.
  template <class InChart, class ChartOf, class Locate>
  void pull_back(const std::vector<int>& inside, const std::vector<SurfacePoint>& old, bool strict,
                 const InChart& in_chart, const ChartOf& chart_of, const Locate& locate) {
    constexpr int kSweeps = 12;
    for (int sweep = 0; sweep < kSweeps; ++sweep) {
      bool moved = false;
      for (size_t i = 0; i < inside.size(); ++i) {
        const int v = inside[i];
        const SurfacePoint current = p_[v];
        if (current.face == old[i].face && current.bary == old[i].bary) continue;
        const std::pair<int, int> now = star_cost(v);
        for (const double t : {1.0, 0.5, 0.25, 0.125}) {
          SurfacePoint q = old[i];
          if (t < 1) {
            if (!in_chart(current) || !in_chart(old[i])) break;
            const Eigen::Vector2d a = chart_of(current), b = chart_of(old[i]);
            if (!locate(Eigen::Vector2d(a + t * (b - a)), q)) continue;
          }
          p_[v] = q;
          const std::pair<int, int> c = star_cost(v);
          if (c.first <= now.first && (!strict || c.second <= now.second)) {
            moved = true;
            break;
          }
          p_[v] = current;
        }
      }
      if (!moved) break;
    }
  }

  // Mean-value weights (Floater 2003) of v's neighbours in `mesh`, from its 3D corner angles.
  static std::vector<std::pair<int, double>> mean_value_weights(const Mesh& mesh,
                                                                const std::vector<std::vector<int>>& vertex_faces,
                                                                int v) {
    std::vector<std::pair<int, double>> out;
    for (int f : vertex_faces[v]) {
      const auto& t = mesh.faces[f];
      const int c = t[0] == v ? 0 : t[1] == v ? 1 : 2;
      const int j = t[(c + 1) % 3], k = t[(c + 2) % 3];
      const Eigen::Vector3d dj = mesh.vertices[j] - mesh.vertices[v], dk = mesh.vertices[k] - mesh.vertices[v];
      const double lj = dj.norm(), lk = dk.norm();
      if (lj == 0 || lk == 0) continue;
      const double half_tan = std::tan(0.5 * std::acos(std::clamp(dj.dot(dk) / (lj * lk), -1.0, 1.0)));
      out.push_back({j, half_tan / lj});
      out.push_back({k, half_tan / lk});
    }
    return out;
  }

  // Adds to `faces` (sorted) what its rims other than the longest enclose: the parts of `to` the
  // images skipped. Leaves `faces` as it was when a rim does not close or encloses too much.
  void fill_holes(std::vector<int>& faces) const {
    const auto region = detail::region_rim(to_, faces);
    std::unordered_map<int, int> next;  // rim: tail -> head
    if (!detail::rim_successors(region, next)) return;  // pinched
    std::vector<std::vector<int>> rims;
    std::unordered_map<int, int> seen;
    for (const auto& [start, head] : region.edges) {
      if (seen.count(start)) continue;
      std::vector<int> rim{start};
      seen[start] = 1;
      for (int v = head; v != start; v = next.at(v)) {
        if (seen.count(v) || !next.count(v)) return;
        seen[v] = 1;
        rim.push_back(v);
      }
      rims.push_back(std::move(rim));
    }
    if (rims.size() < 2) return;
    std::sort(rims.begin(), rims.end(), [](const auto& a, const auto& b) { return a.size() > b.size(); });
    std::vector<char> in(to_.num_faces(), 0);
    for (int f : faces) in[f] = 1;
    std::vector<int> added;
    const size_t limit = faces.size();
    for (size_t r = 1; r < rims.size(); ++r) {
      std::vector<int> stack;
      for (size_t i = 0; i < rims[r].size(); ++i) {
        const int d = to_.directed_edge_index(rims[r][(i + 1) % rims[r].size()], rims[r][i]);
        if (d < 0 || g_.halfedge_face[d] < 0) return;
        stack.push_back(g_.halfedge_face[d]);
      }
      std::vector<int> hole;
      while (!stack.empty()) {
        const int f = stack.back();
        stack.pop_back();
        if (in[f]) continue;
        in[f] = 2;
        hole.push_back(f);
        if (hole.size() + added.size() > limit) {  // the outside, not a hole
          for (int h : hole) in[h] = 0;
          for (int h : added) in[h] = 0;
          return;
        }
        const auto& t = to_.faces[f];
        for (int i = 0; i < 3; ++i) {
          const int d = to_.directed_edge_index(t[(i + 1) % 3], t[i]);
          if (d >= 0 && g_.halfedge_face[d] >= 0 && !in[g_.halfedge_face[d]]) stack.push_back(g_.halfedge_face[d]);
        }
      }
      added.insert(added.end(), hole.begin(), hole.end());
    }
    faces.insert(faces.end(), added.begin(), added.end());
    sort_unique(faces);
  }

  // Lays `faces` of `to` (with their vertices `verts`, sorted) out in the plane when they form a
  // disc: the rim on the unit circle by arc length, the inside by Tutte's embedding. False if not
  // a disc.
  bool lay_out_disc(const std::vector<int>& faces, const std::vector<int>& verts,
                    std::unordered_map<int, Eigen::Vector2d>& chart) const {
    const auto region = detail::region_rim(to_, faces);
    if (region.repeated || region.edges.empty()) return false;
    std::unordered_map<int, int> next;  // rim: tail -> head of the edges with no twin inside
    if (!detail::rim_successors(region, next)) return false;  // pinched rim
    const int64_t edges = static_cast<int64_t>(region.edges.size()) + region.inner_edges;
    if (static_cast<int64_t>(verts.size()) - edges + static_cast<int64_t>(faces.size()) != 1) return false;
    std::vector<int> rim{region.edges.front().first};
    while (true) {
      const auto at = next.find(rim.back());
      if (at == next.end()) return false;
      if (at->second == rim.front()) break;
      rim.push_back(at->second);
      if (rim.size() > next.size()) return false;
    }
    if (rim.size() != next.size()) return false;  // more than one rim: not a disc
    std::vector<double> length(rim.size() + 1, 0.0);
    for (size_t i = 0; i < rim.size(); ++i)
      length[i + 1] = length[i] + (to_.vertices[rim[(i + 1) % rim.size()]] - to_.vertices[rim[i]]).norm();
    if (!(length.back() > 0)) return false;
    constexpr double kTwoPi = 6.283185307179586;
    for (size_t i = 0; i < rim.size(); ++i) {
      const double angle = kTwoPi * length[i] / length.back();
      chart[rim[i]] = Eigen::Vector2d(std::cos(angle), std::sin(angle));
    }
    std::vector<int> inner;
    std::unordered_map<int, int> index;
    for (int v : verts)
      if (!chart.count(v)) index[v] = static_cast<int>(inner.size()), inner.push_back(v);
    const int m = static_cast<int>(inner.size());
    if (m > 0) {
      std::vector<Eigen::Triplet<double>> entries;
      Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(m, 2);
      for (int i = 0; i < m; ++i)
        for (const auto& [w, weight] : mean_value_weights(to_, to_faces_, inner[i])) {
          entries.emplace_back(i, i, weight);
          const auto at = index.find(w);
          if (at != index.end()) {
            entries.emplace_back(i, at->second, -weight);
          } else if (const auto rim_at = chart.find(w); rim_at != chart.end()) {
            rhs.row(i) += weight * rim_at->second.transpose();
          } else {
            return false;  // not a disc after all (a star leaves it)
          }
        }
      Eigen::SparseMatrix<double> a(m, m);
      a.setFromTriplets(entries.begin(), entries.end());
      Eigen::SparseLU<Eigen::SparseMatrix<double>> lu(a);
      if (lu.info() != Eigen::Success) return false;
      const Eigen::MatrixXd u = lu.solve(rhs);
      if (!u.allFinite()) return false;
      for (int i = 0; i < m; ++i) chart[inner[i]] = u.row(i).transpose();
    }
    return true;
  }

  static double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

  const Mesh& from_;
  const Mesh& to_;
  const Geometry& g_;
  const std::vector<std::vector<int>>& from_faces_;
  const std::vector<std::vector<int>>& to_faces_;
  std::vector<SurfacePoint>& p_;
  double shift_budget_ = 0;  // the most one disc may move the points, summed (lengths of `to`)
  // Faces judged (image_orientation) so far, and the most per vertex of `from` (the saved
  // full-resolution results judged 1-510 per vertex; a mirrored map would go on for minutes).
  int64_t work_ = 0;
  static constexpr int64_t kWorkPerVertex = 4000;
  // At least what a 5 000-vertex mesh gets: on a 625-vertex grid the per-vertex budget stopped
  // folds over a squeeze (14-18 faces) at 4-5 inverted, this one takes them to 0 in 2-3 s; a
  // mirrored map of that grid runs out of it in 2.3 s.
  static constexpr int64_t kMinWork = 20'000'000;
  static constexpr int kRepairRings = 3;
  // Unfolding a layout evaluates triangles (a 2 x 2 Jacobian each), cheaper than judging images.
  static constexpr int64_t kUnfoldWorkPerFace = 20000;
  static constexpr int64_t kUnfoldWorkPerJudged = 8;
};

class SideMap {
public:
  SideMap(const Mesh& from, const Mesh& to, const PointMapOptions& options)
      : from_(from), to_(to), g_(compute_geometry(to)), options_(options), from_faces_(vertex_face_table(from)),
        to_faces_(vertex_face_table(to)) {
    const int s = std::max(options.samples, 3);
    for (int i = 1; i < s; ++i)
      for (int j = 1; i + j < s; ++j) grid_.push_back({double(i) / s, double(j) / s, double(s - i - j) / s});
  }

  std::vector<SurfacePoint> run(const Fibres& fb, const std::vector<int>& start) {
    p_.resize(start.size());
    for (size_t v = 0; v < start.size(); ++v) p_[v] = vertex_point(to_, to_faces_, start[v]);
    // 1. Within the fibre, for vertices of inverted or degenerate images.
    for (int sweep = 0; sweep < options_.max_sweeps; ++sweep) {
      bool changed = false;
      for (int v = 0; v < from_.num_vertices(); ++v) {
        if (star_is_fine(v, false)) continue;
        changed = try_points(v, fibre_points(fb, v), false) || changed;
      }
      if (!changed) break;
    }
    // 2. Around the fibre: inverted images, ring by ring; then degenerate ones, up to two rings.
    for (int degenerate = 0; degenerate < 2; ++degenerate)
      for (int ring = 1; ring <= (degenerate ? std::min(2, options_.max_ring) : options_.max_ring); ++ring)
        for (int sweep = 0; sweep < options_.max_sweeps; ++sweep) {
          bool changed = false;
          for (int v = 0; v < from_.num_vertices(); ++v) {
            if (star_is_fine(v, degenerate)) continue;
            changed = try_points(v, ring_points(fb, v, ring), degenerate) || changed;
          }
          if (!changed) break;
        }
    // 3. Discs around what single moves could not fix.
    Untangler(from_, to_, g_, from_faces_, to_faces_, p_, options_.untangle_max_shift).run(options_.untangle_rings);
    return p_;
  }

private:
  int orientation(int f) const {
    const auto& t = from_.faces[f];
    return image_orientation(to_, g_, p_[t[0]], p_[t[1]], p_[t[2]]);
  }
  // No inverted image in v's star (and, when `degenerate`, no degenerate one either).
  bool star_is_fine(int v, bool degenerate) const {
    for (int f : from_faces_[v]) {
      const int o = orientation(f);
      if (o < 0 || (degenerate && o == 0)) return false;
    }
    return true;
  }
  // An inverted image outweighs any number of degenerate ones.
  int64_t cost(int v) const {
    const auto [inverted, degenerate] = image_tally(from_, to_, g_, p_, from_faces_[v]);
    return 1000 * int64_t(inverted) + degenerate;
  }
  // The worst shape in v's star: area over the sum of squared sides (a tie-break).
  double quality(int v) const {
    double q = std::numeric_limits<double>::infinity();
    for (int f : from_faces_[v]) {
      const auto& t = from_.faces[f];
      const Eigen::Vector3d a = point_position(to_, p_[t[0]]), b = point_position(to_, p_[t[1]]),
                            c = point_position(to_, p_[t[2]]);
      const double sides = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
      q = std::min(q, sides > 0 ? (b - a).cross(c - a).norm() / sides : 0.0);
    }
    return q;
  }
  // Moves v to the best of `points` if it lowers the cost, or (when `by_shape`) keeps the cost and
  // makes the worst triangle clearly better. Returns whether v moved.
  bool try_points(int v, const std::vector<SurfacePoint>& points, bool by_shape) {
    const SurfacePoint current = p_[v];
    SurfacePoint best = current;
    int64_t best_cost = cost(v);
    double best_quality = by_shape ? quality(v) : 0.0;
    bool moved = false;
    for (const SurfacePoint& p : points) {
      p_[v] = p;
      const int64_t c = cost(v);
      if (c > best_cost) continue;
      const double q = by_shape ? quality(v) : 0.0;
      if (c < best_cost || (by_shape && q > 1.5 * best_quality)) best = p, best_cost = c, best_quality = q, moved = true;
    }
    p_[v] = best;
    return moved;
  }
  SurfacePoint on_edge(int u, int w, double t) const {
    for (int f : to_faces_[u]) {
      const auto& tri = to_.faces[f];
      int iu = -1, iw = -1;
      for (int i = 0; i < 3; ++i) {
        if (tri[i] == u) iu = i;
        if (tri[i] == w) iw = i;
      }
      if (iw < 0) continue;
      SurfacePoint p{f, {}};
      p.bary[iu] = 1 - t;
      p.bary[iw] = t;
      return p;
    }
    return vertex_point(to_, to_faces_, u);  // not an edge of `to`: Γ never says so
  }
  void add_face_samples(int f, std::vector<SurfacePoint>& out) const {
    for (const auto& b : grid_) out.push_back({f, b});
  }
  std::vector<SurfacePoint> fibre_points(const Fibres& fb, int v) const {
    std::vector<SurfacePoint> out;
    for (int w : fb.vertices[v]) out.push_back(vertex_point(to_, to_faces_, w));
    for (const auto& e : fb.edges[v])
      for (double t : {0.25, 0.5, 0.75}) out.push_back(on_edge(e[0], e[1], t));
    for (int f : fb.faces[v]) add_face_samples(f, out);
    return out;
  }
  // Sample points of the faces within `ring` rings of v's fibre and of its current point.
  std::vector<SurfacePoint> ring_points(const Fibres& fb, int v, int ring) const {
    std::vector<int> verts = fb.vertices[v];
    std::array<int, 3> s{};
    for (int i = 0, k = support(to_, p_[v], s); i < k; ++i) verts.push_back(s[i]);
    std::vector<SurfacePoint> out;
    for (int f : ring_faces(to_, to_faces_, verts, ring)) add_face_samples(f, out);
    return out;
  }

  const Mesh& from_;
  const Mesh& to_;
  const Geometry g_;
  const PointMapOptions options_;
  std::vector<std::vector<int>> from_faces_, to_faces_;
  std::vector<std::array<double, 3>> grid_;
  std::vector<SurfacePoint> p_;
};

}  // namespace

PointMaps point_maps(const ProductSpace& space, const std::vector<int64_t>& gamma, const VertexMaps& start,
                     const PointMapOptions& options) {
  if (static_cast<int>(start.x_to_y.size()) != space.x().num_vertices() ||
      static_cast<int>(start.y_to_x.size()) != space.y().num_vertices())
    throw InvalidInputError("point maps: the vertex maps do not match the meshes");
  for (const auto* m : {&start.x_to_y, &start.y_to_x})
    if (std::find(m->begin(), m->end(), -1) != m->end())
      throw InvalidInputError("point maps: a vertex has no partner (Γ does not cover both shapes)");
  PointMaps maps;
  maps.x_to_y = SideMap(space.x(), space.y(), options).run(fibres(space, gamma, true), start.x_to_y);
  maps.y_to_x = SideMap(space.y(), space.x(), options).run(fibres(space, gamma, false), start.y_to_x);
  return maps;
}

int untangle_point_map(const Mesh& from, const Mesh& to, std::vector<SurfacePoint>& map, int max_rings,
                       double max_shift) {
  if (static_cast<int>(map.size()) != from.num_vertices())
    throw InvalidInputError("untangle: the map does not have one point per vertex");
  if (!(max_shift >= 0)) throw InvalidInputError("untangle: the shift bound must be a number >= 0");
  for (const SurfacePoint& p : map)
    if (p.face < 0 || p.face >= to.num_faces()) throw InvalidInputError("untangle: a point is not on the target");
  const Geometry g = compute_geometry(to);
  const auto from_faces = vertex_face_table(from), to_faces = vertex_face_table(to);
  return Untangler(from, to, g, from_faces, to_faces, map, max_shift).run(max_rings);
}

std::string point_map_text(const std::vector<SurfacePoint>& map) {
  std::ostringstream s;
  s.precision(17);
  for (const SurfacePoint& p : map) s << p.face << ' ' << p.bary[0] << ' ' << p.bary[1] << ' ' << p.bary[2] << '\n';
  return s.str();
}

std::vector<SurfacePoint> read_point_map(const std::string& path, const Mesh& target) {
  std::ifstream in = open_for_reading(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  if (in.bad()) throw IoError(path + ": read error");
  while (!lines.empty() && lines.back().find_first_not_of(" \t\r") == std::string::npos) lines.pop_back();
  if (lines.empty()) throw InvalidInputError(path + ": no points (empty file)");
  std::vector<SurfacePoint> map;
  for (size_t k = 0; k < lines.size(); ++k) {
    // A blank line inside would shift "line k is vertex k", so it is an error like any other.
    const std::string where = path + ": line " + std::to_string(k + 1) + ": ";
    std::istringstream s(lines[k]);
    std::string tokens[5];
    int n = 0;
    while (n < 5 && s >> tokens[n]) ++n;
    if (n != 4) throw InvalidInputError(where + "expected `face b0 b1 b2`");
    char* end = nullptr;
    const long face = std::strtol(tokens[0].c_str(), &end, 10);
    if (*end != '\0' || face < 0 || face >= target.num_faces())
      throw InvalidInputError(where + "'" + tokens[0] + "' is not a face (the mesh has " +
                              std::to_string(target.num_faces()) + ")");
    SurfacePoint p{static_cast<int>(face), {}};
    double sum = 0;
    for (int i = 0; i < 3; ++i) {
      p.bary[i] = std::strtod(tokens[i + 1].c_str(), &end);
      if (*end != '\0' || !std::isfinite(p.bary[i]) || p.bary[i] < -1e-9)
        throw InvalidInputError(where + "'" + tokens[i + 1] + "' is not a barycentric coordinate");
      sum += p.bary[i];
    }
    if (std::abs(sum - 1) > 1e-6) throw InvalidInputError(where + "the coordinates do not sum to 1");
    map.push_back(p);
  }
  return map;
}

}  // namespace shapematch
