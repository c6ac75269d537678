// The subcommands of `reposetwin`; each add_*_command registers one on the app.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

namespace reposetwin::cli {

/// The exit codes of `reposetwin` besides CLI11's own (100-127), each documented in the
/// README's table and in `reposetwin --help` (exit_code_help()).
enum class ExitCode : int {
  kOk = 0,
  kError = 2,          // bad input or another error; nothing was run
  kPhysicsStop = 3,    // run: the engine stopped the run
  kSomeFailed = 4,     // campaign, timestep: some cases failed or gave no angle; paper: items
  kUnreachable = 5,    // calibrate: the target angle cannot be reached
  kPlanRefused = 6,    // a command that simulates: the plan is above the limits, unconfirmed
  kNoPile = 7,         // run, measure-particles: no settled pile to measure (time limit, not
                       // settled, jam, none)
  kNoPhotographs = 8,  // run: the photographs could not be written or measured
  kRefused = 9,        // measure: a photo failed an admission check (vision/admission.hpp)
  kBusy = 10,          // run, render, report: another command holds the run folder's lock
  kIncomplete = 11,    // report: a run folder stopped between stages (pile/run_state.hpp)
};

/// Exit code set by the subcommand that ran (0 = success).
int exit_code();
void set_exit_code(ExitCode code);

/// Every exit code with its meaning, one per line, as `reposetwin --help` ends.
std::string exit_code_help();

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
