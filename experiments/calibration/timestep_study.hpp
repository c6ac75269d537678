// The time-step study (the paper's Fig. 5) as one call: the same pile test at a list of time
// steps, the angle against dt, and the largest dt whose angle stays within a tolerance of the
// angle at the finest dt.
//
// The runs go through the campaign machinery (a sweep over numerics.rayleigh_fraction), so a
// study is resumable and its folder can be reported like any campaign.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "experiments/campaign/campaign.hpp"

namespace reposetwin::experiments {

struct TimestepStudySettings {
  std::vector<double> rayleigh_fractions{0.05, 0.1, 0.2, 0.3, 0.4};  // dt / T_R [-]
  std::vector<std::uint64_t> seeds{1};
  double tolerance_deg = 0.5;    // a dt is stable when its mean angle is this close to the finest's
  bool images = false;           // use the vision angle (renders) instead of particle positions
  RunnerSettings runner;
};

/// Runs the study of `scene_path` into `out_dir` and returns (and writes to
/// out_dir/timestep_study.json) per dt: the step [s], the mean and spread of the angle, and the
/// largest stable dt. Throws InputError for an empty or non-positive fraction list.
/// The study as a campaign (one case per fraction, every seed), parsed from the text the study
/// keeps in its folder (`text`, when given), so it can be planned before anything is written.
/// Throws InputError for an empty or non-positive list of fractions or a missing scene.
Campaign timestep_campaign(const std::string& scene_path, const std::string& out_dir,
                           const TimestepStudySettings& settings, std::string* text = nullptr);

/// Runs the study into `out_dir` and returns timestep_study.json; `summary`, when given,
/// receives the campaign's counts (runs failed, runs without an angle by reason).
nlohmann::json run_timestep_study(const std::string& scene_path, const std::string& out_dir,
                                  const TimestepStudySettings& settings,
                                  CampaignSummary* summary = nullptr);

/// The analysis alone: given (dt, mean angle) points, the largest dt whose angle is within
/// `tolerance_deg` of the angle at the smallest dt, such that every smaller dt is within it too.
double largest_stable_dt(const std::vector<std::pair<double, double>>& dt_angle,
                         double tolerance_deg);

}  // namespace reposetwin::experiments
