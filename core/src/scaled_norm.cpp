#include "scaled_norm.hpp"

#include "parallel.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>
#include <random>

namespace shapematch::detail {

NormEstimate scaled_norm(const SignedCsr& a, const SignedCsr& at, const std::vector<double>& r,
                         const std::vector<double>& d, int max_steps, double tolerance, int threads, double margin,
                         double cap) {
  const int64_t m = a.rows, n = a.cols;
  NormEstimate out;
  if (n == 0 || m == 0 || max_steps <= 0) return out;
  // v: the Lanczos vector, prev: the one before, w: ÃᵀÃv; dv = d∘v and ru = r∘(Ãv), so that
  // each product gathers one array per entry.
  std::vector<double> v(n), prev(n, 0.0), w(n), dv(n), ru(m);
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> uni(0.5, 1.5);
  double nv = 0.0;
  for (auto& x : v) {
    x = uni(rng);
    nv += x * x;
  }
  nv = std::sqrt(nv);
  for (int64_t j = 0; j < n; ++j) dv[j] = d[j] * (v[j] /= nv);
  std::vector<double> alpha, beta;
  double b = 0.0;
  for (int step = 0; step < max_steps; ++step) {
    parallel_for(m, threads, [&](int64_t i) {
      double s = 0.0;
      for (uint32_t k = a.row_ptr[i]; k < a.row_ptr[i + 1]; ++k) {
        const uint32_t e = a.entry[k];
        s += is_negative(e) ? -dv[col_of(e)] : dv[col_of(e)];
      }
      ru[i] = r[i] * (r[i] * s);
    });
    parallel_for(n, threads, [&](int64_t j) {
      double s = 0.0;
      for (uint32_t k = at.row_ptr[j]; k < at.row_ptr[j + 1]; ++k) {
        const uint32_t e = at.entry[k];
        s += is_negative(e) ? -ru[col_of(e)] : ru[col_of(e)];
      }
      w[j] = d[j] * s;
    });
    out.steps = step + 1;
    double al = 0.0;
    for (int64_t j = 0; j < n; ++j) al += v[j] * w[j];
    alpha.push_back(al);
    double nw = 0.0;
    for (int64_t j = 0; j < n; ++j) {
      w[j] -= al * v[j] + b * prev[j];
      nw += w[j] * w[j];
    }
    b = std::sqrt(nw);
    // The largest eigenvalue θ of the tridiagonal T (α on the diagonal, β below) and the last
    // component s of its eigenvector: ‖ÃᵀÃu − θu‖ = β|s| for the Ritz vector u.
    const Eigen::Index k = static_cast<Eigen::Index>(alpha.size());
    Eigen::VectorXd diag = Eigen::Map<const Eigen::VectorXd>(alpha.data(), k);
    Eigen::VectorXd sub = Eigen::Map<const Eigen::VectorXd>(beta.data(), k - 1);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es;
    es.computeFromTridiagonal(diag, sub, Eigen::ComputeEigenvectors);
    const double theta = std::max(0.0, es.eigenvalues()(k - 1));
    out.norm = std::sqrt(theta);
    out.residual = theta > 0.0 ? b * std::abs(es.eigenvectors()(k - 1, k - 1)) / theta : 0.0;
    if (margin * out.norm >= cap || out.residual <= tolerance || !(b > 1e-300)) break;
    beta.push_back(b);
    prev.swap(v);
    for (int64_t j = 0; j < n; ++j) dv[j] = d[j] * (v[j] = w[j] / b);
  }
  return out;
}

}  // namespace shapematch::detail
