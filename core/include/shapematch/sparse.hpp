#pragma once
// Sparse matrices whose entries are all +1 or -1 ("signed CSR"): the LP constraint matrix A and
// its transpose. Values are never stored; the sign lives in bit 31 of each column index, which
// halves the memory traffic of an SpMV compared with (column, value) pairs.
#include <bit>
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

// ±v[col] for one entry, without a branch: the entry's sign bit becomes the value's (a branch on
// it mispredicts about every other entry; signs change at 47 % of A's entries, 61 % of Aᵀ's).
inline double signed_value(uint32_t e, const double* v) {
  const double x = v[col_of(e)];
  return std::bit_cast<double>(std::bit_cast<uint64_t>(x) ^ (uint64_t(e & SignedCsr::kNegative) << 32));
}
// The same for a float vector: the entry's sign bit is already where a float's is.
inline float signed_value(uint32_t e, const float* v) {
  return std::bit_cast<float>(std::bit_cast<uint32_t>(v[col_of(e)]) ^ (e & SignedCsr::kNegative));
}

// Aᵀ in the same format; within each row the columns come out in increasing order.
SignedCsr transpose(const SignedCsr& a);

// y = A x (y has a.rows entries, x has a.cols). The float version accumulates in float, as the
// shader does; the double version is the exact reference.
void spmv(const SignedCsr& a, const float* x, float* y);
void spmv(const SignedCsr& a, const double* x, double* y);

}  // namespace shapematch
