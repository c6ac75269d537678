#include <iostream>
#include <memory>

#include "apps/reposetwin/commands.hpp"
#include "experiments/calibration.hpp"
#include "experiments/campaign.hpp"
#include "experiments/case_runner.hpp"
#include "experiments/provenance.hpp"

namespace reposetwin::cli {
namespace {

struct PoolArgs {
  std::string file;
  std::string out;
  int workers = 2;
  std::string mode = "processes";
  bool force = false;
  bool no_images = false;
  int views = 4;
};

void add_pool_options(CLI::App* cmd, PoolArgs& a) {
  cmd->add_option("campaign", a.file, "Campaign file (TOML)")->required();
  cmd->add_option("--out,-o", a.out, "Output folder (default: runs/<campaign name>)");
  cmd->add_option("--workers", a.workers, "Runs side by side on this machine")->capture_default_str();
  cmd->add_option("--mode", a.mode, "Local pool: processes or threads")
      ->check(CLI::IsMember({"processes", "threads"}))
      ->capture_default_str();
  cmd->add_flag("--force", a.force, "Redo finished runs too");
  cmd->add_flag("--no-images", a.no_images, "Skip renders and vision (particle angles only)");
  cmd->add_option("--views", a.views, "Side views per pile for the image angle")->capture_default_str();
}

experiments::RunnerSettings runner(const PoolArgs& a) {
  experiments::RunnerSettings s;
  s.workers = a.workers;
  s.mode = a.mode == "threads" ? experiments::WorkerMode::kThreads
                               : experiments::WorkerMode::kProcesses;
  s.force = a.force;
  return s;
}

experiments::CaseFn case_fn(const PoolArgs& a) {
  experiments::CaseRunSettings s;
  s.images = !a.no_images;
  s.image.side_views = a.views;
  s.threads = 1;
  return experiments::pile_case_fn(s);
}

}  // namespace

void add_campaign_command(CLI::App& app) {
  auto a = std::make_shared<PoolArgs>();
  auto* cmd = app.add_subcommand(
      "campaign", "Run every case x seed of a campaign file (resumable; spreads over MPI ranks)");
  add_pool_options(cmd, *a);
  cmd->callback([a]() {
    const experiments::Campaign c = experiments::load_campaign(a->file);
    const std::string out = a->out.empty() ? "runs/" + c.name : a->out;
    const experiments::CampaignSummary s =
        experiments::run_campaign(c, out, case_fn(*a), runner(*a));
    std::cout << nlohmann::json{{"campaign", c.name}, {"out", out},      {"total", s.total},
                                {"finished", s.finished}, {"failed", s.failed},
                                {"skipped", s.skipped},   {"ran", s.ran}}
                     .dump(2)
              << "\n";
    set_exit_code(s.failed > 0 ? 4 : 0);
  });
}

void add_calibrate_command(CLI::App& app) {
  auto a = std::make_shared<PoolArgs>();
  auto angle = std::make_shared<std::string>("image");
  auto* cmd = app.add_subcommand(
      "calibrate", "Find mu_r so the simulated angle matches the campaign's [calibration] target");
  add_pool_options(cmd, *a);
  cmd->add_option("--angle", *angle,
                  "Angle matched: image (vision on renders, as the lab photo) or particles")
      ->check(CLI::IsMember({"image", "particles"}))
      ->capture_default_str();
  cmd->callback([a, angle]() {
    const experiments::Campaign c = experiments::load_campaign(a->file);
    if (!c.calibration)
      throw std::invalid_argument(c.file + ": [calibration] is missing (target_deg, mu_r_range)");
    const std::string out = a->out.empty() ? "runs/" + c.name + "_calibration" : a->out;
    PoolArgs pa = *a;
    if (*angle == "particles") pa.no_images = true;
    const experiments::CaseFn fn = case_fn(pa);
    const experiments::RunnerSettings rs = runner(*a);
    const bool prefer_image = *angle == "image";
    auto simulate = [&](const std::vector<std::pair<double, std::uint64_t>>& points) {
      std::vector<experiments::CaseSpec> runs;
      for (const auto& [mu, seed] : points) runs.push_back(experiments::calibration_run(c, mu, seed));
      const std::vector<nlohmann::json> results = experiments::run_batch(c, runs, out, fn, rs);
      std::vector<double> angles;
      for (const nlohmann::json& r : results)
        angles.push_back(experiments::case_angle_deg(r, prefer_image));
      return angles;
    };
    const experiments::CalibrationResult r = experiments::calibrate_batch(
        simulate, c.calibration->target, c.calibration->settings);
    nlohmann::json j = experiments::to_json(r);
    j["campaign"] = c.file;
    j["key"] = c.calibration->key;
    j["angle_method"] = prefer_image ? "vision on renders (atan(2H/D), perspective corrected)"
                                     : "particle positions (atan(2H/D))";
    j["code_version"] = experiments::code_version();
    j["created_utc"] = experiments::utc_now();
    experiments::write_json_atomic(out + "/calibration.json", j);
    std::cout << j.dump(2) << "\n";
  });
}

}  // namespace reposetwin::cli
