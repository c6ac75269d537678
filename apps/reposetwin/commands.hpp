// The subcommands of `reposetwin`; each add_*_command registers one on the app.
#pragma once

#include <CLI/CLI.hpp>

namespace reposetwin::cli {

/// Exit code set by the subcommand that ran (0 = success).
int exit_code();
void set_exit_code(int code);

void add_run_command(CLI::App& app);
void add_render_command(CLI::App& app);
void add_campaign_command(CLI::App& app);
void add_calibrate_command(CLI::App& app);
void add_report_command(CLI::App& app);
void add_timestep_command(CLI::App& app);
void add_measure_command(CLI::App& app);
void add_loop_command(CLI::App& app);  // loop and loop-synth
void add_keys_command(CLI::App& app);
void add_paper_command(CLI::App& app);  // the paper's index: run, list, page
void add_export_command(CLI::App& app);
void add_measure_particles_command(CLI::App& app);

}  // namespace reposetwin::cli
