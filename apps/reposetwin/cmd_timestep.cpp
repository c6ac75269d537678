#include <iostream>
#include <memory>

#include "apps/reposetwin/commands.hpp"
#include "apps/reposetwin/plan_gate.hpp"
#include "apps/reposetwin/validators.hpp"
#include "experiments/calibration/timestep_study.hpp"
#include "experiments/io/numbers.hpp"
#include "experiments/pile/run_folder.hpp"

namespace reposetwin::cli {

void add_timestep_command(CLI::App& app) {
  struct Args {
    std::string scene;
    std::string out = "runs/timestep_study";
    experiments::TimestepStudySettings s;
    int workers = 2;
    std::string seeds;
    std::shared_ptr<PlanArgs> plan = std::make_shared<PlanArgs>();
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "timestep", "Time-step study (Fig. 5): the angle against dt and the largest stable dt");
  cmd->add_option("scene", a->scene, "Scene file")->required();
  cmd->add_option("--out,-o", a->out, "Output folder")->capture_default_str();
  cmd->add_option("--fractions", a->s.rayleigh_fractions, "dt as fractions of the Rayleigh time")
      ->delimiter(',')
      ->check(plain_number());
  cmd->add_option("--seeds", a->seeds, "Seeds per dt, comma separated (default 1)");
  cmd->add_option("--tolerance", a->s.tolerance_deg, "Stable within this of the finest [deg]")
      ->capture_default_str()
      ->check(positive_number());
  add_workers_option(cmd, a->workers, "Runs side by side");
  cmd->add_flag("--images", a->s.images, "Use the vision angle on renders");
  add_plan_options(cmd, a->plan);
  cmd->callback([a]() {
    if (!a->seeds.empty()) a->s.seeds = experiments::parse_seed_list(a->seeds, "--seeds");
    for (double f : a->s.rayleigh_fractions) experiments::positive_finite(f, "--fractions");
    a->s.runner.workers = a->workers;
    experiments::check_output_folder(a->out);
    // The plan of every run (the finest dt costs the most), before anything is written.
    const experiments::BatchPlan plan = experiments::plan_campaign(
        experiments::timestep_campaign(a->scene, a->out, a->s), a->workers);
    if (!accept_plan(experiments::plan_text(plan, a->plan->limits),
                     experiments::plan_refusal(
                         plan, {experiments::KeySource::Kind::kSceneFile, a->scene},
                         a->plan->limits), *a->plan, false)) {
      set_exit_code(ExitCode::kPlanRefused);
      return;
    }
    experiments::CampaignSummary summary;
    const nlohmann::json r = experiments::run_timestep_study(a->scene, a->out, a->s, &summary);
    std::cout << r.dump(2) << "\n";
    // A run that failed or gave no angle leaves its dt with fewer runs than asked, or none:
    // the study did not get what it asked for, and says so by its exit code.
    int with_angle = 0;
    for (const nlohmann::json& p : r.at("points")) with_angle += p.at("runs").get<int>();
    if (summary.failed > 0 || with_angle < summary.total) {
      std::cerr << "reposetwin: timestep: " << summary.total - with_angle << " of "
                << summary.total << " runs failed or gave no angle (" << summary.failed
                << " failed; see " << a->out << ")\n";
      set_exit_code(ExitCode::kSomeFailed);
    }
  });
}

}  // namespace reposetwin::cli
