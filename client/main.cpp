// bathyslam: the command line of the bathyslam service.
#include <cstdio>
#include <exception>

#include "client/commands.h"

int main(int argc, char** argv) {
  CLI::App app{"bathyslam: drift-corrected bathymetric maps from AUV multibeam surveys"};
  app.require_subcommand(1);
  bathyslam::cli::add_simulate_command(app);
  bathyslam::cli::add_inspect_command(app);
  bathyslam::cli::add_process_command(app);
  bathyslam::cli::add_upload_command(app);
  bathyslam::cli::add_site_commands(app);
  bathyslam::cli::add_job_commands(app);
  bathyslam::cli::add_map_commands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bathyslam: %s\n", e.what());
    return 1;
  }
  return 0;
}
