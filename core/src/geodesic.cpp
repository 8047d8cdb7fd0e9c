#include "shapematch/geodesic.hpp"

#include "shapematch/errors.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

namespace shapematch {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

void GeodesicDistance::add_triangle(std::vector<std::vector<Update>>& by_trigger, int target, int p, int q, double lp,
                                    double lq, double lpq) {
  auto add = [&](int trigger, int other, double lt, double lo) {
    const double cx = (lt * lt - lo * lo + lpq * lpq) / (2 * lpq);
    const double cy2 = lt * lt - cx * cx;
    // A (nearly) flat triangle has no interior for a ray to cross; its edges still propagate.
    const bool flat = !(cy2 > 1e-16 * lpq * lpq);
    by_trigger[trigger].push_back({target, flat ? -1 : other, lt, lpq, cx, flat ? 0.0 : std::sqrt(cy2)});
  };
  add(p, q, lp, lq);
  add(q, p, lq, lp);
}

GeodesicDistance::GeodesicDistance(const Mesh& mesh, const GeodesicOptions& options) {
  const int nv = mesh.num_vertices();
  const auto& x = mesh.vertices;
  // The face on the left of each directed edge, and the vertex opposite it there.
  std::vector<int> opposite(2 * static_cast<size_t>(mesh.num_edges()), -1);
  for (const auto& t : mesh.faces)
    for (int i = 0; i < 3; ++i) {
      const int d = mesh.directed_edge_index(t[i], t[(i + 1) % 3]);
      if (d >= 0) opposite[d] = t[(i + 2) % 3];
    }

  std::vector<std::vector<Update>> by_trigger(nv);
  for (const auto& t : mesh.faces)
    for (int i = 0; i < 3; ++i) {
      const int v = t[i], a = t[(i + 1) % 3], b = t[(i + 2) % 3];
      const double la = (x[a] - x[v]).norm(), lb = (x[b] - x[v]).norm(), lab = (x[b] - x[a]).norm();
      add_triangle(by_trigger, v, a, b, la, lb, lab);
      const double cos_v = (x[a] - x[v]).dot(x[b] - x[v]) / (la * lb);
      if (cos_v >= 0) continue;

      // Obtuse at v: a front crossing ab can reach v before a or b, so v would be final before
      // the triangle could update it. Unfold the triangles beyond ab into v's plane until a vertex
      // w falls in the section of directions that makes (v; a, w) and (v; w, b) acute at v
      // (Kimmel & Sethian 1998, section 4), and let those two update v as well.
      const double theta = std::acos(std::max(-1.0, cos_v));
      const double lo = theta - std::numbers::pi / 2, hi = std::numbers::pi / 2;
      const Eigen::Vector2d pa(la, 0.0), pb(lb * std::cos(theta), lb * std::sin(theta));
      int p = a, q = b;
      Eigen::Vector2d pp = pa, pq = pb;
      bool found = false;
      for (int step = 0; step < options.max_unfold_steps && !found; ++step) {
        const int d = mesh.directed_edge_index(q, p);
        const int w = d < 0 ? -1 : opposite[d];
        if (w < 0 || w == v) break;
        const double lpw = (x[w] - x[p]).norm(), lqw = (x[w] - x[q]).norm();
        const Eigen::Vector2d e = (pq - pp).normalized();
        const double len = (pq - pp).norm();
        Eigen::Vector2d n(-e.y(), e.x());
        if (n.dot(-pp) > 0) n = -n;  // away from v, which sits at the origin
        const double s = (lpw * lpw - lqw * lqw + len * len) / (2 * len);
        const Eigen::Vector2d pw = pp + s * e + std::sqrt(std::max(0.0, lpw * lpw - s * s)) * n;
        const double phi = std::atan2(pw.y(), pw.x());
        if (phi >= lo && phi <= hi) {
          const double lw = pw.norm();
          add_triangle(by_trigger, v, a, w, la, lw, (pw - pa).norm());
          add_triangle(by_trigger, v, w, b, lw, lb, (pb - pw).norm());
          found = true;
        } else if (phi < lo) {
          p = w;
          pp = pw;
        } else {
          q = w;
          pq = pw;
        }
      }
      ++(found ? split_corners_ : unsplit_corners_);
    }

  for (const auto& list : by_trigger)
    for (const Update& up : list) max_edge_ = std::max(max_edge_, up.edge);
  update_begin_.assign(nv + 1, 0);
  for (int v = 0; v < nv; ++v) update_begin_[v + 1] = update_begin_[v] + static_cast<int>(by_trigger[v].size());
  updates_.reserve(update_begin_[nv]);
  for (auto& list : by_trigger) updates_.insert(updates_.end(), list.begin(), list.end());
}

void GeodesicDistance::check_vertex(int v, const char* role) const {
  if (v < 0 || v >= num_vertices())
    throw InvalidInputError(std::string("geodesic distance: ") + role + " vertex " + std::to_string(v) +
                            " is not in 0.." + std::to_string(num_vertices() - 1));
}

void GeodesicDistance::march(int source, std::vector<double>& dist, const std::vector<int>* targets) const {
  const int nv = num_vertices();
  check_vertex(source, "source");
  dist.assign(nv, kInf);
  std::vector<char> done(nv, 0), reached;
  int unreached = 0;
  double stop_above = kInf;
  if (targets) {
    reached.assign(nv, 1);
    for (int t : *targets) {
      check_vertex(t, "target");
      if (reached[t]) reached[t] = 0, ++unreached;
    }
  }
  using Entry = std::pair<double, int>;
  std::vector<Entry> heap;
  heap.reserve(nv);
  const auto later = [](const Entry& l, const Entry& r) { return l.first > r.first; };
  dist[source] = 0;
  heap.push_back({0.0, source});
  while (!heap.empty()) {
    std::pop_heap(heap.begin(), heap.end(), later);
    const auto [du, u] = heap.back();
    heap.pop_back();
    if (done[u] || du != dist[u]) continue;  // stale: a shorter distance was pushed later
    if (du > stop_above) return;
    done[u] = 1;
    if (targets && !reached[u] && (reached[u] = 1, --unreached == 0)) {
      // A proposal from a vertex at distance T is at least T minus one (unfolded) edge, so past
      // this margin a target could only drop through a chain of reopenings (below).
      double farthest = 0;
      for (int t : *targets) farthest = std::max(farthest, dist[t]);
      stop_above = farthest + 2 * max_edge_;
    }
    for (int k = update_begin_[u]; k < update_begin_[u + 1]; ++k) {
      const Update& up = updates_[k];
      const int v = up.target;
      double cand = du + up.edge;
      if (up.other >= 0 && done[up.other]) {
        // The point source S below the x axis with |S - trigger| = du and |S - other| = dist[other];
        // the straight ray from S reaches the target through this triangle if it crosses [0, c].
        const double dv = dist[up.other], c = up.c;
        const double sx = ((du - dv) * (du + dv) + c * c) / (2 * c);
        const double sy2 = (du - sx) * (du + sx);
        if (sy2 >= 0) {
          const double sy = -std::sqrt(sy2);
          const double crossing = sx + (up.cx - sx) * (-sy) / (up.cy - sy);
          if (crossing >= 0 && crossing <= c) cand = std::min(cand, std::hypot(up.cx - sx, up.cy - sy));
        }
      }
      // With a curved front even acute triangles are not always causal: a final vertex can
      // still receive a shorter distance. Reopening it (label correcting) makes flat regions
      // exact; it is rare (a few per source on FAUST_r).
      if (cand < (done[v] ? dist[v] * (1 - 1e-10) : dist[v])) {
        done[v] = 0;
        dist[v] = cand;
        heap.push_back({cand, v});
        std::push_heap(heap.begin(), heap.end(), later);
      }
    }
  }
}

std::vector<double> GeodesicDistance::from_vertex(int source) const {
  std::vector<double> dist;
  march(source, dist, nullptr);
  return dist;
}

std::vector<double> GeodesicDistance::to_vertices(int source, const std::vector<int>& targets) const {
  std::vector<double> dist, result;
  if (targets.empty()) {
    check_vertex(source, "source");
    return result;
  }
  march(source, dist, &targets);
  result.reserve(targets.size());
  for (int t : targets) result.push_back(dist[t]);
  return result;
}

std::vector<double> geodesic_distances(const Mesh& mesh, int source, const GeodesicOptions& options) {
  return GeodesicDistance(mesh, options).from_vertex(source);
}

}  // namespace shapematch
