// The native PDHG backend: the reference implementation of every kernel in pdhg_backend.hpp.
#include "pdhg_backend.hpp"
#include "thread_pool.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace shapematch::detail {
namespace {

// Σ ±v[col] over entries [begin, end), in entry order (the shaders add in the same order).
template <class T>
inline double signed_gather(const uint32_t* entry, uint32_t begin, uint32_t end, const T* v) {
  double s = 0.0;
  for (uint32_t k = begin; k < end; ++k) s += signed_value(entry[k], v);
  return s;
}

inline double signed_gather(const SignedCsr& m, int64_t row, const double* v) {
  return signed_gather(m.entry.data(), m.row_ptr[row], m.row_ptr[row + 1], v);
}

// The sum over a long row of A in kLongLanes interleaved partial sums and their pairwise tree
// (pdhg_backend.hpp), in the order of pdhg_dual_long.comp. Independent chains also suit a CPU.
template <class T>
inline double long_row_sum(const uint32_t* e, uint32_t n, const T* v) {
  std::array<double, kLongLanes> s{};
  uint32_t t = 0;
  for (; t + kLongLanes <= n; t += kLongLanes)
    for (uint32_t l = 0; l < kLongLanes; ++l) s[l] += signed_value(e[t + l], v);
  for (uint32_t l = 0; t + l < n; ++l) s[l] += signed_value(e[t + l], v);
  for (uint32_t h = kLongLanes / 2; h > 0; h /= 2)
    for (uint32_t l = 0; l < h; ++l) s[l] += s[l + h];
  return s[0];
}

// A row sum of A: entry order, or the long-row order above kLongRow entries.
template <class T>
inline double a_row_sum(const uint32_t* entry, uint32_t begin, uint32_t end, const T* v) {
  return end - begin > kLongRow ? long_row_sum(entry + begin, end - begin, v) : signed_gather(entry, begin, end, v);
}

// Two rows' sums at once, each in its own entry order (so the same values as signed_gather). A
// row's sum is a chain of dependent additions behind gathers; two interleaved chains ran 14 %
// faster per thread (four: no further gain).
template <class T>
inline void signed_gather2(const uint32_t* e0, uint32_t n0, const uint32_t* e1, uint32_t n1, const T* v,
                           double& s0, double& s1) {
  const uint32_t common = std::min(n0, n1);
  double a = 0.0, b = 0.0;
  for (uint32_t k = 0; k < common; ++k) {
    a += signed_value(e0[k], v);
    b += signed_value(e1[k], v);
  }
  for (uint32_t k = common; k < n0; ++k) a += signed_value(e0[k], v);
  for (uint32_t k = common; k < n1; ++k) b += signed_value(e1[k], v);
  s0 = a;
  s1 = b;
}

// update(row, Σ ±v over the row) for rows [begin, end), two rows at a time (signed_gather2);
// RowsOfA: long rows in the long-row order (a_row_sum).
template <bool RowsOfA, class T, class Update>
inline void for_each_row_sum(const uint32_t* ptr, const uint32_t* entry, const T* v, int64_t begin, int64_t end,
                             Update&& update) {
  int64_t i = begin;
  for (; i + 1 < end; i += 2) {
    if (RowsOfA && (ptr[i + 1] - ptr[i] > kLongRow || ptr[i + 2] - ptr[i + 1] > kLongRow)) {
      update(i, a_row_sum(entry, ptr[i], ptr[i + 1], v));
      update(i + 1, a_row_sum(entry, ptr[i + 1], ptr[i + 2], v));
      continue;
    }
    double s0, s1;
    signed_gather2(entry + ptr[i], ptr[i + 1] - ptr[i], entry + ptr[i + 1], ptr[i + 2] - ptr[i + 1], v, s0, s1);
    update(i, s0);
    update(i + 1, s1);
  }
  if (i < end) update(i, RowsOfA ? a_row_sum(entry, ptr[i], ptr[i + 1], v) : signed_gather(entry, ptr[i], ptr[i + 1], v));
}

// clamp(v, 0, hi) for hi > 0, equal to std::clamp (−0 and NaN pass through) but without the
// data-dependent branch GCC makes of its lower bound (a hot spot in the profile: most x̂_j
// sit at the bound 0, some do not).
inline double clamp_box(double v, double hi) {
  const double t = hi < v ? hi : v;  // minsd
#if defined(__SSE2__)
  return _mm_cvtsd_f64(_mm_max_sd(_mm_setzero_pd(), _mm_set_sd(t)));  // 0 > t ? 0 : t
#else
  return 0.0 > t ? 0.0 : t;
#endif
}

// Boundaries of `parts` contiguous row ranges of about equal cost, a row costing what it moves
// in pdhg_bytes_per_iteration (12 bytes per entry, 52 per row): the π rows at the end of A hold
// a third of its entries, so equal row counts gave one thread twice the other's work.
std::vector<int64_t> split_by_cost(const SignedCsr& m, int parts) {
  const auto cost = [&](int64_t row) { return 12.0 * m.row_ptr[row] + 52.0 * row; };
  const double total = cost(m.rows);
  std::vector<int64_t> split(parts + 1, m.rows);
  split[0] = 0;
  int64_t row = 0;
  for (int t = 1; t < parts; ++t) {
    while (row < m.rows && cost(row) < total * t / parts) ++row;
    split[t] = row;
  }
  return split;
}

// Chunks per thread of the iteration loops: enough that a descheduled thread's share is taken
// over, few enough that claiming them costs nothing measurable.
constexpr int kChunksPerThread = 16;

// What both native backends share: the thread pool, per-thread partial sums, the cost splits of
// the iteration loops and the evaluation at (x̂, ŷ), which is fp64 in both.
class NativeBackend : public PdhgBackend {
protected:
  explicit NativeBackend(int threads) : pool_(threads) {}

  void prepare(const ScaledLp& lp) {
    lp_ = &lp;
    n_ = lp.a->cols;
    m_ = lp.a->rows;
    partial_.assign(pool_.size() * 8, 0.0);
    col_split_ = split_by_cost(*lp.at, pool_.size() * kChunksPerThread);
    row_split_ = split_by_cost(*lp.a, pool_.size() * kChunksPerThread);
  }

  double sum(int slot) const {
    double s = 0.0;
    for (int t = 0; t < pool_.size(); ++t) s += partial_[8 * t + slot];
    return s;
  }

  // kernel(begin, end) over chunks of about equal cost; the last iteration of a batch splits rows
  // evenly, one share per thread into partial_[8t], so that the statistics (and the host's restart
  // decisions on them) do not depend on the cost split.
  // kernel(std::bool_constant<last>, begin, end).
  template <class Kernel>
  void run_split(bool last, const std::vector<int64_t>& split, int64_t count, Kernel&& kernel) {
    const int T = pool_.size();
    if (last)
      pool_.run(T, [&](int t) { partial_[8 * t] = kernel(std::true_type{}, count * t / T, count * (t + 1) / T); });
    else
      pool_.run(int(split.size()) - 1, [&](int c) { kernel(std::false_type{}, split[c], split[c + 1]); });
  }

  // Residual, objective and bound at x̂ = xhat(j), ŷ = yhat(i) (scaled) in original units.
  template <class XHat, class YHat>
  void evaluate_at(XHat&& xhat, YHat&& yhat, BatchStats& stats) {
    const SignedCsr& a = *lp_->a;
    const SignedCsr& at = *lp_->at;
    const double* d = lp_->col_scale.data();
    const double* r = lp_->row_scale.data();
    const int T = pool_.size();
    scratch_x_.resize(n_);
    scratch_y_.resize(m_);
    pool_.run(T, [&](int t) {
      for (int64_t j = n_ * t / T, e = n_ * (t + 1) / T; j < e; ++j) scratch_x_[j] = d[j] * xhat(j);
      for (int64_t i = m_ * t / T, e = m_ * (t + 1) / T; i < e; ++i) scratch_y_[i] = r[i] * yhat(i);
    });
    pool_.run(T, [&](int t) {
      double res = 0.0, by = 0.0;
      for (int64_t i = m_ * t / T, e = m_ * (t + 1) / T; i < e; ++i) {
        const double ri = a_row_sum(a.entry.data(), a.row_ptr[i], a.row_ptr[i + 1], scratch_x_.data()) - lp_->b[i] / r[i];
        res += ri * ri;
        by += double(lp_->b[i]) * yhat(i);
      }
      double cx = 0.0, neg = 0.0;
      for (int64_t j = n_ * t / T, e = n_ * (t + 1) / T; j < e; ++j) {
        cx += double(lp_->c[j]) * xhat(j);
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
  std::vector<double> scratch_x_, scratch_y_;
  std::vector<int64_t> col_split_, row_split_;  // chunks of Aᵀ's and A's rows of about equal cost
  std::vector<double> partial_;  // 8 slots per thread, apart enough to avoid false sharing of hot slots
};

class CpuBackend final : public NativeBackend {
public:
  explicit CpuBackend(int threads) : NativeBackend(threads) {}

  std::string device() const override {
    return "cpu (" + std::to_string(pool_.size()) + " threads)";
  }

  void load(const ScaledLp& lp, const std::vector<double>& x, const std::vector<double>& y) override {
    load_state(lp, x, x, y, y);
  }

  void load_state(const ScaledLp& lp, const std::vector<double>& x, const std::vector<double>& x0,
                  const std::vector<double>& y, const std::vector<double>& y0) override {
    prepare(lp);
    x_ = x;
    x0_ = x0;
    xhat_ = x;  // read() before any iteration returns the start
    xr_.assign(n_, 0.0);  // (written by each primal step before the dual reads it)
    y_ = y;
    y0_ = y0;
    yhat_ = y;
    yr_.resize(m_);
    for (int64_t i = 0; i < m_; ++i) yr_[i] = lp.row_scale[i] * y_[i];  // (as the dual step makes it)
  }

  bool read_state(std::vector<double>& x, std::vector<double>& x0, std::vector<double>& y,
                  std::vector<double>& y0) override {
    x = x_, x0 = x0_, y = y_, y0 = y0_;
    return true;
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
    pool_.run(T, [&](int t) {
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
  void primal(const Step& step, double w, bool last) {
    run_split(last, col_split_, n_, [&](auto l, int64_t b, int64_t e) { return primal_rows<l()>(step, w, b, e); });
  }

  template <bool Last>
  double primal_rows(const Step& step, double w, int64_t begin, int64_t end) {
    const uint32_t* ptr = lp_->at->row_ptr.data();
    const uint32_t* entry = lp_->at->entry.data();
    const double* c = lp_->c.data();
    const double* d = lp_->col_scale.data();
    const double* yr = yr_.data();
    const double* x0 = x0_.data();
    double* x = x_.data();
    double* xr = xr_.data();
    double* xhat = xhat_.data();
    const double tau = step.tau, gamma = step.gamma;
    double dx2 = 0.0;
    const auto update = [&](int64_t j, double aty) {
      const double g = c[j] - d[j] * aty;
      const double xj = x[j];
      const double xh = clamp_box(xj - tau * g, 1.0 / d[j]);
      xr[j] = d[j] * (2.0 * xh - xj);
      x[j] = w * ((1.0 + gamma) * xh - gamma * xj) + (1.0 - w) * x0[j];
      if constexpr (Last) {
        xhat[j] = xh;
        dx2 += (xh - xj) * (xh - xj);
      }
    };
    for_each_row_sum<false>(ptr, entry, yr, begin, end, update);
    return dx2;
  }

  void dual(const Step& step, double w, bool last) {
    run_split(last, row_split_, m_, [&](auto l, int64_t b, int64_t e) { return dual_rows<l()>(step, w, b, e); });
  }

  template <bool Last>
  double dual_rows(const Step& step, double w, int64_t begin, int64_t end) {
    const uint32_t* ptr = lp_->a->row_ptr.data();
    const uint32_t* entry = lp_->a->entry.data();
    const double* b = lp_->b.data();
    const double* r = lp_->row_scale.data();
    const double* xr = xr_.data();
    const double* y0 = y0_.data();
    double* y = y_.data();
    double* yr = yr_.data();
    double* yhat = yhat_.data();
    const double sigma = step.sigma, gamma = step.gamma;
    double dy2 = 0.0;
    const auto update = [&](int64_t i, double ax) {
      const double yi = y[i];
      const double yh = yi + sigma * (b[i] - r[i] * ax);
      y[i] = w * ((1.0 + gamma) * yh - gamma * yi) + (1.0 - w) * y0[i];
      yr[i] = r[i] * y[i];
      if constexpr (Last) {
        yhat[i] = yh;
        dy2 += (yh - yi) * (yh - yi);
      }
    };
    for_each_row_sum<true>(ptr, entry, xr, begin, end, update);
    return dy2;
  }

  void evaluate(BatchStats& stats) {
    evaluate_at([&](int64_t j) { return xhat_[j]; }, [&](int64_t i) { return yhat_[i]; }, stats);
  }

  std::vector<double> x_, x0_, xhat_, xr_, y_, y0_, yhat_, yr_;
};

// The native backend with single-precision vectors: about 40 % fewer bytes per iteration (see
// pdhg_bytes_per_iteration_f32). Plain fp32 iterates stall because c − Aᵀy cancels large duals
// (docs/architecture.md, "Precision"), so the dual is kept as y = y⁰ + δ: the anchor y⁰ in fp64,
// the move δ since the last restart in fp32, and the primal kernel reads the anchor's reduced
// cost g⁰_j = c̃_j − d_j Σ_i ±r_i y⁰_i (computed in fp64 at every restart, stored in fp32 after
// the cancellation) minus d_j Σ_i ±r_i δ_i. The Halpern anchor of δ is 0, so y⁰ is not read per
// iteration either. Sums and every statistic are fp64. Not bit-compatible with the shaders: the
// fp64 CPU backend stays their oracle.
class CpuF32Backend final : public NativeBackend {
public:
  explicit CpuF32Backend(int threads) : NativeBackend(threads) {}

  std::string device() const override { return "cpu fp32 (" + std::to_string(pool_.size()) + " threads)"; }

  void load(const ScaledLp& lp, const std::vector<double>& x, const std::vector<double>& y) override {
    prepare(lp);
    d_.assign(lp.col_scale.begin(), lp.col_scale.end());
    b_.assign(lp.b.begin(), lp.b.end());
    r_.assign(lp.row_scale.begin(), lp.row_scale.end());
    x_.assign(x.begin(), x.end());
    x0_ = x_;
    xhat_ = x_;
    xr_.assign(n_, 0.0f);
    y0_ = y;
    delta_.assign(m_, 0.0f);
    dhat_.assign(m_, 0.0f);
    dr_.assign(m_, 0.0f);
    g0_.resize(n_);
    anchor_reduced_cost();
  }

  BatchStats iterate(int count, int64_t k0, const Step& step) override {
    BatchStats stats;
    for (int it = 0; it < count; ++it) {
      const bool last = it + 1 == count;
      const double kk = static_cast<double>(k0 + it);
      const double w = (kk + 1.0) / (kk + 2.0);
      run_split(last, col_split_, n_, [&](auto l, int64_t b, int64_t e) { return primal_rows<l()>(step, w, b, e); });
      if (last) stats.dx2 = sum(0);
      run_split(last, row_split_, m_, [&](auto l, int64_t b, int64_t e) { return dual_rows<l()>(step, w, b, e); });
      if (last) stats.dy2 = sum(0);
    }
    evaluate(stats);
    return stats;
  }

  std::pair<double, double> restart() override {
    const int T = pool_.size();
    pool_.run(T, [&](int t) {
      double dx = 0.0;
      for (int64_t j = n_ * t / T, e = n_ * (t + 1) / T; j < e; ++j) {
        const double d = double(xhat_[j]) - double(x0_[j]);
        dx += d * d;
        x_[j] = x0_[j] = xhat_[j];
      }
      double dy = 0.0;
      for (int64_t i = m_ * t / T, e = m_ * (t + 1) / T; i < e; ++i) {
        const double d = dhat_[i];  // ŷ − y⁰
        dy += d * d;
        y0_[i] += d;
        delta_[i] = dhat_[i] = dr_[i] = 0.0f;
      }
      partial_[8 * t] = dx;
      partial_[8 * t + 1] = dy;
    });
    anchor_reduced_cost();
    return {sum(0), sum(1)};
  }

  void read(std::vector<double>& xhat, std::vector<double>& yhat) override {
    xhat.assign(xhat_.begin(), xhat_.end());
    yhat.resize(m_);
    for (int64_t i = 0; i < m_; ++i) yhat[i] = y0_[i] + double(dhat_[i]);
  }

private:
  // g⁰_j = c̃_j − d_j Σ_i ±r_i y⁰_i, in fp64 (the cancellation happens here, once per restart).
  void anchor_reduced_cost() {
    scratch_y_.resize(m_);
    const int T = pool_.size();
    pool_.run(T, [&](int t) {
      for (int64_t i = m_ * t / T, e = m_ * (t + 1) / T; i < e; ++i) scratch_y_[i] = lp_->row_scale[i] * y0_[i];
    });
    const SignedCsr& at = *lp_->at;
    pool_.run(T, [&](int t) {
      for (int64_t j = n_ * t / T, e = n_ * (t + 1) / T; j < e; ++j)
        g0_[j] = float(lp_->c[j] - lp_->col_scale[j] * signed_gather(at, j, scratch_y_.data()));
    });
  }

  template <bool Last>
  double primal_rows(const Step& step, double w, int64_t begin, int64_t end) {
    const uint32_t* ptr = lp_->at->row_ptr.data();
    const uint32_t* entry = lp_->at->entry.data();
    const float* g0 = g0_.data();
    const float* d = d_.data();
    const float* x0 = x0_.data();
    float* x = x_.data();
    float* xr = xr_.data();
    float* xhat = xhat_.data();
    const double tau = step.tau, gamma = step.gamma;
    double dx2 = 0.0;
    const auto update = [&](int64_t j, double atd) {
      const double dj = d[j];
      const double g = double(g0[j]) - dj * atd;
      const double xj = x[j];
      const double xh = clamp_box(xj - tau * g, 1.0 / dj);
      xr[j] = float(dj * (2.0 * xh - xj));
      x[j] = float(w * ((1.0 + gamma) * xh - gamma * xj) + (1.0 - w) * double(x0[j]));
      if constexpr (Last) {
        xhat[j] = float(xh);
        dx2 += (xh - xj) * (xh - xj);
      }
    };
    for_each_row_sum<false>(ptr, entry, dr_.data(), begin, end, update);
    return dx2;
  }

  template <bool Last>
  double dual_rows(const Step& step, double w, int64_t begin, int64_t end) {
    const uint32_t* ptr = lp_->a->row_ptr.data();
    const uint32_t* entry = lp_->a->entry.data();
    const float* b = b_.data();
    const float* r = r_.data();
    float* delta = delta_.data();
    float* dr = dr_.data();
    float* dhat = dhat_.data();
    const double sigma = step.sigma, gamma = step.gamma;
    double dy2 = 0.0;
    const auto update = [&](int64_t i, double ax) {
      const double di = delta[i];
      const double dh = di + sigma * (double(b[i]) - double(r[i]) * ax);
      const double dn = w * ((1.0 + gamma) * dh - gamma * di);  // the anchor of δ is 0
      delta[i] = float(dn);
      dr[i] = float(double(r[i]) * dn);
      if constexpr (Last) {
        dhat[i] = float(dh);
        dy2 += (dh - di) * (dh - di);
      }
    };
    for_each_row_sum<true>(ptr, entry, xr_.data(), begin, end, update);
    return dy2;
  }

  // At x̂ and ŷ = y⁰ + δ̂, in fp64.
  void evaluate(BatchStats& stats) {
    evaluate_at([&](int64_t j) { return double(xhat_[j]); }, [&](int64_t i) { return y0_[i] + double(dhat_[i]); },
                stats);
  }

  std::vector<float> g0_, d_, x_, x0_, xhat_, xr_;  // columns
  std::vector<float> b_, r_, delta_, dhat_, dr_;    // rows: δ, δ̂ = ŷ − y⁰, r·δ
  std::vector<double> y0_;                          // the dual anchor
};

}  // namespace

std::unique_ptr<PdhgBackend> make_cpu_backend(int threads) { return std::make_unique<CpuBackend>(threads); }
std::unique_ptr<PdhgBackend> make_cpu_f32_backend(int threads) { return std::make_unique<CpuF32Backend>(threads); }

}  // namespace shapematch::detail
