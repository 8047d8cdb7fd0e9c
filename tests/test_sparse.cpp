#include "shapematch/sparse.hpp"

#include <doctest/doctest.h>

#include <random>
#include <vector>

using namespace shapematch;

namespace {

// A random dense matrix with entries in {-1, 0, 1}, row-major.
std::vector<int> random_dense(int64_t rows, int64_t cols, std::mt19937& rng) {
  std::discrete_distribution<int> pick({1, 3, 1});  // mostly zeros
  std::vector<int> d(static_cast<size_t>(rows * cols));
  for (int& v : d) v = pick(rng) - 1;
  return d;
}

SignedCsr to_csr(const std::vector<int>& d, int64_t rows, int64_t cols) {
  SignedCsr a;
  a.rows = rows;
  a.cols = cols;
  a.row_ptr.push_back(0);
  for (int64_t r = 0; r < rows; ++r) {
    for (int64_t c = 0; c < cols; ++c) {
      const int v = d[static_cast<size_t>(r * cols + c)];
      if (v != 0) a.entry.push_back(static_cast<uint32_t>(c) | (v < 0 ? SignedCsr::kNegative : 0u));
    }
    a.row_ptr.push_back(static_cast<uint32_t>(a.entry.size()));
  }
  return a;
}

}  // namespace

TEST_CASE("sparse: entry encoding") {
  const uint32_t e = 12345u | SignedCsr::kNegative;
  CHECK(col_of(e) == 12345u);
  CHECK(is_negative(e));
  CHECK_FALSE(is_negative(12345u));
  CHECK(col_of(0x7fffffffu) == 0x7fffffffu);
}

TEST_CASE("sparse: transpose equals the dense transpose and twice is the identity") {
  std::mt19937 rng(7);
  for (auto [rows, cols] : {std::pair<int64_t, int64_t>{0, 0}, {1, 1}, {0, 5}, {5, 0}, {3, 7},
                            {40, 13}, {13, 40}}) {
    CAPTURE(rows);
    CAPTURE(cols);
    const std::vector<int> d = random_dense(rows, cols, rng);
    const SignedCsr a = to_csr(d, rows, cols);
    std::vector<int> dt(d.size());
    for (int64_t r = 0; r < rows; ++r)
      for (int64_t c = 0; c < cols; ++c)
        dt[static_cast<size_t>(c * rows + r)] = d[static_cast<size_t>(r * cols + c)];

    const SignedCsr t = transpose(a);
    const SignedCsr expected = to_csr(dt, cols, rows);
    CHECK(t.rows == cols);
    CHECK(t.cols == rows);
    CHECK(t.row_ptr == expected.row_ptr);
    CHECK(t.entry == expected.entry);  // columns sorted within rows, as to_csr makes them

    const SignedCsr tt = transpose(t);
    CHECK(tt.rows == a.rows);
    CHECK(tt.cols == a.cols);
    CHECK(tt.row_ptr == a.row_ptr);
    CHECK(tt.entry == a.entry);
  }
}

TEST_CASE("sparse: spmv equals the dense product") {
  std::mt19937 rng(11);
  const int64_t rows = 37, cols = 23;
  const std::vector<int> d = random_dense(rows, cols, rng);
  const SignedCsr a = to_csr(d, rows, cols);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> x(cols);
  for (double& v : x) v = u(rng);
  std::vector<float> xf(x.begin(), x.end());

  std::vector<double> y(rows);
  std::vector<float> yf(rows);
  spmv(a, x.data(), y.data());
  spmv(a, xf.data(), yf.data());
  for (int64_t r = 0; r < rows; ++r) {
    double dense = 0, dense_f = 0;
    for (int64_t c = 0; c < cols; ++c) {
      dense += d[static_cast<size_t>(r * cols + c)] * x[c];
      dense_f += d[static_cast<size_t>(r * cols + c)] * static_cast<double>(xf[c]);
    }
    CHECK(y[r] == doctest::Approx(dense).epsilon(1e-12));
    CHECK(yf[r] == doctest::Approx(dense_f).epsilon(1e-5));
  }
}
