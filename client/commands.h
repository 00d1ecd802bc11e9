#pragma once
// The `bathyslam` subcommands. Each registers its options on the CLI11 app and runs when chosen.
#include <CLI/CLI.hpp>

namespace bathyslam::cli {

// Offline.
void add_simulate_command(CLI::App& app);
void add_inspect_command(CLI::App& app);
void add_process_command(CLI::App& app);
// Against a server.
void add_upload_command(CLI::App& app);
void add_job_commands(CLI::App& app);  // submit, watch, jobs, report
void add_map_commands(CLI::App& app);  // tiles, map
void add_site_commands(CLI::App& app);  // site create, add, remove, list, show, delete

}  // namespace bathyslam::cli
