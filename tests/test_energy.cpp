#include "shapematch/energy.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/shapes.hpp"
#include "test_helpers.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <numeric>

using namespace shapematch;

namespace {

Triangle3 random_triangle(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  return {Eigen::Vector3d(u(rng), u(rng), u(rng)), Eigen::Vector3d(u(rng), u(rng), u(rng)),
          Eigen::Vector3d(u(rng), u(rng), u(rng))};
}

// The bending and feature weight of vertex v in face f: its corner's mixed Voronoi area (0 on a
// degenerate side, -1 where v is not a corner of f).
double corner_area_of(const Mesh& m, const Geometry& g, int f, int v) {
  if (f < 0) return 0.0;
  for (int c = 0; c < 3; ++c)
    if (m.faces[f][c] == v) return g.corner_area[f][c];
  return -1.0;
}

}  // namespace

TEST_CASE("energy: membrane equals Delingette's spring form on random triangles") {
  std::mt19937 rng(7);
  for (int k = 0; k < 1000; ++k) {
    const Triangle3 s = random_triangle(rng), t = random_triangle(rng);
    const double lambda = 0.2 + (k % 5), mu = 0.5 + (k % 3);
    const double w = membrane_energy(s, t, lambda, mu), ws = membrane_energy_springs(s, t, lambda, mu);
    CHECK(w >= 0.0);
    CHECK(std::abs(w - ws) <= 1e-10 * std::max(1.0, std::abs(w)));
  }
}

TEST_CASE("energy: membrane matches the continuum formula for a uniaxial stretch") {
  // Stretching by s along an axis of an orthonormal frame gives E = diag((s²−1)/2, 0), so
  // W = A((λ/2)e² + μe²) with e = (s²−1)/2, for any triangle shape.
  std::mt19937 rng(3);
  for (int k = 0; k < 100; ++k) {
    Triangle3 src = random_triangle(rng);
    for (auto& p : src) p.z() = 0.0;
    const double s = 0.5 + 0.01 * k, lambda = 1.3, mu = 0.7;
    Triangle3 dst = src;
    for (auto& p : dst) p.x() *= s;
    const double area = 0.5 * (src[1] - src[0]).cross(src[2] - src[0]).norm();
    const double e = (s * s - 1) / 2;
    CHECK(membrane_energy(src, dst, lambda, mu) == doctest::Approx(area * (lambda / 2 + mu) * e * e).epsilon(1e-10));
  }
}

TEST_CASE("energy: membrane is zero for rigid motions and positive otherwise") {
  std::mt19937 rng(11);
  for (int k = 0; k < 200; ++k) {
    const Triangle3 s = random_triangle(rng);
    const Eigen::Matrix3d R = test::random_rotation(rng);
    const Eigen::Vector3d t(0.3, -2.0, 5.0);
    Triangle3 rigid, scaled;
    for (int i = 0; i < 3; ++i) {
      rigid[i] = R * s[i] + t;
      scaled[i] = 1.05 * (R * s[i]) + t;
    }
    CHECK(membrane_energy(s, rigid, 1, 1) < 1e-9);
    CHECK(membrane_energy(s, scaled, 1, 1) > 1e-6);
  }
  // Degenerate source: no area, no energy; degenerate target: finite, positive.
  const Triangle3 line{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(2, 0, 0)};
  const Triangle3 tri{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0)};
  CHECK(membrane_energy(line, tri, 1, 1) == 0.0);
  const double collapse = membrane_energy(tri, line, 1, 1);
  CHECK(std::isfinite(collapse));
  CHECK(collapse > 0.0);
}

TEST_CASE("energy: the identity matching costs nothing; swapping X and Y preserves energies") {
  const Mesh x = shapes::icosphere(1);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  const Mesh y = test::deformed(x, [&](const Eigen::Vector3d& p) {
    return Eigen::Vector3d(1.2 * p.x() + u(rng), p.y() + u(rng), 0.9 * p.z() + u(rng));
  });
  const Geometry gx = compute_geometry(x), gy = compute_geometry(y);
  EnergyOptions opt;
  opt.bending_weight = 0.7;
  const EnergyModel xx(x, gx, x, gx, opt);
  for (const auto& t : identity_matching(x)) CHECK(xx(t) == doctest::Approx(0.0).epsilon(1e-14));

  const EnergyModel xy(x, gx, y, gy, opt), yx(y, gy, x, gx, opt);
  const ProductSpace s = ProductSpace::full(x, y);
  double total = 0.0;
  for (int64_t j = 0; j < s.size(); j += 7) {
    const ProductTriangle t = s[j];
    const ProductTriangle swapped{t.b, t.a, t.fb, t.fa};
    const double e = xy(t);
    CHECK(e >= 0.0);
    CHECK(yx(swapped) == doctest::Approx(e).epsilon(1e-12));
    total += e;
  }
  CHECK(total > 0.0);
  // Identity-like triangles of the deformed pair cost something, but far less than random ones.
  double id_energy = 0.0;
  for (const auto& t : identity_matching(x)) id_energy += xy(t);
  CHECK(id_energy > 0.0);
}

TEST_CASE("energy: the compressive membrane charges compression like SVK and stretch not at all") {
  // Biaxial scaling by (s1, s2) of a planar triangle along the frame axes has principal squared
  // stretches s1², s2²; the compressive energy keeps e_i = (min(s_i², 1) − 1)/2.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.2, 1.8), angle(0, 3.14159);
  for (int k = 0; k < 200; ++k) {
    Triangle3 src = random_triangle(rng);
    for (auto& p : src) p.z() = 0.0;
    const double s1 = u(rng), s2 = u(rng), lambda = 0.5 + (k % 3), mu = 0.4 + (k % 4);
    const Eigen::Matrix3d r = test::random_rotation(rng);
    const double th = angle(rng);
    const Eigen::Matrix2d frame = Eigen::Rotation2Dd(th).toRotationMatrix();
    Eigen::Matrix2d stretch = frame * Eigen::Vector2d(s1, s2).asDiagonal() * frame.transpose();
    Triangle3 dst;
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector2d q = stretch * src[i].head<2>();
      dst[i] = r * Eigen::Vector3d(q.x(), q.y(), 0.0);
    }
    const double area = 0.5 * (src[1] - src[0]).cross(src[2] - src[0]).norm();
    const double e1 = 0.5 * (std::min(s1 * s1, 1.0) - 1), e2 = 0.5 * (std::min(s2 * s2, 1.0) - 1);
    const double expected = area * (0.5 * lambda * (e1 + e2) * (e1 + e2) + mu * (e1 * e1 + e2 * e2));
    CHECK(compressive_membrane_energy(src, dst, lambda, mu) == doctest::Approx(expected).epsilon(1e-9));
    if (s1 <= 1 && s2 <= 1)  // pure compression: exactly St. Venant–Kirchhoff
      CHECK(compressive_membrane_energy(src, dst, lambda, mu) == doctest::Approx(membrane_energy(src, dst, lambda, mu)).epsilon(1e-9));
    if (s1 >= 1 && s2 >= 1) CHECK(compressive_membrane_energy(src, dst, lambda, mu) == doctest::Approx(0.0).epsilon(1e-12));
  }
  // Squashed onto a segment of the same length: e = (−1/2, 0), W = A(λ/8 + μ/4).
  const Triangle3 s{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0)};
  const Triangle3 seg{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 0, 0)};
  CHECK(compressive_membrane_energy(s, seg, 1.0, 1.0) == doctest::Approx(0.5 * (1.0 / 8 + 1.0 / 4)));
  CHECK(compressive_membrane_energy(seg, s, 1.0, 1.0) == 0.0);  // a degenerate source has no metric
}

TEST_CASE("energy: with the compressive membrane a stretch is charged once, as compression the other way") {
  // A product triangle mapping a face onto itself scaled by s > 1: X→Y stretches (free), Y→X
  // compresses by 1/s, on the target's area s²A.
  const Mesh x = shapes::octahedron();
  const double s = 1.4;
  const Mesh y = test::deformed(x, [&](const Eigen::Vector3d& p) { return Eigen::Vector3d(s * p); });
  const Geometry gx = compute_geometry(x), gy = compute_geometry(y);
  EnergyOptions o;
  o.membrane = MembraneModel::Compressive;
  o.bending_weight = 0;
  const EnergyModel model(x, gx, y, gy, o);
  const ProductTriangle t{x.faces[0], y.faces[0], 0, 0};
  const double e = 0.5 * (1 / (s * s) - 1);
  CHECK(model.membrane(t) == doctest::Approx(s * s * gx.face_area[0] * (0.5 * 1 * 4 * e * e + 1 * 2 * e * e)));
  // The reverse pair costs the same: the energy is symmetric in X and Y.
  const EnergyModel reverse(y, gy, x, gx, o);
  CHECK(reverse.membrane(t) == doctest::Approx(model.membrane(t)));
}

TEST_CASE("energy: the feature term is Σ (corner areas) ‖f_X − f_Y‖² over the three corners") {
  const Mesh x = shapes::icosphere(1);
  const Mesh y = test::deformed(x, [](const Eigen::Vector3d& p) { return Eigen::Vector3d(1.3 * p.x(), p.y(), p.z()); });
  const Geometry gx = compute_geometry(x), gy = compute_geometry(y);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::MatrixXd fx(x.num_vertices(), 5), fy(y.num_vertices(), 5);
  for (Eigen::Index i = 0; i < fx.size(); ++i) fx.data()[i] = u(rng);
  for (Eigen::Index i = 0; i < fy.size(); ++i) fy.data()[i] = u(rng);
  EnergyModel model(x, gx, y, gy);
  CHECK(model.feature(identity_matching(x).front()) == 0.0);  // no features: no term
  model.set_features(fx, fy);
  const ProductSpace s = ProductSpace::full(x, y);
  int degenerate = 0;
  for (int64_t j = 0; j < s.size(); j += 13) {
    const ProductTriangle t = s[j];
    degenerate += t.fa < 0 || t.fb < 0;
    double expected = 0.0;
    for (int i = 0; i < 3; ++i)
      expected += (corner_area_of(x, gx, t.fa, t.a[i]) + corner_area_of(y, gy, t.fb, t.b[i])) *
                  (fx.row(t.a[i]) - fy.row(t.b[i])).squaredNorm();
    CHECK(model.feature(t) == doctest::Approx(expected).epsilon(1e-14));  // (added in another order)
  }
  CHECK(degenerate > 0);
  // Equal features on the identity: nothing to pay.
  EnergyModel same(x, gx, x, gx);
  same.set_features(fx, fx);
  for (const auto& t : identity_matching(x)) CHECK(same.feature(t) == 0.0);
  CHECK_THROWS_AS(same.set_features(fx, fy.leftCols(4)), InvalidInputError);
}

TEST_CASE("energy: with a curvature radius the bending term reads H averaged over it, the radius in units of √area") {
  // X of area 4π · 4 (radius 2), so the radius 0.1 is 0.1 · √(16π) in X's units; Y of area 4π.
  const Mesh x = test::deformed(test::bumpy_sphere(0.2), [](const Eigen::Vector3d& p) { return Eigen::Vector3d(2 * p); });
  const Mesh y = test::bumpy_sphere(0.1);
  const Geometry gx = compute_geometry(x), gy = compute_geometry(y);
  auto total = [](const Geometry& g) { return std::accumulate(g.face_area.begin(), g.face_area.end(), 0.0); };
  const std::vector<double> hx = smoothed_mean_curvature(x, gx, 0.1 * std::sqrt(total(gx)));
  const std::vector<double> hy = smoothed_mean_curvature(y, gy, 0.1 * std::sqrt(total(gy)));
  CHECK(hx != gx.mean_curvature);  // the radius reaches past each vertex's own neighbours
  EnergyModel per_vertex(x, gx, y, gy), averaged(x, gx, y, gy, EnergyOptions{.curvature_radius = 0.1});
  const ProductSpace s = ProductSpace::full(x, y);
  int differ = 0;
  for (int64_t j = 0; j < s.size(); j += 101) {
    const ProductTriangle t = s[j];
    double expected = 0.0, raw = 0.0;
    for (int i = 0; i < 3; ++i) {
      const double a = corner_area_of(x, gx, t.fa, t.a[i]) + corner_area_of(y, gy, t.fb, t.b[i]);
      expected += a * (hx[t.a[i]] - hy[t.b[i]]) * (hx[t.a[i]] - hy[t.b[i]]);
      raw += a * (gx.mean_curvature[t.a[i]] - gy.mean_curvature[t.b[i]]) *
             (gx.mean_curvature[t.a[i]] - gy.mean_curvature[t.b[i]]);
    }
    CHECK(averaged.bending(t) == doctest::Approx(expected).epsilon(1e-12));
    CHECK(per_vertex.bending(t) == doctest::Approx(raw).epsilon(1e-12));
    differ += std::abs(expected - raw) > 1e-9 * std::max(1.0, raw);
  }
  CHECK(differ > 0);
  CHECK(averaged.membrane(s[7]) == per_vertex.membrane(s[7]));  // the membrane does not care
}
