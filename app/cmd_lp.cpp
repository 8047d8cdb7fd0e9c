// `shapematch lp X Y`: build the single-level LP relaxation and solve it with one backend.
#include "commands.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/json.hpp"
#include "shapematch/matching.hpp"
#include "shapematch/system.hpp"

#include <spdlog/spdlog.h>

#include <iostream>

namespace shapematch::app {
namespace {

struct LpArgs {
  std::string x, y;
  std::string solver = "clp-dual";
  std::string json_path, mps_path;
  int faces = 0;
  bool keep_scale = false;
  double bending = 1.0;
  std::vector<double> lame{1.0, 1.0};
  SolverParams params;
};

int run_lp(const LpArgs& args) {
  Stopwatch total;
  LoadOptions load;
  load.normalize_area = !args.keep_scale;
  Mesh x = load_mesh(args.x, load);
  Mesh y = load_mesh(args.y, load);
  if (args.faces > 0) {
    x = decimate(x, args.faces);
    y = decimate(y, args.faces);
  }
  spdlog::info("X: {} ({} faces), Y: {} ({} faces)", x.name, x.num_faces(), y.name, y.num_faces());
  const Geometry gx = compute_geometry(x), gy = compute_geometry(y);

  MatchingLpOptions options;
  options.energy.bending_weight = args.bending;
  options.energy.lame_lambda = args.lame.at(0);
  options.energy.lame_mu = args.lame.at(1);
  Stopwatch build_clock;
  const MatchingLp m = build_matching_lp(x, gx, y, gy, options);
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
  out.set("seconds", r.seconds).set("build_seconds", build_seconds).set("total_seconds", total.seconds());
  out.set("peak_rss_mb", peak_rss_mb());
  const std::string text = out.dump();
  std::cout << text << std::endl;
  if (!args.json_path.empty()) write_file_atomic(args.json_path, text + "\n");
  return r.status == LpStatus::Optimal || r.status == LpStatus::Infeasible ? 0 : 3;
}

}  // namespace

Action add_lp_command(CLI::App& app) {
  auto args = std::make_shared<LpArgs>();
  app.add_option("x", args->x, "first mesh (OFF, OBJ, PLY, STL); default: bundled asset");
  app.add_option("y", args->y, "second mesh; default: bundled asset");
  app.add_option("--solver", args->solver, "LP backend")
      ->check(CLI::IsMember(solver_names()))
      ->capture_default_str();
  app.add_option("--json", args->json_path, "also write the JSON result to this file");
  app.add_option("--export-mps", args->mps_path, "write the LP in MPS format");
  app.add_option("--faces", args->faces, "decimate both meshes to about N faces first")->check(CLI::NonNegativeNumber);
  app.add_flag("--keep-scale", args->keep_scale, "do not normalise both shapes to unit area");
  app.add_option("--bending", args->bending, "bending weight λ")->capture_default_str();
  app.add_option("--lame", args->lame, "Lamé parameters λ,μ of the membrane")->delimiter(',')->expected(2);
  app.add_option("--tol", args->params.tolerance, "relative tolerance (first-order solvers)")->capture_default_str();
  app.add_option("--max-iter", args->params.max_iterations, "iteration limit");
  app.add_option("--time-limit", args->params.time_limit, "time limit in seconds");
  return [args] {
    if (args->x.empty() != args->y.empty()) throw InvalidInputError("give both meshes X and Y, or neither");
    if (args->x.empty()) {
      args->x = default_mesh_x();
      args->y = default_mesh_y();
    }
    return run_lp(*args);
  };
}

}  // namespace shapematch::app
