// A tiny campaign of real pile runs (two cases, no images) and the report built from it: every
// case appears with its angle, and the HTML links the case files.
#include <gtest/gtest.h>

#include "../../support/tiny_scene.hpp"

#include <filesystem>
#include <fstream>

#include "experiments/calibration/campaign_target.hpp"
#include "experiments/campaign/campaign.hpp"
#include "experiments/campaign/case_runner.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/report/report.hpp"
#include "experiments/calibration/timestep_study.hpp"
#include "experiments/io/input_error.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

using test_support::kTinyScene;

TEST(Report, BuildsFromATinyCampaignWithEveryCase) {
  const fs::path dir = fs::temp_directory_path() / "reposetwin_report_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "tiny.toml") << kTinyScene;
  std::ofstream(dir / "campaign.toml") << R"(
name = "tiny_campaign"
paper = "test"
scene = "tiny.toml"
seeds = [1]
[[case]]
name = "low_mu"
overrides = { "contacts.rock-rock.rolling_friction" = 0.05 }
[[case]]
name = "high_mu"
overrides = { "contacts.rock-rock.rolling_friction" = 0.4 }
)";
  const Campaign c = load_campaign((dir / "campaign.toml").string());
  CaseRunSettings cs;
  cs.images = false;
  RunnerSettings rs;
  rs.mode = WorkerMode::kThreads;
  rs.progress = false;
  const fs::path out = dir / "out";
  const CampaignSummary s = run_campaign(c, out.string(), pile_case_fn(cs), rs);
  ASSERT_EQ(s.finished, 2);
  const nlohmann::json report = build_report(out.string());
  ASSERT_EQ(report["cases"].size(), 2u);
  const std::string html = read_file((out / "report" / "index.html").string());
  EXPECT_NE(html.find("low_mu"), std::string::npos);
  EXPECT_NE(html.find("high_mu"), std::string::npos);
  EXPECT_NE(html.find("series.pvd"), std::string::npos);
  // More rolling resistance, steeper pile (the physics shows through the whole chain).
  double low = 0, high = 0;
  for (const auto& k : report["cases"])
    (k["case"] == "low_mu" ? low : high) = k["particle_theta_mean_deg"].get<double>();
  EXPECT_GT(high, low);
  EXPECT_THROW(build_report((dir / "nothing_here").string()), InputError);
}

}  // namespace
}  // namespace reposetwin::experiments

namespace reposetwin::experiments {
namespace {

TEST(TimestepStudy, LargestStableStepStopsAtTheFirstDeparture) {
  // Angles converge as dt shrinks: stable up to 2e-6 (within 0.5 deg of the finest), and a
  // later point back within tolerance does not count once one has left it.
  const std::vector<std::pair<double, double>> pts = {
      {4e-6, 21.0}, {1e-6, 22.5}, {2e-6, 22.2}, {3e-6, 21.8}, {5e-6, 22.4}};
  EXPECT_DOUBLE_EQ(largest_stable_dt(pts, 0.5), 2e-6);
  EXPECT_DOUBLE_EQ(largest_stable_dt(pts, 1.0), 4e-6 - 1e-6);
  EXPECT_THROW(largest_stable_dt({}, 0.5), InputError);
}

TEST(TimestepStudy, RunsASweepOfTinyPiles) {
  const fs::path dir = fs::temp_directory_path() / "reposetwin_timestep_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "tiny.toml") << kTinyScene;
  TimestepStudySettings s;
  s.rayleigh_fractions = {0.15, 0.3};
  s.runner.mode = WorkerMode::kThreads;
  s.runner.progress = false;
  const nlohmann::json r = run_timestep_study((dir / "tiny.toml").string(), (dir / "out").string(), s);
  ASSERT_EQ(r["points"].size(), 2u);
  EXPECT_LT(r["points"][0]["time_step_s"].get<double>(), r["points"][1]["time_step_s"].get<double>());
  EXPECT_NEAR(r["points"][1]["time_step_s"].get<double>() / r["points"][0]["time_step_s"].get<double>(), 2.0, 1e-9);
  EXPECT_TRUE(r.contains("largest_stable_time_step_s"));
  EXPECT_THROW(run_timestep_study((dir / "missing.toml").string(), (dir / "o2").string(), s), InputError);
}

}  // namespace
}  // namespace reposetwin::experiments
