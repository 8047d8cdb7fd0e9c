#include "shapematch/sparse.hpp"

#include <cstddef>

namespace shapematch {

SignedCsr transpose(const SignedCsr& a) {
  SignedCsr t;
  t.rows = a.cols;
  t.cols = a.rows;
  t.row_ptr.assign(static_cast<size_t>(a.cols) + 1, 0);
  t.entry.resize(a.entry.size());
  // Counting sort by column: count, prefix-sum, scatter. Scanning the rows of A in order makes
  // the columns of each row of Aᵀ come out sorted.
  for (uint32_t e : a.entry) ++t.row_ptr[col_of(e) + 1];
  for (size_t c = 0; c < static_cast<size_t>(a.cols); ++c) t.row_ptr[c + 1] += t.row_ptr[c];
  std::vector<uint32_t> next(t.row_ptr.begin(), t.row_ptr.end() - 1);
  for (size_t r = 0; r < static_cast<size_t>(a.rows); ++r) {
    for (uint32_t k = a.row_ptr[r]; k < a.row_ptr[r + 1]; ++k) {
      const uint32_t e = a.entry[k];
      t.entry[next[col_of(e)]++] = static_cast<uint32_t>(r) | (e & SignedCsr::kNegative);
    }
  }
  return t;
}

template <class T>
static void spmv_impl(const SignedCsr& a, const T* x, T* y) {
  for (size_t r = 0; r < static_cast<size_t>(a.rows); ++r) {
    T sum = 0;
    for (uint32_t k = a.row_ptr[r]; k < a.row_ptr[r + 1]; ++k) {
      const uint32_t e = a.entry[k];
      sum += is_negative(e) ? -x[col_of(e)] : x[col_of(e)];
    }
    y[r] = sum;
  }
}

void spmv(const SignedCsr& a, const float* x, float* y) { spmv_impl(a, x, y); }
void spmv(const SignedCsr& a, const double* x, double* y) { spmv_impl(a, x, y); }

}  // namespace shapematch
