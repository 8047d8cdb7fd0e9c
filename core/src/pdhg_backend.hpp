#pragma once
// The kernels of restarted Halpern PDHG, behind one interface so that the algorithm (the host
// driver in pdhg.cpp) is written once and runs natively or on a Vulkan device.
//
// The backend works on the diagonally scaled problem Ã = D_r A D_c (A stored as signed CSR,
// the scalings as two vectors), c̃ = D_c c, b̃ = D_r b, 0 ≤ x̃_j ≤ 1/d_j. Vectors are fp64:
// measured on matching LPs, fp32 iterates stall at a gap of ~1e-5..1e-4 because reduced costs
// c − Aᵀy cancel large dual values; the matrix (the bulk of the bytes) stays 4 bytes/entry.
// Kernel semantics (every backend must implement exactly these; the CPU one is the oracle):
//
//   primal (over columns j), at Halpern index k, w = (k+1)/(k+2):
//     g_j   = c̃_j − d_j Σ_i sign_ij yr_i                (yr_i = r_i y_i, kept by the dual kernel)
//     x̂_j  = clamp(x_j − τ g_j, 0, 1/d_j)
//     xr_j  = d_j (2x̂_j − x_j)                          (the extrapolated point, pre-scaled)
//     x_j  ← w((1+γ)x̂_j − γx_j) + (1−w) x⁰_j
//   dual (over rows i):
//     ŷ_i  = y_i + σ(b̃_i − r_i Σ_j sign_ij xr_j)
//     y_i  ← w((1+γ)ŷ_i − γy_i) + (1−w) y⁰_i ;  yr_i = r_i y_i
//   On the last iteration of a batch the kernels also keep x̂, ŷ and reduce
//     Σ (x̂−x)², Σ (ŷ−y)²                                 (fixed-point residual, before the update)
//   and then evaluate, at (x̂, ŷ), in the ORIGINAL units (x = D_c x̂, y = D_r ŷ):
//     Σ_i ((A x)_i − b_i)²,  cᵀx = Σ c̃_j x̂_j,  bᵀy = Σ b̃_i ŷ_i,  Σ_j min(0, c_j − (Aᵀy)_j).
//   restart: x⁰ ← x ← x̂, y⁰ ← y ← ŷ (and yr), returning Σ(x̂−x⁰_old)², Σ(ŷ−y⁰_old)².
// Every Σ over a row adds in entry order, except over a long row of A (kLongRow below).
#include "shapematch/sparse.hpp"

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace shapematch::detail {

// A row of A with more than kLongRow entries (in a matching LP the projection rows: thousands of
// entries, against at most ~32 elsewhere) is summed in kLongLanes interleaved partial sums, lane
// l taking entries l, l + kLongLanes, l + 2·kLongLanes, … in order, which are then added
// pairwise: lane l += lane l + h for h = kLongLanes/2, …, 2, 1; the row's sum is lane 0. A GPU
// spreads such a row over a workgroup instead of leaving one invocation a chain of thousands
// of dependent gathers that the whole step waits for (measured on an H100: docs/benchmarks.md);
// the CPU adds in the same order, so both backends still compute the same iterates.
inline constexpr uint32_t kLongRow = 256;
inline constexpr uint32_t kLongLanes = 64;  // local_size_x of pdhg_*_long.comp

struct ScaledLp {
  const SignedCsr* a = nullptr;   // m x n
  const SignedCsr* at = nullptr;  // n x m
  std::vector<double> c, b;        // c̃ (n), b̃ (m)
  std::vector<double> col_scale;   // d (n)
  std::vector<double> row_scale;   // r (m)
};

struct BatchStats {
  double dx2 = 0, dy2 = 0;   // ‖x̂ − x‖², ‖ŷ − y‖² (scaled space) at the last iteration
  double residual2 = 0;      // ‖A x − b‖² (original units)
  double cx = 0, by = 0;     // primal objective, bᵀy
  double reduced_neg = 0;    // Σ_j min(0, c_j − (Aᵀy)_j)
};

struct Step {
  double tau = 0, sigma = 0, gamma = 1;
};

class PdhgBackend {
public:
  virtual ~PdhgBackend() = default;
  virtual std::string device() const = 0;
  // Uploads the problem and the (scaled) starting point; the anchor starts at the same point.
  virtual void load(const ScaledLp& lp, const std::vector<double>& x, const std::vector<double>& y) = 0;
  // An exact state (SolverState): read_state gives the iterate (x, y) and the anchor (x⁰, y⁰) as
  // they go into the next iteration, load_state uploads the problem at such a state; iterating on
  // from there repeats what the backend would have computed. false / not supported where the
  // backend keeps its vectors in another form (the fp32 one).
  virtual bool read_state(std::vector<double>& x, std::vector<double>& x0, std::vector<double>& y,
                          std::vector<double>& y0) {
    return false;
  }
  virtual void load_state(const ScaledLp& lp, const std::vector<double>& x, const std::vector<double>& x0,
                          const std::vector<double>& y, const std::vector<double>& y0) {
    throw std::logic_error("this PDHG backend keeps no exact state");
  }
  // Runs `count` ≥ 1 iterations with Halpern indices k0, k0+1, …; the last one reports stats.
  virtual BatchStats iterate(int count, int64_t k0, const Step& step) = 0;
  // Restarts at the last (x̂, ŷ); returns the anchor's displacement (Σ dx², Σ dy²).
  virtual std::pair<double, double> restart() = 0;
  // The last (x̂, ŷ), scaled.
  virtual void read(std::vector<double>& xhat, std::vector<double>& yhat) = 0;
};

std::unique_ptr<PdhgBackend> make_cpu_backend(int threads);
std::unique_ptr<PdhgBackend> make_cpu_f32_backend(int threads);  // fp32 vectors, dual relative to its anchor
std::unique_ptr<PdhgBackend> make_vulkan_backend(int device_index);

}  // namespace shapematch::detail
