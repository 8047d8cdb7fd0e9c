#include "clp_solver.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/pdhg.hpp"

namespace shapematch {

std::vector<std::string> solver_names() { return {"pdhg-cpu", "pdhg-cpu-f32", "pdhg-vulkan", "clp-dual", "clp-barrier"}; }

std::unique_ptr<LpSolver> make_solver(const std::string& name) { return make_solver(name, PdhgOptions{}); }

std::unique_ptr<LpSolver> make_solver(const std::string& name, const PdhgOptions& pdhg) {
  if (name == "pdhg-cpu") return std::make_unique<PdhgSolver>(PdhgBackendKind::Cpu, pdhg);
  if (name == "pdhg-cpu-f32") return std::make_unique<PdhgSolver>(PdhgBackendKind::CpuF32, pdhg);
  if (name == "pdhg-vulkan") return std::make_unique<PdhgSolver>(PdhgBackendKind::Vulkan, pdhg);
  if (name == "clp-dual") return std::make_unique<ClpSolver>(ClpSolver::Method::DualSimplex);
  if (name == "clp-barrier") return std::make_unique<ClpSolver>(ClpSolver::Method::Barrier);
  std::string known;
  for (const auto& s : solver_names()) known += (known.empty() ? "" : ", ") + s;
  throw InvalidInputError("unknown solver '" + name + "' (known: " + known + ")");
}

}  // namespace shapematch
