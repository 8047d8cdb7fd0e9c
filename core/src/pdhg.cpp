// The host driver of restarted Halpern PDHG: scaling, step size, restarts, primal weight and
// termination. The kernels live in a PdhgBackend (native C++ or Vulkan).
#include "shapematch/pdhg.hpp"

#include "divergence_watch.hpp"
#include "parallel.hpp"
#include "pdhg_backend.hpp"
#include "scaled_norm.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/system.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace shapematch {
namespace {

// r_i /= √row_i and d_j /= √col_j where positive.
void rescale(std::vector<double>& r, const std::vector<double>& row, std::vector<double>& d,
             const std::vector<double>& col, int threads) {
  detail::parallel_for(int64_t(r.size()), threads, [&](int64_t i) {
    if (row[i] > 0) r[i] /= std::sqrt(row[i]);
  });
  detail::parallel_for(int64_t(d.size()), threads, [&](int64_t j) {
    if (col[j] > 0) d[j] /= std::sqrt(col[j]);
  });
}

// Ruiz equilibration then Pock–Chambolle (α = 1) scaling of A, kept as two diagonal vectors.
// Rows and columns are independent, so the loops run in parallel with the same result.
void compute_scaling(const LpProblem& p, int ruiz_iterations, int threads, std::vector<double>& r,
                     std::vector<double>& d) {
  const int64_t m = p.rows(), n = p.cols();
  r.assign(m, 1.0);
  d.assign(n, 1.0);
  std::vector<double> row(m), col(n);
  for (int it = 0; it < ruiz_iterations; ++it) {
    // |Ã_ij| = r_i d_j: infinity norms of rows and columns.
    detail::parallel_rows(p.a.row_ptr, threads, [&](int64_t i) {
      double mx = 0.0;
      for (uint32_t k = p.a.row_ptr[i]; k < p.a.row_ptr[i + 1]; ++k) mx = std::max(mx, d[col_of(p.a.entry[k])]);
      row[i] = r[i] * mx;
    });
    detail::parallel_for(n, threads, [&](int64_t j) {
      double mx = 0.0;
      for (uint32_t k = p.at.row_ptr[j]; k < p.at.row_ptr[j + 1]; ++k) mx = std::max(mx, r[col_of(p.at.entry[k])]);
      col[j] = d[j] * mx;
    });
    rescale(r, row, d, col, threads);
  }
  detail::parallel_rows(p.a.row_ptr, threads, [&](int64_t i) {
    double s = 0.0;
    for (uint32_t k = p.a.row_ptr[i]; k < p.a.row_ptr[i + 1]; ++k) s += d[col_of(p.a.entry[k])];
    row[i] = r[i] * s;
  });
  detail::parallel_for(n, threads, [&](int64_t j) {
    double s = 0.0;
    for (uint32_t k = p.at.row_ptr[j]; k < p.at.row_ptr[j + 1]; ++k) s += r[col_of(p.at.entry[k])];
    col[j] = d[j] * s;
  });
  rescale(r, row, d, col, threads);
}

// A row whose achievable range over the box excludes b_i proves infeasibility at once
// (e.g. a face of X left with no product triangle after fixing).
bool row_bounds_infeasible(const LpProblem& p) {
  for (int64_t i = 0; i < p.rows(); ++i) {
    double lo = 0.0, hi = 0.0;
    for (uint32_t k = p.a.row_ptr[i]; k < p.a.row_ptr[i + 1]; ++k) (is_negative(p.a.entry[k]) ? lo : hi) += 1.0;
    if (p.b[i] > hi + 1e-9 || p.b[i] < -lo - 1e-9) return true;
  }
  return false;
}

// Which LP, scaling and options a SolverState belongs to: the LP's sizes, objective scale, c and b
// (bits) and A's pattern and signs, the diagonal scaling (r, d: another build's Ruiz passes would
// put the state's scaled vectors in another space) and every option the iterations depend on, mixed
// word by word (splitmix64's finaliser over a running sum: a changed word changes the result).
uint64_t fingerprint(const LpProblem& p, const std::vector<double>& r, const std::vector<double>& d,
                     const PdhgOptions& o) {
  uint64_t h = 0x9e3779b97f4a7c15ull;
  const auto mix = [&h](uint64_t v) {
    uint64_t z = (h += v + 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    h = z ^ (z >> 31);
  };
  const auto bits = [](double v) {
    uint64_t u;
    std::memcpy(&u, &v, sizeof u);
    return u;
  };
  mix(uint64_t(p.rows())), mix(uint64_t(p.cols())), mix(uint64_t(p.nonzeros())), mix(bits(p.objective_scale));
  for (double v : p.c) mix(bits(v));
  for (double v : p.b) mix(bits(v));
  for (uint32_t v : p.a.row_ptr) mix(v);
  for (size_t k = 0; k + 1 < p.a.entry.size(); k += 2) mix(uint64_t(p.a.entry[k]) << 32 | p.a.entry[k + 1]);
  if (p.a.entry.size() % 2 == 1) mix(p.a.entry.back());
  for (double v : r) mix(bits(v));
  for (double v : d) mix(bits(v));
  for (double v : {o.reflection, o.restart_sufficient, o.restart_necessary, o.primal_weight_smoothing})
    mix(bits(v));
  mix(uint64_t(o.check_interval));
  return h;
}

}  // namespace

LpResult PdhgSolver::solve(const LpProblem& problem, const SolverParams& params) {
  problem.check();
  Stopwatch clock;
  const int64_t m = problem.rows(), n = problem.cols();
  LpResult result;
  result.solver = name();

  if (row_bounds_infeasible(problem)) {
    result.status = LpStatus::Infeasible;
    result.device = "presolve";
    result.seconds = clock.seconds();
    return result;
  }
  if (!params.initial_x.empty() && params.initial_x.size() != size_t(n))
    throw InvalidInputError("warm start x has " + std::to_string(params.initial_x.size()) + " entries, expected " + std::to_string(n));
  if (!params.initial_y.empty() && params.initial_y.size() != size_t(m))
    throw InvalidInputError("warm start y has " + std::to_string(params.initial_y.size()) + " entries, expected " + std::to_string(m));

  std::vector<double> r, d;
  compute_scaling(problem, options_.ruiz_iterations, params.threads, r, d);
  const double scaling_seconds = clock.seconds();
  // An exact state to go on from, where it is this LP's, scaling's and solver's (else the warm start).
  const bool exact = params.exact_state && backend_ != PdhgBackendKind::CpuF32;
  const uint64_t print = exact || params.resume_state ? fingerprint(problem, r, d, options_) : 0;
  const SolverState* resume = params.resume_state.get();
  if (resume && (resume->solver != name() || resume->fingerprint != print || resume->x.size() != size_t(n) ||
                 resume->x0.size() != size_t(n) || resume->y.size() != size_t(m) || resume->y0.size() != size_t(m) ||
                 !(resume->window_y.empty() || resume->window_y.size() == size_t(m)) || !(resume->step > 0.0) ||
                 !(resume->primal_weight > 0.0))) {
    spdlog::debug("{}: the state to go on from is another LP's or solver's ({}); going on from the warm start",
                  name(), resume->solver);
    resume = nullptr;
  }
  // The Lanczos estimate approaches ‖Ã‖ from below (within norm_tolerance of an eigenvalue when it
  // stops), so add a margin; Pock–Chambolle scaling with α = 1 guarantees ‖Ã‖ ≤ 1, which caps it.
  // (Gone on from a state: its step, which the estimate made; ten seconds at full resolution.)
  const detail::NormEstimate estimate =
      resume ? detail::NormEstimate{}
             : detail::scaled_norm(problem.a, problem.at, r, d, options_.norm_steps, options_.norm_tolerance,
                                   params.threads, 1.01, 1.0);
  double norm = std::min(1.0, 1.01 * estimate.norm);
  if (!(norm > 1e-12)) norm = 1.0;  // no nonzeros (or no Lanczos steps): the Pock–Chambolle bound
  const double eta = resume ? resume->step : options_.step_safety / norm;
  if (resume) norm = options_.step_safety / eta;
  const double norm_seconds = clock.seconds() - scaling_seconds;

  detail::ScaledLp lp;
  lp.a = &problem.a;
  lp.at = &problem.at;
  lp.c.resize(n);
  lp.col_scale.resize(n);
  lp.b.resize(m);
  lp.row_scale.resize(m);
  double cnorm = 0.0, bnorm = 0.0, bnorm_orig = 0.0;
  for (int64_t j = 0; j < n; ++j) {
    lp.c[j] = d[j] * problem.c[j];
    lp.col_scale[j] = d[j];
    cnorm += double(lp.c[j]) * lp.c[j];
  }
  // The largest objective a feasible point can have: a dual bound above it proves infeasibility.
  const double largest_objective = objective_upper_bound(problem);
  for (int64_t i = 0; i < m; ++i) {
    lp.b[i] = r[i] * problem.b[i];
    lp.row_scale[i] = r[i];
    bnorm += double(lp.b[i]) * lp.b[i];
    bnorm_orig += problem.b[i] * problem.b[i];
  }
  cnorm = std::sqrt(cnorm);
  bnorm = std::sqrt(bnorm);
  bnorm_orig = std::sqrt(bnorm_orig);
  double omega = resume                                                      ? resume->primal_weight
                 : params.initial_primal_weight > 0                          ? params.initial_primal_weight
                 : params.cold_primal_weight > 0 && params.initial_x.empty() ? params.cold_primal_weight
                 : options_.initial_primal_weight > 0                        ? options_.initial_primal_weight
                 : (cnorm > 1e-10 && bnorm > 1e-10) ? cnorm / bnorm
                                                    : 1.0;

  std::vector<double> x0(resume ? 0 : n, 0.0), y0(resume ? 0 : m, 0.0);  // (a state brings its own)
  if (!params.initial_x.empty() && !resume)
    for (int64_t j = 0; j < n; ++j) x0[j] = std::clamp(params.initial_x[j], 0.0, 1.0) / d[j];
  if (!params.initial_y.empty() && !resume)
    for (int64_t i = 0; i < m; ++i) y0[i] = params.initial_y[i] / r[i];

  auto backend = backend_ == PdhgBackendKind::Cpu      ? detail::make_cpu_backend(params.threads)
                 : backend_ == PdhgBackendKind::CpuF32 ? detail::make_cpu_f32_backend(params.threads)
                                                       : detail::make_vulkan_backend(params.device);
  result.device = backend->device();
  if (resume)
    backend->load_state(lp, resume->x, resume->x0, resume->y, resume->y0);
  else
    backend->load(lp, x0, y0);
  // Sums over threads or a device's workgroups add in their own order: elsewhere the same point
  // goes on, not the same iterations bit for bit.
  if (resume && resume->device != result.device)
    spdlog::info("{}: going on from its state of {} iterations on {} where it was made on {}: the same point, but "
                 "not bit for bit the iterations it would have made there",
                 name(), resume->iterations, result.device, resume->device);
  result.setup_seconds = clock.seconds();
  spdlog::debug("{}: set up in {:.2f} s (scaling {:.2f} s, norm {:.2f} s in {} Lanczos steps)", name(),
                result.setup_seconds, scaling_seconds, norm_seconds, estimate.steps);
  spdlog::debug("{}: {} x {}, ‖Ã‖ ≈ {:.4g}, step {:.4g}, primal weight {:.4g}, on {}", name(), m, n, norm, eta,
                omega, result.device);
  // A stop asked for during the set-up (tens of seconds at full resolution) leaves off here where
  // this solve saves nothing; where it does (a snapshot: a round's LP saves the rounding's decisions
  // with it), at the first residual check, after saving.
  if (stop_requested() != 0 && !(params.snapshot && params.snapshot_seconds > 0.0))
    throw Stopped("stopped before an LP's first iteration");

  const double restart_artificial = resume ? resume->restart_artificial
                                    : params.cold_restart_artificial > 0 && params.initial_x.empty()
                                        ? params.cold_restart_artificial
                                        : options_.restart_artificial;
  int64_t total = 0, k = resume ? resume->since_restart : 0;
  const int64_t before = resume                    ? resume->iterations
                         : params.initial_x.empty() ? 0
                                                    : std::max<int64_t>(params.iterations_before, 0);
  double restart_base = resume ? resume->restart_base : -1.0;
  double previous = resume ? resume->previous : std::numeric_limits<double>::infinity();
  // Divergence watch (params.stop_on_divergence); the dual at the start of each window gives
  // the growth returned as the ray.
  // (Gone on from a snapshot's watch only with its warm start: a cold solve is a new one.)
  detail::DivergenceWatch watch(params.tolerance, params.patient_divergence_watch,
                                resume                    ? resume->watch
                                : params.initial_y.empty() ? DivergenceWatchState{}
                                                           : params.initial_watch);
  int64_t window_end = resume ? resume->window_left : detail::DivergenceWatch::kWindow;
  // (From a warm start's dual: a bound past params.divergence_bound may stop the first window, its
  // growth a change of a given dual. From a cold start the first window's "growth" would be the
  // whole dual, its ordinary duals included: it waits for a second, as the watch's own rules do.)
  std::vector<double> window_y;
  if (resume)
    window_y = resume->window_y;
  else if (params.stop_on_divergence && !params.initial_y.empty())
    window_y = y0;
  int restarts = resume ? resume->restarts : 0;
  if (resume)
    spdlog::debug("{}: going on from its state after {} iterations ({} since its last restart)", name(),
                  before, k);
  Stopwatch since_snapshot;
  int snapshots = 0;  // taken so far (params.snapshot_first_seconds)
  result.status = LpStatus::IterationLimit;
  while (true) {
    if (total >= params.max_iterations) {
      result.status = LpStatus::IterationLimit;
      break;
    }
    if (clock.seconds() >= params.time_limit) {
      result.status = LpStatus::TimeLimit;
      break;
    }
    const int count =
        static_cast<int>(std::min<int64_t>(std::max(1, options_.check_interval), params.max_iterations - total));
    const detail::Step step{eta / omega, eta * omega, options_.reflection};
    const detail::BatchStats s = backend->iterate(count, k, step);
    total += count;
    k += count;

    const double primal = std::sqrt(s.residual2) / (1.0 + bnorm_orig);
    const double dual_obj = s.by + s.reduced_neg;
    const double gap = std::abs(s.cx - dual_obj) / (1.0 + std::abs(s.cx) + std::abs(dual_obj));
    const double fixed_point = std::sqrt(omega * s.dx2 + s.dy2 / omega);
    if (params.verbose || spdlog::should_log(spdlog::level::debug))
      spdlog::debug("{:>8} it  primal {:.3e}  gap {:.3e}  obj {:.8g}  bound {:.8g}  fp {:.3e}  ω {:.3g}", total,
                    primal, gap, s.cx * problem.objective_scale, dual_obj * problem.objective_scale, fixed_point, omega);
    if (!std::isfinite(fixed_point) || !std::isfinite(dual_obj)) {
      result.status = LpStatus::NumericalTrouble;
      break;
    }
    if (primal <= params.tolerance && gap <= params.tolerance) {
      result.status = LpStatus::Optimal;
      break;
    }
    // Any dual point whose bound exceeds the largest objective a feasible point can have proves
    // infeasibility; confirm in double precision before trusting the fp32 reduction.
    if (dual_obj > largest_objective + 1e-3 * (1.0 + largest_objective)) {
      std::vector<double> xh, yh;
      backend->read(xh, yh);
      std::vector<double> y(m);
      for (int64_t i = 0; i < m; ++i) y[i] = r[i] * yh[i];
      if (certified_lower_bound(problem, y) > problem.objective_scale * largest_objective) {
        result.status = LpStatus::Infeasible;
        if (options_.ray_iterations > 0) {  // LpResult::ray
          backend->iterate(options_.ray_iterations, k, step);
          k += options_.ray_iterations;
          total += options_.ray_iterations;
          backend->read(xh, yh);
          std::vector<double> ray(m);
          for (int64_t i = 0; i < m; ++i) ray[i] = r[i] * yh[i] - y[i];
          const double rate = farkas_rate(problem, ray);
          spdlog::debug("{}: infeasible; the dual's growth over {} iterations more {} a Farkas ray (rate {:.4g})", name(),
                        options_.ray_iterations, rate > 0.0 ? "is" : "is not", rate);
          if (rate > 0.0) result.ray = std::move(ray);
        }
        result.y = std::move(y);
        break;
      }
    }

    // An infeasible LP's primal residual stalls while its dual bound climbs without limit; the
    // watch (divergence_watch.hpp) says when that has gone on long enough. The window is 512
    // iterations: FAUST_r 020-024's finest reduced LP (10.9 M variables) had its residual at
    // 8.2e-3, 7.5e-3, 7.4e-3 after 1536, 2048, 3072 iterations while its bound rose 27.6, 31.1,
    // 43.6 against an objective of 25; a 1024-iteration window stopped it at 3072 (4.3 min on 2
    // cores), this one at 2048, and its rule on the gap at 1024.
    if (params.stop_on_divergence && total >= window_end) {
      std::vector<double> xh, yh;
      backend->read(xh, yh);
      const bool watched = watch.diverging(primal, gap, s.cx, dual_obj) && !window_y.empty();
      // A bound past params.divergence_bound, confirmed in double precision (the running one is
      // an fp32 reduction on a device).
      double certified = -std::numeric_limits<double>::infinity();
      if (!window_y.empty() && dual_obj * problem.objective_scale > params.divergence_bound) {
        std::vector<double> y(m);
        for (int64_t i = 0; i < m; ++i) y[i] = r[i] * yh[i];
        certified = certified_lower_bound(problem, y);
      }
      const bool bounded = certified > params.divergence_bound;
      const bool diverging = watched || bounded;
      const bool debug = !window_y.empty() && spdlog::should_log(spdlog::level::debug);
      std::vector<double> ray;  // the window's dual growth: about a Farkas ray where the LP is infeasible
      if (diverging || debug) {
        ray.resize(m);
        for (int64_t i = 0; i < m; ++i) ray[i] = r[i] * (yh[i] - window_y[i]);
      }
      if (debug) {  // how far from a proof (diagnostic)
        double bd = 0.0;
        for (int64_t i = 0; i < m; ++i) bd += problem.b[i] * ray[i];
        spdlog::debug("{}: window to {} it: the dual's growth has bᵀd {:.4g}, Farkas rate {:.4g}{}", name(), total,
                      bd, farkas_rate(problem, ray),
                      watched   ? " (the watch stops it)"
                      : bounded ? fmt::format(" (stopped: its certified bound {:.6g} is above {:.6g})", certified,
                                              params.divergence_bound)
                                : std::string());
      }
      if (diverging) {
        result.status = LpStatus::Diverging;
        result.y = std::move(ray);
        result.last_y.resize(m);
        for (int64_t i = 0; i < m; ++i) result.last_y[i] = r[i] * yh[i];
        result.x.resize(n);
        for (int64_t j = 0; j < n; ++j) result.x[j] = d[j] * xh[j];
        break;
      }
      window_y = std::move(yh);
      window_end = total + detail::DivergenceWatch::kWindow;
    }

    // Restarts on the fixed-point residual (cuPDLPx): sufficient decay, necessary decay without
    // progress, or a long stretch since the last restart.
    if (restart_base >= 0.0 &&
        (fixed_point <= options_.restart_sufficient * restart_base ||
         (fixed_point <= options_.restart_necessary * restart_base && fixed_point > previous) ||
         k >= restart_artificial * (total + before))) {
      const auto [dx2, dy2] = backend->restart();
      const double dx = std::sqrt(dx2), dy = std::sqrt(dy2);
      if (dx > 1e-10 && dy > 1e-10) {
        const double theta = options_.primal_weight_smoothing;
        omega = std::exp(theta * std::log(dy / dx) + (1.0 - theta) * std::log(omega));
      }
      ++restarts;
      k = 0;
      restart_base = fixed_point;
      previous = std::numeric_limits<double>::infinity();
    } else {
      if (restart_base < 0.0) restart_base = fixed_point;
      previous = fixed_point;
    }

    // A point to start this solve again from, for the caller's checkpoint (SolverParams::snapshot),
    // taken where the next batch starts (after a restart) so that its exact state is whole.
    // (At once where a stop is asked for: request_stop.)
    const double wait =
        snapshots == 0 && params.snapshot_first_seconds >= 0.0 ? params.snapshot_first_seconds : params.snapshot_seconds;
    const bool stopping = stop_requested() != 0;
    if (params.snapshot && params.snapshot_seconds > 0.0 && (since_snapshot.seconds() >= wait || stopping)) {
      SolveSnapshot snap;
      backend->read(snap.x, snap.y);
      for (int64_t j = 0; j < n; ++j) snap.x[j] *= d[j];  // (in place: at 30 M columns each copy counts)
      for (int64_t i = 0; i < m; ++i) snap.y[i] *= r[i];
      snap.primal_weight = omega;
      snap.iterations = total;
      snap.seconds = clock.seconds();
      if (params.stop_on_divergence) snap.watch = watch.state();
      // (None at the iteration cap, where the loop ends: a solve gone on from there would make one more.)
      if (exact && total < params.max_iterations) {
        auto state = std::make_shared<SolverState>();
        if (backend->read_state(state->x, state->x0, state->y, state->y0)) {
          state->solver = name();
          state->device = result.device;
          state->fingerprint = print;
          state->window_y = window_y;
          state->step = eta;
          state->primal_weight = omega;
          state->restart_artificial = restart_artificial;
          state->restart_base = restart_base;
          state->previous = previous;
          state->since_restart = k;
          state->iterations = total + before;
          state->window_left = window_end - total;
          state->restarts = restarts;
          state->watch = watch.state();
          snap.state = std::move(state);
        }
      }
      params.snapshot(snap);
      since_snapshot.reset();
      ++snapshots;
    }
    if (stopping) throw Stopped(fmt::format("stopped in an LP after {} iterations", total));
  }

  if (result.status == LpStatus::Diverging) {
    // (Valid for any y: the growth's is weak, the last iterate's the one divergence_bound saw.)
    result.lower_bound = std::max(certified_lower_bound(problem, result.y), certified_lower_bound(problem, result.last_y));
  } else if (result.status != LpStatus::Infeasible) {
    std::vector<double> xh, yh;
    backend->read(xh, yh);
    result.x.resize(n);
    result.y.resize(m);
    for (int64_t j = 0; j < n; ++j) result.x[j] = d[j] * xh[j];
    for (int64_t i = 0; i < m; ++i) result.y[i] = r[i] * yh[i];
    evaluate_solution(problem, result);
  } else {
    result.lower_bound = certified_lower_bound(problem, result.y);
  }
  result.iterations = total;
  result.primal_weight = omega;
  result.seconds = clock.seconds();
  // The summary line (its max |y| a pass over the duals: only where it is logged).
  if (result.status == LpStatus::Infeasible && spdlog::should_log(spdlog::level::debug)) {
    double top = 0.0;
    for (double v : result.y) top = std::max(top, std::abs(v));
    spdlog::debug("{}: infeasible after {} iterations and {} restarts ({:.3f} s); its proof's bound {:.4g} against "
                  "{:.4g}, max |y| {:.3g}",
                  name(), total, restarts, result.seconds, result.lower_bound,
                  problem.objective_scale * largest_objective, top);
  } else if (result.status != LpStatus::Infeasible) {
    spdlog::debug("{}: {} after {} iterations and {} restarts ({:.3f} s); residual {:.3g} relative, {:.3g} in a row",
                  name(), to_string(result.status), total, restarts, result.seconds, result.primal_residual,
                  result.row_residual);
  }
  return result;
}

double pdhg_bytes_per_iteration(const LpProblem& problem) {
  const double n = double(problem.cols()), m = double(problem.rows()), nnz = double(problem.nonzeros());
  const double primal = 4.0 * (n + 1) + (4.0 + 8.0) * nnz + 8.0 * 4 * n + 8.0 * 2 * n;
  const double dual = 4.0 * (m + 1) + (4.0 + 8.0) * nnz + 8.0 * 4 * m + 8.0 * 2 * m;
  return primal + dual;
}

double pdhg_bytes_per_iteration_f32(const LpProblem& problem) {
  const double n = double(problem.cols()), m = double(problem.rows()), nnz = double(problem.nonzeros());
  const double primal = 4.0 * (n + 1) + (4.0 + 4.0) * nnz + 4.0 * 4 * n + 4.0 * 2 * n;
  const double dual = 4.0 * (m + 1) + (4.0 + 4.0) * nnz + 4.0 * 3 * m + 4.0 * 2 * m;
  return primal + dual;
}

}  // namespace shapematch
