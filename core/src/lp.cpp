#include "shapematch/lp.hpp"

#include "parallel.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/files.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <numeric>

namespace shapematch {

void LpProblem::check() const {
  auto bad = [](const std::string& what) { throw InvalidInputError("LP: " + what); };
  if (a.rows != at.cols || a.cols != at.rows) bad("A and Aᵀ sizes disagree");
  if (a.row_ptr.size() != size_t(a.rows + 1) || at.row_ptr.size() != size_t(at.rows + 1)) bad("bad row pointers");
  if (a.entry.size() != at.entry.size()) bad("A and Aᵀ have different numbers of nonzeros");
  if (b.size() != size_t(a.rows)) bad("b has " + std::to_string(b.size()) + " entries, A has " + std::to_string(a.rows) + " rows");
  if (c.size() != size_t(a.cols)) bad("c has " + std::to_string(c.size()) + " entries, A has " + std::to_string(a.cols) + " columns");
  for (double v : b)
    if (!std::isfinite(v)) bad("b is not finite");
  for (double v : c)
    if (!std::isfinite(v)) bad("c is not finite");
  if (!(objective_scale > 0) || !std::isfinite(objective_scale)) bad("objective scale must be positive");
}

const char* to_string(LpStatus status) {
  switch (status) {
    case LpStatus::Optimal: return "optimal";
    case LpStatus::Infeasible: return "infeasible";
    case LpStatus::IterationLimit: return "iteration_limit";
    case LpStatus::TimeLimit: return "time_limit";
    case LpStatus::NumericalTrouble: return "numerical_trouble";
    case LpStatus::Diverging: return "diverging";
  }
  return "unknown";
}

namespace {
// bᵀy + Σ_j min(0, c_j − (Aᵀy)_j), with c taken as 0 where `costs` is false; summed per thread
// then combined (deterministic for a fixed thread count).
double lagrangian(const LpProblem& p, const std::vector<double>& y, bool costs) {
  double by = 0.0;
  for (int64_t i = 0; i < p.rows(); ++i) by += p.b[i] * y[i];
  const int threads = worker_threads();
  std::vector<double> partial(threads, 0.0);
  detail::parallel_chunks(p.cols(), threads, [&](int64_t b, int64_t e, int t) {
    double s = 0.0;
    for (int64_t j = b; j < e; ++j) {
      double r = costs ? p.c[j] : 0.0;
      for (uint32_t k = p.at.row_ptr[j]; k < p.at.row_ptr[j + 1]; ++k) {
        const uint32_t en = p.at.entry[k];
        r -= (en & SignedCsr::kNegative) ? -y[col_of(en)] : y[col_of(en)];
      }
      s += std::min(0.0, r);
    }
    partial[t] = s;
  });
  return by + std::accumulate(partial.begin(), partial.end(), 0.0);
}
}  // namespace

double certified_lower_bound(const LpProblem& p, const std::vector<double>& y) {
  if (y.size() != size_t(p.rows())) return -std::numeric_limits<double>::infinity();
  const double bound = p.objective_scale * lagrangian(p, y, true);
  const bool nonnegative = p.objective_scale >= 0.0 && std::all_of(p.c.begin(), p.c.end(), [](double c) { return c >= 0.0; });
  return nonnegative ? std::max(bound, 0.0) : bound;
}

double farkas_rate(const LpProblem& p, const std::vector<double>& d) {
  if (d.size() != size_t(p.rows())) return -std::numeric_limits<double>::infinity();
  return lagrangian(p, d, false);
}

double objective_upper_bound(const LpProblem& p) {
  const int64_t m = p.rows(), n = p.cols();
  std::vector<char> cover(m, 0);
  for (int64_t i = 0; i < m; ++i) {
    if (!(p.b[i] >= 0.0)) continue;
    bool positive = true;
    for (uint32_t k = p.a.row_ptr[i]; k < p.a.row_ptr[i + 1] && positive; ++k) positive = !is_negative(p.a.entry[k]);
    cover[i] = positive;
  }
  std::vector<double> largest(m, 0.0);
  double bound = 0.0;
  for (int64_t j = 0; j < n; ++j) {
    const double cost = std::max(0.0, p.c[j]);
    int64_t row = -1;
    for (uint32_t k = p.at.row_ptr[j]; k < p.at.row_ptr[j + 1] && row < 0; ++k)
      if (cover[col_of(p.at.entry[k])]) row = col_of(p.at.entry[k]);
    if (row < 0)
      bound += cost;
    else
      largest[row] = std::max(largest[row], cost);
  }
  for (int64_t i = 0; i < m; ++i) bound += p.b[i] * largest[i];
  return bound;
}

void evaluate_solution(const LpProblem& p, LpResult& r) {
  if (r.x.size() == size_t(p.cols())) {
    std::vector<double> ax(p.rows());
    spmv(p.a, r.x.data(), ax.data());
    double res = 0.0, nb = 0.0, cx = 0.0, worst = 0.0;
    for (int64_t i = 0; i < p.rows(); ++i) {
      res += (ax[i] - p.b[i]) * (ax[i] - p.b[i]);
      nb += p.b[i] * p.b[i];
      const double off = std::abs(ax[i] - p.b[i]);
      if (!(off <= worst)) worst = off;  // a NaN stays (std::max would drop it and pass a bound)
    }
    for (int64_t j = 0; j < p.cols(); ++j) cx += p.c[j] * r.x[j];
    r.primal_residual = std::sqrt(res) / (1.0 + std::sqrt(nb));
    r.row_residual = worst;
    r.objective = p.objective_scale * cx;
  }
  if (r.y.size() == size_t(p.rows())) {
    r.lower_bound = certified_lower_bound(p, r.y);
    // With finite bounds 0 ≤ x ≤ 1 on every variable, any reduced cost is absorbed by a bound
    // multiplier, so the dual residual of this problem class is identically zero.
    r.dual_residual = 0.0;
  }
  if (std::isfinite(r.objective) && std::isfinite(r.lower_bound))
    r.gap = std::abs(r.objective - r.lower_bound) / (1.0 + std::abs(r.objective) + std::abs(r.lower_bound));
}

LpResult solve_lp(const LpProblem& problem, const std::string& solver, const SolverParams& params) {
  return make_solver(solver)->solve(problem, params);
}

namespace {

// "SMLP", format version, then little-endian fields as laid out in write_lp.
constexpr char kLpMagic[4] = {'S', 'M', 'L', 'P'};
constexpr uint32_t kLpVersion = 1;

template <class T>
void put(std::ostream& out, const T* data, size_t count) {
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(count * sizeof(T)));
}

}  // namespace

void write_lp(const LpProblem& p, const std::string& path) {
  p.check();
  write_file_atomic(path, [&](std::ostream& out) {
    const int64_t sizes[3] = {p.rows(), p.cols(), p.nonzeros()};
    put(out, kLpMagic, 4);
    put(out, &kLpVersion, 1);
    put(out, sizes, 3);
    put(out, &p.objective_scale, 1);
    put(out, p.a.row_ptr.data(), p.a.row_ptr.size());
    put(out, p.a.entry.data(), p.a.entry.size());
    put(out, p.b.data(), p.b.size());
    put(out, p.c.data(), p.c.size());
  });
}

LpProblem read_lp(const std::string& path) {
  std::ifstream in = open_for_reading(path, std::ios::binary);
  auto bad = [&](const std::string& what) { throw InvalidInputError(path + ": " + what); };
  auto get = [&](auto* data, size_t count) {
    in.read(reinterpret_cast<char*>(data), static_cast<std::streamsize>(count * sizeof(*data)));
    if (!in) bad("truncated");
  };
  in.seekg(0, std::ios::end);
  const auto length = static_cast<uint64_t>(in.tellg());
  in.seekg(0);
  char magic[4];
  uint32_t version = 0;
  int64_t sizes[3];
  get(magic, 4);
  if (std::memcmp(magic, kLpMagic, 4) != 0) bad("not a shapematch LP file");
  get(&version, 1);
  if (version != kLpVersion) bad("LP file version " + std::to_string(version) + ", expected " + std::to_string(kLpVersion));
  get(sizes, 3);
  const auto [m, n, nnz] = sizes;
  // Check the sizes against the file's length before allocating anything.
  const uint64_t header = 4 + 4 + 3 * 8 + 8;
  if (m < 0 || n < 0 || nnz < 0 || nnz > int64_t(UINT32_MAX) || n > int64_t(SignedCsr::kNegative) ||
      length != header + 4 * uint64_t(m + 1) + 4 * uint64_t(nnz) + 8 * uint64_t(m) + 8 * uint64_t(n))
    bad("sizes " + std::to_string(m) + " x " + std::to_string(n) + " (" + std::to_string(nnz) +
        " nonzeros) do not match the file's length");
  LpProblem p;
  get(&p.objective_scale, 1);
  p.a.rows = m;
  p.a.cols = n;
  p.a.row_ptr.resize(size_t(m) + 1);
  p.a.entry.resize(size_t(nnz));
  p.b.resize(size_t(m));
  p.c.resize(size_t(n));
  get(p.a.row_ptr.data(), p.a.row_ptr.size());
  get(p.a.entry.data(), p.a.entry.size());
  get(p.b.data(), p.b.size());
  get(p.c.data(), p.c.size());
  if (p.a.row_ptr[0] != 0 || p.a.row_ptr[size_t(m)] != uint32_t(nnz)) bad("bad row pointers");
  for (int64_t i = 0; i < m; ++i)
    if (p.a.row_ptr[size_t(i) + 1] < p.a.row_ptr[size_t(i)]) bad("bad row pointers");
  for (uint32_t e : p.a.entry)
    if (int64_t(col_of(e)) >= n) bad("a column index out of range");
  p.at = transpose(p.a);
  try {
    p.check();
  } catch (const InvalidInputError& e) {
    bad(e.what());
  }
  return p;
}

}  // namespace shapematch
