// Tests of the Vulkan PDHG backend against the native one (the oracle for every kernel) and of
// the solver on it against Clp. They need a Vulkan device (CI points VK_ICD_FILENAMES at
// lavapipe) and fail without one, unless SHAPEMATCH_SKIP_VULKAN=1.
#include "pdhg_backend.hpp"
#include "shapematch/device.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/matching.hpp"
#include "shapematch/shapes.hpp"
#include "test_helpers.hpp"
#include "vk/context.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <random>
#include <string>

using namespace shapematch;

namespace {


// A random scaled problem with a starting point; ScaledLp points into a and at, so this stays put.
struct RandomLp {
  SignedCsr a, at;
  detail::ScaledLp lp;
  std::vector<double> x, y;

  // rows x cols with 0..max_per_row entries per row (empty rows and columns occur); every
  // long_every-th row has the next of long_lengths entries instead.
  RandomLp(int64_t rows, int64_t cols, int max_per_row, uint32_t seed, const std::vector<int>& long_lengths = {},
           int64_t long_every = 0) {
    std::minstd_rand rng(seed);  // fast enough for the 40M-entry case
    std::uniform_int_distribution<int> count(0, max_per_row);
    std::uniform_int_distribution<uint32_t> col(0, static_cast<uint32_t>(cols - 1));
    std::uniform_real_distribution<double> u(0.0, 1.0);
    a.rows = rows;
    a.cols = cols;
    a.row_ptr.reserve(size_t(rows) + 1);
    a.entry.reserve(size_t(rows) * max_per_row / 2 + 16);
    a.row_ptr.push_back(0);
    for (int64_t r = 0; r < rows; ++r) {
      const bool longer = long_every > 0 && r % long_every == 3;
      for (int k = longer ? long_lengths[size_t(r / long_every) % long_lengths.size()] : count(rng); k > 0; --k) a.entry.push_back(col(rng) | (u(rng) < 0.5 ? SignedCsr::kNegative : 0u));
      a.row_ptr.push_back(static_cast<uint32_t>(a.entry.size()));
    }
    at = transpose(a);
    lp.a = &a;
    lp.at = &at;
    for (int64_t j = 0; j < cols; ++j) {
      lp.col_scale.push_back(0.5 + u(rng));
      lp.c.push_back(2.0 * u(rng) - 0.5);
      x.push_back(u(rng) < 0.3 ? 0.0 : u(rng) / lp.col_scale.back());
    }
    for (int64_t i = 0; i < rows; ++i) {
      lp.row_scale.push_back(0.5 + u(rng));
      lp.b.push_back(3.0 * u(rng) - 1.0);
      y.push_back(2.0 * u(rng) - 1.0);
    }
  }
};

// |a − b| within tol of the larger magnitude (plus a floor for sums that cancel to ~0).
void check_close(const char* what, double gpu, double cpu, double tol, double floor) {
  CAPTURE(what);
  CAPTURE(gpu);
  CAPTURE(cpu);
  CHECK(std::abs(gpu - cpu) <= tol * std::max(std::abs(gpu), std::abs(cpu)) + floor);
}

void check_stats(const detail::BatchStats& gpu, const detail::BatchStats& cpu, double tol, double floor) {
  check_close("dx2", gpu.dx2, cpu.dx2, tol, floor);
  check_close("dy2", gpu.dy2, cpu.dy2, tol, floor);
  check_close("residual2", gpu.residual2, cpu.residual2, tol, floor);
  check_close("cx", gpu.cx, cpu.cx, tol, floor);
  check_close("by", gpu.by, cpu.by, tol, floor);
  check_close("reduced_neg", gpu.reduced_neg, cpu.reduced_neg, tol, floor);
}

// Entrywise within tol of the vector's largest magnitude: sums in a different order differ by
// rounding relative to their terms, not to a result that cancels.
void check_vector(const char* what, const std::vector<double>& gpu, const std::vector<double>& cpu, double tol) {
  CAPTURE(what);
  REQUIRE(gpu.size() == cpu.size());
  double scale = 0.0;
  for (double v : cpu) scale = std::max(scale, std::abs(v));
  size_t worst = 0;
  double worst_error = 0.0;
  for (size_t k = 0; k < cpu.size(); ++k) {
    const double error = std::abs(gpu[k] - cpu[k]);
    if (error > worst_error) worst_error = error, worst = k;
  }
  CAPTURE(worst);
  CAPTURE(scale);
  CHECK(worst_error <= tol * scale);
}

void check_read(detail::PdhgBackend& gpu, detail::PdhgBackend& cpu, double tol) {
  std::vector<double> gx, gy, cx, cy;
  gpu.read(gx, gy);
  cpu.read(cx, cy);
  check_vector("x̂", gx, cx, tol);
  check_vector("ŷ", gy, cy, tol);
}

// Runs both backends side by side: one iteration, a batch, a restart, a batch after it. Both
// compute in fp64 with the gathers in the same order; only the reductions add in another order
// (measured: ~1e-15 relative), so any kernel error stands out.
void compare_backends(const RandomLp& p, const detail::Step& step, int batch) {
  constexpr double tol = 1e-11, floor = 1e-12;
  const auto gpu = detail::make_vulkan_backend(-1);
  const auto cpu = detail::make_cpu_backend(2);
  gpu->load(p.lp, p.x, p.y);
  cpu->load(p.lp, p.x, p.y);
  check_read(*gpu, *cpu, 0.0);  // zeros before any iteration

  check_stats(gpu->iterate(1, 0, step), cpu->iterate(1, 0, step), tol, floor);
  check_read(*gpu, *cpu, tol);

  check_stats(gpu->iterate(batch, 1, step), cpu->iterate(batch, 1, step), tol, floor);
  check_read(*gpu, *cpu, tol);

  const auto [gdx, gdy] = gpu->restart();
  const auto [cdx, cdy] = cpu->restart();
  check_close("restart dx2", gdx, cdx, tol, floor);
  check_close("restart dy2", gdy, cdy, tol, floor);
  // After the restart both continue from x̂, ŷ (and yr = r ŷ).
  check_stats(gpu->iterate(batch, 0, step), cpu->iterate(batch, 0, step), tol, floor);
  check_read(*gpu, *cpu, tol);
}

LpProblem matching_lp() {
  const Mesh x = shapes::octahedron();
  const Mesh y = test::deformed(x, [](const Eigen::Vector3d& p) {
    return Eigen::Vector3d(1.3 * p.x() + 0.1 * p.z(), p.y(), 0.8 * p.z() + 0.05 * p.x() * p.y());
  });
  return build_matching_lp(x, compute_geometry(x), y, compute_geometry(y)).lp;
}

SolverParams tight() {
  SolverParams params;
  params.tolerance = 1e-5;
  params.max_iterations = 400000;
  return params;
}

}  // namespace

TEST_CASE("pdhg-vulkan: every kernel equals the CPU backend on a small random problem") {
  if (!test::vulkan_wanted()) return;
  // Sizes not multiples of the workgroup; more columns than rows and the converse.
  for (const auto& [rows, cols] : {std::pair<int64_t, int64_t>{333, 1000}, {1000, 333}}) {
    CAPTURE(rows);
    const RandomLp p(rows, cols, 8, 7);
    for (double gamma : {1.0, 0.5}) {
      CAPTURE(gamma);
      compare_backends(p, detail::Step{0.3, 0.2, gamma}, 7);
    }
  }
}

// Rows of A above kLongRow entries go to the long-row kernels (a workgroup per row, the lanes'
// partial sums added pairwise), the others to the row kernels; both must give the CPU's values.
// Rows of exactly kLongRow and kLongRow + 1 entries sit on either side of the split.
TEST_CASE("pdhg-vulkan: long rows of A equal the CPU backend") {
  if (!test::vulkan_wanted()) return;
  constexpr int kLong = int(detail::kLongRow), kLanes = int(detail::kLongLanes);
  const RandomLp p(700, 3000, 8, 5, {kLong, kLong + 1, 300, 20 * kLanes, 20 * kLanes + 7, 2017}, 50);
  int64_t long_rows = 0;
  for (int64_t i = 0; i < p.a.rows; ++i) long_rows += p.a.row_ptr[i + 1] - p.a.row_ptr[i] > detail::kLongRow;
  CAPTURE(long_rows);
  REQUIRE(long_rows >= 10);
  for (const double gamma : {1.0, 0.5}) {
    CAPTURE(gamma);
    compare_backends(p, detail::Step{0.05, 0.05, gamma}, 7);
  }
}

// lavapipe: A's entry arrays exceed maxStorageBufferRange (128 MiB) and the rows need a 2D grid
// (more than 65535 workgroups).
TEST_CASE("pdhg-vulkan: kernels on arrays above 128 MiB and a 2D grid equal the CPU backend" *
          doctest::test_suite("slow")) {
  if (!test::vulkan_wanted()) return;
  const int64_t rows = int64_t{65535} * 256 + 1000;
  const RandomLp p(rows, 4'000'000, 5, 11);  // ~42M entries, 168 MB
  REQUIRE(p.a.entry.size() * sizeof(uint32_t) > (uint64_t{128} << 20));
  compare_backends(p, detail::Step{0.2, 0.2, 1.0}, 1);
}

TEST_CASE("pdhg-vulkan: a buffer beyond one allocation is a clear DeviceError") {
  if (!test::vulkan_wanted()) return;
  vk::Context context;
  REQUIRE(context.limits().buffer_device_address);
  try {
    context.addressed_buffer(context.limits().max_memory_allocation_size + 4);
    FAIL("no DeviceError");
  } catch (const DeviceError& e) {
    CHECK(std::string(e.what()).find("maxMemoryAllocationSize") != std::string::npos);
  }
}

// 7 column vectors of doubles alone overflow the device: refused before any allocation.
TEST_CASE("pdhg-vulkan: a problem larger than the device is a clear DeviceError") {
  if (!test::vulkan_wanted()) return;
  const auto gpu = detail::make_vulkan_backend(-1);
  const uint64_t heap = vk::Context().limits().device_local_bytes;
  if (heap > (uint64_t{4} << 30)) {
    MESSAGE("device memory above 4 GiB: the oversized problem would not fit on the host either; skipped");
    return;
  }
  const int64_t n = int64_t(heap / (7 * sizeof(double))) + 1000;
  SignedCsr a, at;  // 1 x n without entries
  a.rows = 1;
  a.cols = n;
  a.row_ptr = {0, 0};
  at.rows = n;
  at.cols = 1;
  at.row_ptr.assign(size_t(n) + 1, 0);
  detail::ScaledLp lp;
  lp.a = &a;
  lp.at = &at;
  lp.c.assign(size_t(n), 1.0);
  lp.col_scale.assign(size_t(n), 1.0);
  lp.b = {0.0};
  lp.row_scale = {1.0};
  try {
    gpu->load(lp, std::vector<double>(size_t(n), 0.0), {0.0});
    FAIL("no DeviceError");
  } catch (const DeviceError& e) {
    CHECK(std::string(e.what()).find("MiB of device memory") != std::string::npos);
  }
  CHECK_THROWS_AS(gpu->restart(), DeviceError);  // nothing half-loaded is used
}

TEST_CASE("pdhg-vulkan: calls before load() are refused") {
  if (!test::vulkan_wanted()) return;
  const auto gpu = detail::make_vulkan_backend(-1);
  CHECK_THROWS_AS(gpu->iterate(1, 0, detail::Step{}), DeviceError);
  CHECK_THROWS_AS(gpu->restart(), DeviceError);
}

TEST_CASE("pdhg-vulkan: a matching LP agrees with Clp within 1e-4 relative") {
  if (!test::vulkan_wanted()) return;
  const LpProblem lp = matching_lp();
  const LpResult exact = solve_lp(lp, "clp-dual");
  REQUIRE(exact.status == LpStatus::Optimal);
  const LpResult r = solve_lp(lp, "pdhg-vulkan", tight());
  CAPTURE(r.iterations);
  REQUIRE(r.status == LpStatus::Optimal);
  CHECK(r.device.find("vulkan") != std::string::npos);
  CHECK(std::abs(r.objective - exact.objective) <= 1e-4 * std::abs(exact.objective));
  CHECK(r.lower_bound <= exact.objective * (1 + 1e-9));
}

TEST_CASE("pdhg-vulkan: both backends converge to the same objective") {
  if (!test::vulkan_wanted()) return;
  const LpProblem lp = matching_lp();
  const LpResult cpu = solve_lp(lp, "pdhg-cpu", tight());
  const LpResult gpu = solve_lp(lp, "pdhg-vulkan", tight());
  REQUIRE(cpu.status == LpStatus::Optimal);
  REQUIRE(gpu.status == LpStatus::Optimal);
  CAPTURE(cpu.iterations);
  CAPTURE(gpu.iterations);
  CHECK(std::abs(gpu.objective - cpu.objective) <= 1e-4 * std::abs(cpu.objective));
  // The same algorithm in fp32 with sums in another order: the paths stay close.
  CHECK(std::abs(double(gpu.iterations - cpu.iterations)) <= 0.25 * double(cpu.iterations));
}

TEST_CASE("pdhg-vulkan: a snapshot read from the device starts the solve again near where it was") {
  if (!test::vulkan_wanted()) return;
  const LpProblem lp = matching_lp();
  SolverParams params = tight();
  std::vector<SolveSnapshot> seen;
  params.snapshot_seconds = 1e-9;  // (at every residual check)
  params.snapshot = [&](const SolveSnapshot& s) { seen.push_back(s); };
  const LpResult whole = solve_lp(lp, "pdhg-vulkan", params);
  REQUIRE(whole.status == LpStatus::Optimal);
  REQUIRE(seen.size() >= 2);
  const SolveSnapshot& last = seen.back();
  CHECK(last.x.size() == size_t(lp.cols()));
  CHECK(last.y.size() == size_t(lp.rows()));
  CHECK(last.iterations < whole.iterations);
  SolverParams again = tight();
  again.initial_x = last.x;
  again.initial_y = last.y;
  again.initial_primal_weight = last.primal_weight;
  const LpResult rest = solve_lp(lp, "pdhg-vulkan", again);
  REQUIRE(rest.status == LpStatus::Optimal);
  CAPTURE(whole.iterations);
  CAPTURE(last.iterations);
  CHECK(rest.iterations <= whole.iterations - last.iterations + 64);
  CHECK(std::abs(rest.objective - whole.objective) <= 1e-4 * std::abs(whole.objective));
}

TEST_CASE("pdhg-vulkan: a state read from the device goes on as the uninterrupted solve, bit for bit") {
  // The device's iterate and anchor come back as they go into the next batch (read_state) and go
  // up again with the problem (load_state): the solve gone on from a snapshot's state ends where
  // the whole one did, in as many iterations. (Its step too: no Lanczos estimate of its own.)
  if (!test::vulkan_wanted()) return;
  const LpProblem lp = matching_lp();
  SolverParams params = tight();
  params.exact_state = true;
  std::vector<SolveSnapshot> seen;
  params.snapshot_seconds = 1e-9;  // (at every residual check)
  params.snapshot = [&](const SolveSnapshot& s) { seen.push_back(s); };
  const LpResult whole = solve_lp(lp, "pdhg-vulkan", params);
  REQUIRE(whole.status == LpStatus::Optimal);
  REQUIRE(seen.size() >= 3);
  for (size_t k : {size_t(1), seen.size() - 1}) {
    CAPTURE(seen[k].iterations);
    REQUIRE(seen[k].state != nullptr);
    CHECK(seen[k].state->solver == "pdhg-vulkan");
    SolverParams from = params;
    from.snapshot = {};
    from.resume_state = seen[k].state;
    from.max_iterations = params.max_iterations - seen[k].iterations;
    const LpResult rest = solve_lp(lp, "pdhg-vulkan", from);
    CHECK(rest.status == whole.status);
    CHECK(rest.iterations == whole.iterations - seen[k].iterations);
    CHECK(rest.x == whole.x);
    CHECK(rest.y == whole.y);
    CHECK(rest.primal_weight == whole.primal_weight);
  }
  // The CPU backend (the shaders' oracle) takes no state of the device's: another solver's.
  SolverParams cpu = tight();
  const LpResult plain = solve_lp(lp, "pdhg-cpu", cpu);
  cpu.resume_state = seen.back().state;
  const LpResult given = solve_lp(lp, "pdhg-cpu", cpu);
  CHECK(given.iterations == plain.iterations);
  CHECK(given.x == plain.x);
}
