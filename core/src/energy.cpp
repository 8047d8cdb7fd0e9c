#include "shapematch/energy.hpp"

#include "shapematch/errors.hpp"

#include "parallel.hpp"

#include <Eigen/Dense>
#include <cmath>

namespace shapematch {
namespace {

Eigen::Matrix2d gram(const Triangle3& t) {
  const Eigen::Vector3d e1 = t[1] - t[0], e2 = t[2] - t[0];
  Eigen::Matrix2d g;
  g << e1.dot(e1), e1.dot(e2), e1.dot(e2), e2.dot(e2);
  return g;
}

double area(const Triangle3& t) { return 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).norm(); }

// A triangle whose area is below this fraction of its squared longest edge counts as degenerate
// (then it has no metric to be a source of strain).
constexpr double kDegenerate = 1e-14;

bool degenerate(const Triangle3& t) {
  const double l2 = std::max({(t[1] - t[0]).squaredNorm(), (t[2] - t[1]).squaredNorm(), (t[0] - t[2]).squaredNorm()});
  return !(area(t) > kDegenerate * l2);
}

int corner_of(const std::array<int, 3>& face, int v) {
  for (int k = 0; k < 3; ++k)
    if (face[k] == v) return k;
  return -1;
}


}  // namespace

double membrane_energy(const Triangle3& s, const Triangle3& t, double lambda, double mu) {
  if (degenerate(s)) return 0.0;
  const Eigen::Matrix2d e = 0.5 * (gram(s).inverse() * gram(t) - Eigen::Matrix2d::Identity());
  const double tr = e.trace();
  return area(s) * (0.5 * lambda * tr * tr + mu * (e * e).trace());
}

double compressive_membrane_energy(const Triangle3& s, const Triangle3& t, double lambda, double mu) {
  if (degenerate(s)) return 0.0;
  // Squared principal stretches: the eigenvalues of C = G_s⁻¹G_t (similar to a symmetric PSD matrix).
  const Eigen::Matrix2d c = gram(s).inverse() * gram(t);
  const double half_tr = 0.5 * c.trace(), det = c.determinant();
  const double root = std::sqrt(std::max(0.0, half_tr * half_tr - det));
  const double e1 = 0.5 * (std::min(1.0, std::max(0.0, half_tr + root)) - 1.0);
  const double e2 = 0.5 * (std::min(1.0, std::max(0.0, half_tr - root)) - 1.0);
  return area(s) * (0.5 * lambda * (e1 + e2) * (e1 + e2) + mu * (e1 * e1 + e2 * e2));
}

double membrane_energy_springs(const Triangle3& s, const Triangle3& t, double lambda, double mu) {
  if (degenerate(s)) return 0.0;
  const double a = area(s);
  std::array<double, 3> cot{}, delta{};
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    const Eigen::Vector3d u = s[j] - s[i], v = s[k] - s[i];
    cot[i] = u.dot(v) / u.cross(v).norm();
    delta[i] = (t[k] - t[j]).squaredNorm() - (s[k] - s[j]).squaredNorm();  // edge opposite vertex i
  }
  double w = 0.0;
  for (int i = 0; i < 3; ++i) w += (cot[i] * cot[i] * (lambda + 2 * mu) + mu) / (32 * a) * delta[i] * delta[i];
  for (int i = 0; i < 3; ++i)
    for (int j = i + 1; j < 3; ++j)
      w += (cot[i] * cot[j] * (lambda + 2 * mu) - mu) / (16 * a) * delta[i] * delta[j];
  return w;
}

EnergyModel::EnergyModel(const Mesh& x, const Geometry& gx, const Mesh& y, const Geometry& gy, EnergyOptions options)
    : x_(x), gx_(gx), y_(y), gy_(gy), options_(options) {
  auto curvature = [&](const Mesh& m, const Geometry& g) {
    double area = 0.0;
    for (double a : g.face_area) area += a;
    return smoothed_mean_curvature(m, g, options_.curvature_radius * std::sqrt(area));
  };
  hx_ = curvature(x, gx);
  hy_ = curvature(y, gy);
}

void EnergyModel::set_features(Eigen::MatrixXd fx, Eigen::MatrixXd fy) {
  if (fx.size() > 0 && (fx.rows() != x_.num_vertices() || fy.rows() != y_.num_vertices() || fx.cols() != fy.cols()))
    throw InvalidInputError("features: need one row per vertex on each shape and the same number of columns");
  fx_ = std::move(fx);
  fy_ = std::move(fy);
}

double EnergyModel::membrane(const ProductTriangle& p) const {
  const Triangle3 s{x_.vertices[p.a[0]], x_.vertices[p.a[1]], x_.vertices[p.a[2]]};
  const Triangle3 t{y_.vertices[p.b[0]], y_.vertices[p.b[1]], y_.vertices[p.b[2]]};
  const double l = options_.lame_lambda, m = options_.lame_mu;
  const auto w = options_.membrane == MembraneModel::StVenantKirchhoff ? membrane_energy : compressive_membrane_energy;
  // Symmetrised (DESIGN.md §5): a degenerate side has no area, so the other direction counts twice.
  if (p.fa >= 0 && p.fb >= 0) return w(s, t, l, m) + w(t, s, l, m);
  if (p.fa >= 0) return 2.0 * w(s, t, l, m);
  return 2.0 * w(t, s, l, m);
}

double EnergyModel::bending(const ProductTriangle& p) const {
  double e = 0.0;
  for (int i = 0; i < 3; ++i) {
    // A vertex repeated in a degenerate tuple is counted once per corner, with zero area on that side.
    const double ax = p.fa >= 0 ? gx_.corner_area[p.fa][corner_of(x_.faces[p.fa], p.a[i])] : 0.0;
    const double ay = p.fb >= 0 ? gy_.corner_area[p.fb][corner_of(y_.faces[p.fb], p.b[i])] : 0.0;
    const double dh = hx_[p.a[i]] - hy_[p.b[i]];
    e += (ax + ay) * dh * dh;
  }
  return e;
}

namespace {
// ‖u − w‖² in four sums side by side: one sum's chain of dependent additions made the feature
// term 12 % of the finest level's rebuilds (perf, FAUST_r 024-043 at full resolution, 100 WKS
// columns: 3 × 100 additions per product triangle, ~10 M triangles per rebuild).
double squared_distance(const double* u, const double* w, Eigen::Index n) {
  double s[4] = {0.0, 0.0, 0.0, 0.0};
  Eigen::Index k = 0;
  for (; k + 4 <= n; k += 4)
    for (int i = 0; i < 4; ++i) s[i] += (u[k + i] - w[k + i]) * (u[k + i] - w[k + i]);
  for (; k < n; ++k) s[0] += (u[k] - w[k]) * (u[k] - w[k]);
  return (s[0] + s[1]) + (s[2] + s[3]);
}
}  // namespace

double EnergyModel::feature(const ProductTriangle& p) const {
  if (fx_.size() == 0) return 0.0;
  double e = 0.0;
  for (int i = 0; i < 3; ++i) {
    const double ax = p.fa >= 0 ? gx_.corner_area[p.fa][corner_of(x_.faces[p.fa], p.a[i])] : 0.0;
    const double ay = p.fb >= 0 ? gy_.corner_area[p.fb][corner_of(y_.faces[p.fb], p.b[i])] : 0.0;
    const double* u = fx_.data() + fx_.cols() * p.a[i];
    const double* w = fy_.data() + fy_.cols() * p.b[i];
    e += (ax + ay) * squared_distance(u, w, fx_.cols());
  }
  return e;
}

double EnergyModel::operator()(const ProductTriangle& p) const {
  double e = membrane(p);
  if (options_.bending_weight != 0.0) e += options_.bending_weight * bending(p);
  if (options_.feature_weight != 0.0) e += options_.feature_weight * feature(p);
  if (options_.degenerate_penalty != 0.0 && (p.fa < 0 || p.fb < 0))
    e += options_.degenerate_penalty * (p.fa >= 0 ? gx_.face_area[p.fa] : gy_.face_area[p.fb]);
  return e;
}

std::vector<double> energy_vector(const ProductSpace& space, const EnergyModel& model) {
  std::vector<double> c(space.size());
  detail::parallel_for(space.size(), 0, [&](int64_t j) { c[j] = model(space[j]); });
  return c;
}

}  // namespace shapematch
