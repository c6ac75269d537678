#include <filesystem>
#include <iostream>
#include <memory>

#include "apps/reposetwin/commands.hpp"
#include "apps/reposetwin/plan_gate.hpp"
#include "apps/reposetwin/validators.hpp"
#include "experiments/calibration/calibrate_campaign.hpp"
#include "experiments/calibration/calibration.hpp"
#include "experiments/calibration/campaign_target.hpp"
#include "experiments/campaign/campaign.hpp"
#include "experiments/campaign/case_runner.hpp"
#include "experiments/io/format.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/loop/sheet_campaign.hpp"
#include "experiments/pile/run_folder.hpp"

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
  bool quiet = false;
  std::string cache;
};

void add_pool_options(CLI::App* cmd, PoolArgs& a, const char* force_help,
                      bool campaign_required = true) {
  auto* file = cmd->add_option("campaign", a.file, "Campaign file (TOML)");
  if (campaign_required) file->required();
  cmd->add_option("--out,-o", a.out, "Output folder (default: runs/<campaign name>)");
  add_workers_option(cmd, a.workers, "Runs side by side on this machine");
  cmd->add_option("--mode", a.mode, "Local pool: processes or threads")
      ->check(CLI::IsMember({"processes", "threads"}))
      ->capture_default_str();
  cmd->add_flag("--force", a.force, force_help);
  cmd->add_flag("--no-images", a.no_images, "Skip renders and vision (particle angles only)");
  cmd->add_option("--views", a.views, "Side views per pile for the image angle")
      ->check(whole_number_in(1, 64))
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
  auto plan = std::make_shared<PlanArgs>();
  cmd->add_flag("--quiet,-q", a->quiet, "No plan lines");
  add_plan_options(cmd, plan);
  cmd->callback([a, plan]() {
    const experiments::Campaign c = experiments::load_campaign(a->file);
    experiments::check_pile_cases(c);
    const std::string out = a->out.empty() ? "runs/" + c.name : a->out;
    experiments::check_output_folder(out);
    if (!a->cache.empty()) experiments::check_output_folder(a->cache, "--cache");
    const experiments::BatchPlan bp = experiments::plan_campaign(c, a->workers);
    if (!accept_plan(experiments::plan_text(bp, plan->limits),
                     experiments::plan_refusal(
                         bp, {experiments::KeySource::Kind::kCampaignFile, c.file}, plan->limits),
                     *plan, a->quiet)) {
      set_exit_code(ExitCode::kPlanRefused);
      return;
    }
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

namespace {

// A calibration from the lab's sheets (--tests, --sieve, --scene) instead of a campaign file.
struct SheetArgs {
  std::string tests, sieve, scene;
  std::vector<double> mu_r_range = {0.02, 0.5};
  bool given() const { return !tests.empty() || !sieve.empty() || !scene.empty(); }
};

// The campaign the calibrate command runs: the campaign file, or the lab's sheets made into one
// (loop/sheet_campaign.hpp), whose text is returned in `sheet_text` to be written to OUT.
experiments::Campaign calibrate_campaign(const PoolArgs& a, const SheetArgs& sheets,
                                         const std::string& angle, std::string& out,
                                         std::string& sheet_text) {
  if (!sheets.given()) {
    if (a.file.empty())
      throw std::invalid_argument(
          "calibrate: give a campaign file, or the lab's sheets: --tests TESTS.csv --scene "
          "BASE.toml [--sieve SIEVE.csv] (docs/calibration.md)");
    experiments::Campaign c = experiments::load_campaign(a.file);
    out = a.out.empty() ? "runs/" + c.name + "_calibration" : a.out;
    return c;
  }
  if (!a.file.empty())
    throw std::invalid_argument("calibrate: a campaign file (" + a.file +
                                ") or the sheets (--tests, --sieve, --scene), not both");
  if (sheets.tests.empty() || sheets.scene.empty())
    throw std::invalid_argument(std::string("calibrate: --") +
                                (sheets.tests.empty() ? "tests" : "scene") +
                                " is missing: a calibration from the lab's sheets takes --tests "
                                "TESTS.csv, --scene BASE.toml and (optional) --sieve SIEVE.csv");
  if (sheets.mu_r_range.size() != 2 || !(sheets.mu_r_range[0] >= 0.0) ||
      !(sheets.mu_r_range[1] > sheets.mu_r_range[0]))
    throw std::invalid_argument("--mu-r-range: need two numbers 0 <= lo < hi");
  experiments::SheetCalibrationRequest r;
  r.tests_csv = sheets.tests;
  r.sieve_sheet = sheets.sieve;
  r.scene = sheets.scene;
  r.mu_r_lo = sheets.mu_r_range[0];
  r.mu_r_hi = sheets.mu_r_range[1];
  if (!angle.empty()) r.angle = experiments::parse_angle_measure(angle, "--angle");
  const std::string stem =
      experiments::sanitize_name(std::filesystem::path(sheets.tests).stem().string());
  out = a.out.empty() ? "runs/" + stem + "_calibration" : a.out;
  r.campaign_file = (std::filesystem::path(out) / "campaign.toml").string();
  experiments::SheetCampaign sc = experiments::sheet_campaign(r);
  sheet_text = sc.text;
  return std::move(sc.campaign);
}

// Writes the sheets' campaign file to OUT, unless another one is there (then --force).
void write_sheet_campaign(const experiments::Campaign& c, const std::string& text, bool force) {
  std::error_code ec;
  if (std::filesystem::is_regular_file(c.file, ec) && !force &&
      experiments::read_file(c.file) != text)
    throw std::runtime_error(c.file + ": another calibration's campaign file is here; give "
                             "another --out, or --force to replace it");
  std::filesystem::create_directories(std::filesystem::path(c.file).parent_path());
  experiments::write_file_atomic(c.file, text);
}

// The calibration's one line: mu_r and its interval, or why there is none.
std::string calibration_line(const experiments::CalibrationRecord& cal, const std::string& out) {
  const auto num = [](double v) { return experiments::significant(v, 3); };
  const std::string status = experiments::to_string(cal.status);
  std::string t;
  if (cal.mu_r)
    t = "mu_r " + num(*cal.mu_r) + " (95% " + num(cal.mu_r_lo) + " to " + num(cal.mu_r_hi) +
        ") for the target " + num(cal.target.angle_deg) + " deg; status " + status;
  else
    t = "no mu_r: the target " + num(cal.target.angle_deg) + " deg is out of reach (" + status +
        ")";
  // The line ends with what to run next, on the folder as typed (the user's shell stands where
  // it was typed).
  std::string next;
  for (const auto& step : experiments::calibration_next_steps(out, cal.reached()))
    next += (next.empty() ? "; next: `" : ", `") + step.command + "` (" + step.what + ")";
  return t + "; " + std::to_string(cal.simulations) + " pile runs; " + out + "/calibration.json" +
         next;
}

}  // namespace

void add_calibrate_command(CLI::App& app) {
  auto a = std::make_shared<PoolArgs>();
  auto angle = std::make_shared<std::string>();
  auto predict_only = std::make_shared<bool>(false);
  auto json = std::make_shared<bool>(false);
  auto only = std::make_shared<std::vector<std::string>>();
  auto sheets = std::make_shared<SheetArgs>();
  auto plan = std::make_shared<PlanArgs>();
  auto* cmd = app.add_subcommand(
      "calibrate",
      "Find mu_r so the simulated angle matches the campaign's [calibration] target (or the lab's "
      "test sheet, --tests), then run its [[predict]] tests at the calibrated mu_r (exit code 5: "
      "the target cannot be reached)");
  add_pool_options(cmd, *a,
                   "Redo finished runs too, and replace a finished OUT/calibration.json made for "
                   "another question (target, mu_r range, keys or angle)",
                   false);
  cmd->add_option("--tests", sheets->tests,
                  "The lab's test sheet (CSV: id, mass, funnel, photo or H_mm/D_mm/angle_deg; "
                  "docs/calibration.md), instead of a campaign file");
  cmd->add_option("--sieve", sheets->sieve,
                  "The lab's sieve sheet (CSV sieve_mm,passing_percent, or TOML [psd]) for every "
                  "test (default: the base scene's own)");
  cmd->add_option("--scene", sheets->scene, "The base scene of the test sheet's tests (TOML)");
  cmd->add_option("--mu-r-range", sheets->mu_r_range,
                  "With --tests: the mu_r range searched, its two ends first")
      ->delimiter(',')
      ->check(plain_number())
      ->expected(2)
      ->capture_default_str();
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
  cmd->add_flag("--json", *json, "Also print calibration.json and the predictions as JSON");
  cmd->add_flag("--quiet,-q", a->quiet, "No plan lines");
  add_plan_options(cmd, plan);
  cmd->callback([a, angle, predict_only, only, sheets, plan, json]() {
    std::string out, sheet_text;
    experiments::Campaign c = calibrate_campaign(*a, *sheets, *angle, out, sheet_text);
    experiments::check_output_folder(out);
    if (!a->cache.empty()) experiments::check_output_folder(a->cache, "--cache");
    if (!only->empty()) experiments::keep_only_predictions(c, *only);
    if (!c.calibration)
      throw std::invalid_argument(c.file + ": [calibration] is missing (target_deg, mu_r_range)");
    experiments::check_pile_cases(c);
    if (*predict_only && c.predictions.empty())
      throw std::invalid_argument(c.file + ": --predict-only but the file has no [[predict]]");
    const experiments::AngleMeasure measure =
        angle->empty() ? c.calibration->angle
                       : experiments::parse_angle_measure(*angle, "--angle");
    PoolArgs pa = *a;
    if (!experiments::angle_measure_needs_images(measure)) pa.no_images = true;
    if (pa.no_images && experiments::angle_measure_needs_images(measure))
      throw std::invalid_argument("--no-images: the angle '" +
                                  experiments::angle_measure_name(measure) +
                                  "' is measured on the renders, so the runs need them");
    const experiments::BatchPlan bp = experiments::plan_calibration(c, a->workers);
    // The plan's advice names what this call takes: the test sheet's columns, or the campaign
    // file's overrides (calibrate takes no --set).
    const experiments::KeySource keys_from =
        sheets->given()
            ? experiments::KeySource{experiments::KeySource::Kind::kTestSheet, sheets->tests}
            : experiments::KeySource{experiments::KeySource::Kind::kCampaignFile, c.file};
    if (!accept_plan(experiments::calibration_order_text(c) +
                         experiments::plan_text(bp, plan->limits),
                     experiments::plan_refusal(bp, keys_from, plan->limits), *plan, a->quiet)) {
      set_exit_code(ExitCode::kPlanRefused);
      return;
    }
    if (!sheet_text.empty()) write_sheet_campaign(c, sheet_text, a->force);
    const experiments::CalibrateOutcome o = experiments::calibrate_and_predict(
        c, out, measure, case_fn(pa), runner(*a), *predict_only);
    const experiments::CalibrationRecord& cal = o.calibration;
    if (*json && !*predict_only) std::cout << experiments::to_json(cal).dump(2) << "\n";
    if (!o.reached) {  // cannot reach: exit code 5
      std::cerr << experiments::cannot_reach_advice(c, cal, measure)
                << (c.predictions.empty() ? "" : "no predictions run\n");
      std::cout << calibration_line(cal, out) << std::endl;
      set_exit_code(ExitCode::kUnreachable);
      return;
    }
    if (o.predictions) {
      const nlohmann::json& p = *o.predictions;
      nlohmann::json brief = nlohmann::json::array();
      for (const auto& q : p["predictions"]) {
        brief.push_back({{"name", q["name"]},
                         {"mu_r", q["mu_r"]},
                         {"mean_deg", q["mean_deg"]},
                         {"seed_sd_deg", q["seed_sd_deg"]},
                         {"measured_deg", q["measured_deg"]},
                         {"error_deg", q["error_deg"]},
                         {"interval_effect_deg", q["interval_effect"]["angle_range_deg"]}});
        if (!*json)
          std::cout << "predict " << q.value("name", std::string()) << ": "
                    << (q["mean_deg"].is_number()
                            ? experiments::significant(q["mean_deg"].get<double>(), 3) + " deg"
                            : std::string("no pile"))
                    << ", measured "
                    << experiments::significant(q.value("measured_deg", 0.0), 3) << " deg\n";
      }
      if (*json)
        std::cout << nlohmann::json{{"predictions", brief}, {"file", out + "/predictions.json"}}
                         .dump(2)
                  << "\n";
    }
    if (cal.status != experiments::CalibrationStatus::kCalibrated)
      std::cerr << "reposetwin calibrate: " << cal.message << "\n";
    std::cout << calibration_line(cal, out) << std::endl;
  });
}

}  // namespace reposetwin::cli
