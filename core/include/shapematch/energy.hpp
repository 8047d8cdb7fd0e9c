#pragma once
// The thin-shell matching energy of DESIGN.md §5, in double precision.
#include "shapematch/geometry.hpp"
#include "shapematch/product_space.hpp"

namespace shapematch {

// St. Venant–Kirchhoff (the paper) is quartic in stretch but bounded in compression, so with the
// symmetrisation a shape squashed onto curves of the other costs less than any stretched
// matching; `Compressive` keeps only the compressive principal strains of each direction, so
// that stretch in X→Y is charged once, as compression in Y→X (docs/architecture.md).
enum class MembraneModel { StVenantKirchhoff, Compressive };

struct EnergyOptions {
  MembraneModel membrane = MembraneModel::Compressive;  // measured: docs/architecture.md
  double lame_lambda = 1.0;   // Lamé λ of the membrane (St. Venant–Kirchhoff)
  double lame_mu = 1.0;       // Lamé μ
  // Measured (docs/results-log.md): at 1 the bending term pushes Γ towards folds at finer levels
  // (FAUST 020–024, 316 faces: error 0.27 against 0.086) and the bundled pair rounds worse.
  double bending_weight = 0.1;
  double feature_weight = 0.0;
  // κ·(area of the real face) added to every degenerate product triangle (not in the paper):
  // the St. Venant–Kirchhoff membrane charges a face squashed to a segment only 0.75 of its area,
  // so without it the LP prefers folding both shapes onto curves (docs/architecture.md).
  double degenerate_penalty = 0.0;
  // The bending term's mean curvature averaged over this radius (times √area of each shape, so
  // that with unit area it is in those units; smoothed_mean_curvature). 0: per vertex, the paper's.
  double curvature_radius = 0.0;
};

using Triangle3 = std::array<Eigen::Vector3d, 3>;

// W(s→t) = A_s((λ/2)(tr E)² + μ tr(E²)), E = (G_s⁻¹G_t − I)/2: the membrane energy of mapping the
// source triangle onto the target, vertices matched in order. 0 if the source is degenerate.
double membrane_energy(const Triangle3& source, const Triangle3& target, double lambda, double mu);
// The same with the principal squared stretches clamped to ≤ 1: only compression costs.
double compressive_membrane_energy(const Triangle3& source, const Triangle3& target, double lambda, double mu);
// The same quantity in Delingette's biquadratic spring form (an independent formula for tests).
double membrane_energy_springs(const Triangle3& source, const Triangle3& target, double lambda, double mu);

// Energy of product triangles for a fixed pair of shapes. Per-vertex descriptors are optional.
class EnergyModel {
public:
  EnergyModel(const Mesh& x, const Geometry& gx, const Mesh& y, const Geometry& gy,
              EnergyOptions options = {});
  // Per-vertex descriptors (rows = vertices) for the feature term; empty disables it.
  void set_features(Eigen::MatrixXd fx, Eigen::MatrixXd fy);

  double membrane(const ProductTriangle& t) const;
  double bending(const ProductTriangle& t) const;
  double feature(const ProductTriangle& t) const;
  double operator()(const ProductTriangle& t) const;

  const EnergyOptions& options() const { return options_; }

private:
  const Mesh& x_;
  const Geometry& gx_;
  const Mesh& y_;
  const Geometry& gy_;
  EnergyOptions options_;
  std::vector<double> hx_, hy_;  // the mean curvature the bending term reads (curvature_radius)
  // Row-major: the feature term reads one vertex's descriptor at a time (column-major put each
  // of its numbers on a cache line of its own).
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> fx_, fy_;
};

// c_j = energy of every variable of the space (multi-threaded).
std::vector<double> energy_vector(const ProductSpace& space, const EnergyModel& model);

}  // namespace shapematch
