#include "clp_solver.hpp"

#include "shapematch/errors.hpp"
#include "shapematch/system.hpp"

#include <ClpSimplex.hpp>
#include <ClpSolve.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>

namespace shapematch {
namespace {

// Clp takes A column-major: the rows of our Aᵀ are exactly its columns.
void load(ClpSimplex& model, const LpProblem& p) {
  const int64_t n = p.cols(), m = p.rows();
  if (p.at.row_ptr.back() > uint32_t(std::numeric_limits<CoinBigIndex>::max()))
    throw SolverError("Clp: too many nonzeros");
  std::vector<CoinBigIndex> start(p.at.row_ptr.begin(), p.at.row_ptr.end());
  std::vector<int> index(p.at.entry.size());
  std::vector<double> value(p.at.entry.size());
  for (size_t k = 0; k < p.at.entry.size(); ++k) {
    index[k] = static_cast<int>(col_of(p.at.entry[k]));
    value[k] = is_negative(p.at.entry[k]) ? -1.0 : 1.0;
  }
  std::vector<double> lo(n, 0.0), hi(n, 1.0);
  model.loadProblem(static_cast<int>(n), static_cast<int>(m), start.data(), index.data(), value.data(),
                    lo.data(), hi.data(), p.c.data(), p.b.data(), p.b.data());
}

}  // namespace

LpResult ClpSolver::solve(const LpProblem& problem, const SolverParams& params) {
  problem.check();
  Stopwatch clock;
  ClpSimplex model;
  model.setLogLevel(params.verbose ? 1 : 0);
  load(model, problem);
  if (std::isfinite(params.time_limit)) model.setMaximumSeconds(params.time_limit);
  if (params.max_iterations < std::numeric_limits<int>::max())
    model.setMaximumIterations(static_cast<int>(params.max_iterations));

  ClpSolve options;
  if (method_ == Method::DualSimplex) {
    options.setSolveType(ClpSolve::useDual);
    if (params.farkas_ray) options.setPresolveType(ClpSolve::presolveOff);
  } else {
    options.setSolveType(ClpSolve::useBarrier);  // with crossover to an exact vertex
  }
  // No interrupt handling of Clp's: it would take SIGINT during the solve (an LP cut short, the
  // run going on) and put the program's handler back without its flags (match --checkpoint's stop
  // on a signal; test_lp).
  options.setSpecialOption(2, 1);
  model.initialSolve(options);

  LpResult r;
  r.solver = name();
  r.device = "cpu (Clp, 1 thread)";
  r.seconds = clock.seconds();
  r.iterations = model.numberIterations();
  switch (model.status()) {
    case 0: r.status = LpStatus::Optimal; break;
    case 1: r.status = LpStatus::Infeasible; break;
    case 3:
      r.status = (std::isfinite(params.time_limit) && r.seconds >= params.time_limit * 0.99) ? LpStatus::TimeLimit
                                                                                         : LpStatus::IterationLimit;
      break;
    default: r.status = LpStatus::NumericalTrouble; break;
  }
  if (r.status == LpStatus::Infeasible) {
    // Clp's Farkas ray where it kept one (callers use it to tell which rows clash; sign is Clp's).
    if (double* ray = model.infeasibilityRay()) {
      r.y.assign(ray, ray + problem.rows());
      delete[] ray;
    }
  } else {
    const double* x = model.primalColumnSolution();
    const double* y = model.dualRowSolution();
    r.x.assign(x, x + problem.cols());
    r.y.assign(y, y + problem.rows());
    evaluate_solution(problem, r);
    if (r.status == LpStatus::Optimal) r.objective = problem.objective_scale * model.objectiveValue();
  }
  return r;
}

void ClpSolver::write_mps(const LpProblem& problem, const std::string& path) {
  problem.check();
  ClpSimplex model;
  model.setLogLevel(0);
  load(model, problem);
  const std::string tmp = path + ".tmp";
  if (model.writeMps(tmp.c_str(), 1 /* extra accuracy */) != 0) {
    std::remove(tmp.c_str());
    throw IoError(path + ": cannot write MPS");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw IoError(path + ": " + ec.message());
}

void write_mps(const LpProblem& problem, const std::string& path) { ClpSolver::write_mps(problem, path); }

}  // namespace shapematch
