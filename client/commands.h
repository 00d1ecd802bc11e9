#pragma once
// The `bathyslam` subcommands. Each registers its options on the CLI11 app and runs when chosen.
#include <CLI/CLI.hpp>

namespace bathyslam::cli {

void add_simulate_command(CLI::App& app);
void add_inspect_command(CLI::App& app);
void add_process_command(CLI::App& app);

}  // namespace bathyslam::cli
