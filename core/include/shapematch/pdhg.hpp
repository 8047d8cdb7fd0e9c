#pragma once
// Restarted Halpern PDHG with reflection (the cuPDLPx family) for
//   min cᵀx  s.t.  A x = b,  0 ≤ x ≤ 1,  A with entries ±1,
// one algorithm on two backends: native multi-threaded C++ and Vulkan compute shaders.
#include "shapematch/lp.hpp"

namespace shapematch {

struct PdhgOptions {
  int ruiz_iterations = 10;        // Ruiz equilibration passes before Pock–Chambolle scaling
  int norm_steps = 100;            // Lanczos steps at most for the estimate of ‖Ã‖₂ that sets the step (+1 %)
  double norm_tolerance = 1e-3;    // … done when its Ritz pair's relative residual is below this
  double step_safety = 0.998;      // η = step_safety / ‖Ã‖₂
  double reflection = 1.0;         // γ in z⁺ = (k+1)/(k+2)((1+γ)T(z) − γz) + z⁰/(k+2)
  int check_interval = 64;         // iterations between termination/restart checks
  double restart_sufficient = 0.2; // restart when the fixed-point residual fell below this × its value at the last restart
  double restart_necessary = 0.8;  // … or below this and stopped falling
  double restart_artificial = 0.36;// … or when this fraction of all iterations passed since the last restart
  double primal_weight_smoothing = 0.5;
  // ω₀; 0 = ‖c̃‖₂/‖b̃‖₂ (PDLP's choice). Matching LPs have a dense c and a b that is nonzero only
  // on the π rows, which puts PDLP's ω₀ ~1e5 above where ω settles (~0.01) and made the bundled
  // pair at 100 faces diverge; 1 converges there and halved the iterations at 40 faces.
  double initial_primal_weight = 1.0;
  // After an infeasibility proof, this many iterations more give LpResult::ray (0: none, the
  // default). On a hand-made LP (two causes of infeasibility in one part, costs of 10 beside the
  // first) the dual's growth over 64 named 48 of 51 rows, over 256 the 41 of the second cause
  // alone, where y itself named the first cause's 4 rows, its ordinary duals. But at full
  // resolution (TOSCA_r cat2-cat9's level-6 rounding, five parts of 30 831-43 111 variables
  // proved infeasible) the growth over 256 was no ray once (Farkas rates -886 to -53): the
  // ordinary duals still move that much, and the iterations bought nothing.
  int ray_iterations = 0;
};

// CpuF32: the native kernels with fp32 vectors and the dual kept relative to its anchor
// (pdhg_cpu.cpp): fewer bytes per iteration, the same stopping rules; results differ in the last
// digits from Cpu, which is the Vulkan shaders' bit-for-bit oracle.
enum class PdhgBackendKind { Cpu, CpuF32, Vulkan };

class PdhgSolver final : public LpSolver {
public:
  explicit PdhgSolver(PdhgBackendKind backend, PdhgOptions options = {}) : backend_(backend), options_(options) {}
  std::string name() const override {
    return backend_ == PdhgBackendKind::Cpu ? "pdhg-cpu" : backend_ == PdhgBackendKind::CpuF32 ? "pdhg-cpu-f32" : "pdhg-vulkan";
  }
  LpResult solve(const LpProblem& problem, const SolverParams& params) override;

private:
  PdhgBackendKind backend_;
  PdhgOptions options_;
};

// make_solver (lp.hpp) with these options for the PDHG backends; other solvers ignore them.
std::unique_ptr<LpSolver> make_solver(const std::string& name, const PdhgOptions& pdhg);

// Memory traffic of one PDHG iteration in the data layout of pdhg_backend.hpp, counting every
// array element touched once (gathers as 8 bytes, no write-allocate): the primal kernel reads
// Aᵀ's row_ptr and entries (4 bytes each), gathers yr per nonzero and reads c, d, x, x⁰ and writes
// x, xr (8 bytes each); the dual kernel does the same over A with b, r, y, y⁰ and writes y, yr.
// Dividing it by a measured streaming bandwidth gives the time bound of one iteration.
double pdhg_bytes_per_iteration(const LpProblem& problem);
// The same for PdhgBackendKind::CpuF32: gathers of 4 bytes; per column g⁰, d, x, x⁰ read and x,
// xr written; per row b, r, δ read and δ, r·δ written (4 bytes each).
double pdhg_bytes_per_iteration_f32(const LpProblem& problem);

}  // namespace shapematch
