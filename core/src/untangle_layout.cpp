#include "untangle_layout.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <utility>

namespace shapematch::detail {
namespace {

// The relaxed barrier's denominator; for d < 0 in the form that does not cancel to 0.
double chi(double d, double eps, double root) { return d >= 0 ? 0.5 * (d + root) : 0.5 * eps * eps / (root - d); }
double chi(double d, double eps) { return chi(d, eps, std::sqrt(eps * eps + d * d)); }

// The energy of a layout for one ε, with its gradient in the free vertices' coordinates.
class LayoutEnergy {
public:
  LayoutEnergy(const std::vector<std::array<int, 3>>& triangles, std::vector<Eigen::Matrix2d> inverse_rest,
               std::vector<double> weight, const std::vector<int>& unknown, double area_weight)
      : triangles_(triangles), inverse_rest_(std::move(inverse_rest)), weight_(std::move(weight)), unknown_(unknown),
        area_weight_(area_weight) {}

  // The Jacobian of triangle t (rest shape -> layout).
  Eigen::Matrix2d jacobian(size_t t, const std::vector<Eigen::Vector2d>& layout) const {
    const auto& tri = triangles_[t];
    Eigen::Matrix2d edges;
    edges.col(0) = layout[tri[1]] - layout[tri[0]];
    edges.col(1) = layout[tri[2]] - layout[tri[0]];
    return edges * inverse_rest_[t];
  }

  double min_det(const std::vector<Eigen::Vector2d>& layout, int* inverted) const {
    double low = std::numeric_limits<double>::infinity();
    int count = 0;
    for (size_t t = 0; t < triangles_.size(); ++t) {
      const double d = jacobian(t, layout).determinant();
      low = std::min(low, d);
      count += d <= 0 ? 1 : 0;
    }
    if (inverted) *inverted = count;
    return low;
  }

  double operator()(const std::vector<Eigen::Vector2d>& layout, double eps, Eigen::VectorXd& grad) {
    work += static_cast<int64_t>(triangles_.size());
    grad.setZero();
    double energy = 0;
    for (size_t t = 0; t < triangles_.size(); ++t) {
      const Eigen::Matrix2d j = jacobian(t, layout);
      const double d = j.determinant(), root = std::sqrt(eps * eps + d * d), c = chi(d, eps, root);
      const double dc = 0.5 * (1 + d / root);  // χ'(d)
      const double conformal = j.squaredNorm() / c, area = (d * d + 1) / c;
      energy += weight_[t] * ((1 - area_weight_) * conformal + area_weight_ * area);
      Eigen::Matrix2d cofactor;  // ∂det/∂J
      cofactor << j(1, 1), -j(1, 0), -j(0, 1), j(0, 0);
      const Eigen::Matrix2d d_j =
          weight_[t] * ((1 - area_weight_) * (2 * j / c - conformal * dc / c * cofactor) +
                        area_weight_ * (2 * d / c - area * dc / c) * cofactor);
      const Eigen::Matrix2d d_edges = d_j * inverse_rest_[t].transpose();
      const auto& tri = triangles_[t];
      const Eigen::Vector2d g1 = d_edges.col(0), g2 = d_edges.col(1);
      add(grad, tri[1], g1);
      add(grad, tri[2], g2);
      add(grad, tri[0], -(g1 + g2));
    }
    return energy;
  }

  int64_t work = 0;

private:
  void add(Eigen::VectorXd& grad, int v, const Eigen::Vector2d& g) const {
    const int i = unknown_[v];
    if (i >= 0) grad.segment<2>(2 * i) += g;
  }

  const std::vector<std::array<int, 3>>& triangles_;
  std::vector<Eigen::Matrix2d> inverse_rest_;
  std::vector<double> weight_;
  const std::vector<int>& unknown_;
  double area_weight_;
};

}  // namespace

UntangleLayoutResult untangle_layout(const std::vector<std::array<int, 3>>& triangles,
                                     const std::vector<Eigen::Vector3d>& rest, const std::vector<char>& free,
                                     std::vector<Eigen::Vector2d>& layout, const UntangleLayoutOptions& options) {
  UntangleLayoutResult result;
  const size_t n = layout.size();
  std::vector<int> unknown(n, -1);
  int m = 0;
  for (size_t v = 0; v < n; ++v)
    if (free[v]) unknown[v] = m++;

  // Rest shapes: each triangle flattened, all scaled to the area the layout encloses (the sum of
  // its signed areas, whatever the folds), so that det J = 1 is the ideal.
  std::vector<Eigen::Matrix2d> rest_edges(triangles.size());
  double rest_area = 0, layout_area = 0;
  auto signed_area = [&layout](const std::array<int, 3>& tri) {
    const Eigen::Vector2d a = layout[tri[1]] - layout[tri[0]], b = layout[tri[2]] - layout[tri[0]];
    return 0.5 * (a.x() * b.y() - a.y() * b.x());
  };
  for (size_t t = 0; t < triangles.size(); ++t) {
    const auto& tri = triangles[t];
    const Eigen::Vector3d e1 = rest[tri[1]] - rest[tri[0]], e2 = rest[tri[2]] - rest[tri[0]];
    const double l1 = e1.norm(), height = l1 > 0 ? e1.cross(e2).norm() / l1 : 0.0;
    rest_edges[t] << l1, (l1 > 0 ? e1.dot(e2) / l1 : 0.0), 0.0, height;
    rest_area += 0.5 * rest_edges[t].determinant();
    const double area = signed_area(tri);
    layout_area += area;
    result.inverted_before += area > 0 ? 0 : 1;
  }
  result.inverted_after = result.inverted_before;
  if (!(rest_area > 0) || !(layout_area > 0) || m == 0 || result.inverted_before == 0) return result;
  const double scale = std::sqrt(layout_area / rest_area);
  const double mean_area = layout_area / static_cast<double>(triangles.size());
  std::vector<Eigen::Matrix2d> inverse_rest(triangles.size());
  std::vector<double> weight(triangles.size());
  for (size_t t = 0; t < triangles.size(); ++t) {
    Eigen::Matrix2d r = scale * rest_edges[t];
    if (!(0.5 * r.determinant() > 1e-6 * mean_area)) {  // a sliver: an equilateral of the mean area
      const double side = std::sqrt(4 * mean_area / std::sqrt(3.0));
      r << side, 0.5 * side, 0.0, 0.5 * std::sqrt(3.0) * side;
    }
    inverse_rest[t] = r.inverse();
    weight[t] = 0.5 * r.determinant() / layout_area;
  }
  LayoutEnergy energy(triangles, std::move(inverse_rest), std::move(weight), unknown, options.area_weight);

  double low = energy.min_det(layout, nullptr);

  std::vector<Eigen::Vector2d> x = layout, trial = layout;
  auto set = [&](std::vector<Eigen::Vector2d>& to, const std::vector<Eigen::Vector2d>& from,
                 const Eigen::VectorXd& step, double s) {
    for (size_t v = 0; v < n; ++v)
      if (unknown[v] >= 0) to[v] = from[v] + s * step.segment<2>(2 * unknown[v]);
  };
  // Until the worst triangle is clearly right: where a fold only just opens, going back onto the
  // surface through the chart could close it again.
  constexpr double kMargin = 1e-3;
  constexpr double kFirstMu = 0.1;
  double mu = kFirstMu, best_low = low;
  double eps = 2 * std::sqrt(mu * (mu - low));
  Eigen::VectorXd grad(2 * m), next_grad(2 * m), direction(2 * m);
  for (int round = 0; round < options.max_rounds && energy.work < options.max_work; ++round) {
    result.rounds = round + 1;
    double e = energy(x, eps, grad);
    const double first = e;
    // L-BFGS with a backtracking (Armijo) line search.
    std::deque<std::pair<Eigen::VectorXd, Eigen::VectorXd>> history;  // (s, y)
    constexpr size_t kHistory = 8;
    for (int step = 0; step < options.max_steps && energy.work < options.max_work; ++step) {
      direction = -grad;
      std::vector<double> alpha(history.size());
      for (size_t k = history.size(); k-- > 0;) {
        const auto& [s, y] = history[k];
        alpha[k] = s.dot(direction) / y.dot(s);
        direction -= alpha[k] * y;
      }
      if (!history.empty()) {  // the initial Hessian guess: sᵀy / yᵀy of the last step
        const auto& [s, y] = history.back();
        direction *= s.dot(y) / y.squaredNorm();
      }
      for (size_t k = 0; k < history.size(); ++k) {
        const auto& [s, y] = history[k];
        direction += (alpha[k] - y.dot(direction) / y.dot(s)) * s;
      }
      double slope = grad.dot(direction);
      if (!(slope < 0)) {
        history.clear();
        direction = -grad;
        slope = -grad.squaredNorm();
      }
      if (!(slope < 0)) break;
      double s = 1, next = 0;
      bool accepted = false;
      for (int tries = 0; tries < 40; ++tries, s *= 0.5) {
        set(trial, x, direction, s);
        next = energy(trial, eps, next_grad);
        if (std::isfinite(next) && next <= e + 1e-4 * s * slope) {
          accepted = true;
          break;
        }
      }
      if (!accepted) {
        if (history.empty()) break;
        history.clear();  // once more downhill, then give up
        continue;
      }
      history.emplace_back(s * direction, next_grad - grad);
      if (history.back().second.dot(history.back().first) <= 0) history.pop_back();
      if (history.size() > kHistory) history.pop_front();
      x.swap(trial);
      grad.swap(next_grad);
      const double drop = e - next;
      e = next;
      if (drop <= 1e-10 * std::abs(e)) break;
    }
    int inverted = 0;
    low = energy.min_det(x, &inverted);
    if (inverted < result.inverted_after || (inverted == result.inverted_after && low > best_low)) {
      result.inverted_after = inverted;
      best_low = low;
      layout = x;
    }
    if (low > kMargin) break;
    // The next ε puts the worst triangle's χ a little below where it is now, by as much as the
    // last minimisation gained (at least a tenth).
    const double gain = std::max(first > 0 ? 1 - e / first : 0.0, 0.1);
    mu = (1 - gain) * chi(low, eps);
    if (!(mu > 0)) break;
    // Every triangle right but not clearly: the barrier all but exact from here.
    eps = low < mu ? 2 * std::sqrt(mu * (mu - low)) : 1e-9 * mu;
  }
  result.work = energy.work;
  return result;
}

}  // namespace shapematch::detail
