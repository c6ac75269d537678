// reposetwin: the one command-line entry point. Thin: each subcommand lives in its own
// apps/reposetwin/cmd_*.cpp and is registered in the table below.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "apps/reposetwin/commands.hpp"
#include "experiments/io/provenance.hpp"

int main(int argc, char** argv) {
  CLI::App app{"ReposeTwin: a DEM digital twin of the angle-of-repose pile test"};
  app.set_version_flag("--version", reposetwin::experiments::code_version());
  app.require_subcommand(1);
  // Subcommand registry: one line per command.
  reposetwin::cli::add_run_command(app);
  reposetwin::cli::add_render_command(app);
  reposetwin::cli::add_campaign_command(app);
  reposetwin::cli::add_calibrate_command(app);
  reposetwin::cli::add_report_command(app);
  reposetwin::cli::add_timestep_command(app);
  reposetwin::cli::add_measure_command(app);
  reposetwin::cli::add_loop_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::cerr << "reposetwin: error: " << e.what() << "\n";
    return 2;
  }
  return reposetwin::cli::exit_code();
}
