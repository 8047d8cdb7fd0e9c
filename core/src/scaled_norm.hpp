#pragma once
// ‖Ã‖₂ of the scaled matrix Ã = D_r A D_c, which sets PDHG's step.
#include "shapematch/sparse.hpp"

#include <vector>

namespace shapematch::detail {

struct NormEstimate {
  double norm = 0.0;     // the largest Ritz value's square root: ≤ ‖Ã‖₂ up to rounding
  double residual = 0.0; // ‖ÃᵀÃu − θu‖ of its Ritz vector u, relative to θ
  int steps = 0;         // products with ÃᵀÃ
};

// Lanczos on ÃᵀÃ from a fixed random start, without reorthogonalisation (three vectors: only the
// largest Ritz value is wanted, and lost orthogonality adds copies of converged values, never
// values above λ_max). Stops when the Ritz pair's relative residual is below `tolerance`, after
// `max_steps`, or once `margin` × the estimate reaches `cap` (the caller caps the norm there, so
// more steps cannot change its result). Each step is one product with A and one with Aᵀ.
NormEstimate scaled_norm(const SignedCsr& a, const SignedCsr& at, const std::vector<double>& r,
                         const std::vector<double>& d, int max_steps, double tolerance, int threads, double margin,
                         double cap);

}  // namespace shapematch::detail
