// The plan gate of the commands that simulate (run, calibrate, campaign, timestep, loop, paper):
// the plan is printed before anything runs, and a plan above the limits starts only when
// confirmed.
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "experiments/pile/run_plan.hpp"

namespace reposetwin::cli {

/// The plan options as the command line gives them.
struct PlanArgs {
  experiments::PlanSettings limits;
  bool yes = false;
};

/// Adds --yes, --max-particles and --max-hours to `cmd`.
void add_plan_options(CLI::App* cmd, const std::shared_ptr<PlanArgs>& args);

/// Prints `plan` to stderr (unless `quiet`); a plan above the limits (`refusal` not empty) goes
/// ahead only with --yes or, when a person is at the terminal, their "y". Returns false when it
/// must not start, after saying why.
bool accept_plan(const std::string& plan, const std::string& refusal, const PlanArgs& args,
                 bool quiet);

}  // namespace reposetwin::cli
