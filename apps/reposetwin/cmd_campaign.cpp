#include <iostream>
#include <memory>

#include "apps/reposetwin/commands.hpp"
#include "experiments/calibration/calibration.hpp"
#include "experiments/calibration/calibrate_campaign.hpp"
#include "experiments/calibration/campaign_target.hpp"
#include "experiments/campaign/campaign.hpp"
#include "experiments/campaign/case_runner.hpp"
#include "experiments/io/provenance.hpp"

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
  std::string cache;
};

void add_pool_options(CLI::App* cmd, PoolArgs& a, const char* force_help) {
  cmd->add_option("campaign", a.file, "Campaign file (TOML)")->required();
  cmd->add_option("--out,-o", a.out, "Output folder (default: runs/<campaign name>)");
  cmd->add_option("--workers", a.workers, "Runs side by side on this machine")
      ->capture_default_str();
  cmd->add_option("--mode", a.mode, "Local pool: processes or threads")
      ->check(CLI::IsMember({"processes", "threads"}))
      ->capture_default_str();
  cmd->add_flag("--force", a.force, force_help);
  cmd->add_flag("--no-images", a.no_images, "Skip renders and vision (particle angles only)");
  cmd->add_option("--views", a.views, "Side views per pile for the image angle")
      ->capture_default_str();
  cmd->add_option("--cache", a.cache,
                  "Pile store (default OUT/cache): piles already poured there by a campaign, a "
                  "calibration or a loop for the same scene, overrides and seed are not poured "
                  "again");
}

experiments::RunnerSettings runner(const PoolArgs& a) {
  experiments::RunnerSettings s;
  s.workers = a.workers;
  s.mode =
      a.mode == "threads" ? experiments::WorkerMode::kThreads : experiments::WorkerMode::kProcesses;
  s.force = a.force;
  s.outcome_of = experiments::case_outcome_word;  // counts piles apart from jams and physics stops
  return s;
}

experiments::CaseFn case_fn(const PoolArgs& a) {
  experiments::CaseRunSettings s;
  s.images = !a.no_images;
  s.image.side_views = a.views;
  s.threads = 1;
  s.store = a.cache;
  return experiments::pile_case_fn(s);
}

}  // namespace

void add_campaign_command(CLI::App& app) {
  auto a = std::make_shared<PoolArgs>();
  auto* cmd = app.add_subcommand(
      "campaign", "Run every case x seed of a campaign file (resumable; spreads over MPI ranks)");
  add_pool_options(cmd, *a, "Redo finished runs too");
  cmd->callback([a]() {
    const experiments::Campaign c = experiments::load_campaign(a->file);
    experiments::check_pile_cases(c);
    const std::string out = a->out.empty() ? "runs/" + c.name : a->out;
    const experiments::CampaignSummary s =
        experiments::run_campaign(c, out, case_fn(*a), runner(*a));
    std::cout << nlohmann::json{{"campaign", c.name},
                                {"out", out},
                                {"total", s.total},
                                {"finished", s.finished},
                                {"piles", s.piles},
                                {"without_pile", s.without_pile},
                                {"failed", s.failed},
                                {"skipped", s.skipped},
                                {"ran", s.ran}}
                     .dump(2)
              << "\n";
    // A run that gave no angle (jammed, not settled, time limit, no pile, physics stop) counts
    // as failed here: the campaign did not get what it asked for.
    int without_angle = 0;
    for (const auto& [reason, n] : s.without_pile) without_angle += n;
    set_exit_code(s.failed + without_angle > 0 ? ExitCode::kSomeFailed : ExitCode::kOk);
  });
}

void add_calibrate_command(CLI::App& app) {
  auto a = std::make_shared<PoolArgs>();
  auto angle = std::make_shared<std::string>();
  auto predict_only = std::make_shared<bool>(false);
  auto only = std::make_shared<std::vector<std::string>>();
  auto* cmd = app.add_subcommand(
      "calibrate",
      "Find mu_r so the simulated angle matches the campaign's [calibration] target, then run "
      "its [[predict]] tests at the calibrated mu_r (exit code 5: the target cannot be reached)");
  add_pool_options(cmd, *a,
                   "Redo finished runs too, and replace a finished OUT/calibration.json made for "
                   "another question (target, mu_r range, keys or angle)");
  cmd->add_option("--angle", *angle,
                  "Angle matched, instead of the campaign's calibration.angle (default image): "
                  "image (atan(2H/D) by vision on renders, as the lab photo), image_flank "
                  "(flank lines by vision on renders), particles (atan(2H/D) from positions) or "
                  "slice (protractor on centre slices, EDEM's)")
      ->check(CLI::IsMember({"image", "image_flank", "particles", "slice"}));
  cmd->add_flag("--predict-only", *predict_only,
                "Reuse the finished OUT/calibration.json (never recalibrate) and run only the "
                "[[predict]] tests");
  cmd->add_option("--only", *only,
                  "Run only these [[predict]] tests (by name); predictions.json then lists "
                  "them alone, and a later call without --only adds the others")
      ->delimiter(',');
  cmd->callback([a, angle, predict_only, only]() {
    experiments::Campaign c = experiments::load_campaign(a->file);
    if (!only->empty()) experiments::keep_only_predictions(c, *only);
    if (!c.calibration)
      throw std::invalid_argument(c.file + ": [calibration] is missing (target_deg, mu_r_range)");
    experiments::check_pile_cases(c);
    if (*predict_only && c.predictions.empty())
      throw std::invalid_argument(c.file + ": --predict-only but the file has no [[predict]]");
    const std::string out = a->out.empty() ? "runs/" + c.name + "_calibration" : a->out;
    const experiments::AngleMeasure measure =
        angle->empty() ? c.calibration->angle
                       : experiments::parse_angle_measure(*angle, "--angle");
    PoolArgs pa = *a;
    if (!experiments::angle_measure_needs_images(measure)) pa.no_images = true;
    if (pa.no_images && experiments::angle_measure_needs_images(measure))
      throw std::invalid_argument("--no-images: the angle '" +
                                  experiments::angle_measure_name(measure) +
                                  "' is measured on the renders, so the runs need them");
    const experiments::CalibrateOutcome o = experiments::calibrate_and_predict(
        c, out, measure, case_fn(pa), runner(*a), *predict_only);
    const nlohmann::json& cal = o.calibration;
    if (!*predict_only) std::cout << cal.dump(2) << "\n";
    std::cerr << "reposetwin calibrate: " << cal.value("simulations", 0) << " pile runs ("
              << cal.value("method", std::string("sequential")) << ")\n";
    if (!o.reached) {  // cannot reach: exit code 5
      std::cerr << "reposetwin calibrate: " << cal.value("message", "")
                << (c.predictions.empty() ? "" : "; no predictions run") << "\n";
      set_exit_code(ExitCode::kUnreachable);
      return;
    }
    if (!o.predictions) return;
    const nlohmann::json& p = *o.predictions;
    nlohmann::json brief = nlohmann::json::array();
    for (const auto& q : p["predictions"])
      brief.push_back({{"name", q["name"]},
                       {"mu_r", q["mu_r"]},
                       {"mean_deg", q["mean_deg"]},
                       {"seed_sd_deg", q["seed_sd_deg"]},
                       {"measured_deg", q["measured_deg"]},
                       {"error_deg", q["error_deg"]},
                       {"interval_effect_deg", q["interval_effect"]["angle_range_deg"]}});
    std::cout << nlohmann::json{{"predictions", brief}, {"file", out + "/predictions.json"}}.dump(2)
              << "\n";
  });
}

}  // namespace reposetwin::cli
