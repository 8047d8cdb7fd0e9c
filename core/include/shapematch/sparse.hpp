#pragma once
// Sparse matrices whose entries are all +1 or -1 ("signed CSR"): the LP constraint matrix A and
// its transpose. Values are never stored; the sign lives in bit 31 of each column index, which
// halves the memory traffic of an SpMV compared with (column, value) pairs.
#include <cstdint>
#include <vector>

namespace shapematch {

struct SignedCsr {
  int64_t rows = 0, cols = 0;
  std::vector<uint32_t> row_ptr;  // rows + 1 offsets into entry
  std::vector<uint32_t> entry;    // column | kNegative for a -1 entry

  static constexpr uint32_t kNegative = 0x80000000u;
};

inline uint32_t col_of(uint32_t e) { return e & ~SignedCsr::kNegative; }
inline bool is_negative(uint32_t e) { return (e & SignedCsr::kNegative) != 0; }

// Aᵀ in the same format; within each row the columns come out in increasing order.
SignedCsr transpose(const SignedCsr& a);

// y = A x (y has a.rows entries, x has a.cols). The float version accumulates in float, as the
// shader does; the double version is the exact reference.
void spmv(const SignedCsr& a, const float* x, float* y);
void spmv(const SignedCsr& a, const double* x, double* y);

}  // namespace shapematch
