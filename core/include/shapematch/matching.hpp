#pragma once
// The single-level matching LP of two meshes: product space, constraints, energy → LpProblem.
#include "shapematch/constraints.hpp"
#include "shapematch/energy.hpp"
#include "shapematch/lp.hpp"

namespace shapematch {

struct MatchingLpOptions {
  EnergyOptions energy;
  // Costs are divided by their mean over the variables so the LP is well conditioned.
  bool scale_costs = true;
};

struct MatchingLp {
  ProductSpace space;
  LpProblem lp;
  std::vector<double> energy;  // unscaled energy of each variable (lp.c * lp.objective_scale)
  int64_t closedness_rows = 0;
};

MatchingLp build_matching_lp(const Mesh& x, const Geometry& gx, const Mesh& y, const Geometry& gy,
                             const MatchingLpOptions& options = {});

}  // namespace shapematch
