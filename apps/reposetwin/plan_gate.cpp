#include "apps/reposetwin/plan_gate.hpp"

#include <unistd.h>

#include <iostream>
#include <optional>

#include "apps/reposetwin/validators.hpp"
#include "experiments/campaign/pool.hpp"

namespace reposetwin::cli {

void add_plan_options(CLI::App* cmd, const std::shared_ptr<PlanArgs>& args) {
  cmd->add_flag("--yes,-y", args->yes,
                "Start even when the plan is above the limits (--max-particles, --max-hours)");
  cmd->add_option("--max-particles", args->limits.max_particles,
                  "Plan limit: more particles in a run need --yes")
      ->capture_default_str()
      ->check(whole_number_in(1, 1'000'000'000'000));
  auto* hours = cmd->add_option_function<double>(
      "--max-hours", [args](double h) { args->limits.max_wall_s = 3600.0 * h; },
      "Plan limit: a longer estimated wall time needs --yes [h] (default 1)");
  hours->check(positive_number());
}

bool accept_plan(const std::string& plan, const std::string& refusal, const PlanArgs& args,
                 bool quiet) {
  // Under mpirun every rank plans the same piles and decides alike, but only rank 0 speaks: N
  // copies of one plan bury the progress lines. No rank asks at the terminal, since one rank's
  // answer would not reach the others; --yes is the only way past a refusal there.
  const std::optional<experiments::RankInfo> rank = experiments::detect_mpi_rank();
  const bool speaks = !rank || rank->rank == 0;
  if (!quiet && speaks) std::cerr << plan;
  if (refusal.empty() || args.yes) return true;
  if (!rank && isatty(STDIN_FILENO) && isatty(STDERR_FILENO)) {
    if (quiet) std::cerr << plan;
    std::cerr << refusal << "\nRun it anyway? [y/N] ";
    std::string answer;
    std::getline(std::cin, answer);
    if (answer == "y" || answer == "Y" || answer == "yes") return true;
  }
  if (speaks) std::cerr << "reposetwin: refused: " << refusal << "\n";
  return false;
}

}  // namespace reposetwin::cli
