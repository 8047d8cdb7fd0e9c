// `shapematch lp X Y`: build the single-level LP relaxation and solve it with one backend.
#include "commands.hpp"
#include "inputs.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/json.hpp"
#include "shapematch/matching.hpp"
#include "shapematch/pdhg.hpp"
#include "shapematch/system.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <iostream>

namespace shapematch::app {
namespace {

struct LpArgs {
  PairArgs pair;
  std::string solver = "clp-dual";
  std::string json_path, mps_path, lp_path, from;
  SolverParams params;
  PdhgOptions pdhg;
  bool zero_cost = false;
};

int run_lp(const LpArgs& args) {
  Stopwatch total;
  Json out = Json::object();
  Stopwatch build_clock;
  LpProblem lp;
  if (!args.from.empty()) {
    if (!args.pair.x.empty()) throw InvalidInputError("give meshes X Y or --from, not both");
    lp = read_lp(args.from);
    out.set("from", args.from);
  } else {
    const MeshPair p = load_pair(args.pair);
    const Mesh& x = p.x;
    const Mesh& y = p.y;
    const Geometry gx = compute_geometry(x), gy = compute_geometry(y);
    lp = std::move(build_matching_lp(x, gx, y, gy, matching_options(args.pair, p)).lp);
    out.set("x", x.name).set("y", y.name);
    out.set("faces_x", x.num_faces()).set("faces_y", y.num_faces());
  }
  const double build_seconds = build_clock.seconds();
  spdlog::info("LP: {} variables, {} constraints, {} nonzeros ({:.2f} s)", lp.cols(), lp.rows(), lp.nonzeros(),
               build_seconds);
  if (!args.mps_path.empty()) write_mps(lp, args.mps_path);
  if (!args.lp_path.empty()) write_lp(lp, args.lp_path);
  // A feasibility problem: how soon a solver proves an LP infeasible without costs to chase.
  if (args.zero_cost) std::fill(lp.c.begin(), lp.c.end(), 0.0);
  out.set("zero_cost", args.zero_cost);

  const LpResult r = make_solver(args.solver, args.pdhg)->solve(lp, args.params);
  spdlog::info("{}: {} after {} iterations, objective {:.9g} ({:.2f} s)", r.solver, to_string(r.status),
               r.iterations, r.objective, r.seconds);

  out.set("variables", lp.cols()).set("constraints", lp.rows()).set("nonzeros", lp.nonzeros());
  out.set("solver", r.solver).set("device", r.device);
  out.set("status", to_string(r.status));
  out.set("objective", r.objective).set("lower_bound", r.lower_bound);
  out.set("primal_residual", r.primal_residual).set("dual_residual", r.dual_residual).set("gap", r.gap);
  out.set("iterations", r.iterations).set("primal_weight", r.primal_weight);
  out.set("seconds", r.seconds).set("setup_seconds", r.setup_seconds);
  out.set("build_seconds", build_seconds).set("total_seconds", total.seconds());
  out.set("peak_rss_mb", peak_rss_mb());
  const std::string text = out.dump();
  std::cout << text << std::endl;
  if (!args.json_path.empty()) write_file_atomic(args.json_path, text + "\n");
  return r.status == LpStatus::Optimal || r.status == LpStatus::Infeasible ? 0 : 3;
}

}  // namespace

Action add_lp_command(CLI::App& app) {
  auto args = std::make_shared<LpArgs>();
  add_pair_options(app, args->pair);
  app.add_option("--solver", args->solver, "LP backend")
      ->check(CLI::IsMember(solver_names()))
      ->capture_default_str();
  app.add_option("--json", args->json_path, "also write the JSON result to this file");
  app.add_option("--from", args->from, "solve the LP in this file (shapematch's LP format, e.g. from `match "
                                      "--dump-first-lps`) instead of the one of meshes X and Y");
  app.add_option("--export-mps", args->mps_path, "write the LP in MPS format");
  app.add_option("--export-lp", args->lp_path, "write the LP in shapematch's binary LP format");
  app.add_option("--tol", args->params.tolerance, "relative tolerance (first-order solvers)")
      ->check(positive_number())
      ->capture_default_str();
  app.add_option("--max-iter", args->params.max_iterations, "iteration limit")->check(positive_number());
  app.add_option("--time-limit", args->params.time_limit, "time limit in seconds")->check(positive_number());
  app.add_option("--initial-primal-weight", args->params.initial_primal_weight,
                 "PDHG's primal weight ω to start from (0: the solver's own)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--threads", args->params.threads, "CPU threads (0: all)")->check(non_negative_number());
  app.add_option("--primal-weight-smoothing", args->pdhg.primal_weight_smoothing,
                 "PDHG: at a restart log ω moves this fraction of the way to log(Δy/Δx)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--restart-artificial", args->pdhg.restart_artificial,
                 "PDHG: restart when this fraction of all iterations passed since the last restart")
      ->check(CLI::Range(0.01, 1.0))
      ->capture_default_str();
  app.add_flag("--stop-on-divergence", args->params.stop_on_divergence,
               "stop PDHG where the divergence watch says the LP behaves like an infeasible one");
  app.add_flag("--zero-cost", args->zero_cost,
               "solve with every cost set to 0 (a feasibility problem; after --export-mps/--export-lp)");
  return [args] { return run_lp(*args); };
}

}  // namespace shapematch::app
