// `shapematch lp X Y`: build the single-level LP relaxation and solve it with one backend.
#include "commands.hpp"
#include "inputs.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/json.hpp"
#include "shapematch/matching.hpp"
#include "shapematch/system.hpp"

#include <spdlog/spdlog.h>

#include <iostream>

namespace shapematch::app {
namespace {

struct LpArgs {
  PairArgs pair;
  std::string solver = "clp-dual";
  std::string json_path, mps_path;
  SolverParams params;
};

int run_lp(const LpArgs& args) {
  Stopwatch total;
  const MeshPair p = load_pair(args.pair);
  const Mesh& x = p.x;
  const Mesh& y = p.y;
  Stopwatch build_clock;
  const Geometry gx = compute_geometry(x), gy = compute_geometry(y);
  const MatchingLp m = build_matching_lp(x, gx, y, gy, matching_options(args.pair, p));
  const double build_seconds = build_clock.seconds();
  spdlog::info("LP: {} variables, {} constraints, {} nonzeros ({:.2f} s)", m.lp.cols(), m.lp.rows(),
               m.lp.nonzeros(), build_seconds);
  if (!args.mps_path.empty()) write_mps(m.lp, args.mps_path);

  const LpResult r = solve_lp(m.lp, args.solver, args.params);
  spdlog::info("{}: {} after {} iterations, objective {:.9g} ({:.2f} s)", r.solver, to_string(r.status),
               r.iterations, r.objective, r.seconds);

  Json out = Json::object();
  out.set("x", x.name).set("y", y.name);
  out.set("faces_x", x.num_faces()).set("faces_y", y.num_faces());
  out.set("variables", m.lp.cols()).set("constraints", m.lp.rows()).set("nonzeros", m.lp.nonzeros());
  out.set("solver", r.solver).set("device", r.device);
  out.set("status", to_string(r.status));
  out.set("objective", r.objective).set("lower_bound", r.lower_bound);
  out.set("primal_residual", r.primal_residual).set("dual_residual", r.dual_residual).set("gap", r.gap);
  out.set("iterations", r.iterations);
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
  app.add_option("--export-mps", args->mps_path, "write the LP in MPS format");
  app.add_option("--tol", args->params.tolerance, "relative tolerance (first-order solvers)")->capture_default_str();
  app.add_option("--max-iter", args->params.max_iterations, "iteration limit");
  app.add_option("--time-limit", args->params.time_limit, "time limit in seconds");
  return [args] { return run_lp(*args); };
}

}  // namespace shapematch::app
