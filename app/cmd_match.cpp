// `shapematch match X Y`: the whole pipeline — load, LP, rounding, verification, outputs.
#include "commands.hpp"
#include "inputs.hpp"
#include "json_read.hpp"
#include "shapematch/coarse_to_fine.hpp"
#include "shapematch/device.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/json.hpp"
#include "shapematch/evaluation.hpp"
#include "shapematch/files.hpp"
#include "shapematch/matching.hpp"
#include "shapematch/point_map.hpp"
#include "shapematch/render.hpp"
#include "shapematch/rounding.hpp"
#include "shapematch/system.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <optional>
#include <sstream>

#include <fcntl.h>
#include <stdio.h>  // (renameat2)
#include <unistd.h>

namespace fs = std::filesystem;

namespace shapematch::app {
namespace {

struct MatchArgs {
  PairArgs pair{.faces = 100};
  std::string out = "shapematch-out";
  std::string backend = "auto";
  int threads = 0;
  double threshold = 0.5;
  std::vector<double> alternative_thresholds = RoundingOptions{}.alternative_thresholds;
  int64_t alternatives_below = RoundingOptions{}.alternatives_below;
  int max_rounds = RoundingOptions{}.max_rounds;
  double later_round_iterations = RoundingOptions{}.later_round_iterations;
  bool carry_round_weights = RoundingOptions{}.carry_weights;
  double fractional_batch = RoundingOptions{}.fractional_batch;
  bool close_pockets = RoundingOptions{}.close_pockets;
  int untangle_rings = PointMapOptions{}.untangle_rings;
  double untangle_max_shift = PointMapOptions{}.untangle_max_shift;
  bool whole_lp = !RoundingOptions{}.split_parts;
  int64_t greedy_above = RoundingOptions{}.greedy_above;
  int greedy_margin = RoundingOptions{}.greedy_margin;
  double greedy_fallback = RoundingOptions{}.greedy_fallback;
  bool remember_refuted = RoundingOptions{}.remember_refuted;
  bool certificate_release = RoundingOptions{}.certificate_release;
  int64_t search_below = RoundingOptions{}.search_below;
  bool search_backjump = RoundingOptions{}.search_backjump;
  bool search_proof_release = RoundingOptions{}.search_proof_release;
  int release_reach_cap = RoundingOptions{}.release_reach_cap;
  bool converged_first = RoundingOptions{}.converged_first;
  double exact_pivots_per_column = RoundingOptions{}.exact_pivots_per_column;
  double exact_part_seconds = RoundingOptions{}.exact_part_seconds;
  int64_t exact_below = RoundingOptions{}.exact_below;
  int64_t feasibility_first = RoundingOptions{}.feasibility_iterations;
  int64_t feasibility_later = RoundingOptions{}.later_feasibility_iterations;
  double feasibility_tol = RoundingOptions{}.feasibility_tolerance;
  int64_t feasibility_skip_below = RoundingOptions{}.later_feasibility_skip_below;
  double feasibility_skip_residual = RoundingOptions{}.later_feasibility_skip_residual;
  double feasibility_skip_row = RoundingOptions{}.later_feasibility_skip_row;
  int release_after_trims = RoundingOptions{}.release_after_trims;
  double tolerance = 1e-4;
  double coarse_tolerance = CoarseToFineOptions{}.coarse_tolerance;
  double time_limit = std::numeric_limits<double>::infinity();
  double cold_primal_weight = 0.0;
  double cold_restart_artificial = 0.0;
  int device = -1;
  HierarchyOptions hierarchy;
  int ring = 1, max_ring = 3;
  int coarse_ring = CoarseToFineOptions{}.coarse_ring;
  int coarse_ring_faces = CoarseToFineOptions{}.coarse_ring_faces;
  std::string neighbourhood = "fine";
  std::string widen = "local";
  int widen_margin = CoarseToFineOptions{}.widen_margin;
  int widen_around = CoarseToFineOptions{}.widen_around;
  int y_margin = CoarseToFineOptions{}.y_margin;
  int max_local_widenings = CoarseToFineOptions{}.max_local_widenings;
  int max_propagation_widenings = CoarseToFineOptions{}.max_propagation_widenings;
  int recurring_margin = CoarseToFineOptions{}.recurring_margin;
  double recurring_max_share = CoarseToFineOptions{}.recurring_max_share;
  int recurring_beyond = CoarseToFineOptions{}.recurring_beyond;
  int proof_beyond = CoarseToFineOptions{}.proof_beyond;
  bool watch_resolve = CoarseToFineOptions{}.watch_resolve;
  int max_suspected_widenings = CoarseToFineOptions{}.max_suspected_widenings;
  int suspicion_rings = CoarseToFineOptions{}.suspicion_rings;
  int suspicion_margins = CoarseToFineOptions{}.suspicion_margins;
  std::string suspicion_margin_around = "widened";
  double divergence_bound_factor = CoarseToFineOptions{}.divergence_bound_factor;
  int zero_cost_proof_rings = CoarseToFineOptions{}.zero_cost_proof_rings;
  double second_start_budget = CoarseToFineOptions{}.second_start_budget;
  bool warm_widening = CoarseToFineOptions{}.warm_widening;
  bool carry_primal_weight = CoarseToFineOptions{}.carry_primal_weight;
  std::string dump_first_lps;
  std::string dump_slow_parts;
  std::string checkpoint;
  int inherit_widening = CoarseToFineOptions{}.inherit_widening;
  int price_dual_sweeps = CoarseToFineOptions{}.price_dual_sweeps;
  double stuck_after = CoarseToFineOptions{}.stuck_after;
  bool stuck_carry = CoarseToFineOptions{}.stuck_carry;
  bool blame_residual = RoundingOptions{}.blame_residual;
  int64_t local_proof = RoundingOptions{}.local_proof_columns;
  std::string local_proof_solver = RoundingOptions{}.local_proof_solver;
  int stuck_carry_margin = CoarseToFineOptions{}.stuck_carry_margin;
  int stuck_restarts = CoarseToFineOptions{}.stuck_restarts;
  double rounding_checkpoint_seconds = CoarseToFineOptions{}.rounding_checkpoint_seconds;
  double lp_checkpoint_seconds = CoarseToFineOptions{}.lp_checkpoint_seconds;
  int stuck_stalled = RoundingOptions{}.stuck_stalled;
  int price_widenings = CoarseToFineOptions{}.price_widenings;
  int lookahead_levels = CoarseToFineOptions{}.lookahead_levels;
  bool lookahead_drop_stuck = CoarseToFineOptions{}.lookahead_drop_stuck;
  bool lookahead_bound_drop = CoarseToFineOptions{}.lookahead_bound_drop;
  double price_threshold = CoarseToFineOptions{}.price_threshold;
  double price_tolerance = CoarseToFineOptions{}.price_tolerance;
  // The diagnostic of CoarseToFineOptions::truth: ground truth as eval takes it.
  std::string truth, truth_x, truth_y, truth_map;
  int truth_rings = CoarseToFineOptions{}.truth_rings;
  int branch_depth = CoarseToFineOptions{}.branch_depth;
  int branch_rings = CoarseToFineOptions{}.branch_rings;
  double branch_min_split = CoarseToFineOptions{}.branch_min_split;
  double branch_gap = CoarseToFineOptions{}.branch_gap;
};

bool truth_given(const MatchArgs& args) {
  return !args.truth.empty() || !args.truth_x.empty() || !args.truth_map.empty();
}

// The true map of CoarseToFineOptions::truth from the ground truth named (none: empty), read
// against the files as loaded for matching.
std::vector<int> true_map(const MatchArgs& args, const MeshPair& p, std::string& name) {
  if (!truth_given(args)) return {};
  LoadOptions load;
  load.close_holes = args.pair.close_holes;
  const Mesh x = load_mesh(p.x_file, load), y = load_mesh(p.y_file, load);
  // (Indexing the files' own vertices: with --close-holes a fan's vertex has no truth.)
  const int xf = p.x_file_vertices, yf = p.y_file_vertices;
  GroundTruth truth;
  if (!args.truth_map.empty()) {
    truth = read_map_ground_truth(args.truth_map, xf, yf);
    name = args.truth_map;
  } else if (!args.truth_x.empty()) {
    truth = read_vts_ground_truth(args.truth_x, args.truth_y, xf, yf);
    name = args.truth_x + " <-> " + args.truth_y;
  } else {
    truth = identity_ground_truth(xf, yf);
    name = "identity";
  }
  try {
    return truth_at(x, y, p.x_ids, p.y_ids, truth);
  } catch (const InvalidInputError& e) {
    throw InvalidInputError(name + ": " + e.what());
  }
}

// auto: a GPU if there is one, else the native solver (lavapipe is for testing, not speed).
std::string solver_for(const MatchArgs& a) {
  if (a.device >= 0 && a.backend != "auto" && a.backend != "vulkan")
    spdlog::warn("--device {} is for the Vulkan backend; --backend {} does not use it", a.device, a.backend);
  if (a.backend == "cpu") return "pdhg-cpu";
  if (a.backend == "cpu-f32") return "pdhg-cpu-f32";
  if (a.backend == "vulkan") return "pdhg-vulkan";
  if (a.backend == "clp") return "clp-dual";
  try {
    const DeviceInfo d = choose_device(a.device);
    if (d.type == "discrete" || d.type == "integrated") return "pdhg-vulkan";
    if (a.device >= 0)  // (asked for by index, yet not a GPU: say why it is not used)
      spdlog::warn("--device {} is {} ({}), not a GPU: --backend auto uses the CPU (--backend vulkan runs on it)",
                   a.device, d.name, d.type);
  } catch (const DeviceError&) {
    if (a.device >= 0) throw;  // a device asked for by index that is not there is an error, not a fallback
  }
  return "pdhg-cpu";
}

std::string lines(const std::vector<int>& values) {
  std::string s;
  for (int v : values) s += std::to_string(v) + "\n";
  return s;
}

// Marker files that tell a later run what a sibling of the output directory is, so that only
// shapematch's own leftovers are ever removed: a temporary output holds kWriting until it is
// renamed into place; an output being replaced gets kReplaced before it is moved aside.
constexpr const char* kWriting = ".shapematch-writing";
constexpr const char* kReplaced = ".shapematch-replaced";

// Whether `dir` holds a match output: its report.json parses with match's keys, and the map is
// there (a folder of the user's with a report.json of its own is not one).
bool is_match_output(const fs::path& dir) {
  std::error_code ec;
  if (!fs::is_regular_file(dir / "report.json", ec) || !fs::is_regular_file(dir / "map_x_to_y.txt", ec)) return false;
  try {
    const JsonNode report = read_json_file((dir / "report.json").string());
    return report.get("energy") && report.get("verified") && report.get("levels");
  } catch (const Error&) {
    return false;
  }
}

// The output directory --out names, absolute. Refused (before any work) unless it does not
// exist yet, is empty, or is an earlier match's output: publish replaces it whole, and a
// mistyped -o must not remove a user's own files.
fs::path output_directory(const std::string& arg) {
  if (arg.empty()) throw InvalidInputError("--out: empty path");
  fs::path out = fs::absolute(arg).lexically_normal();
  if (!out.has_filename()) out = out.parent_path();  // "dir/" names dir
  if (out == out.root_path()) throw InvalidInputError(out.string() + ": the root cannot be an output directory");
  std::error_code ec;
  if (const fs::path cwd = fs::current_path(ec); !ec) {
    const fs::path inside = cwd.lexically_relative(out);
    if (!inside.empty() && *inside.begin() != "..")
      throw InvalidInputError(out.string() + ": is the current directory or holds it (it would be moved away)");
  }
  const fs::file_status status = fs::symlink_status(out, ec);
  if (fs::is_symlink(status))
    throw InvalidInputError(out.string() + ": is a symbolic link; name the directory it points to");
  if (!fs::exists(status)) return out;
  if (!fs::is_directory(status))
    throw InvalidInputError(out.string() + ": exists and is not a directory (--out names the output directory)");
  const bool empty = fs::is_empty(out, ec);
  if (ec) throw IoError(out.string() + ": cannot read (" + ec.message() + ")");
  if (!empty && !is_match_output(out))
    throw InvalidInputError(out.string() + ": exists and is not a match output (no report.json and map of "
                                           "shapematch's); remove it or name another --out");
  return out;
}

// The entries of `folder` named PREFIX + PID whose process has gone: what a run stopped while
// writing (Ctrl-C, killed) leaves and cannot clean up itself. This run's own pid counts as gone
// (nothing of it exists yet when it sweeps); a pid it may not signal, or a name that is no pid, not.
std::vector<fs::path> leftovers(const fs::path& folder, const std::string& prefix) {
  std::vector<fs::path> found;
  std::error_code ec;
  for (auto it = fs::directory_iterator(folder, ec); !ec && it != fs::directory_iterator(); it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string digits = name.substr(prefix.size());
    if (digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
    const pid_t pid = static_cast<pid_t>(std::stol(digits));
    if (pid == ::getpid() || (pid > 0 && ::kill(pid, 0) != 0 && errno == ESRCH)) found.push_back(it->path());
  }
  return found;
}

// A checkpoint's temporary files (CKPT.tmp-PID, files.hpp) left by a run killed while saving it:
// nothing reads them.
void remove_stale_checkpoint_files(const fs::path& checkpoint) {
  std::error_code ec;
  const fs::path folder = fs::absolute(checkpoint, ec).parent_path();
  for (const auto& file : leftovers(folder, checkpoint.filename().string() + ".tmp-")) {
    std::error_code removed;
    if (fs::is_regular_file(file, removed) && fs::remove(file, removed))
      spdlog::info("{}: removed, left by a run killed while saving its checkpoint", file.string());
  }
}

// `out`'s leftovers: OUT.tmp-PID with kWriting (removed) and OUT.old-PID with kReplaced (put back
// where no `out` took its place, the newest if several; else removed). Anything without its
// marker is left alone.
void remove_stale_siblings(const fs::path& out) {
  const auto marked = [](std::vector<fs::path> dirs, const char* marker) {
    std::erase_if(dirs, [&](const fs::path& dir) {
      std::error_code ec;
      return !fs::exists(dir / marker, ec);
    });
    return dirs;
  };
  const std::string name = out.filename().string();
  const std::vector<fs::path> writing = marked(leftovers(out.parent_path(), name + ".tmp-"), kWriting);
  std::vector<fs::path> replaced = marked(leftovers(out.parent_path(), name + ".old-"), kReplaced);
  const auto written = [](const fs::path& dir) {
    std::error_code e;
    return fs::last_write_time(dir / kReplaced, e);
  };
  std::sort(replaced.begin(), replaced.end(), [&](const fs::path& a, const fs::path& b) { return written(a) > written(b); });
  std::error_code none;
  if (!replaced.empty() && !fs::exists(fs::symlink_status(out, none))) {
    std::error_code back;
    fs::rename(replaced.front(), out, back);
    if (!back) {
      fs::remove(out / kReplaced, back);
      spdlog::info("{}: put back as {}, left by a run that stopped while replacing it", replaced.front().string(),
                   out.string());
      replaced.erase(replaced.begin());
    }
  }
  for (const auto& dir : writing) replaced.push_back(dir);
  for (const auto& dir : replaced) {
    std::error_code removed;
    fs::remove_all(dir, removed);
    if (!removed) spdlog::info("{}: removed, left by a run that stopped while writing", dir.string());
  }
}

// `from` renamed to `to` only where `to` does not exist (renameat2's RENAME_NOREPLACE, so that a
// directory made at `to` just before is never replaced or merged; where the file system cannot,
// a plain rename, which fails on a non-empty `to`). False where `to` exists; `ec` any other failure.
bool rename_if_absent(const fs::path& from, const fs::path& to, std::error_code& ec) {
  ec.clear();
  if (::renameat2(AT_FDCWD, from.c_str(), AT_FDCWD, to.c_str(), RENAME_NOREPLACE) == 0) return true;
  if (errno == EEXIST || errno == ENOTEMPTY) return false;
  if (errno != EINVAL && errno != ENOSYS) {
    ec = std::error_code(errno, std::generic_category());
    return true;
  }
  if (fs::exists(fs::symlink_status(to, ec))) return false;
  fs::rename(from, to, ec);
  return !(ec == std::errc::directory_not_empty || ec == std::errc::file_exists);
}

// `from` moved to `name`, or where that exists (a process id used again, as in a container whose
// runs all have the same one) NAME.1, NAME.2, ...: the name it got; empty with `ec` where it
// could not be moved.
fs::path move_aside(const fs::path& from, const std::string& name, std::error_code& ec) {
  for (int k = 0; k < 1000; ++k) {
    const fs::path to = k == 0 ? fs::path(name) : fs::path(name + "." + std::to_string(k));
    if (rename_if_absent(from, to, ec)) return ec ? fs::path() : to;
  }
  ec = std::make_error_code(std::errc::file_exists);
  return {};
}

// `tmp` kept as OUT.new-PID where `out` became something this run may not replace while it
// worked; throws the error that says so (`why`), naming where the output is. (Where it cannot be
// moved, it stays where it is, unmarked, so that nothing removes it.)
[[noreturn]] void keep_beside(const fs::path& tmp, const fs::path& out, const std::string& why) {
  std::error_code ec;
  fs::remove(tmp / kWriting, ec);
  const fs::path kept = move_aside(tmp, out.string() + ".new-" + std::to_string(::getpid()), ec);
  throw IoError(why + " (it changed while this run worked; its output is in " + (kept.empty() ? tmp : kept).string() + ")");
}

// Renames the finished temporary directory `tmp` into place as `out`, so that a failure never
// leaves a half-written output directory. Where `out` has become something this run may not
// replace meanwhile, the output is kept as OUT.new-PID and the error names it. Past this point a
// failure leaves the finished output where the error says (run_match removes `tmp` only while it
// holds kWriting).
void publish(const fs::path& tmp, const fs::path& out) {
  std::error_code ec;
  fs::path old;
  if (fs::exists(fs::symlink_status(out, ec))) {
    try {
      output_directory(out.string());
    } catch (const Error& e) {
      keep_beside(tmp, out, e.what());
    }
    write_file_atomic((out / kReplaced).string(), std::to_string(::getpid()) + "\n");
    old = move_aside(out, out.string() + ".old-" + std::to_string(::getpid()), ec);
    if (old.empty()) {
      const std::string why = ec.message();
      fs::remove(out / kReplaced, ec);
      throw IoError(out.string() + ": cannot replace (" + why + ")");
    }
  }
  fs::remove(tmp / kWriting, ec);
  if (!rename_if_absent(tmp, out, ec)) {  // (made meanwhile: the user's; the output it replaced stays beside)
    std::error_code restore;
    if (!old.empty()) fs::remove(old / kReplaced, restore);
    keep_beside(tmp, out, out.string() + ": was made by someone else just as this run was putting its output there" +
                              (old.empty() ? std::string() : "; the output it replaced is " + old.string()));
  }
  if (ec) {
    const std::string why = ec.message();
    std::error_code restore;
    if (!old.empty() && rename_if_absent(old, out, restore) && !restore) fs::remove(out / kReplaced, restore);
    throw IoError(out.string() + ": " + why + " (its output is left in " + tmp.string() + ")");
  }
  if (!old.empty() && (fs::remove_all(old, ec), ec))
    spdlog::warn("{}: could not remove the previous output ({})", old.string(), ec.message());
}

// SIGINT and SIGTERM while a run with a checkpoint solves: the run leaves off where it can be
// saved (PDHG's next residual check, after a snapshot of its LP where the level keeps one, or
// its rounding's next round) and then dies by that signal (main.cpp); a second signal of either
// kind stops it at once (the default action). Not installed for a signal the process inherited
// as ignored (a background job of a script, nohup). Restored when the solve ends: writing the
// output is not stopped half-way.
extern "C" void on_stop_signal(int signal) {
  const int saved = errno;
  request_stop(signal);
  struct sigaction fallback {};
  fallback.sa_handler = SIG_DFL;
  sigemptyset(&fallback.sa_mask);
  ::sigaction(SIGINT, &fallback, nullptr);
  ::sigaction(SIGTERM, &fallback, nullptr);
  static const char said[] = "\nshapematch: stopping where the run can be saved (once more to stop at once)\n";
  [[maybe_unused]] const ssize_t n = ::write(STDERR_FILENO, said, sizeof said - 1);
  errno = saved;
}

class StopOnSignals {
public:
  StopOnSignals() {
    struct sigaction action {};
    action.sa_handler = on_stop_signal;
    sigemptyset(&action.sa_mask);
    sigaddset(&action.sa_mask, SIGINT);
    sigaddset(&action.sa_mask, SIGTERM);
    action.sa_flags = SA_RESTART;
    for (auto& [signal, old, set] : installed_) {
      ::sigaction(signal, nullptr, &old);
      set = old.sa_handler != SIG_IGN && ::sigaction(signal, &action, nullptr) == 0;
    }
  }
  ~StopOnSignals() {
    for (auto& [signal, old, set] : installed_)
      if (set) ::sigaction(signal, &old, nullptr);
  }
  StopOnSignals(const StopOnSignals&) = delete;
  StopOnSignals& operator=(const StopOnSignals&) = delete;

private:
  struct Installed {
    int signal;
    struct sigaction old;
    bool set;
  };
  std::array<Installed, 2> installed_{{{SIGINT, {}, false}, {SIGTERM, {}, false}}};
};

// `solve()` with StopOnSignals where there is a checkpoint to leave off in; a Stopped it throws
// says what the checkpoint holds.
template <class Solve>
auto stoppable(const std::string& checkpoint, Solve&& solve) {
  if (checkpoint.empty()) return solve();
  StopOnSignals stops;
  try {
    return solve();
  } catch (const Stopped& e) {
    const int signal = stop_requested();
    const std::string name = signal == SIGINT ? "SIGINT" : signal == SIGTERM ? "SIGTERM" : "a stop request";
    std::error_code ec;
    throw Stopped(fmt::format("stopped by {} ({}): {}", name, e.what(),
                              fs::exists(checkpoint, ec)
                                  ? checkpoint + " holds where the run got; the same command goes on from it"
                                  : "no checkpoint was written yet (" + checkpoint + ")"));
  }
}

int run_match(const MatchArgs& args) {
  Stopwatch total, stage;
  Json seconds = Json::object();
  if (truth_given(args) && !args.checkpoint.empty())
    throw InvalidInputError("--truth* and --checkpoint exclude each other (a diagnostic run is not gone on from)");
  const fs::path out = output_directory(args.out);
  remove_stale_siblings(out);
  if (!args.checkpoint.empty()) remove_stale_checkpoint_files(args.checkpoint);
  // The device first: a missing driver or device is an error before minutes of loading and assembly.
  if (args.backend == "vulkan") choose_device(args.device);
  const std::string solver = solver_for(args);
  const MeshPair p = load_pair(args.pair);

  CoarseToFineOptions co;
  co.hierarchy = args.hierarchy;
  // Shapes both at or below the coarsest size would repeat the same level (each level the same
  // full product space): one level does that work once.
  if (co.hierarchy.levels > 1 && p.x.num_faces() <= co.hierarchy.coarsest_faces &&
      p.y.num_faces() <= co.hierarchy.coarsest_faces) {
    spdlog::warn("both shapes have at most --coarsest-faces {} faces ({} and {}): one level", co.hierarchy.coarsest_faces,
                 p.x.num_faces(), p.y.num_faces());
    co.hierarchy.levels = 1;
  }
  if (co.hierarchy.second_faces > 0 && co.hierarchy.second_faces <= co.hierarchy.coarsest_faces)
    spdlog::warn("--second-faces {} is not above --coarsest-faces {}: no second start", co.hierarchy.second_faces,
                 co.hierarchy.coarsest_faces);
  co.ring = args.ring;
  co.neighbourhood = args.neighbourhood == "fine" ? Neighbourhood::Fine : Neighbourhood::Coarse;
  co.coarse_ring = args.coarse_ring;
  co.coarse_ring_faces = args.coarse_ring_faces;
  co.max_ring = std::max({args.max_ring, args.ring, args.coarse_ring_faces > 0 ? args.coarse_ring : 0});
  co.local_widening = args.widen == "local";
  co.coarse_tolerance = args.coarse_tolerance;
  co.widen_margin = args.widen_margin;
  co.widen_around = args.widen_around;
  co.y_margin = args.y_margin;
  co.max_local_widenings = args.max_local_widenings;
  co.max_propagation_widenings = args.max_propagation_widenings;
  co.recurring_margin = args.recurring_margin;
  co.recurring_max_share = args.recurring_max_share;
  co.recurring_beyond = args.recurring_beyond;
  co.proof_beyond = args.proof_beyond;
  co.watch_resolve = args.watch_resolve;
  co.max_suspected_widenings = args.max_suspected_widenings;
  co.suspicion_rings = args.suspicion_rings;
  co.suspicion_margins = args.suspicion_margins;
  co.suspicion_margin_scope = args.suspicion_margin_around == "named" ? CoarseToFineOptions::MarginScope::named
                                                                      : CoarseToFineOptions::MarginScope::widened;
  co.divergence_bound_factor = args.divergence_bound_factor;
  co.zero_cost_proof_rings = args.zero_cost_proof_rings;
  co.second_start_budget = args.second_start_budget;
  co.warm_widening = args.warm_widening;
  co.carry_primal_weight = args.carry_primal_weight;
  co.dump_first_lps = args.dump_first_lps;
  co.dump_slow_parts = args.dump_slow_parts;
  for (const std::string& dir : {co.dump_first_lps, co.dump_slow_parts})
    if (!dir.empty()) {
      std::error_code ec;
      fs::create_directories(dir, ec);
      if (ec) throw IoError(dir + ": cannot create the directory (" + ec.message() + ")");
    }
  co.inherit_widening = args.inherit_widening;
  co.price_dual_sweeps = args.price_dual_sweeps;
  co.stuck_after = args.stuck_after;
  co.stuck_carry = args.stuck_carry;
  co.stuck_carry_margin = args.stuck_carry_margin;
  co.stuck_restarts = args.stuck_restarts;
  co.rounding_checkpoint_seconds = args.rounding_checkpoint_seconds;
  co.lp_checkpoint_seconds = args.lp_checkpoint_seconds;
  co.price_widenings = args.price_widenings;
  co.lookahead_levels = args.lookahead_levels;
  co.lookahead_drop_stuck = args.lookahead_drop_stuck;
  co.lookahead_bound_drop = args.lookahead_bound_drop;
  co.price_threshold = args.price_threshold;
  co.price_tolerance = args.price_tolerance;
  co.matching = matching_options(args.pair, p);
  std::string truth_name;
  co.truth = true_map(args, p, truth_name);
  co.truth_rings = args.truth_rings;
  co.branch_depth = args.branch_depth;
  co.branch_rings = args.branch_rings;
  co.branch_min_split = args.branch_min_split;
  co.branch_gap = args.branch_gap;
  const CoarseToFineOptions defaults;
  if (args.branch_depth == 0 && (args.branch_rings != defaults.branch_rings ||
                                 args.branch_min_split != defaults.branch_min_split || args.branch_gap != defaults.branch_gap))
    spdlog::warn("--branch-rings, --branch-min-split or --branch-gap without --branch-depth: no effect");
  if (args.branch_depth > 0 && truth_given(args))
    spdlog::warn("--branch-depth with --truth*: no effect (the coarsest level is the truth's space, not the full one)");
  if (!truth_given(args) && args.truth_rings != defaults.truth_rings)
    spdlog::warn("--truth-rings without --truth, --truth-x or --truth-map: no effect");
  RoundingOptions& ro = co.rounding;
  ro.solver = solver;
  ro.threshold = args.threshold;
  ro.alternative_thresholds = args.alternative_thresholds;
  ro.alternatives_below = args.alternatives_below;
  ro.max_rounds = args.max_rounds;
  ro.blame_residual = args.blame_residual;
  ro.local_proof_columns = args.local_proof;
  ro.local_proof_solver = args.local_proof_solver;
  ro.later_round_iterations = args.later_round_iterations;
  ro.carry_weights = args.carry_round_weights;
  ro.fractional_batch = args.fractional_batch;
  ro.close_pockets = args.close_pockets;
  ro.split_parts = !args.whole_lp;
  ro.greedy_above = args.greedy_above;
  ro.greedy_margin = args.greedy_margin;
  ro.greedy_fallback = args.greedy_fallback;
  ro.remember_refuted = args.remember_refuted;
  ro.certificate_release = args.certificate_release;
  ro.search_below = args.search_below;
  ro.search_backjump = args.search_backjump;
  ro.search_proof_release = args.search_proof_release;
  ro.release_reach_cap = args.release_reach_cap;
  ro.stuck_stalled = args.stuck_stalled;
  ro.converged_first = args.converged_first;
  ro.exact_pivots_per_column = args.exact_pivots_per_column;
  ro.exact_part_seconds = args.exact_part_seconds;
  ro.exact_below = args.exact_below;
  ro.feasibility_iterations = args.feasibility_first;
  ro.later_feasibility_iterations = args.feasibility_later;
  ro.feasibility_tolerance = args.feasibility_tol;
  ro.later_feasibility_skip_below = args.feasibility_skip_below;
  ro.later_feasibility_skip_residual = args.feasibility_skip_residual;
  ro.later_feasibility_skip_row = args.feasibility_skip_row;
  ro.release_after_trims = args.release_after_trims;
  ro.lp.tolerance = args.tolerance;
  ro.lp.time_limit = args.time_limit;
  ro.lp.cold_primal_weight = args.cold_primal_weight;
  ro.lp.cold_restart_artificial = args.cold_restart_artificial;
  ro.lp.device = args.device;
  const CoarseToFineMatcher matcher(p.x, p.y, co);
  seconds.set("load", stage.seconds());
  // The finest level is the preprocessed input itself, vertex for vertex.
  const Mesh& x = matcher.x_levels().levels.back().mesh;
  const Mesh& y = matcher.y_levels().levels.back().mesh;

  // A checkpoint that exists is gone on from; every level below the finest then replaces it.
  std::optional<LevelCheckpoint> resume;
  if (!args.checkpoint.empty() && fs::exists(args.checkpoint)) {
    resume = load_checkpoint(args.checkpoint);
    try {
      matcher.check(*resume);
    } catch (const InvalidInputError& e) {
      throw InvalidInputError(args.checkpoint + ": " + e.what());
    }
  }
  CoarseToFineMatcher::Checkpointing checkpointing;
  if (!args.checkpoint.empty())
    checkpointing = [&](const LevelCheckpoint& c) {
      save_checkpoint(args.checkpoint, c);
      const LevelAttempt& a = c.in_progress();
      const std::string chain = c.chains.empty() ? std::string()
                                : c.chains[0].attempt.empty() ? " (the lookahead's second chain)"
                                                              : " (the lookahead's first chain)";
      if (a.empty() && c.first_chain_ahead())
        spdlog::info("checkpoint in level {}: the lookahead's first chain has done it: {}", c.done() + 1,
                     args.checkpoint);
      else if (a.empty())
        spdlog::info("checkpoint after level {}{}: {}", c.done(), c.chains.empty() ? "" : " (both chains of its lookahead)",
                     args.checkpoint);
      else if (!a.rounding.empty())
        spdlog::info("checkpoint in level {}'s rounding{}, after round {} ({} fixings to 1): {}", c.done() + 1, chain,
                     a.rounding.rounds, a.rounding.ones.size(), args.checkpoint);
      else if (!a.solving.empty())
        spdlog::info("checkpoint in level {}{}'s {} at {} iterations: {}", c.done() + 1, chain,
                     a.solving_resolve ? "re-solve after pricing" : "first LP", a.solving_iterations, args.checkpoint);
      else
        spdlog::info("checkpoint in level {}{}, before its next attempt (ring {}, {} faces with extra rings): {}",
                     c.done() + 1, chain, a.ring,
                     std::count_if(a.extra.begin(), a.extra.end(), [](int e) { return e > 0; }), args.checkpoint);
      if (stop_requested()) throw Stopped("after saving its checkpoint");  // (StopOnSignals)
    };

  stage.reset();
  const CoarseToFineResult c2f = stoppable(args.checkpoint, [&] { return matcher.run([&](const LevelReport& level, const RoundingRound& r) {
    const std::string at = matcher.x_levels().size() > 1 ? fmt::format("level {} ", level.level + 1) : std::string();
    const std::string parts = r.parts > 1 ? fmt::format(" in {} parts", r.parts) : std::string();
    // A release around a part: how much of what was fixed it freed, and how far it reached.
    const std::string around = r.release_depth > 0 ? fmt::format("released {} of {} fixings within {} LP steps around",
                                                                 r.released, r.release_pool, r.release_depth)
                                                   : fmt::format("released {} fixings around", r.released);
    if (r.search) {  // a search round (RoundingOptions::search_below)
      spdlog::info("{}round {:>2}: {:>9} variables{}, searched: {} parts finished in {} nodes, net fixed {} to 1 and "
                   "{} to 0{} ({:.2f} s)",
                   at, r.round, r.variables, parts, r.searched_parts, r.iterations, r.fixed_to_one, r.fixed_to_zero,
                   r.search_proof_released > 0
                       ? fmt::format(", released {} fixings that the proofs of the rest rest on", r.released)
                   : r.released > 0 ? fmt::format(", {} the rest", around)
                                    : std::string(),
                   r.seconds);
      return;
    }
    // A backtrack over an earlier round leaves fewer fixed than before: say "undid", not "fixed -n".
    const std::string fixed = r.fixed_to_one <= 0 && r.fixed_to_zero <= 0 && r.fixed_to_one + r.fixed_to_zero < 0
                                  ? fmt::format("undid {} to 1 and {} to 0 of earlier rounds", -r.fixed_to_one,
                                                -r.fixed_to_zero)
                                  : fmt::format("fixed {} to 1 and {} to 0", r.fixed_to_one, r.fixed_to_zero);
    const std::string undone =
        r.certificate_released > 0
            ? fmt::format(" (its proof survives undoing the last fixing: released {} fixings that carry it)",
                          r.certificate_released)
        : r.released > 0 ? fmt::format(" (a part failed away from the last fixing or again after trims: {} it)", around)
        : r.undone     ? std::string(" (undone: fixed fewer)")
                       : std::string();
    const std::string zero_cost =
        r.later_pretest_seconds > 0.0 ? fmt::format(", {:.2f} s of them at zero cost", r.later_pretest_seconds)
                                      : std::string();
    spdlog::info("{}round {:>2}: {:>9} variables{}, LP {} in {} it, objective {:.6g}, {}{} ({:.2f} s{})", at, r.round,
                 r.variables, parts, to_string(r.status), r.iterations, r.objective, fixed, undone, r.seconds,
                 zero_cost);
  }, resume ? &*resume : nullptr, checkpointing); });
  const MatchingLp& m = c2f.finest;
  const RoundingResult& rr = c2f.rounding;
  // The finest rounding's rounds, with those before a checkpoint inside it that this run went on
  // from, or before a stuck restart (rr holds only the rounds after it).
  const int64_t finest_rounds = c2f.levels.empty() ? int64_t(rr.rounds.size()) : c2f.levels.back().rounds;
  seconds.set("solve_and_round", stage.seconds());

  stage.reset();
  // The rounding already checked A x = b exactly in integers (it throws otherwise); Theorem 1 is
  // checked here independently. Coverage and orientation hold by construction: a failure is a bug.
  const GraphSurfaceCheck theorem = check_graph_surface(m.space, rr.gamma);
  if (!theorem.covers_x || !theorem.covers_y || !theorem.orientation)
    throw SolverError(std::string("the rounded matching failed verification (a bug; covers X ") +
                      (theorem.covers_x ? "yes" : "no") +
                      ", covers Y " + (theorem.covers_y ? "yes" : "no") + ", orientation " +
                      (theorem.orientation ? "yes" : "no") + "); nothing was written");
  // Continuity is checked, not assumed: report a failure rather than hide it.
  if (!theorem.continuous)
    spdlog::warn("continuity: {} vertices and {} edges of X, {} vertices and {} edges of Y are related to "
                 "disconnected sets of the other shape",
                 theorem.discontinuous_vertices_x, theorem.discontinuous_edges_x, theorem.discontinuous_vertices_y,
                 theorem.discontinuous_edges_y);
  const VertexMaps maps = vertex_maps(m.space, rr.gamma);
  seconds.set("verify", stage.seconds());
  stage.reset();
  // Points follow Γ where one partner vertex cannot (a vertex blown up, an edge stretched).
  PointMapOptions po;
  po.untangle_rings = args.untangle_rings;
  po.untangle_max_shift = args.untangle_max_shift;
  const PointMaps points = point_maps(m.space, rr.gamma, maps, po);
  const OrientationFlips vertex_flips = count_orientation_flips(x, y, maps.x_to_y);
  const OrientationFlips point_flips = count_orientation_flips(x, y, points.x_to_y);
  // The other way too: a matching is judged in both directions.
  const OrientationFlips vertex_flips_yx = count_orientation_flips(y, x, maps.y_to_x);
  const OrientationFlips point_flips_yx = count_orientation_flips(y, x, points.y_to_x);
  seconds.set("point_maps", stage.seconds());
  spdlog::info("faces of X inverted by the vertex map: {} ({} degenerate); by the point map: {} ({} degenerate)",
               vertex_flips.flips, vertex_flips.degenerate, point_flips.flips, point_flips.degenerate);
  spdlog::info("faces of Y inverted by the vertex map: {} ({} degenerate); by the point map: {} ({} degenerate)",
               vertex_flips_yx.flips, vertex_flips_yx.degenerate, point_flips_yx.flips, point_flips_yx.degenerate);
  spdlog::info("energy {:.6g}, lower bound {:.6g}, gap {:.2f} %, {} rounds{}, verified", rr.energy, rr.lower_bound,
               100 * rr.gap, finest_rounds,
               rr.pockets_closed > 0 ? fmt::format(", {} pockets closed", rr.pockets_closed) : std::string());

  stage.reset();
  const fs::path tmp = out.string() + ".tmp-" + std::to_string(::getpid());
  if (std::error_code there; fs::exists(fs::symlink_status(tmp, there)))  // (the sweep removed any of ours)
    throw IoError(tmp.string() + ": exists, and is not a run's temporary output; remove it");
  fs::create_directories(tmp);
  try {
    write_file_atomic((tmp / kWriting).string(), std::to_string(::getpid()) + "\n");
    write_file_atomic((tmp / "map_x_to_y.txt").string(), lines(maps.x_to_y));
    write_file_atomic((tmp / "map_y_to_x.txt").string(), lines(maps.y_to_x));
    write_file_atomic((tmp / "map_x_to_y_points.txt").string(), point_map_text(points.x_to_y));
    write_file_atomic((tmp / "map_y_to_x_points.txt").string(), point_map_text(points.y_to_x));
    write_file_atomic((tmp / "x_vertex_ids.txt").string(), lines(p.x_ids));
    write_file_atomic((tmp / "y_vertex_ids.txt").string(), lines(p.y_ids));
    // Every coarser level's vertex map, in input vertices: where eval can see an error arise.
    if (c2f.levels.size() > 1) {
      fs::create_directories(tmp / "levels");
      for (const LevelReport& level : c2f.levels) {
        if (level.level + 1 >= matcher.x_levels().size()) continue;  // the finest is map_x_to_y.txt
        const MeshLevel& lx = matcher.x_levels().levels[level.level];
        const MeshLevel& ly = matcher.y_levels().levels[level.level];
        const ProductSpace space = ProductSpace::from_list(lx.mesh, ly.mesh, level.gamma);
        std::vector<int64_t> all(level.gamma.size());
        std::iota(all.begin(), all.end(), int64_t{0});
        const VertexMaps vm = vertex_maps(space, all);
        std::string text;
        for (int v = 0; v < lx.mesh.num_vertices(); ++v)
          text += fmt::format("{} {}\n", p.x_ids[lx.input_vertex[v]], p.y_ids[ly.input_vertex[vm.x_to_y[v]]]);
        write_file_atomic((tmp / "levels" / fmt::format("level_{}.txt", level.level + 1)).string(), text);
      }
    }
    std::ostringstream gs;
    for (int64_t j : rr.gamma) {
      const ProductTriangle t = m.space[j];
      gs << t.a[0] << ' ' << t.a[1] << ' ' << t.a[2] << ' ' << t.b[0] << ' ' << t.b[1] << ' ' << t.b[2] << '\n';
    }
    write_file_atomic((tmp / "graph_surface.txt").string(), gs.str());
    const auto colors_x = smooth_colors(x);
    const auto colors_y = transfer_colors(colors_x, maps.y_to_x);
    save_mesh(x, (tmp / "x.ply").string(), colors_x);
    save_mesh(y, (tmp / "y.ply").string(), colors_y);
    write_png(render_side_by_side(x, colors_x, y, colors_y, RenderOptions{}), (tmp / "match.png").string());
    seconds.set("features", p.features_seconds);
    seconds.set("output", stage.seconds());
    seconds.set("total", total.seconds());

    // Numbered as the log numbers them: on from the rounds before a checkpoint or stuck restart.
    const int64_t rounds_before = std::max<int64_t>(0, finest_rounds - static_cast<int64_t>(rr.rounds.size()));
    Json rounds = Json::array();
    for (const auto& r : rr.rounds)
      rounds.push(Json::object()
                      .set("round", r.round + rounds_before)
                      .set("variables", r.variables)
                      .set("constraints", r.constraints)
                      .set("status", to_string(r.status))
                      .set("iterations", r.iterations)
                      .set("objective", r.objective)
                      .set("fixed_to_one", r.fixed_to_one)
                      .set("fixed_to_zero", r.fixed_to_zero)
                      .set("undone", r.undone)
                      .set("parts", r.parts)
                      .set("exact_parts", r.exact_parts)
                      .set("start_primal_weight", r.start_primal_weight)
                      .set("primal_weight", r.primal_weight)
                      .set("search", r.search)
                      .set("searched_parts", r.searched_parts)
                      .set("released", r.released)
                      .set("release_depth", r.release_depth)
                      .set("release_pool", r.release_pool)
                      .set("certificate_released", r.certificate_released)
                      .set("search_proof_released", r.search_proof_released)
                      .set("seconds", r.seconds));
    Json report = Json::object();
    auto shape = [](const std::string& file, int file_vertices, int input_vertices, const Mesh& mesh) {
      return Json::object()
          .set("file", file)
          .set("vertices_file", file_vertices)
          .set("vertices_input", input_vertices)
          .set("vertices", mesh.num_vertices())
          .set("faces", mesh.num_faces());
    };
    // Absolute, so that `shapematch eval DIR` finds the inputs from any working directory.
    report.set("x", shape(fs::absolute(p.x_file).lexically_normal().string(), p.x_file_vertices, p.x_input_vertices, x));
    report.set("y", shape(fs::absolute(p.y_file).lexically_normal().string(), p.y_file_vertices, p.y_input_vertices, y));
    report.set("variables", m.lp.cols()).set("constraints", m.lp.rows()).set("nonzeros", m.lp.nonzeros());
    report.set("backend", ro.solver).set("device", rr.first_lp.device).set("threads", worker_threads());
    report.set("energy", rr.energy).set("lower_bound", rr.lower_bound).set("gap", rr.gap);
    // Above one level the bound certifies the finest level's reduced space, not the full one.
    report.set("bound_scope", c2f.levels.size() > 1 ? "reduced space of the finest level" : "full product space");
    report.set("first_lp_objective", rr.first_lp.objective).set("first_lp_status", to_string(rr.first_lp.status));
    report.set("rounds", finest_rounds);
    // (first_lp_* and the log per round then describe the rounds after the checkpoint or restart.)
    report.set("rounds_before_checkpoint", rounds_before);
    report.set("verified", true);
    report.set("theorem1", Json::object()
                               .set("covers_x", theorem.covers_x)
                               .set("covers_y", theorem.covers_y)
                               .set("orientation_preserved", theorem.orientation)
                               .set("continuous", theorem.continuous)
                               .set("discontinuous_vertices_x", theorem.discontinuous_vertices_x)
                               .set("discontinuous_vertices_y", theorem.discontinuous_vertices_y)
                               .set("discontinuous_edges_x", theorem.discontinuous_edges_x)
                               .set("discontinuous_edges_y", theorem.discontinuous_edges_y)
                               .set("pockets_closed", rr.pockets_closed));
    report.set("graph_surface_triangles", static_cast<int64_t>(rr.gamma.size()));
    auto flips_json = [](const OrientationFlips& f) {
      return Json::object().set("faces", f.faces).set("inverted", f.flips).set("degenerate", f.degenerate);
    };
    report.set("maps", Json::object()
                           .set("vertex_x_to_y", flips_json(vertex_flips))
                           .set("point_x_to_y", flips_json(point_flips))
                           .set("vertex_y_to_x", flips_json(vertex_flips_yx))
                           .set("point_y_to_x", flips_json(point_flips_yx)));
    report.set("options", Json::object()
                              .set("bending", args.pair.bending)
                              .set("curvature_radius", args.pair.curvature_radius)
                              .set("lame_lambda", args.pair.lame.at(0))
                              .set("lame_mu", args.pair.lame.at(1))
                              .set("threshold", args.threshold)
                              .set("alternative_thresholds", [&] {
                                Json a = Json::array();
                                for (double t : args.alternative_thresholds) a.push(Json(t));
                                return a;
                              }())
                              .set("alternatives_below", args.alternatives_below)
                              .set("fractional_batch", args.fractional_batch)
                              .set("later_round_iterations", args.later_round_iterations)
                              .set("carry_round_weights", args.carry_round_weights)
                              .set("close_pockets", args.close_pockets)
                              .set("untangle_rings", args.untangle_rings)
                              .set("untangle_max_shift", args.untangle_max_shift)
                              .set("greedy_above", args.greedy_above)
                              .set("greedy_margin", args.greedy_margin)
                              .set("greedy_fallback", args.greedy_fallback)
                              .set("remember_refuted", args.remember_refuted)
                              .set("certificate_release", args.certificate_release)
                              .set("search_below", args.search_below)
                              .set("search_backjump", args.search_backjump)
                              .set("search_proof_release", args.search_proof_release)
                              .set("release_reach_cap", args.release_reach_cap)
                              .set("converged_first", args.converged_first)
                              .set("exact_pivots_per_column", args.exact_pivots_per_column)
                              .set("exact_part_seconds", args.exact_part_seconds)
                              .set("exact_below", args.exact_below)
                              .set("feasibility_first", args.feasibility_first)
                              .set("feasibility_later", args.feasibility_later)
                              .set("feasibility_tol", args.feasibility_tol)
                              .set("feasibility_skip_below", args.feasibility_skip_below)
                              .set("feasibility_skip_residual", args.feasibility_skip_residual)
                              .set("feasibility_skip_row", args.feasibility_skip_row)
                              // Since the seventy-fifth session --max-rounds counts only the
                              // rounds without a new low of free variables; say so, so that
                              // reports from before and after can be told apart.
                              .set("max_rounds", args.max_rounds)
                              .set("max_rounds_counts", "rounds without a new low")
                              .set("time_limit", args.time_limit)
                              .set("release_after_trims", args.release_after_trims)
                              .set("split_parts", !args.whole_lp)
                              .set("tolerance", args.tolerance)
                              .set("cold_primal_weight", args.cold_primal_weight)
                              .set("cold_restart_artificial", args.cold_restart_artificial)
                              .set("coarse_tolerance", co.coarse_tolerance)
                              .set("faces", args.pair.faces)
                              .set("keep_scale", args.pair.keep_scale)
                              .set("close_holes", args.pair.close_holes)
                              .set("features", p.features)
                              .set("feature_weight", args.pair.feature_weight)
                              .set("levels", matcher.x_levels().size())
                              .set("coarsest_faces", args.hierarchy.coarsest_faces)
                              .set("second_faces", args.hierarchy.second_faces)
                              .set("lookahead_levels", args.lookahead_levels)
                              .set("lookahead_drop_stuck", args.lookahead_drop_stuck)
                              .set("lookahead_bound_drop", args.lookahead_bound_drop)
                              .set("surface_parents", args.hierarchy.surface_parents)
                              .set("level_ratio", args.hierarchy.ratio)
                              .set("ring", args.ring)
                              .set("max_ring", co.max_ring)  // as used: at least --ring
                              .set("coarse_ring", args.coarse_ring)
                              .set("coarse_ring_faces", args.coarse_ring_faces)
                              .set("neighbourhood", args.neighbourhood)
                              .set("widen", args.widen)
                              .set("widen_margin", args.widen_margin)
                              .set("widen_around", args.widen_around)
                              .set("y_margin", args.y_margin)
                              .set("max_local_widenings", args.max_local_widenings)
                              .set("max_propagation_widenings", args.max_propagation_widenings)
                              .set("recurring_margin", args.recurring_margin)
                              .set("recurring_max_share", args.recurring_max_share)
                              .set("recurring_beyond", args.recurring_beyond)
                              .set("proof_beyond", args.proof_beyond)
                              .set("watch_resolve", args.watch_resolve)
                              .set("max_suspected_widenings", args.max_suspected_widenings)
                              .set("suspicion_rings", args.suspicion_rings)
                              .set("suspicion_margins", args.suspicion_margins)
                              .set("suspicion_margin_around", args.suspicion_margin_around)
                              .set("divergence_bound_factor", args.divergence_bound_factor)
                              .set("zero_cost_proof_rings", args.zero_cost_proof_rings)
                              .set("second_start_budget", args.second_start_budget)
                              .set("warm_widening", args.warm_widening)
                              .set("carry_primal_weight", args.carry_primal_weight)
                              .set("inherit_widening", args.inherit_widening)
                              .set("price_dual_sweeps", args.price_dual_sweeps)
                              .set("stuck_after", args.stuck_after)
                              .set("stuck_carry", args.stuck_carry)
                              .set("blame_residual", args.blame_residual)
                              .set("local_proof", args.local_proof)
                              .set("local_proof_solver", args.local_proof_solver)
                              .set("stuck_carry_margin", args.stuck_carry_margin)
                              .set("stuck_restarts", args.stuck_restarts)
                              .set("rounding_checkpoint_seconds", args.rounding_checkpoint_seconds)
                              .set("lp_checkpoint_seconds", args.lp_checkpoint_seconds)
                              .set("stuck_stalled", args.stuck_stalled)
                              .set("price_widenings", args.price_widenings)
                              .set("price_threshold", args.price_threshold)
                              .set("price_tolerance", args.price_tolerance)
                              .set("truth", truth_name)
                              .set("truth_rings", args.truth_rings)
                              .set("branch_depth", args.branch_depth)
                              .set("branch_rings", args.branch_rings)
                              .set("branch_min_split", args.branch_min_split)
                              .set("branch_gap", args.branch_gap));
    // Levels taken from a checkpoint keep the seconds and memory of the run that solved them.
    report.set("resumed_after_level", resume ? static_cast<int64_t>(resume->levels.size()) : int64_t(0));
    report.set("seconds", seconds);
    report.set("peak_rss_mb", peak_rss_mb());
    report.set("round_log", rounds);
    Json levels = Json::array();
    for (const LevelReport& l : c2f.levels)
      levels.push(Json::object()
                      .set("level", l.level)
                      .set("faces_x", l.faces_x)
                      .set("faces_y", l.faces_y)
                      .set("variables", l.variables)
                      .set("full_variables", l.full_variables)
                      .set("constraints", l.constraints)
                      .set("ring", l.ring)
                      .set("widenings", l.widenings)
                      .set("local_widenings", l.local_widenings)
                      .set("margin_widenings", l.margin_widenings)
                      .set("widened_faces", l.widened_faces)
                      .set("stuck_widenings", l.stuck_widenings)
                      .set("stuck_restarts", l.stuck_restarts)
                      .set("price_widenings", l.price_widenings)
                      .set("propagation_widenings", l.propagation_widenings)
                      .set("recurring_widenings", l.recurring_widenings)
                      .set("proof_rechecks", l.proof_rechecks)
                      .set("inherited_faces", l.inherited_faces)
                      .set("carried_fixings", l.carried_fixings)
                      .set("iterations_bound", l.iterations_bound)
                      .set("rounds", l.rounds)
                      .set("iterations", l.iterations)
                      .set("lower_bound", l.lower_bound)
                      .set("energy", l.energy)
                      .set("gap", l.gap)
                      .set("threshold", l.threshold)
                      .set("roundings", l.roundings)
                      .set("second_start_energy", l.second_start_energy)
                      .set("second_start_kept", l.second_start_kept)
                      .set("lookahead_other_energy", l.lookahead_other_energy)
                      .set("lookahead_other_bound", l.lookahead_other_bound)
                      .set("lookahead_other_stuck", l.lookahead_other_stuck)
                      .set("lookahead_switched", l.lookahead_switched)
                      .set("branch_roundings", l.branch_roundings)
                      .set("branch_energy", l.branch_energy)
                      .set("branch_kept", l.branch_kept)
                      .set("seconds", l.seconds)
                      .set("peak_rss_mb", l.peak_rss_mb));
    report.set("levels", levels);
    write_file_atomic((tmp / "report.json").string(), report.dump() + "\n");
    publish(tmp, out);
  } catch (...) {
    std::error_code ec;  // (a finished output that publish could not put in place is kept: it says where)
    if (fs::exists(tmp / kWriting, ec) || fs::is_empty(tmp, ec)) fs::remove_all(tmp, ec);
    throw;
  }
  spdlog::info("wrote {}", out.string());
  return 0;
}

}  // namespace

Action add_match_command(CLI::App& app) {
  auto a = std::make_shared<MatchArgs>();
  add_pair_options(app, a->pair);
  app.add_option("-o,--out", a->out, "output directory")->capture_default_str();
  app.add_option("--backend", a->backend, "LP backend")
      ->check(CLI::IsMember({"auto", "vulkan", "cpu", "cpu-f32", "clp"}))
      ->capture_default_str();
  app.add_option("--device", a->device, "Vulkan device index (see `shapematch devices`)");
  // Several matches sharing a machine (a pair table's jobs) each start one thread per CPU by
  // default; fewer each spares the scheduler the oversubscription.
  app.add_option("--threads", a->threads, "host threads (0: every CPU this process may use)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--threshold", a->threshold, "fix LP values above this to 1")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option_function<std::string>(
         "--alt-thresholds",
         [a](const std::string& list) {
           a->alternative_thresholds.clear();
           if (list == "none") return;
           std::stringstream in(list);
           for (std::string item; std::getline(in, item, ',');) {
             std::size_t used = 0;
             double t = -1.0;
             try {
               t = std::stod(item, &used);
             } catch (const std::exception&) {
             }
             if (used != item.size() || !(t > 0.0 && t < 1.0))
               throw CLI::ValidationError("--alt-thresholds", "need `none` or thresholds in (0, 1) separated by commas");
             a->alternative_thresholds.push_back(t);
           }
         },
         "where a level's LP has at most --alternatives-below variables, round it again from its first LP's "
         "optimum with each of these thresholds (comma-separated) and keep the Γ of least energy; `none`: one "
         "rounding (default 0.7)");
  app.add_option("--alternatives-below", a->alternatives_below,
                 "variables of a level's LP above which it is rounded once (--alt-thresholds)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_flag("--close-pockets", a->close_pockets,
               "replace each pocket (an edge stretched over a whole star, a tear that A x = b admits) by the star collapsed onto one vertex: continuous, but costs energy");
  app.add_option("--untangle-rings", a->untangle_rings,
                 "where the point map still inverts a face, lay discs of up to this many rings around it out again "
                 "(Tutte's embedding in a chart of the other shape, then back towards the old points where that inverts "
                 "no more faces), kept where fewer faces invert, none more are degenerate and the points moved little "
                 "(--untangle-max-shift); 0: off")
      ->check(CLI::Range(0, 64))
      ->capture_default_str();
  app.add_option("--untangle-max-shift", a->untangle_max_shift,
                 "the most one untangled disc may move the point map's points, summed, divided by sqrt(area) of the "
                 "other shape and by the vertex count: about what one disc may add to the mean geodesic error")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--fractional-batch", a->fractional_batch,
                 "where no LP value exceeds the threshold, fix the largest of up to this fraction of the open faces "
                 "(0: the single largest)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--max-rounds", a->max_rounds,
                 "rounding rounds that bring its free variables to no new low, before giving up (rounds that do "
                 "are progress and not counted)")->capture_default_str();
  app.add_flag("--converged-first", a->converged_first,
               "in a later round whose LP stopped at its iteration cap in some parts, fix only from the parts that "
               "converged; the others go on from their iterate one round more");
  app.add_option("--exact-pivots-per-column", a->exact_pivots_per_column,
                 "stop Clp after this many pivots per column of a later round's part (at least 1 000 columns' worth) "
                 "and give the part to PDHG (0: no cap)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--exact-part-seconds", a->exact_part_seconds,
                 "stop Clp after this many seconds on a later round's part and give it to PDHG, with the parts of "
                 "its size or larger for the rest of that rounding (0: no limit)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--exact-below", a->exact_below,
                 "solve a later round's parts under this many columns by Clp's dual simplex, the others by the "
                 "first-order solver (0: all by it)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--feasibility-first", a->feasibility_first,
                 "before a refined level's first LP, solve it without costs for at most N PDHG iterations: an "
                 "infeasible one is proved there (0: off)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--feasibility-later", a->feasibility_later,
                 "in the later rounds, solve each part PDHG would solve without costs first for at most N "
                 "iterations: an infeasible one is proved there (0: off)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--feasibility-skip-below", a->feasibility_skip_below,
                 "with --feasibility-later, run each part's costed solve first for N iterations: a part optimal "
                 "by then skips its zero-cost solve (0: every part has it first)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--feasibility-skip-residual", a->feasibility_skip_residual,
                 "with --feasibility-skip-below: skip the zero-cost solve only where the costed one ended with its "
                 "relative primal residual at most this (0: any)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--feasibility-skip-row", a->feasibility_skip_row,
                 "with --feasibility-skip-below: skip the zero-cost solve only where the costed one ended with no "
                 "row off by more than this (0: any)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--feasibility-tol", a->feasibility_tol,
                 "the tolerance of the zero-cost solves (--feasibility-first, --feasibility-later, the re-proof of "
                 "a part proved infeasible): a part counts as feasible there only with its relative residual "
                 "under it (0: --tol's)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--release-after-trims", a->release_after_trims,
                 "where a part's LP has failed after this many trims of the last fixing in a row, release the "
                 "fixings around the part instead of trimming again (0: never)")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  app.add_option("--search-below", a->search_below,
                 "where rounding stalls on at most this many free variables, finish each part by depth-first "
                 "search over exact LPs, releasing the fixings around a part without a binary solution (0: never)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_flag("--search-backjump,!--no-search-backjump", a->search_backjump,
               "where both values of a search's branch have failed, go back to the deepest decision that the "
               "failures' proofs need, not one level up (default on)");
  app.add_flag("--search-proof-release,!--no-search-proof-release", a->search_proof_release,
               "where the search proves a part without a binary solution, release the fixings outside it that its "
               "proofs rest on, not every fixing within 2, 4, 8 ... LP steps of it (default on)");
  app.add_option("--release-reach-cap", a->release_reach_cap,
                 "where the same part fails again and the next release around it would reach beyond this many LP "
                 "steps, call the rounding stuck there (coarse to fine widens around it) instead (0: no cap)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--later-round-iterations", a->later_round_iterations,
                 "LP iterations of a rounding round after the first, at most this many times the first LP's (at "
                 "least 2000; then it fixes from its iterate); 0: no limit")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_flag("--carry-round-weights,!--no-carry-round-weights", a->carry_round_weights,
               "rounding rounds after the first start each PDHG part from the primal weight its columns' last "
               "solve ended with (default: the solver's own start)")
      ->capture_default_str();
  app.add_option("--greedy-above", a->greedy_above,
                 "where a round's candidates clash and its LP has more free variables than this, fix each candidate "
                 "that does not clash with larger ones (below: fix the larger half and solve again); 0: always")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--greedy-margin", a->greedy_margin,
                 "those rounds fix only candidates with no undecided variable (valued in (0.1, 0.9)) in their rows "
                 "or within this many - 1 closedness steps of them; 0: every candidate")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--greedy-fallback", a->greedy_fallback,
                 "where no candidate of such a round stands away from the undecided part, fix the largest of each "
                 "undecided region, at most this share of them (at least one; 1: the whole batch)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_flag("--remember-refuted,!--no-remember-refuted", a->remember_refuted,
               "fixings an infeasibility proof blamed are not made again from the state they were made from, also "
               "after backtracking away from it and back (default on)");
  app.add_flag("--certificate-release,!--no-certificate-release", a->certificate_release,
               "where an infeasibility proof of a later round's LP would survive undoing the last fixing whole, "
               "release the fixings of any round that carry it instead of trimming the last (default on)");
  app.add_flag("--whole-lp", a->whole_lp,
               "solve each rounding LP after the first as one, not as its independent parts (small parts exactly)");
  app.add_option("--tol", a->tolerance, "LP tolerance")->check(positive_number())->capture_default_str();
  app.add_option("--coarse-tol", a->coarse_tolerance, "LP tolerance of the levels below the finest (0: --tol)")
      ->check(CLI::Range(0.0, 0.5))
      ->capture_default_str();
  app.add_option("--time-limit", a->time_limit, "time limit of each LP solve, seconds")->check(positive_number());
  app.add_option("--cold-primal-weight", a->cold_primal_weight,
                 "PDHG's primal weight ω for LPs solved from a cold start (0: PDHG's own)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--cold-restart-artificial", a->cold_restart_artificial,
                 "PDHG restarts at the latest after this fraction of all iterations, in LPs solved from a cold start "
                 "(0: PDHG's own, 0.36)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--levels", a->hierarchy.levels, "coarse-to-fine levels including the finest (0: from --coarsest-faces)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--level-ratio", a->hierarchy.ratio,
                 "with --levels 0: faces grow by at most this factor from level to level")
      ->check(CLI::Range(1.01, 1e6))
      ->capture_default_str();
  app.add_option("--coarsest-faces", a->hierarchy.coarsest_faces, "faces of the coarsest level")
      ->check(CLI::Range(4, 1 << 30))
      ->capture_default_str();
  app.add_flag("--surface-parents,!--space-parents", a->hierarchy.surface_parents,
               "a fine face's parent is the nearest coarse face among those around the kept vertices nearest on the "
               "fine surface (default), or (--space-parents) the nearest in space, which can lie across a gap")
      ->capture_default_str();
  app.add_option("--second-faces", a->hierarchy.second_faces,
                 "faces of the level above the coarsest, which is also solved over its full product space (the "
                 "lower-energy Γ goes on); 0: off, levels geometric from the coarsest")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--lookahead-levels", a->lookahead_levels,
                 "where the second start and the refined Γ both exist, refine both through this many more levels "
                 "(never the finest) and go on with the lower energy there; 0: decide at the second level")
      ->check(CLI::Range(0, 16))
      ->capture_default_str();
  app.add_flag("--lookahead-drop-stuck", a->lookahead_drop_stuck,
               "inside lookahead, a chain whose rounding gets stuck at a level drops out there instead of widening "
               "(the other chain goes on; where it finds no Γ either, the first solves the level again)");
  app.add_flag("--lookahead-bound-drop,!--no-lookahead-bound-drop", a->lookahead_bound_drop,
               "at the level where lookahead decides, the chain solving it second stops after a first LP whose "
               "bound is at or above the first chain's energy there (it cannot win)")
      ->capture_default_str();
  app.add_option("--ring", a->ring, "neighbourhood rings of the reduced product space (eq. 17)")
      ->check(CLI::Range(0, 8))
      ->capture_default_str();
  app.add_option("--coarse-ring", a->coarse_ring,
                 "the ring at the levels below the finest with at most --coarse-ring-faces faces")
      ->check(CLI::Range(0, 8))
      ->capture_default_str();
  app.add_option("--coarse-ring-faces", a->coarse_ring_faces,
                 "levels below the finest with at most this many faces start at --coarse-ring (0: --ring everywhere)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--neighbourhood", a->neighbourhood,
                 "where rings count: coarse (eq. 17 on the coarse level) or fine (on Y's fine level)")
      ->check(CLI::IsMember({"coarse", "fine"}))
      ->capture_default_str();
  app.add_option("--max-ring", a->max_ring, "widen the ring up to this when a reduced LP is infeasible")
      ->check(CLI::Range(0, 8))
      ->capture_default_str();
  app.add_option("--widen", a->widen,
                 "after an infeasible reduced LP: local (near the proof first, then everywhere) or global")
      ->check(CLI::IsMember({"local", "global"}))
      ->capture_default_str();
  app.add_flag("--warm-widening", a->warm_widening,
               "start the LP of a widened space from the previous attempt's iterate (measured slower after a "
               "diverging attempt)");
  app.add_flag("--carry-primal-weight,!--no-carry-primal-weight", a->carry_primal_weight,
               "warm starts (a pricing's re-solve, --warm-widening) also start from the primal weight their "
               "iterate's solve ended with (default off: measured no faster)");
  app.add_option("--checkpoint", a->checkpoint,
                 "after every level below the finest, save the run's state to FILE; where FILE exists, go on "
                 "after the levels it holds (solved with whatever options made them)");
  app.add_option("--rounding-checkpoint-seconds", a->rounding_checkpoint_seconds,
                 "with --checkpoint: save where a level's rounding has got after its rounds, at most this often "
                 "(seconds)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--lp-checkpoint-seconds", a->lp_checkpoint_seconds,
                 "with --checkpoint: save a refined level's first LP's iterate with its attempt at most this often "
                 "(seconds), so that a run gone on from it starts that LP there (0: never)")
      ->check(non_negative_number())
      ->capture_default_str();
  auto* tr = app.add_option("--truth", a->truth,
                            "a diagnostic: the coarsest level keeps only product triangles near the true map (vertex "
                            "i of X <-> vertex i of Y), and has no second start")
                 ->check(CLI::IsMember({"identity"}));
  auto* tx = app.add_option("--truth-x", a->truth_x, "as --truth, from 1-based .vts files: line k <-> line k of --truth-y");
  auto* ty = app.add_option("--truth-y", a->truth_y, "1-based .vts file of Y");
  auto* tm = app.add_option("--truth-map", a->truth_map, "as --truth, from two 1-based columns: X vertex, Y vertex");
  tx->needs(ty);
  ty->needs(tx);
  tr->excludes(tx)->excludes(ty)->excludes(tm);
  tm->excludes(tx)->excludes(ty);
  app.add_option("--truth-rings", a->truth_rings,
                 "with --truth*: each corner's Y vertex within this many edges of its true image on the coarsest Y")
      ->check(CLI::Range(0, 16))
      ->capture_default_str();
  app.add_option("--branch-depth", a->branch_depth,
                 "where the coarsest level's Γ is over --branch-gap above its LP's bound, dive this many steps: split "
                 "on the X vertex whose image the LP spreads most between two places of Y, round each side, keep the "
                 "lowest Γ, go on from the lower side (0: off)")
      ->check(CLI::Range(0, 16))
      ->capture_default_str();
  app.add_option("--branch-rings", a->branch_rings, "with --branch-depth: each place is a ball of this many edges of Y")
      ->check(CLI::Range(0, 16))
      ->capture_default_str();
  app.add_option("--branch-min-split", a->branch_min_split,
                 "with --branch-depth: split only where the second place holds at least this share of the image")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--branch-gap", a->branch_gap,
                 "with --branch-depth: dive only where the coarsest gap (energy over bound, relative) is above this")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--dump-first-lps", a->dump_first_lps,
                 "write every first LP of a rounding to this directory (level<L>-<NNN>.smlp), to solve it again "
                 "with `shapematch lp --from`");
  app.add_option("--dump-slow-parts", a->dump_slow_parts,
                 "write every later round's part that Clp took 10 s or more on to this directory "
                 "(level<L>-slow-<NNN>.smlp), to solve it again with `shapematch lp --from`");
  app.add_option("--price-dual-sweeps", a->price_dual_sweeps,
                 "with --price-widenings: the re-solve starts the new rows' duals where this many sweeps of "
                 "coordinate ascent on the Lagrangian bound put them, not at 0 (0: off)")
      ->check(CLI::Range(0, 100));
  app.add_option("--inherit-widening", a->inherit_widening,
                 "fine X faces whose parent's space was widened at the level before start with that many extra "
                 "rings, up to this (0: off)")
      ->check(CLI::Range(0, 8));
  app.add_option("--max-local-widenings", a->max_local_widenings,
                 "local widenings per level before the ring widens everywhere (those where propagation found the "
                 "contradiction not counted)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--max-suspected-widenings", a->max_suspected_widenings,
                 "widenings in a row at a level on first LPs that the divergence watch stopped (no proof) before "
                 "the level's next first LPs are watched patiently, stopped only by a long climb (0: no limit)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--suspicion-rings", a->suspicion_rings,
                 "where --max-suspected-widenings ends the watch, every X face within this many fine rings of "
                 "the faces widened so far at the level gets one more ring first (0: off)")
      ->check(CLI::Range(0, 16))
      ->capture_default_str();
  app.add_option("--suspicion-margins", a->suspicion_margins,
                 "at most this many --suspicion-rings margins per ring of a level (0: one at every suspicion "
                 "that ends the watch's trust)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--suspicion-margin-around", a->suspicion_margin_around,
                 "what a --suspicion-rings margin is drawn around: widened (every X face widened so far at the "
                 "level) or named (only the X faces the suspicion itself named)")
      ->check(CLI::IsMember({"widened", "named"}))
      ->capture_default_str();
  app.add_option("--divergence-bound-factor", a->divergence_bound_factor,
                 "a watched first LP of a refined level also stops as diverging where its dual proves its optimum "
                 "above this many times the coarser level's energy, while a ring is left to widen to (0: off)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--zero-cost-proof-rings", a->zero_cost_proof_rings,
                 "where --feasibility-first proves a level's first LP infeasible for the first time at its ring, "
                 "every X face within this many fine rings of the faces widened so far gets one more ring too "
                 "(0: off)")
      ->check(CLI::Range(0, 16))
      ->capture_default_str();
  app.add_option("--max-propagation-widenings", a->max_propagation_widenings,
                 "local widenings per level where unit propagation found the contradiction (before any LP)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--recurring-margin", a->recurring_margin,
                 "where propagation's contradiction comes back in the same π row, the k-th time widen X faces "
                 "within 1 + this·k rings of it to the largest ring at once (0: off)")
      ->check(CLI::Range(0, 64))
      ->capture_default_str();
  app.add_option("--recurring-max-share", a->recurring_max_share,
                 "with --recurring-margin: where that would widen more than this share of the X faces, widen at the "
                 "proof as for any contradiction instead (0: no limit)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--recurring-beyond", a->recurring_beyond,
                 "with --recurring-margin: such a return widens its faces to --max-ring plus this many rings")
      ->check(CLI::Range(1, 3))
      ->capture_default_str();
  app.add_option("--proof-beyond", a->proof_beyond,
                 "with --local-proof: the faces a proved-infeasible region grew from widen up to --max-ring plus this "
                 "many rings, one per proof (the other widenings stop at 3 more)")
      ->check(CLI::Range(1, 12))
      ->capture_default_str();
  app.add_option("--second-start-budget", a->second_start_budget,
                 "beside a refined Γ, the second start's rounding gives up once its rounds after the first did this "
                 "many times its first LP's work (iterations × variables), the alternative thresholds still trying (0: no budget)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_flag("--watch-resolve", a->watch_resolve,
               "let the divergence watch stop the re-solve after pricing too (off: it starts at the optimum of a "
               "space it contains and stops at the cold first LP's iterations)");
  app.add_option("--widen-margin", a->widen_margin, "fine rings of faces around the proof that widen with it")
      ->check(CLI::Range(0, 64))
      ->capture_default_str();
  app.add_option("--widen-around", a->widen_around,
                 "once propagation finds no more contradictions at a level where it found some, one more ring on "
                 "every X face within this many fine rings of those widened so far, before the first LP (0: off)")
      ->check(CLI::Range(0, 64))
      ->capture_default_str();
  app.add_option("--stuck-after", a->stuck_after,
                 "where the LPs after the rounding's fixings at a refined level keep failing for this many times "
                 "its first LP's seconds, or it runs out of rounds, widen the space around them and solve the level "
                 "again (0: off)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--stuck-stalled", a->stuck_stalled,
                 "with --stuck-after: also where the rounding's free variables reach no new low for this many "
                 "rounds taking that long (0: off)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_flag("--blame-residual", a->blame_residual,
               "where a refined level's first LP stops as diverging, widen also around the rows its stalled "
               "iterate leaves furthest from b, not only those its dual grew on");
  app.add_option("--local-proof", a->local_proof,
                 "where a refined level's first LP stops as diverging, look for a proof of infeasibility on a "
                 "relaxation over the X faces around its stalled residual, up to N columns (0: off); a proof widens "
                 "those faces (past --max-ring if need be) and is checked again before the next LP")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--local-proof-solver", a->local_proof_solver,
                 "with --local-proof: pdhg-cpu (its dual at zero cost, checked as a Farkas ray) or clp-dual (the "
                 "simplex's ray; ran into its time cap at full resolution)")
      ->check(CLI::IsMember({"clp-dual", "pdhg-cpu"}))
      ->capture_default_str();
  app.add_flag("--stuck-carry", a->stuck_carry,
               "with --stuck-after: go on from the stuck rounding's fixings in the widened space instead of "
               "afresh (measured slower)");
  app.add_option("--stuck-carry-margin", a->stuck_carry_margin,
                 "with --stuck-carry: also drop the stuck rounding's fixings over the X faces within K fine rings "
                 "of those widened")
      ->check(CLI::Range(0, 64))
      ->capture_default_str();
  app.add_option("--stuck-restarts", a->stuck_restarts,
                 "with --stuck-after: the first N times a level's rounding is stuck, start it again in the same "
                 "space from its fixings to 1, its other state afresh, before widening (0: off)")
      ->check(CLI::Range(0, 100))
      ->capture_default_str();
  app.add_option("--price-widenings", a->price_widenings,
                 "after a refined level's first LP, price the columns one ring out against its dual and widen the X "
                 "faces of those below zero, up to this many times per level, before rounding (0: off)")
      ->check(CLI::Range(0, 16))
      ->capture_default_str();
  app.add_option("--price-tolerance", a->price_tolerance,
                 "price the wider space at this looser LP tolerance, then solve on (0: price the optimum)")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--price-threshold", a->price_threshold,
                 "with --price-widenings: how far below zero (energy units) a column's reduced cost must be")
      ->check(non_negative_number())
      ->capture_default_str();
  app.add_option("--y-margin", a->y_margin,
                 "more fine rings on Y around every face's candidates, at every ring (fine neighbourhood)")
      ->check(CLI::Range(0, 8))
      ->capture_default_str();
  return [a] {
    set_worker_threads(a->threads);
    return run_match(*a);
  };
}

}  // namespace shapematch::app
