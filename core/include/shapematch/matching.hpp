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
  // Per-vertex descriptors of X and Y (rows = vertices) for the feature term; empty: none.
  Eigen::MatrixXd features_x, features_y;
};

struct MatchingLp {
  ProductSpace space;
  LpProblem lp;
  std::vector<double> energy;  // unscaled energy of each variable (lp.c * lp.objective_scale)
  int64_t closedness_rows = 0;
  std::vector<int64_t> row_edge;  // product-edge id of each closedness row, increasing
};

// Over the full product space.
MatchingLp build_matching_lp(const Mesh& x, const Geometry& gx, const Mesh& y, const Geometry& gy,
                             const MatchingLpOptions& options = {});
// Over any space (the reduced spaces of coarse to fine), with a ready energy model.
MatchingLp build_matching_lp(ProductSpace space, const EnergyModel& model, bool scale_costs = true);

}  // namespace shapematch
