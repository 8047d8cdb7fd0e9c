// The native PDHG backend: the reference implementation of every kernel in pdhg_backend.hpp.
#include "pdhg_backend.hpp"
#include "thread_pool.hpp"

#include <algorithm>
#include <cmath>
#include <thread>

namespace shapematch::detail {
namespace {

inline double signed_gather(const SignedCsr& m, int64_t row, const double* v) {
  double s = 0.0;
  for (uint32_t k = m.row_ptr[row]; k < m.row_ptr[row + 1]; ++k) {
    const uint32_t e = m.entry[k];
    s += is_negative(e) ? -v[col_of(e)] : v[col_of(e)];
  }
  return s;
}

class CpuBackend final : public PdhgBackend {
public:
  explicit CpuBackend(int threads) : pool_(threads) {}

  std::string device() const override {
    return "cpu (" + std::to_string(pool_.size()) + " threads)";
  }

  void load(const ScaledLp& lp, const std::vector<double>& x, const std::vector<double>& y) override {
    lp_ = &lp;
    n_ = lp.a->cols;
    m_ = lp.a->rows;
    x_ = x;
    x0_ = x;
    xhat_ = x;  // read() before any iteration returns the start
    xr_.assign(n_, 0.0);
    y_ = y;
    y0_ = y;
    yhat_ = y;
    yr_.resize(m_);
    for (int64_t i = 0; i < m_; ++i) yr_[i] = lp.row_scale[i] * y_[i];
    partial_.assign(pool_.size() * 8, 0.0);
  }

  BatchStats iterate(int count, int64_t k0, const Step& step) override {
    BatchStats stats;
    for (int it = 0; it < count; ++it) {
      const bool last = it + 1 == count;
      const double kk = static_cast<double>(k0 + it);
      const double w = static_cast<double>((kk + 1.0) / (kk + 2.0));
      primal(step, w, last);
      if (last) stats.dx2 = sum(0);
      dual(step, w, last);
      if (last) stats.dy2 = sum(0);
    }
    evaluate(stats);
    return stats;
  }

  std::pair<double, double> restart() override {
    const int T = pool_.size();
    pool_.run([&](int t) {
      double dx = 0.0;
      for (int64_t j = n_ * t / T, e = n_ * (t + 1) / T; j < e; ++j) {
        const double d = xhat_[j] - x0_[j];
        dx += d * d;
        x_[j] = x0_[j] = xhat_[j];
      }
      double dy = 0.0;
      for (int64_t i = m_ * t / T, e = m_ * (t + 1) / T; i < e; ++i) {
        const double d = yhat_[i] - y0_[i];
        dy += d * d;
        y_[i] = y0_[i] = yhat_[i];
        yr_[i] = lp_->row_scale[i] * y_[i];
      }
      partial_[8 * t] = dx;
      partial_[8 * t + 1] = dy;
    });
    return {sum(0), sum(1)};
  }

  void read(std::vector<double>& xhat, std::vector<double>& yhat) override {
    xhat = xhat_;
    yhat = yhat_;
  }

private:
  double sum(int slot) const {
    double s = 0.0;
    for (int t = 0; t < pool_.size(); ++t) s += partial_[8 * t + slot];
    return s;
  }

  void primal(const Step& step, double w, bool last) {
    const SignedCsr& at = *lp_->at;
    const double* c = lp_->c.data();
    const double* d = lp_->col_scale.data();
    const int T = pool_.size();
    pool_.run([&](int t) {
      double dx2 = 0.0;
      for (int64_t j = n_ * t / T, e = n_ * (t + 1) / T; j < e; ++j) {
        const double g = c[j] - d[j] * signed_gather(at, j, yr_.data());
        const double xj = x_[j];
        const double xh = std::clamp(xj - step.tau * g, 0.0, 1.0 / d[j]);
        xr_[j] = d[j] * (2.0 * xh - xj);
        x_[j] = w * ((1.0 + step.gamma) * xh - step.gamma * xj) + (1.0 - w) * x0_[j];
        if (last) {
          xhat_[j] = xh;
          dx2 += (xh - xj) * (xh - xj);
        }
      }
      partial_[8 * t] = dx2;
    });
  }

  void dual(const Step& step, double w, bool last) {
    const SignedCsr& a = *lp_->a;
    const double* b = lp_->b.data();
    const double* r = lp_->row_scale.data();
    const int T = pool_.size();
    pool_.run([&](int t) {
      double dy2 = 0.0;
      for (int64_t i = m_ * t / T, e = m_ * (t + 1) / T; i < e; ++i) {
        const double yi = y_[i];
        const double yh = yi + step.sigma * (b[i] - r[i] * signed_gather(a, i, xr_.data()));
        y_[i] = w * ((1.0 + step.gamma) * yh - step.gamma * yi) + (1.0 - w) * y0_[i];
        yr_[i] = r[i] * y_[i];
        if (last) {
          yhat_[i] = yh;
          dy2 += (yh - yi) * (yh - yi);
        }
      }
      partial_[8 * t] = dy2;
    });
  }

  // Residual, objective and bound at (x̂, ŷ) in original units; reuses xr_/yr_-sized scratch.
  void evaluate(BatchStats& stats) {
    const SignedCsr& a = *lp_->a;
    const SignedCsr& at = *lp_->at;
    const double* d = lp_->col_scale.data();
    const double* r = lp_->row_scale.data();
    const int T = pool_.size();
    scratch_x_.resize(n_);
    scratch_y_.resize(m_);
    pool_.run([&](int t) {
      for (int64_t j = n_ * t / T, e = n_ * (t + 1) / T; j < e; ++j) scratch_x_[j] = d[j] * xhat_[j];
      for (int64_t i = m_ * t / T, e = m_ * (t + 1) / T; i < e; ++i) scratch_y_[i] = r[i] * yhat_[i];
    });
    pool_.run([&](int t) {
      double res = 0.0, by = 0.0;
      for (int64_t i = m_ * t / T, e = m_ * (t + 1) / T; i < e; ++i) {
        const double ri = double(signed_gather(a, i, scratch_x_.data())) - double(lp_->b[i]) / r[i];
        res += ri * ri;
        by += double(lp_->b[i]) * yhat_[i];
      }
      double cx = 0.0, neg = 0.0;
      for (int64_t j = n_ * t / T, e = n_ * (t + 1) / T; j < e; ++j) {
        cx += double(lp_->c[j]) * xhat_[j];
        const double rc = double(lp_->c[j]) / d[j] - double(signed_gather(at, j, scratch_y_.data()));
        neg += std::min(0.0, rc);
      }
      partial_[8 * t] = res;
      partial_[8 * t + 1] = by;
      partial_[8 * t + 2] = cx;
      partial_[8 * t + 3] = neg;
    });
    stats.residual2 = sum(0);
    stats.by = sum(1);
    stats.cx = sum(2);
    stats.reduced_neg = sum(3);
  }

  ThreadPool pool_;
  const ScaledLp* lp_ = nullptr;
  int64_t n_ = 0, m_ = 0;
  std::vector<double> x_, x0_, xhat_, xr_, y_, y0_, yhat_, yr_, scratch_x_, scratch_y_;
  std::vector<double> partial_;  // 8 slots per thread, apart enough to avoid false sharing of hot slots
};

}  // namespace

std::unique_ptr<PdhgBackend> make_cpu_backend(int threads) { return std::make_unique<CpuBackend>(threads); }

}  // namespace shapematch::detail
