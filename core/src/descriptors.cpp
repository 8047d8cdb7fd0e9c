#include "shapematch/descriptors.hpp"

#include "shapematch/errors.hpp"
#include "shapematch/files.hpp"
#include "shapematch/geometry.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <Spectra/SymEigsShiftSolver.h>
#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numeric>
#include <sstream>

namespace shapematch {

namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;
using Ldlt = Eigen::SimplicialLDLT<SparseMatrix>;

SparseMatrix minus_shift(const SparseMatrix& a, double shift) {
  SparseMatrix identity(a.rows(), a.cols());
  identity.setIdentity();
  return a - shift * identity;
}

// Sylvester's law of inertia: the number of eigenvalues of A below `tau` is the number of
// negative pivots of an LDLᵀ factorisation of A - τI; -1 if that factorisation breaks down.
int count_below(const SparseMatrix& a, double tau) {
  const Ldlt ldlt(minus_shift(a, tau));
  if (ldlt.info() != Eigen::Success) return -1;
  return static_cast<int>((ldlt.vectorD().array() < 0).count());
}

// P (A - σI)⁻¹ P for Spectra's shift-invert mode, P the orthogonal projector onto the complement
// of `deflate`'s columns (orthonormal eigenvectors already found). A - σI is positive definite
// for σ < 0, so the caller factorises it once with a sparse Cholesky (Spectra's own operator
// uses LU) for the σ it also gives Spectra; set_shift therefore has nothing to do.
class DeflatedShiftInvert {
 public:
  using Scalar = double;
  DeflatedShiftInvert(const Ldlt& ldlt, const Eigen::MatrixXd& deflate) : ldlt_(ldlt), deflate_(deflate) {}
  Eigen::Index rows() const { return ldlt_.rows(); }
  Eigen::Index cols() const { return ldlt_.cols(); }
  void set_shift(double) {}
  void perform_op(const double* x, double* y) const {
    Eigen::Map<Eigen::VectorXd> out(y, rows());
    out = ldlt_.solve(project(Eigen::Map<const Eigen::VectorXd>(x, rows())));
    out = project(out);
  }

 private:
  Eigen::VectorXd project(const Eigen::VectorXd& v) const {
    if (deflate_.cols() == 0) return v;
    return v - deflate_ * (deflate_.transpose() * v);
  }
  const Ldlt& ldlt_;
  const Eigen::MatrixXd& deflate_;
};

struct Eigenpairs {
  Eigen::VectorXd values;  // ascending
  Eigen::MatrixXd vectors;
};

// The `count` eigenpairs of A nearest the shift σ, orthogonal to `deflate`.
Eigenpairs lanczos(const Mesh& mesh, const Ldlt& ldlt, double shift, const Eigen::MatrixXd& deflate, int count) {
  DeflatedShiftInvert op(ldlt, deflate);
  const int ncv = std::min(static_cast<int>(ldlt.rows()), std::max(2 * count + 1, 20));
  Spectra::SymEigsShiftSolver<DeflatedShiftInvert> eigs(op, count, ncv, shift);
  eigs.init();
  eigs.compute(Spectra::SortRule::LargestMagn, 1000, 1e-10, Spectra::SortRule::SmallestAlge);
  if (eigs.info() != Spectra::CompInfo::Successful)
    throw SolverError(mesh.name + ": Laplace eigensolver (Spectra) did not converge for " + std::to_string(count) +
                      " eigenpairs");
  return {eigs.eigenvalues(), eigs.eigenvectors()};
}

// The `count` smallest eigenpairs of the sparse positive semi-definite A, by shift-invert Lanczos.
Eigenpairs smallest_eigenpairs(const Mesh& mesh, const SparseMatrix& a, int count) {
  // A small negative shift, relative to A's typical diagonal so it means the same at every
  // scale, keeps A - σI non-singular despite the constant null vector.
  const double shift = -1e-8 * a.diagonal().mean();
  const Ldlt ldlt(minus_shift(a, shift));
  if (ldlt.info() != Eigen::Success)
    throw SolverError(mesh.name + ": Cholesky factorisation of the shifted Laplacian failed");
  Eigenpairs e = lanczos(mesh, ldlt, shift, Eigen::MatrixXd(), count);
  // Lanczos may find only some copies of a repeated eigenvalue (measured: one of the 4-fold l = 3
  // eigenvalues of icosphere(4) was skipped for the l = 4 level), which symmetric meshes have.
  // The inertia below the largest value found tells whether any are missing; a deflated run
  // then looks for them in the complement of those found.
  for (int round = 0; count > 1; ++round) {
    const double top = e.values[count - 1] - 1e-6 * std::abs(e.values[count - 1]);
    const int below = count_below(a, top);
    const int found = static_cast<int>((e.values.array() < top).count());
    if (below <= found) break;
    if (round == 4)
      throw SolverError(mesh.name + ": Laplace eigensolver (Spectra) still misses " + std::to_string(below - found) +
                        " of the " + std::to_string(count) + " smallest eigenvalues after 4 deflated runs");
    const Eigenpairs more = lanczos(mesh, ldlt, shift, e.vectors, below - found);
    Eigen::VectorXd values(count + more.values.size());
    values << e.values, more.values;
    Eigen::MatrixXd vectors(a.rows(), values.size());
    vectors << e.vectors, more.vectors;
    std::vector<int> order(values.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int i, int j) { return values[i] < values[j]; });
    for (int k = 0; k < count; ++k) {
      e.values[k] = values[order[k]];
      e.vectors.col(k) = vectors.col(order[k]);
    }
  }
  return e;
}

// With M diagonal, L φ = λ M φ becomes the standard symmetric problem A ψ = λ ψ with
// A = M^-1/2 L M^-1/2 and φ = M^-1/2 ψ; orthonormal ψ give M-orthonormal φ.
LaplaceSpectrum spectrum_of(const Mesh& mesh, const Geometry& g, int count) {
  if (count < 1)
    throw InvalidInputError(mesh.name + ": Laplace spectrum needs at least 1 eigenpair, got " + std::to_string(count));
  const int n = mesh.num_vertices();
  count = std::min(count, n);
  Eigen::VectorXd inv_sqrt_mass(n);
  for (int v = 0; v < n; ++v) inv_sqrt_mass[v] = 1.0 / std::sqrt(g.vertex_area[v]);
  const SparseMatrix a = inv_sqrt_mass.asDiagonal() * g.cotan_laplacian * inv_sqrt_mass.asDiagonal();

  Eigenpairs e;
  // Lanczos needs a subspace of ~2 count + 1 vectors; when that is most of the space a dense
  // solve is as fast (measured: 252 vertices, 101 pairs: 15 ms dense, 26 ms Spectra).
  if (3 * count >= n) {
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig{Eigen::MatrixXd(a)};
    if (eig.info() != Eigen::Success) throw SolverError(mesh.name + ": dense Laplace eigensolver failed");
    e = {eig.eigenvalues().head(count), eig.eigenvectors().leftCols(count)};
  } else {
    e = smallest_eigenpairs(mesh, a, count);
  }
  return {e.values, inv_sqrt_mass.asDiagonal() * e.vectors};
}

}  // namespace

LaplaceSpectrum laplace_spectrum(const Mesh& mesh, int count) {
  return spectrum_of(mesh, compute_geometry(mesh), count);
}

// Convention (Aubry et al. 2011, §4): with ℓ_k = log λ_k over the nonzero eigenvalues
// λ_1 ≤ … ≤ λ_K, energies e_j = e_min + j δ (j = 0 … E-1), e_min = ℓ_1 + 2σ, e_max = ℓ_K - 2σ,
// σ = variance · δ. Solving these for δ gives δ = (ℓ_K - ℓ_1) / (E - 1 + 4 variance). Then
//   WKS(x, e) = Σ_k φ_k(x)² exp(-(e - ℓ_k)²/2σ²) / Σ_k exp(-(e - ℓ_k)²/2σ²).
Eigen::MatrixXd wave_kernel_signature(const Mesh& mesh, const WksOptions& options) {
  if (options.eigenpairs < 1 || options.energies < 1 || !(options.variance > 0) || !std::isfinite(options.variance))
    throw InvalidInputError(mesh.name + ": WKS needs eigenpairs >= 1, energies >= 1 and variance > 0");
  const int n = mesh.num_vertices();
  const int k_count = std::min(options.eigenpairs, n - 1);
  const int e_count = options.energies;
  const Geometry g = compute_geometry(mesh);
  const LaplaceSpectrum s = spectrum_of(mesh, g, k_count + 1);
  if (!(s.values[1] > 0))
    throw SolverError(mesh.name + ": second Laplace eigenvalue " + std::to_string(s.values[1]) + " is not positive");

  const Eigen::ArrayXd log_lambda = s.values.tail(k_count).array().log();
  const double range = log_lambda[k_count - 1] - log_lambda[0];
  double step = range / (e_count - 1 + 4 * options.variance);
  double sigma = options.variance * step;
  // All eigenvalues equal (a tiny symmetric mesh): every energy weighs them equally.
  if (range <= 1e-9) step = 0, sigma = 1;

  Eigen::MatrixXd weight(k_count, e_count);  // column j: normalised Gaussian weights at e_j
  for (int j = 0; j < e_count; ++j) {
    const double e = log_lambda[0] + 2 * sigma + j * step;
    const Eigen::ArrayXd z = (e - log_lambda).square() / (2 * sigma * sigma);
    // Subtracting the smallest exponent avoids underflow of every weight; the ratio is unchanged.
    const Eigen::ArrayXd w = (-(z - z.minCoeff())).exp();
    weight.col(j) = (w / w.sum()).matrix();
  }
  Eigen::MatrixXd wks = s.vectors.rightCols(k_count).array().square().matrix() * weight;

  if (options.normalize) {
    // φ_k² scale as 1/area and low energies are far larger than high ones, so each column is
    // divided by its area-weighted RMS (the L2 norm over sqrt(area), which makes the result
    // scale-invariant; a constant column becomes 1). Dividing also by sqrt(E) makes a row's
    // squared norm an average over energies, with area-weighted mean 1 for any E. Measured on
    // FAUST_r 020/043 (unit area): median ‖d_X(a) - d_Y(b)‖² 0.64 for random pairs, 0.04 for
    // true correspondences.
    const Eigen::Map<const Eigen::VectorXd> area(g.vertex_area.data(), n);
    const double total_area = area.sum();
    for (int j = 0; j < e_count; ++j) {
      const double rms = std::sqrt(area.dot(wks.col(j).cwiseAbs2()) / total_area);
      wks.col(j) /= rms * std::sqrt(static_cast<double>(e_count));
    }
  }
  return wks;
}

namespace {

[[noreturn]] void bad(const std::string& path, const std::string& problem) {
  throw InvalidInputError(path + ": " + problem);
}

std::string read_file(const std::string& path) {
  std::ifstream in = open_for_reading(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw IoError(path + ": read error");
  return bytes;
}

void check_finite(const std::string& path, const Eigen::MatrixXd& m) {
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c)
      if (!std::isfinite(m(r, c)))
        bad(path, std::string(std::isnan(m(r, c)) ? "NaN" : "infinite value") + " in row " + std::to_string(r) +
                      ", column " + std::to_string(c) + " (0-based)");
}

void check_rows(const std::string& path, uint64_t rows, int expected) {
  if (expected < 0 || rows != static_cast<uint64_t>(expected))
    bad(path, std::to_string(rows) + " rows but the mesh has " + std::to_string(expected) + " vertices");
}

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

double parse_number(const std::string& path, int line, std::string_view token) {
  std::string_view digits = token;
  if (digits.size() > 1 && digits[0] == '+') digits.remove_prefix(1);  // from_chars rejects '+'
  double value = 0;
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (ec == std::errc::result_out_of_range)  // e.g. 1e999: rejected rather than clamped
    bad(path, "line " + std::to_string(line) + ": number out of range '" + std::string(token) + "'");
  if (ec != std::errc() || end != digits.data() + digits.size())
    bad(path, "line " + std::to_string(line) + ": not a number '" + std::string(token) + "'");
  return value;
}

// One row per non-blank, non-comment line. Fields are separated by whitespace or by a comma
// (with optional whitespace around it); an empty field between commas is an error, not a skip.
Eigen::MatrixXd parse_text(const std::string& path, const std::string& text, int expected_rows) {
  std::vector<double> values;
  Eigen::Index cols = -1;
  int first_line = 0, rows = 0, line = 0;
  std::vector<int> row_line;  // row -> line, for messages about values
  size_t pos = 0;
  while (pos < text.size()) {
    size_t eol = text.find('\n', pos);
    if (eol == std::string::npos) eol = text.size();
    const std::string_view s(text.data() + pos, eol - pos);
    pos = eol + 1;
    ++line;
    size_t i = 0;
    while (i < s.size() && is_space(s[i])) ++i;
    if (i == s.size() || s[i] == '#') continue;
    Eigen::Index count = 0;
    bool need_field = false;  // after a comma
    while (true) {
      while (i < s.size() && is_space(s[i])) ++i;
      if (i == s.size() || s[i] == ',') {
        if (need_field || (i < s.size() && count == 0)) bad(path, "line " + std::to_string(line) + ": empty field");
        if (i == s.size()) break;
        ++i;
        need_field = true;
        continue;
      }
      size_t j = i;
      while (j < s.size() && !is_space(s[j]) && s[j] != ',') ++j;
      values.push_back(parse_number(path, line, s.substr(i, j - i)));
      ++count;
      need_field = false;
      i = j;
    }
    if (cols < 0) {
      cols = count;
      first_line = line;
    } else if (count != cols) {
      bad(path, "line " + std::to_string(line) + ": " + std::to_string(count) + " values but line " +
                    std::to_string(first_line) + " has " + std::to_string(cols));
    }
    row_line.push_back(line);
    ++rows;
  }
  check_rows(path, rows, expected_rows);
  cols = std::max<Eigen::Index>(cols, 0);
  for (size_t v = 0; v < values.size(); ++v)
    if (!std::isfinite(values[v]))
      bad(path, "line " + std::to_string(row_line[v / cols]) + ": " +
                    (std::isnan(values[v]) ? "NaN" : "infinite value") + " in row " + std::to_string(v / cols) +
                    ", column " + std::to_string(v % cols) + " (0-based)");
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(values.data(), rows,
                                                                                                  cols);
}

uint64_t little_endian(const std::string& bytes, size_t at, int size) {
  uint64_t v = 0;
  for (int b = size - 1; b >= 0; --b) v = (v << 8) | static_cast<unsigned char>(bytes[at + b]);
  return v;
}

// The value of 'key' in the .npy header, a Python dict literal, as the text up to the next
// top-level comma or closing brace (a tuple's commas are inside parentheses).
std::string header_value(const std::string& path, const std::string& header, const std::string& key) {
  size_t at = header.find("'" + key + "'");
  if (at == std::string::npos) at = header.find("\"" + key + "\"");
  if (at == std::string::npos) bad(path, "malformed .npy header (no '" + key + "')");
  at = header.find(':', at);
  if (at == std::string::npos) bad(path, "malformed .npy header (no value for '" + key + "')");
  size_t end = ++at;
  int depth = 0;
  while (end < header.size() && (depth > 0 || (header[end] != ',' && header[end] != '}'))) {
    if (header[end] == '(') ++depth;
    if (header[end] == ')') --depth;
    ++end;
  }
  std::string v = header.substr(at, end - at);
  const auto first = v.find_first_not_of(" \t");
  const auto last = v.find_last_not_of(" \t");
  return first == std::string::npos ? std::string() : v.substr(first, last - first + 1);
}

Eigen::MatrixXd parse_npy(const std::string& path, const std::string& bytes, int expected_rows) {
  if (bytes.size() < 10) bad(path, "truncated .npy header");
  const int major = static_cast<unsigned char>(bytes[6]), minor = static_cast<unsigned char>(bytes[7]);
  if (major != 1 && major != 2)
    bad(path, "unsupported .npy version " + std::to_string(major) + "." + std::to_string(minor) + " (need 1.0 or 2.0)");
  const size_t len_size = major == 1 ? 2 : 4;
  if (bytes.size() < 8 + len_size) bad(path, "truncated .npy header");
  const size_t header_len = little_endian(bytes, 8, static_cast<int>(len_size));
  const size_t data_at = 8 + len_size + header_len;
  if (bytes.size() < data_at) bad(path, "truncated .npy header");
  const std::string header = bytes.substr(8 + len_size, header_len);

  std::string descr = header_value(path, header, "descr");
  if (descr.size() >= 2 && (descr.front() == '\'' || descr.front() == '"')) descr = descr.substr(1, descr.size() - 2);
  if (descr != "<f8" && descr != "<f4")
    bad(path, "unsupported .npy dtype '" + descr + "' (need little-endian float: '<f8' or '<f4')");
  const std::string fortran = header_value(path, header, "fortran_order");
  if (fortran != "False") bad(path, "Fortran-order .npy arrays are not supported (save a C-order array)");

  const std::string shape_text = header_value(path, header, "shape");
  if (shape_text.size() < 2 || shape_text.front() != '(' || shape_text.back() != ')')
    bad(path, "malformed .npy shape " + shape_text);
  std::vector<uint64_t> shape;
  std::istringstream in(shape_text.substr(1, shape_text.size() - 2));
  for (std::string item; std::getline(in, item, ',');) {
    const auto first = item.find_first_not_of(" \t");
    if (first == std::string::npos) continue;  // the trailing comma of a 1-tuple
    uint64_t d = 0;
    const auto [end, ec] = std::from_chars(item.data() + first, item.data() + item.size(), d);
    if (ec != std::errc() || item.find_first_not_of(" \t", end - item.data()) != std::string::npos)
      bad(path, "malformed .npy shape " + shape_text);
    shape.push_back(d);
  }
  if (shape.size() != 1 && shape.size() != 2) bad(path, ".npy array of shape " + shape_text + " is not 1-D or 2-D");
  const uint64_t rows = shape[0], cols = shape.size() == 2 ? shape[1] : 1;
  check_rows(path, rows, expected_rows);
  if (cols == 0) bad(path, ".npy array has 0 columns");
  const size_t item = descr == "<f8" ? 8 : 4;
  const uint64_t available = bytes.size() - data_at;
  // The first test keeps rows * cols * item from overflowing.
  if (cols > available / item / std::max<uint64_t>(rows, 1) || available != rows * cols * item)
    bad(path, std::to_string(available) + " data bytes do not fit shape " + shape_text + " of '" + descr + "'");

  Eigen::MatrixXd m(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(cols));
  size_t at = data_at;
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c, at += item)
      m(r, c) = item == 8 ? std::bit_cast<double>(little_endian(bytes, at, 8))
                          : std::bit_cast<float>(static_cast<uint32_t>(little_endian(bytes, at, 4)));
  check_finite(path, m);
  return m;
}

}  // namespace

Eigen::MatrixXd load_features(const std::string& path, int expected_rows) {
  const std::string bytes = read_file(path);
  if (bytes.compare(0, 6, "\x93NUMPY") == 0) return parse_npy(path, bytes, expected_rows);
  return parse_text(path, bytes, expected_rows);
}

Eigen::MatrixXd select_rows(const Eigen::MatrixXd& features, const std::vector<int>& rows) {
  Eigen::MatrixXd out(static_cast<Eigen::Index>(rows.size()), features.cols());
  for (size_t i = 0; i < rows.size(); ++i) {
    if (rows[i] < 0 || rows[i] >= features.rows())
      throw InvalidInputError("select_rows: index " + std::to_string(rows[i]) + " out of range for " +
                              std::to_string(features.rows()) + " feature rows");
    out.row(static_cast<Eigen::Index>(i)) = features.row(rows[i]);
  }
  return out;
}

}  // namespace shapematch
