// shapematch: consistent, orientation-preserving 3D shape matching (Windheuser et al. 2011).
#include "commands.hpp"
#include "shapematch/errors.hpp"
#include "shapematch/system.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <new>
#include <vector>

namespace shapematch::app {

std::string data_dir() {
  // (From the executable's own path, so that an installed tree works wherever it is put and after
  // the source tree is gone; the build tree's binary finds none there and uses the source.)
  static const std::string found = [] {
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    // (equivalent: the build folder's path as configured may pass through a symbolic link)
    if (ec || fs::equivalent(exe.parent_path(), fs::path(SHAPEMATCH_BUILD_DIR), ec))
      return std::string(SHAPEMATCH_SOURCE_DIR);
    std::vector<fs::path> looked;
    looked.push_back((exe.parent_path() / SHAPEMATCH_DATA_FROM_BIN).lexically_normal());
    looked.push_back(SHAPEMATCH_INSTALL_DATA_DIR);
    for (const fs::path& dir : looked)
      if (fs::is_directory(dir / "assets", ec)) return dir.string();
    // A binary outside its build tree without its data beside it (a bin/ reached through a
    // symbolic link, e.g. /bin -> usr/bin with --prefix /): said, not silently the source's.
    spdlog::warn("shapematch: its data (assets/, tools/) is not in {} or {}; using the source tree's, {}",
                 looked.front().string(), looked.back().string(), SHAPEMATCH_SOURCE_DIR);
    return std::string(SHAPEMATCH_SOURCE_DIR);
  }();
  return found;
}
std::string default_mesh_x() { return data_dir() + "/assets/dolphin_straight.off"; }
std::string default_mesh_y() { return data_dir() + "/assets/dolphin_swimming.off"; }
std::vector<std::string> default_bench_lp_pair() {
  return {data_dir() + "/assets/finger_straight.off", data_dir() + "/assets/finger_bent.off"};
}

}  // namespace shapematch::app

int main(int argc, char** argv) {
  using namespace shapematch;
  // Logs go to stderr so that stdout carries only the machine-readable result.
  spdlog::set_default_logger(spdlog::stderr_color_mt("shapematch"));
  spdlog::set_pattern("[%H:%M:%S.%e] %^%l%$ %v");

  CLI::App cli{"shapematch: consistent, orientation-preserving 3D shape matching"};
  cli.set_version_flag("--version", std::string(SHAPEMATCH_VERSION));
  cli.require_subcommand(1);
  bool verbose = false;
  cli.add_flag("-v,--verbose", verbose, "debug logging");

  std::map<CLI::App*, app::Action> actions;
  auto add = [&](app::Action (*make)(CLI::App&), const char* name, const char* help) {
    CLI::App* sub = cli.add_subcommand(name, help);
    actions[sub] = make(*sub);
  };
  add(app::add_match_command, "match", "match two meshes: LP, rounding, verified outputs");
  add(app::add_lp_command, "lp", "build the single-level matching LP and solve its relaxation");
  add(app::add_devices_command, "devices", "list Vulkan compute devices");
  add(app::add_generate_assets_command, "generate-assets", "regenerate the bundled demo meshes");
  add(app::add_bench_command, "bench", "benchmarks: LP solvers (Fig. 4), memory bandwidth, match scaling and pair tables");
  add(app::add_eval_command, "eval", "evaluate a match output against ground truth: geodesic error, PCK, flips");
  add(app::add_checkpoint_command, "checkpoint", "show where a stopped run stands (a match --checkpoint file), as JSON");

  try {
    cli.parse(argc, argv);
    app::check_finite_options(cli);
  } catch (const CLI::ParseError& e) {
    // --help and --version end here too (exit 0). A usage error is an error like any other: one
    // line in the documented form, exit 1 (CLI11's own codes, 105-114, would be a second scheme).
    if (e.get_exit_code() == 0) return cli.exit(e);
    std::string what = e.what();
    std::replace(what.begin(), what.end(), '\n', ' ');
    std::cerr << "shapematch: error: " << what << " (see --help)\n";
    return 1;
  }
  spdlog::set_level(verbose ? spdlog::level::debug : spdlog::level::info);
  try {
    for (auto& [sub, action] : actions)
      if (sub->parsed()) return action();
  } catch (const shapematch::Error& e) {
    std::cerr << "shapematch: error: " << e.what() << "\n";
    return 1;
  } catch (const shapematch::Stopped& e) {  // (match's StopOnSignals)
    std::cerr << "shapematch: " << e.what() << std::endl;
    // Dies by the signal, as without the handler, so that a script's loop stops too (its status
    // is 128 + the signal, 130 or 143, either way).
    const int signal = shapematch::stop_requested() > 0 ? shapematch::stop_requested() : SIGINT;
    std::signal(signal, SIG_DFL);
    std::raise(signal);
    return 128 + signal;
  } catch (const std::bad_alloc&) {
    std::cerr << "shapematch: error: out of memory\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "shapematch: internal error: " << e.what() << "\n";
    return 2;
  }
  return 1;
}
