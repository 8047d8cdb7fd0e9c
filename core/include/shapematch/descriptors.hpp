#pragma once
// Per-vertex feature descriptors for the feature energy (DESIGN.md §5 "Features"): the Wave
// Kernel Signature (Aubry, Schlickewei & Cremers 2011) and descriptors a user supplies per vertex.
#include "shapematch/mesh.hpp"

#include <Eigen/Core>
#include <string>
#include <vector>

namespace shapematch {

// The smallest eigenpairs of L φ = λ M φ: L the cotangent Laplacian (positive semi-definite),
// M the diagonal mixed Voronoi mass matrix (Geometry::vertex_area).
struct LaplaceSpectrum {
  Eigen::VectorXd values;   // ascending; values[0] ≈ 0 (the constant eigenvector)
  Eigen::MatrixXd vectors;  // |V| x count, M-orthonormal: vectorsᵀ M vectors = I
};

// The `count` smallest eigenpairs (count is clamped to |V|). Throws SolverError naming the mesh
// if the eigensolver does not converge, InvalidInputError if count < 1.
LaplaceSpectrum laplace_spectrum(const Mesh& mesh, int count);

struct WksOptions {
  int eigenpairs = 100;   // nonzero eigenpairs used (clamped to |V| - 1); the constant one is skipped
  int energies = 100;     // columns of the signature
  double variance = 6.0;  // Gaussian width in log-energy, in grid steps
  // Scale every column to unit area-weighted RMS and divide by sqrt(energies), so that two
  // shapes' signatures are comparable and a row's squared norm averages 1 over the surface;
  // false gives the raw signature (which scales as 1/area).
  bool normalize = true;
};

// |V| x energies. Invariant to rigid motion and uniform scaling of the mesh.
Eigen::MatrixXd wave_kernel_signature(const Mesh& mesh, const WksOptions& options = {});

// Reads per-vertex features: a .npy file (v1.0/2.0, '<f8' or '<f4', C order, 1-D or 2-D; detected
// by its magic bytes) or text (one row of whitespace- or comma-separated numbers per vertex;
// blank lines and lines starting with # are ignored). Checks that there are `expected_rows` rows
// of equal length and that every value is finite. Throws IoError (unreadable) or
// InvalidInputError (bad content), both "<path>: <problem>".
Eigen::MatrixXd load_features(const std::string& path, int expected_rows);

// The given rows in the given order (e.g. the original indices of a decimated mesh's vertices).
// Throws InvalidInputError for an index out of range.
Eigen::MatrixXd select_rows(const Eigen::MatrixXd& features, const std::vector<int>& rows);

}  // namespace shapematch
