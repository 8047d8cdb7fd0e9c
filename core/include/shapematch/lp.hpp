#pragma once
// Linear programs of the form  min cᵀx  s.t.  A x = b,  0 ≤ x ≤ 1,  A with entries ±1,
// and the solver interface (HiGHS/cuPDLPx style: problem + parameters in, result out, with a
// termination status that is separate from whether the call itself worked).
#include "shapematch/sparse.hpp"

#include <cstdint>
#include <limits>
#include <memory>
#include <functional>
#include <string>
#include <vector>

namespace shapematch {

struct LpProblem {
  SignedCsr a;                  // m x n, entries ±1
  SignedCsr at;                 // n x m, the transpose (kept explicitly for gather-only SpMV)
  std::vector<double> b;        // m
  std::vector<double> c;        // n, already scaled for conditioning
  double objective_scale = 1.0; // reported objective = objective_scale * cᵀx

  int64_t rows() const { return a.rows; }
  int64_t cols() const { return a.cols; }
  int64_t nonzeros() const { return static_cast<int64_t>(a.entry.size()); }
  // Throws InvalidInputError if the sizes disagree or a value is not finite.
  void check() const;
};

enum class LpStatus {
  Optimal,         // converged to the requested tolerance (exact for simplex)
  Infeasible,      // certified primal infeasible
  IterationLimit,
  TimeLimit,
  NumericalTrouble,
  // Not certified (first-order methods, only with SolverParams::stop_on_divergence): the primal
  // residual stalled while the dual bound kept rising past the objective, the way an infeasible
  // LP behaves. `y` is the dual's growth over the last window: about a Farkas ray.
  Diverging,
};
const char* to_string(LpStatus status);

// PDHG's divergence watch as it stood at a window's end (detail::DivergenceWatch), so that a solve
// started again from a snapshot watches on from there rather than from its first window (about:
// its next window ends 512 iterations after the snapshot, so it spans up to 1 023 of the
// uninterrupted solve's, its dual growth measured from the snapshot's dual).
// Measured (TOSCA_r dog3-dog8 at full resolution, level 6's 12.7 M-variable first LP): a run gone
// on from its checkpoint after 7 232 iterations, four windows into the patient watch's eight, started
// them over: 2 560 iterations more on one thread before it could stop.
struct DivergenceWatchState {
  int windows = 0;   // seen so far (0: a fresh watch)
  int creeping = 0;  // windows in a row of the creeping rule
  int climbing = 0;  // … of the patient rule
  double primal = 0.0, gap = 0.0, bound = 0.0;  // the last window's
  double excess[2] = {0.0, 0.0};                // bound − objective two windows back and one back
  bool operator==(const DivergenceWatchState&) const = default;
};

// The whole state of a PDHG solve between two batches of iterations (SolverParams::exact_state):
// going on from it (SolverParams::resume_state) repeats, bit for bit, the iterations the solve
// would have made uninterrupted, on the same backend and device (thread count, GPU; elsewhere the
// same point goes on, not bit for bit: sums add in another order). The vectors are the
// backend's, in its scaled space (opaque to callers: for pdhg-cpu-f32, which keeps none, no state).
struct SolverState {
  std::string solver;            // the solver that made it (its name())
  std::string device;            // … and where (LpResult::device: the CPU threads, the GPU)
  uint64_t fingerprint = 0;      // of the LP, its scaling and the solver's options
  std::vector<double> x, x0;     // the iterate and its Halpern anchor (columns)
  std::vector<double> y, y0;     // … (rows)
  std::vector<double> window_y;  // the dual at the divergence watch's window start (empty: none yet)
  double step = 0.0;             // η (from the Lanczos estimate of ‖Ã‖)
  double primal_weight = 0.0;    // ω
  double restart_artificial = 0.0, restart_base = -1.0, previous = 0.0;
  int64_t since_restart = 0;     // the Halpern index k
  int64_t iterations = 0;        // the solve's count for its artificial restarts (those before included)
  int64_t window_left = 0;       // iterations to the watch window's end
  int restarts = 0;
  DivergenceWatchState watch;
  bool operator==(const SolverState&) const = default;
};

// A point a first-order solve could start again from (SolverParams::snapshot).
struct SolveSnapshot {
  std::vector<double> x, y;   // in the problem's units
  double primal_weight = 0.0;  // PDHG's ω there
  int64_t iterations = 0;      // so far
  double seconds = 0.0;        // so far, its set-up included
  DivergenceWatchState watch;  // at the last window's end (fresh where the solve was not watched)
  // With SolverParams::exact_state, where the solver keeps one: its whole state, to go on exactly.
  std::shared_ptr<const SolverState> state;
};

struct SolverParams {
  double tolerance = 1e-4;        // relative primal residual and gap (first-order methods)
  int64_t max_iterations = 1'000'000;
  double time_limit = std::numeric_limits<double>::infinity();  // seconds
  int threads = 0;                // 0 = all hardware threads
  int device = -1;                // Vulkan device index, -1 = preferred
  bool verbose = false;
  // Stop early with LpStatus::Diverging when the iterates behave like an infeasible LP's (see
  // there). For callers that only need to know where to enlarge an LP, not a proof: PDHG's
  // certificate of infeasibility takes long to emerge (a 10 k-face reduced matching LP: its dual
  // bound rose by about 1.4 every 64 iterations, and the proof came after 10 minutes).
  bool stop_on_divergence = false;
  // Exact solvers: solve without presolve, so that an infeasible LP comes with its Farkas ray
  // (Clp's presolve finds some infeasibilities itself and then keeps none).
  bool farkas_ray = false;
  // With stop_on_divergence: only the slowest climb stops it, held twice as long
  // (detail::DivergenceWatch, patient). For an LP whose earlier suspicions came to nothing.
  bool patient_divergence_watch = false;
  // With stop_on_divergence: a dual iterate whose certified bound (certified_lower_bound, in
  // double precision) lies above this at a window's end stops the LP as Diverging too, whatever
  // the watch's rules say: its optimum lies above it. For a caller that knows no optimum that high
  // is worth finishing (coarse to fine: CoarseToFineOptions::divergence_bound_factor). +∞: never.
  double divergence_bound = std::numeric_limits<double>::infinity();
  // With stop_on_divergence and a warm start: the watch to go on from (a snapshot's `watch`; its
  // windows restart at this solve's start). Fresh by default.
  DivergenceWatchState initial_watch;
  // With a warm start that goes on from a snapshot of this LP: the iterations it had made. PDHG's
  // artificial restart (after a fraction of all the iterations so far) counts them, so that the
  // solve restarts about as the uninterrupted one would have (the snapshot is a restart point: the
  // count since the last restart starts there) rather than as a cold start does, at every
  // residual check at first, each restart moving ω. Measured (TOSCA_r dog3-dog8 at full
  // resolution, level 6's 12.7 M-variable first LP gone on after 7 232 iterations at ω 24.3): ω
  // went 69, 303, 1 420, 5 430 in the first 832 iterations, 72 500 by 1 984.
  int64_t iterations_before = 0;
  // PDHG: snapshots carry the solve's whole state (SolveSnapshot::state; two copies of the
  // iterate more than the point alone).
  bool exact_state = false;
  // PDHG: go on from this state (an earlier solve's snapshot of the same LP by the same solver)
  // instead of from initial_x/initial_y and the step, ω and restarts they would get; ignored where
  // it belongs to another LP or solver. max_iterations still counts this solve's iterations only.
  std::shared_ptr<const SolverState> resume_state;
  // Warm start (first-order methods): both empty or of the right sizes.
  std::vector<double> initial_x;
  std::vector<double> initial_y;
  // PDHG's primal weight ω to start from (0: the solver's own choice). A warm start near an
  // optimum wants the ω that solve ended with: started at 1, a re-solve moved its iterate away
  // from the optimum it was given before ω came back (FAUST_r 026-029's finest LP after pricing:
  // the primal residual went 2.5e-3 → 0.21 in 64 iterations, and took 768 to come back).
  double initial_primal_weight = 0.0;
  // … and the one for a cold start (no initial_x), where initial_primal_weight is 0 (0: the
  // solver's own). Warm starts keep theirs: started at a high ω, a re-solve from an optimum
  // hit its iteration cap (FAUST_r 020-024 at 2 000 faces, ω 30).
  double cold_primal_weight = 0.0;
  // PDHG's artificial restart fraction for a cold start (0: the solver's own); warm starts keep
  // theirs. At 0.2 against 0.36: six first LPs dumped from horse0-horse5, -21 % iterations; three
  // FAUST_r pairs at 2 000 faces, -10 to -26 % of PDHG's work; FAUST_r 021-024 at full resolution
  // took another path to a harder finest LP and more work. Hence not the default.
  double cold_restart_artificial = 0.0;
  // PDHG: called every snapshot_seconds at most (at a residual check) with the point a restart
  // would start from, so that a long solve can be checkpointed and started again near where it
  // was (coarse to fine: CoarseToFineOptions::lp_checkpoint_seconds). Other solvers do not call
  // it. 0 or unset: never.
  std::function<void(const SolveSnapshot&)> snapshot;
  double snapshot_seconds = 0.0;
  // The first call's wait, where ≥ 0 (then every snapshot_seconds): for a caller whose own clock
  // started before this solve (a round solved in parts). < 0: snapshot_seconds.
  double snapshot_first_seconds = -1.0;
};

struct LpResult {
  LpStatus status = LpStatus::NumericalTrouble;
  double objective = std::numeric_limits<double>::quiet_NaN();    // objective_scale * cᵀx
  double lower_bound = -std::numeric_limits<double>::infinity();  // certified, see certified_lower_bound
  double primal_residual = std::numeric_limits<double>::quiet_NaN();  // ‖Ax−b‖₂ / (1 + ‖b‖₂)
  // ‖Ax−b‖∞ (NaN without x, e.g. a Diverging PDHG result). The relative residual could hide a
  // row far off in an LP of 10⁵ rows (at 3e-3 and ‖b‖₂ ≈ 200, one row off by a half); measured,
  // FAUST_r 043-065's level 6 at full resolution: 467 of rounding's PDHG solves ended with at
  // most 0.018 in a row (seventy-second session).
  double row_residual = std::numeric_limits<double>::quiet_NaN();
  double dual_residual = std::numeric_limits<double>::quiet_NaN();    // relative
  double gap = std::numeric_limits<double>::quiet_NaN();  // |objective − bound| / (1 + |objective| + |bound|)
  std::vector<double> x;
  std::vector<double> y;
  // Diverging only (y holds the dual's growth there): the dual iterate where it stopped. There
  // lower_bound is the better of the two duals' certified bounds.
  std::vector<double> last_y;
  // Infeasible (PDHG, with PdhgOptions::ray_iterations): the dual's growth over those iterations
  // after the proof, where that is a Farkas ray (empty otherwise). Its large entries name the
  // rows of the infeasibility; y's also hold the ordinary duals, which can outweigh a ray still
  // short. (Rounding names a proof's rows by y: at full resolution this was never a ray.)
  std::vector<double> ray;
  int64_t iterations = 0;
  // PDHG's primal weight ω where it stopped (scaled space); NaN for other solvers.
  double primal_weight = std::numeric_limits<double>::quiet_NaN();
  double seconds = 0.0;
  // Of `seconds`, the part before the first iteration: scaling, the ‖A‖ estimate, the device's
  // set-up and the upload (PDHG; 0 for Clp). Time per iteration excludes it.
  double setup_seconds = 0.0;
  std::string solver;
  std::string device;
};

class LpSolver {
public:
  virtual ~LpSolver() = default;
  virtual std::string name() const = 0;
  // Throws SolverError/DeviceError when the call itself fails; LP outcomes are statuses.
  virtual LpResult solve(const LpProblem& problem, const SolverParams& params) = 0;
};

// "clp-dual", "clp-barrier" (and later "pdhg-cpu", "pdhg-vulkan"). Throws InvalidInputError
// for an unknown name.
std::unique_ptr<LpSolver> make_solver(const std::string& name);
std::vector<std::string> solver_names();

// One-off convenience.
LpResult solve_lp(const LpProblem& problem, const std::string& solver, const SolverParams& params = {});

// L(y) = bᵀy + Σ_j min(0, (c − Aᵀy)_j) in the problem's reported units (times objective_scale):
// a lower bound on the LP optimum for ANY y because 0 ≤ x ≤ 1. Evaluated in double precision.
// Where every cost is ≥ 0 (every matching LP), max(L(y), 0): 0 bounds such an LP too, and an
// optimum of 0 (a shape matched with itself) would otherwise have a bound a little below it, its
// relative gap 100 %.
double certified_lower_bound(const LpProblem& problem, const std::vector<double>& y);

// How L(y + t·d) grows with t → ∞: bᵀd + Σ_j min(0, −(Aᵀd)_j), costs aside. Positive proves the
// LP infeasible (Farkas: any feasible x has bᵀd = xᵀAᵀd ≤ Σ_j max(0, (Aᵀd)_j)); a diverging
// PDHG's dual growth is such a ray only where the LP is infeasible. In the problem's own units.
double farkas_rate(const LpProblem& problem, const std::vector<double>& d);

// An upper bound on cᵀx over every feasible x (0 ≤ x ≤ 1, A x = b), in the problem's own units
// (not times objective_scale). A row with only +1 entries and b_i ≥ 0 caps the sum of its
// columns at b_i, so the columns assigned to it add at most b_i times their largest positive
// cost; a column in no such row adds its own positive cost. Any y with L(y) above it proves the
// LP infeasible. On matching LPs every column lies in a face's projection row, which makes this
// about the number of faces times a typical cost, not the sum over all product triangles.
double objective_upper_bound(const LpProblem& problem);
// Fills residual and gap fields of `result` from its x and y, in double precision.
void evaluate_solution(const LpProblem& problem, LpResult& result);

// Writes the LP in free MPS format (through a temporary file renamed into place).
void write_mps(const LpProblem& problem, const std::string& path);

// The LP in shapematch's own binary format (docs/formats.md), exactly as solved: A, b, the
// scaled c and objective_scale. For reproducing one LP of a long run on its own (`match
// --dump-first-lps`, `lp --from`). Written through a temporary file renamed into place.
void write_lp(const LpProblem& problem, const std::string& path);
// Throws IoError if the file cannot be read, InvalidInputError (naming the file) if it is not such
// a file or is truncated or inconsistent. Aᵀ is rebuilt.
LpProblem read_lp(const std::string& path);

}  // namespace shapematch
