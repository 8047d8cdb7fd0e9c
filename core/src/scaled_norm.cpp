#include "scaled_norm.hpp"

#include "parallel.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <random>

namespace shapematch::detail {

namespace {

// Vector sums in blocks of a fixed size, added in block order: the same value for any number of
// threads (the partition into threads only decides who sums which blocks).
constexpr int64_t kBlock = 8192;

template <class Term>
double blocked_sum(int64_t n, int threads, std::vector<double>& partial, Term&& term) {
  const int64_t blocks = (n + kBlock - 1) / kBlock;
  partial.assign(blocks, 0.0);
  parallel_for(blocks, threads, [&](int64_t b) {
    double s = 0.0;
    for (int64_t j = b * kBlock, e = std::min(n, j + kBlock); j < e; ++j) s += term(j);
    partial[b] = s;
  }, 2);  // a second thread from two blocks (16 384 entries) on
  double s = 0.0;
  for (double p : partial) s += p;
  return s;
}

}  // namespace

NormEstimate scaled_norm(const SignedCsr& a, const SignedCsr& at, const std::vector<double>& r,
                         const std::vector<double>& d, int max_steps, double tolerance, int threads, double margin,
                         double cap) {
  const int64_t m = a.rows, n = a.cols;
  NormEstimate out;
  if (n == 0 || m == 0 || max_steps <= 0) return out;
  // v: the Lanczos vector, prev: the one before, w: ÃᵀÃv; dv = d∘v and ru = r∘(Ãv), so that
  // each product gathers one array per entry.
  std::vector<double> v(n), prev(n, 0.0), w(n), dv(n), ru(m), partial;
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
    parallel_rows(a.row_ptr, threads, [&](int64_t i) {
      double s = 0.0;
      for (uint32_t k = a.row_ptr[i]; k < a.row_ptr[i + 1]; ++k) s += signed_value(a.entry[k], dv.data());
      ru[i] = r[i] * (r[i] * s);
    });
    // w = ÃᵀÃv and α = v·w in one pass.
    const double al = blocked_sum(n, threads, partial, [&](int64_t j) {
      double s = 0.0;
      for (uint32_t k = at.row_ptr[j]; k < at.row_ptr[j + 1]; ++k) s += signed_value(at.entry[k], ru.data());
      w[j] = d[j] * s;
      return v[j] * w[j];
    });
    out.steps = step + 1;
    alpha.push_back(al);
    const double nw = blocked_sum(n, threads, partial, [&](int64_t j) {
      w[j] -= al * v[j] + b * prev[j];
      return w[j] * w[j];
    });
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
    parallel_for(n, threads, [&](int64_t j) { dv[j] = d[j] * (v[j] = w[j] / b); });
  }
  return out;
}

}  // namespace shapematch::detail
