#include "shapematch/matching.hpp"

#include "shapematch/errors.hpp"

#include <numeric>

namespace shapematch {

MatchingLp build_matching_lp(const Mesh& x, const Geometry& gx, const Mesh& y, const Geometry& gy,
                             const MatchingLpOptions& options) {
  EnergyModel model(x, gx, y, gy, options.energy);
  if (options.features_x.size() > 0) model.set_features(options.features_x, options.features_y);
  return build_matching_lp(ProductSpace::full(x, y), model, options.scale_costs);
}

MatchingLp build_matching_lp(ProductSpace space, const EnergyModel& model, bool scale_costs) {
  MatchingLp out{std::move(space), {}, {}, 0, {}};
  ConstraintSystem cs = build_constraints(out.space);
  out.energy = energy_vector(out.space, model);

  double scale = 1.0;
  if (scale_costs && !out.energy.empty()) {
    const double mean = std::accumulate(out.energy.begin(), out.energy.end(), 0.0) / double(out.energy.size());
    if (mean > 0) scale = mean;
  }
  out.lp.a = std::move(cs.a);
  out.lp.at = std::move(cs.at);
  out.lp.b = std::move(cs.b);
  out.lp.c.resize(out.energy.size());
  for (size_t j = 0; j < out.energy.size(); ++j) out.lp.c[j] = out.energy[j] / scale;
  out.lp.objective_scale = scale;
  out.closedness_rows = cs.closedness_rows;
  out.row_edge = std::move(cs.row_edge);
  return out;
}

}  // namespace shapematch
