#pragma once
// Each subcommand registers its options on the CLI11 app and returns the action to run.
#include "validators.hpp"

#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

namespace shapematch::app {

using Action = std::function<int()>;

Action add_lp_command(CLI::App& app);
Action add_match_command(CLI::App& app);
Action add_devices_command(CLI::App& app);
Action add_generate_assets_command(CLI::App& app);
Action add_bench_command(CLI::App& app);
Action add_eval_command(CLI::App& app);
Action add_checkpoint_command(CLI::App& app);

// Where the bundled meshes (assets/) and plotting scripts (tools/) are: an installed binary's
// share/shapematch beside its bin/ (`cmake --install`), else the source tree it was built from.
std::string data_dir();
// The bundled demo pair (assets/), used when a command is given no meshes.
std::string default_mesh_x();
std::string default_mesh_y();
// `bench lp`'s default pair: the bundled finger, on which docs/benchmarks.md was measured, so
// that its numbers stay comparable from run to run.
std::vector<std::string> default_bench_lp_pair();

}  // namespace shapematch::app
