#pragma once
// Clp (COIN-OR) as the exact reference LP solver: dual simplex or barrier with crossover.
#include "shapematch/lp.hpp"

namespace shapematch {

class ClpSolver final : public LpSolver {
public:
  enum class Method { DualSimplex, Barrier };
  explicit ClpSolver(Method method) : method_(method) {}
  std::string name() const override { return method_ == Method::DualSimplex ? "clp-dual" : "clp-barrier"; }
  LpResult solve(const LpProblem& problem, const SolverParams& params) override;

  // Loads the problem into Clp and writes free MPS.
  static void write_mps(const LpProblem& problem, const std::string& path);

private:
  Method method_;
};

}  // namespace shapematch
