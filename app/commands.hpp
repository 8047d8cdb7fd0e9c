#pragma once
// Each subcommand registers its options on the CLI11 app and returns the action to run.
#include <CLI/CLI.hpp>
#include <functional>
#include <string>

namespace shapematch::app {

using Action = std::function<int()>;

Action add_lp_command(CLI::App& app);
Action add_match_command(CLI::App& app);
Action add_devices_command(CLI::App& app);
Action add_generate_assets_command(CLI::App& app);
Action add_bench_command(CLI::App& app);
Action add_eval_command(CLI::App& app);

// The bundled demo pair (assets/), used when a command is given no meshes.
std::string default_mesh_x();
std::string default_mesh_y();

}  // namespace shapematch::app
