#include <iostream>
#include <memory>

#include "apps/reposetwin/commands.hpp"
#include "apps/reposetwin/validators.hpp"
#include "experiments/io/numbers.hpp"
#include "experiments/calibration/timestep_study.hpp"

namespace reposetwin::cli {

void add_timestep_command(CLI::App& app) {
  struct Args {
    std::string scene;
    std::string out = "runs/timestep_study";
    experiments::TimestepStudySettings s;
    int workers = 2;
    std::string seeds;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "timestep", "Time-step study (Fig. 5): the angle against dt and the largest stable dt");
  cmd->add_option("scene", a->scene, "Scene file")->required();
  cmd->add_option("--out,-o", a->out, "Output folder")->capture_default_str();
  cmd->add_option("--fractions", a->s.rayleigh_fractions, "dt as fractions of the Rayleigh time")
      ->delimiter(',');
  cmd->add_option("--seeds", a->seeds, "Seeds per dt, comma separated (default 1)");
  cmd->add_option("--tolerance", a->s.tolerance_deg, "Stable within this of the finest [deg]")
      ->capture_default_str()
      ->check(positive_number());
  cmd->add_option("--workers", a->workers, "Runs side by side")->capture_default_str();
  cmd->add_flag("--images", a->s.images, "Use the vision angle on renders");
  cmd->callback([a]() {
    if (!a->seeds.empty()) a->s.seeds = experiments::parse_seed_list(a->seeds, "--seeds");
    for (double f : a->s.rayleigh_fractions) experiments::positive_finite(f, "--fractions");
    a->s.runner.workers = a->workers;
    const nlohmann::json r = experiments::run_timestep_study(a->scene, a->out, a->s);
    std::cout << r.dump(2) << "\n";
  });
}

}  // namespace reposetwin::cli
