#include "shapematch/descriptors.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/geometry.hpp"
#include "shapematch/shapes.hpp"
#include "test_helpers.hpp"

#include <doctest/doctest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

using namespace shapematch;
namespace fs = std::filesystem;

namespace {

// Every vertex pushed in or out at random: no symmetry, so no exactly repeated eigenvalues.
Mesh jittered(const Mesh& m, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(0.9, 1.1);
  return test::deformed(
      m, [&](const Eigen::Vector3d& p) { return Eigen::Vector3d(p * jitter(rng)); }, m.name);
}

Eigen::VectorXd mass_of(const Mesh& m) {
  const Geometry g = compute_geometry(m);
  return Eigen::Map<const Eigen::VectorXd>(g.vertex_area.data(), m.num_vertices());
}

double max_relative_difference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff() / a.cwiseAbs().maxCoeff();
}

using test::TempDir;

// A .npy file encoded by hand: magic, version, little-endian header length, the dict padded with
// spaces to a multiple of 64 bytes and ended by '\n', then the raw data.
std::string npy(const std::string& dict, const std::string& data, int major = 1) {
  const size_t prefix = major == 1 ? 10 : 12;
  std::string header = dict;
  while ((prefix + header.size() + 1) % 64 != 0) header += ' ';
  header += '\n';
  std::string out = "\x93NUMPY";
  out += static_cast<char>(major);
  out += '\0';
  for (size_t b = 0; b < prefix - 8; ++b) out += static_cast<char>((header.size() >> (8 * b)) & 0xff);
  return out + header + data;
}

template <class T>
std::string raw_bytes(const std::vector<T>& values) {
  static_assert(std::endian::native == std::endian::little, "the hand-encoded .npy data is little-endian");
  return std::string(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
}

// `load_features(path, rows)` throws exactly E with "<path>: " and `problem` in its message.
template <class E>
void check_throws(const std::string& path, int rows, const std::string& problem) {
  CAPTURE(path);
  CAPTURE(problem);
  try {
    load_features(path, rows);
    FAIL("no exception");
  } catch (const E& e) {
    const std::string what = e.what();
    CAPTURE(what);
    CHECK(what.rfind(path + ": ", 0) == 0);
    CHECK(what.find(problem) != std::string::npos);
    CHECK(what.find('\n') == std::string::npos);
  } catch (const std::exception& e) {
    FAIL("wrong exception type: " << e.what());
  }
}

}  // namespace

TEST_CASE("descriptors: Laplace spectrum of a sphere is l(l+1)/r² with multiplicity 2l+1") {
  const double r = 1.5;
  for (int subdivisions : {3, 4}) {
    const Mesh m = shapes::icosphere(subdivisions, r);
    const Eigen::VectorXd mass = mass_of(m);
    const Eigen::SparseMatrix<double> laplacian = compute_geometry(m).cotan_laplacian;
    // 16 = levels 0 … 3, 25 = levels 0 … 4. Icosahedral symmetry keeps 4-fold repeated eigenvalues
    // in level 3; with 16, Lanczos alone once returned the first of level 4 instead of one of them.
    for (int count : {16, 25}) {
      CAPTURE(subdivisions);
      CAPTURE(count);
      const LaplaceSpectrum s = laplace_spectrum(m, count);
      REQUIRE(s.values.size() == count);
      REQUIRE(s.vectors.rows() == m.num_vertices());
      REQUIRE(s.vectors.cols() == count);
      CHECK(std::abs(s.values[0]) < 1e-8);
      int k = 1;
      for (int l = 1; k < count; ++l)
        for (int i = 0; i < 2 * l + 1; ++i, ++k) {
          CAPTURE(k);
          // Measured: at most 2.6 % (subdivision 3) and 0.7 % (subdivision 4) low, at l = 4.
          CHECK(s.values[k] == doctest::Approx(l * (l + 1) / (r * r)).epsilon(subdivisions == 3 ? 0.035 : 0.01));
        }
      CHECK(std::is_sorted(s.values.begin(), s.values.end()));

      const Eigen::MatrixXd gram = s.vectors.transpose() * mass.asDiagonal() * s.vectors;
      CHECK((gram - Eigen::MatrixXd::Identity(count, count)).cwiseAbs().maxCoeff() < 1e-8);
      const Eigen::MatrixXd residual = laplacian * s.vectors - mass.asDiagonal() * s.vectors * s.values.asDiagonal();
      CHECK(residual.cwiseAbs().maxCoeff() < 1e-8);
    }
  }
}

TEST_CASE("descriptors: Laplace spectrum agrees between the Lanczos and the dense path") {
  const Mesh m = jittered(shapes::icosphere(2), 5);         // 162 vertices
  const LaplaceSpectrum lanczos = laplace_spectrum(m, 20);  // 3 * 20 < 162: Spectra
  const LaplaceSpectrum dense = laplace_spectrum(m, 60);    // 3 * 60 >= 162: dense
  CHECK((lanczos.values - dense.values.head(20)).cwiseAbs().maxCoeff() < 1e-9 * dense.values[19]);
  // Without repeated eigenvalues the eigenvectors agree up to sign.
  for (int k = 1; k < 20; ++k) {
    CAPTURE(k);
    const double sign = lanczos.vectors.col(k).dot(dense.vectors.col(k)) < 0 ? -1 : 1;
    CHECK((lanczos.vectors.col(k) - sign * dense.vectors.col(k)).cwiseAbs().maxCoeff() < 1e-6);
  }
  // count is clamped to |V|; the dense path still gives M-orthonormal vectors.
  const LaplaceSpectrum all = laplace_spectrum(shapes::octahedron(), 10);
  CHECK(all.values.size() == 6);
  const Eigen::VectorXd mass = mass_of(shapes::octahedron());
  CHECK((all.vectors.transpose() * mass.asDiagonal() * all.vectors - Eigen::MatrixXd::Identity(6, 6)).norm() < 1e-12);
  CHECK_THROWS_AS(laplace_spectrum(m, 0), InvalidInputError);
}

TEST_CASE("descriptors: WKS is invariant to rigid motion and uniform scaling") {
  std::mt19937 rng(11);
  for (const Mesh& m :
       {jittered(shapes::icosphere(3), 1), jittered(shapes::torus(24, 10), 2), shapes::bent_finger(40)}) {
    CAPTURE(m.name);
    const Eigen::Matrix3d rotation = test::random_rotation(rng);
    const Eigen::Vector3d shift(0.3, -2.0, 5.0);
    Mesh moved =
        test::deformed(m, [&](const Eigen::Vector3d& p) { return Eigen::Vector3d(3.7 * rotation * p + shift); });
    const Eigen::MatrixXd wks = wave_kernel_signature(m);
    REQUIRE(wks.rows() == m.num_vertices());
    REQUIRE(wks.cols() == 100);
    CHECK(wks.allFinite());
    // The normalised signature needs no area normalisation: columns are rescaled anyway.
    CHECK(max_relative_difference(wks, wave_kernel_signature(moved)) < 1e-6);
    // The raw one scales as 1/area, so it agrees once both shapes have unit area.
    Mesh unit = m;
    normalize_area(unit);
    normalize_area(moved);
    const WksOptions raw{.normalize = false};
    const Eigen::MatrixXd raw_unit = wave_kernel_signature(unit, raw);
    CHECK(max_relative_difference(raw_unit, wave_kernel_signature(moved, raw)) < 1e-6);
    // Each raw column is a weighted mean of φ_k², whose area integrals are 1.
    const Eigen::RowVectorXd integrals = mass_of(unit).transpose() * raw_unit;
    CHECK((integrals.array() - 1).abs().maxCoeff() < 1e-9);
    // Normalised: a row's squared norm has area-weighted mean 1.
    CHECK(mass_of(m).dot(wks.rowwise().squaredNorm()) / surface_area(m) == doctest::Approx(1.0).epsilon(1e-9));
  }
}

TEST_CASE("descriptors: WKS is constant on a sphere and tells a torus's inner equator from its outer one") {
  // 15 eigenpairs are the complete levels l = 1, 2, 3: the sum of |Y_lm|² over a level is constant.
  const Mesh sphere = shapes::icosphere(3);
  const Eigen::MatrixXd s = wave_kernel_signature(sphere, {.eigenpairs = 15, .energies = 20});
  const Eigen::ArrayXd spread = (s.colwise().maxCoeff() - s.colwise().minCoeff()).array() / s.colwise().mean().array();
  CHECK(spread.maxCoeff() < 0.02);  // measured 0.6 %; 10 % with all 100 eigenpairs, which split level 10

  // The torus's rotational symmetry makes eigenvalues come in exact pairs; 30 eigenpairs end
  // between two levels, so every vertex of one ring of the tube gets the same signature.
  const int n_major = 32, n_minor = 12;
  const Mesh torus = shapes::torus(n_major, n_minor, 1.0, 0.4);
  const LaplaceSpectrum spectrum = laplace_spectrum(torus, 32);
  REQUIRE(spectrum.values[31] - spectrum.values[30] > 0.03 * spectrum.values[30]);  // measured 5 %
  const Eigen::MatrixXd t = wave_kernel_signature(torus, {.eigenpairs = 30, .energies = 20});
  double within = 0, between = 0;
  for (int i = 0; i < n_major; ++i) {
    const int outer = i * n_minor, inner = i * n_minor + n_minor / 2;  // ring angle 0 and π
    within = std::max({within, (t.row(outer) - t.row(0)).norm(), (t.row(inner) - t.row(n_minor / 2)).norm()});
    between = std::max(between, (t.row(outer) - t.row(inner)).norm());
  }
  CHECK(within < 1e-6 * t.row(0).norm());  // measured 1e-9
  CHECK(between > 0.2 * t.row(0).norm());  // measured 0.4
}

TEST_CASE("descriptors: WKS on tiny meshes and bad options") {
  // 4 and 6 vertices: eigenpairs clamp to |V| - 1. The regular tetrahedron's three nonzero
  // eigenvalues are equal, so all energies coincide.
  for (const Mesh& m : {shapes::tetrahedron(), shapes::octahedron()}) {
    CAPTURE(m.name);
    const Eigen::MatrixXd w = wave_kernel_signature(m);
    CHECK(w.rows() == m.num_vertices());
    CHECK(w.cols() == 100);
    CHECK(w.allFinite());
    // Both are vertex-transitive: every vertex has the same signature, 1/sqrt(E) after scaling.
    CHECK((w.array() - 0.1).abs().maxCoeff() < 1e-9);
  }
  const Mesh m = shapes::octahedron();
  CHECK_THROWS_AS(wave_kernel_signature(m, {.eigenpairs = 0}), InvalidInputError);
  CHECK_THROWS_AS(wave_kernel_signature(m, {.energies = 0}), InvalidInputError);
  CHECK_THROWS_AS(wave_kernel_signature(m, {.variance = 0}), InvalidInputError);
  CHECK_THROWS_AS(wave_kernel_signature(m, {.variance = std::numeric_limits<double>::infinity()}), InvalidInputError);
}

TEST_CASE("descriptors: features round-trip through text and .npy files") {
  TempDir dir;
  Eigen::MatrixXd expected(3, 2);
  expected << 1.0, -2.5, 0.1, 3e-7, 1e300, -0.0;

  const std::string text = dir.file("f.txt",
                                    "# exported features\n"
                                    "\n"
                                    "1 -2.5\r\n"
                                    "   # indented comment\n"
                                    "0.1000000000000000055511151231257827,  +3e-7\n"
                                    "\t1e300 ,-0.0   \n");
  CHECK(load_features(text, 3) == expected);

  const std::vector<double> f8 = {1.0, -2.5, 0.1, 3e-7, 1e300, -0.0};
  CHECK(load_features(
            dir.file("f8.npy", npy("{'descr': '<f8', 'fortran_order': False, 'shape': (3, 2), }", raw_bytes(f8))), 3) ==
        expected);

  const std::vector<float> f4 = {0.5f, 0.1f, -7.25f, 1e-3f};
  Eigen::MatrixXd expected_f4(2, 2);
  expected_f4 << 0.5, double(0.1f), -7.25, double(1e-3f);
  CHECK(load_features(
            dir.file("f4.npy", npy("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 2), }", raw_bytes(f4), 2)),
            2) == expected_f4);

  // 1-D: one column.
  const Eigen::MatrixXd column =
      load_features(dir.file("v.npy", npy("{\"descr\": \"<f8\", \"fortran_order\": False, \"shape\": (3,)}",
                                          raw_bytes(std::vector<double>{4, 5, 6}))),
                    3);
  CHECK(column.cols() == 1);
  CHECK(column == Eigen::Vector3d(4, 5, 6));
}

TEST_CASE("descriptors: malformed feature files are rejected naming the file and the problem") {
  TempDir dir;
  const std::string f8_header = "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 2), }";
  const std::string four = raw_bytes(std::vector<double>{1, 2, 3, 4});

  check_throws<InvalidInputError>(dir.file("rows.txt", "1 2\n3 4\n"), 3, "2 rows but the mesh has 3 vertices");
  check_throws<InvalidInputError>(dir.file("rows.npy", npy(f8_header, four)), 3, "2 rows but the mesh has 3 vertices");
  check_throws<InvalidInputError>(dir.file("empty.txt", "# nothing\n\n"), 3, "0 rows but the mesh has 3 vertices");
  check_throws<InvalidInputError>(dir.file("ragged.txt", "1 2\n3 4 5\n6 7\n"), 3, "line 2: 3 values but line 1 has 2");
  check_throws<InvalidInputError>(dir.file("word.txt", "1 2\n3 abc\n"), 2, "line 2: not a number 'abc'");
  check_throws<InvalidInputError>(dir.file("suffix.txt", "1 2\n3 4x\n"), 2, "line 2: not a number '4x'");
  check_throws<InvalidInputError>(dir.file("huge.txt", "1 2\n3 1e999\n"), 2, "line 2: number out of range '1e999'");
  check_throws<InvalidInputError>(dir.file("comma.txt", "1,,2\n3,4\n"), 2, "line 1: empty field");
  check_throws<InvalidInputError>(dir.file("trailing.txt", "1,2,\n3,4\n"), 2, "line 1: empty field");
  check_throws<InvalidInputError>(dir.file("nan.txt", "# c\n1 2\n3 nan\n"), 2, "line 3: NaN in row 1, column 1");
  check_throws<InvalidInputError>(dir.file("inf.txt", "1 -inf\n3 4\n"), 2, "infinite value in row 0, column 1");
  check_throws<InvalidInputError>(dir.file("nan.npy", npy(f8_header, raw_bytes(std::vector<double>{1, 2, 3, NAN}))), 2,
                                  "NaN in row 1, column 1");
  check_throws<InvalidInputError>(
      dir.file("big.npy", npy("{'descr': '>f8', 'fortran_order': False, 'shape': (2, 2), }", four)), 2,
      "unsupported .npy dtype '>f8'");
  check_throws<InvalidInputError>(
      dir.file("int.npy", npy("{'descr': '<i8', 'fortran_order': False, 'shape': (2, 2), }", four)), 2,
      "unsupported .npy dtype '<i8'");
  check_throws<InvalidInputError>(
      dir.file("fortran.npy", npy("{'descr': '<f8', 'fortran_order': True, 'shape': (2, 2), }", four)), 2,
      "Fortran-order");
  check_throws<InvalidInputError>(
      dir.file("3d.npy", npy("{'descr': '<f8', 'fortran_order': False, 'shape': (2, 1, 2), }", four)), 2,
      "not 1-D or 2-D");
  check_throws<InvalidInputError>(dir.file("short.npy", npy(f8_header, four.substr(0, 24))), 2,
                                  "24 data bytes do not fit shape (2, 2) of '<f8'");
  check_throws<InvalidInputError>(dir.file("v3.npy", npy(f8_header, four, 3)), 2, "unsupported .npy version 3.0");
  check_throws<IoError>((dir.path / "missing.txt").string(), 2, "cannot open");
  check_throws<IoError>(dir.path.string(), 2, "is a directory");
}

TEST_CASE("descriptors: select_rows picks feature rows by original vertex index") {
  Eigen::MatrixXd f(4, 2);
  f << 0, 1, 10, 11, 20, 21, 30, 31;
  Eigen::MatrixXd expected(3, 2);
  expected << 30, 31, 0, 1, 30, 31;
  CHECK(select_rows(f, {3, 0, 3}) == expected);
  CHECK_THROWS_AS(select_rows(f, {4}), InvalidInputError);
  CHECK_THROWS_AS(select_rows(f, {-1}), InvalidInputError);
}

// Real shapes: timing, and how far apart true correspondences are compared with random pairs.
TEST_CASE("descriptors: WKS on FAUST_r separates true correspondences from random pairs" *
          doctest::test_suite("slow")) {
  const fs::path dir = fs::path(SHAPEMATCH_DATASETS_DIR) / "faust_r_bcicp";
  const fs::path a = dir / "off/tr_reg_020.off", b = dir / "off/tr_reg_043.off";
  const fs::path ga = dir / "corres/tr_reg_020.vts", gb = dir / "corres/tr_reg_043.vts";
  for (const fs::path& p : {a, b, ga, gb})
    if (!fs::exists(p)) {
      MESSAGE("dataset file absent, skipped: " << p.string());
      return;
    }
  const Mesh x = load_mesh(a.string()), y = load_mesh(b.string());
  const auto start = std::chrono::steady_clock::now();
  const Eigen::MatrixXd dx = wave_kernel_signature(x);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const Eigen::MatrixXd dy = wave_kernel_signature(y);
  const Mesh small = decimate(x, 500);
  const auto start_small = std::chrono::steady_clock::now();
  CHECK(wave_kernel_signature(small).allFinite());
  const double seconds_small = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_small).count();
  MESSAGE("WKS: " << x.num_vertices() << " vertices " << seconds << " s; " << small.num_faces() << " faces "
                  << seconds_small << " s");

  // Ground truth: line k of one .vts file corresponds to line k of the other (1-based).
  auto read_vts = [](const fs::path& p) {
    std::vector<int> v;
    std::ifstream in(p);
    for (int i; in >> i;) v.push_back(i - 1);
    return v;
  };
  const std::vector<int> ia = read_vts(ga), ib = read_vts(gb);
  REQUIRE(ia.size() == ib.size());
  std::mt19937 rng(1);
  std::vector<double> truth, random;
  for (size_t k = 0; k < ia.size(); ++k) {
    truth.push_back((dx.row(ia[k]) - dy.row(ib[k])).squaredNorm());
    random.push_back((dx.row(ia[k]) - dy.row(ib[rng() % ib.size()])).squaredNorm());
  }
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  MESSAGE("median squared WKS distance: true pairs " << median(truth) << ", random pairs " << median(random));
  CHECK(median(random) > 0.2);  // O(1) for unrelated points (measured 0.64)
  CHECK(median(random) < 5);
  CHECK(median(truth) < 0.2 * median(random));  // measured 0.04
}
