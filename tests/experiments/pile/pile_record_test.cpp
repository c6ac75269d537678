// The pile run's typed record: every record round-trips through its one JSON form, a stop's
// reason keeps its enum through the file, and a physics stop travels as sim::Status from the
// engine through result.json into a campaign's case result, where it has no angle.
#include "experiments/pile/pile_record.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "../../support/tiny_scene.hpp"
#include "experiments/campaign/case_runner.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/scene.hpp"
#include "experiments/pile/pile_run.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

TEST(PileRecord, EveryStopReasonRoundTripsAndAnUnknownOneIsRefused) {
  std::vector<RunStop> stops = {{StopReason::kSettled, sim::Status::kOk, "calm", ""},
                                {StopReason::kSettleTimeLimit, sim::Status::kOk, "", ""},
                                {StopReason::kTimeLimit, sim::Status::kOk, "phase lift", ""},
                                {StopReason::kClogged, sim::Status::kOk, "no pile: 3 lodged", ""}};
  for (sim::Status s : {sim::Status::kNan, sim::Status::kOverlap, sim::Status::kEscaped})
    stops.push_back({StopReason::kPhysics, s, "particle 7", "numerics.rayleigh_fraction = 0.2"});
  for (const RunStop& s : stops) {
    const RunStop back = stop_from_json(to_json(s));
    EXPECT_EQ(back.reason, s.reason) << stop_reason_text(s);
    EXPECT_EQ(back.physics, s.physics) << stop_reason_text(s);
    EXPECT_EQ(back.detail, s.detail);
    EXPECT_EQ(back.likely_cause, s.likely_cause);
    EXPECT_EQ(back.is_physics(), s.reason == StopReason::kPhysics);
  }
  EXPECT_EQ(stop_reason_text({StopReason::kPhysics, sim::Status::kNan, "", ""}), "physics: nan");
  EXPECT_THROW(stop_from_json({{"reason", "physics: gremlins"}}), std::invalid_argument);
  EXPECT_THROW(stop_from_json({{"reason", "done"}}), std::invalid_argument);
}

PileRun sample_run() {
  PileRun r;
  r.provenance.scene_file = "/x/scene.toml";
  r.provenance.scene_name = "s";
  r.provenance.seed = 42;
  r.provenance.code_version = "0.1.0+abc";
  r.provenance.time_step_s = 1.25e-6;
  r.provenance.rayleigh_time_s = 5e-6;
  r.provenance.softened_youngs_modulus_pa = 4.68e6;
  r.provenance.youngs_modulus_real_pa = 46.8e9;
  r.provenance.threads = 2;
  r.provenance.created_utc = "2026-12-01T00:00:00Z";
  r.provenance.extra = {{"campaign_case", "m200/seed_1"}};
  r.stop = {StopReason::kSettled, sim::Status::kOk, "kinetic energy below", ""};
  r.pile.status = sim::PileStatus::kOk;
  r.pile.height_m = 0.0123;
  r.pile.base_diameter_m = 0.0456;
  r.pile.theta_hd_deg = 28.1;
  r.pile.slice_angle_mean_deg = 30.2;
  r.pile.slice_angle_sd_deg = std::nan("");  // JSON null: must come back as NaN
  r.pile.valid_slices = 15;
  r.pile.centre_x_m = 1e-4;
  r.pile.centre_y_m = -2e-4;
  r.pile.pile_count = 300;
  r.pile.slices = {{0.0, true, 29.0, 27.5}, {11.25, false, 0.0, 0.0}};
  r.psd.source = "data/psd/s1.toml";
  r.psd.name = "s1";
  r.psd.provenance = "Fuller";
  r.psd.assumption = "assumed";
  r.psd.count = 321;
  r.psd.d_min_mm = 4.0;
  r.psd.d_max_mm = 8.0;
  r.psd.fines_fraction_not_simulated = 0.55;
  r.psd.fines_policy = sim::FinesPolicy::kDrop;
  r.psd.intervals = {{4.0, 6.3, 0.4, 0.41, 200}, {6.3, 8.0, 0.6, 0.59, 121}};
  r.particles = {321, 300, 21, 0.0012};
  r.procedure = {0.01,
                 0.4,
                 1.7,
                 2.9,
                 1.0,
                 0.1,
                 3e-9,
                 "funnel",
                 0.04,
                 0.19,
                 0.12,
                 {run_event(0.0, "filled", 321), run_event(0.4, "lift started"),
                  run_event(1.0, "resumed", std::nullopt, "v2")}};
  r.performance = {123456, 12.5, 11.75, 3.2e6, 17, 0.031};
  return r;
}

TEST(PileRecord, APileRunRoundTripsThroughItsJson) {
  const json once = to_json(sample_run());
  const PileRun back = pile_run_from_json(once);
  EXPECT_EQ(to_json(back).dump(), once.dump());
  EXPECT_TRUE(std::isnan(back.pile.slice_angle_sd_deg));
  EXPECT_EQ(back.provenance.extra.at("campaign_case"), "m200/seed_1");
  EXPECT_EQ(back.psd.fines_policy, sim::FinesPolicy::kDrop);
  ASSERT_EQ(back.procedure.events.size(), 3u);
  EXPECT_EQ(back.procedure.events[2].code_version.value_or(""), "v2");
  EXPECT_FALSE(back.procedure.events[1].particles.has_value());

  PileRun clogged = sample_run();
  clogged.stop = {StopReason::kClogged, sim::Status::kOk, "no pile: 9 particles lodged", ""};
  clogged.pile = clogged_pile(9, clogged.stop.detail);
  const PileRun c = pile_run_from_json(to_json(clogged));
  EXPECT_TRUE(c.pile.clogged);
  EXPECT_EQ(c.pile.lodged, 9);
  EXPECT_FALSE(c.pile_ok());
  EXPECT_EQ(to_json(c).dump(), to_json(clogged).dump());
  EXPECT_THROW(pile_run_from_json({{"stop", {{"reason", "settled"}}}}), std::invalid_argument);
}

// A field of the wrong type is refused with its name (through json_read.hpp's number reader),
// where a missing one takes the default a file older than the field had.
TEST(PileRecord, AMistypedNumberIsRefusedByNameAndAMissingOneDefaults) {
  json j = to_json(sample_run());
  j["pile"]["height_m"] = "tall";
  try {
    (void)pile_run_from_json(j);
    FAIL() << "a string height was read";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("/height_m: is string, not a number"), std::string::npos)
        << e.what();
  }
  json c = to_json(sample_run());
  c["procedure"].erase("lift_start_s");
  EXPECT_EQ(pile_run_from_json(c).procedure.lift_start_s, -1.0);
}

TEST(PileRecord, ACaseResultRoundTripsThroughItsJson) {
  const PileRun run = sample_run();
  CaseResult r;
  r.stop = run.stop;
  r.pile = run.pile;
  r.particles = run.particles;
  r.performance = run.performance;
  r.provenance = run.provenance;
  r.psd_fines_fraction = 0.55;
  r.image = CaseImages{27.0, 0.4, 0.012, 0.047, std::nan(""), "run/images"};
  const json once = to_json(r);
  const CaseResult back = case_result_from_json(json{{"result", once}});
  EXPECT_EQ(to_json(back).dump(), once.dump());
  ASSERT_TRUE(back.image.has_value());
  EXPECT_TRUE(std::isnan(back.image->flank_deg));
  EXPECT_DOUBLE_EQ(case_angle_deg(once, AngleMeasure::kImage), 27.0);
}

// A sample far too soft for its weight overlaps past the engine's limit: the engine's status
// reaches the record as an enum, result.json says so, and the case result has no angle.
TEST(PileRecord, APhysicsStopTravelsAsItsEnumFromTheEngineToTheCaseResult) {
  const fs::path dir = fs::temp_directory_path() / "reposetwin_test_physics_stop";
  fs::remove_all(dir);
  const fs::path scene_path = dir / "soft.toml";
  write_file_atomic(scene_path.string(), std::string(test_support::kTinyScene));
  std::string text(test_support::kTinyScene);
  const std::string stiff = "softened_youngs_modulus_pa = 5e6";
  ASSERT_NE(text.find(stiff), std::string::npos);
  text.replace(text.find(stiff), stiff.size(), "softened_youngs_modulus_pa = 1e2");
  const SceneConfig scene = parse_scene_text(text, scene_path.string());
  RunOptions opt;
  opt.out_dir = (dir / "run").string();
  opt.progress = false;
  opt.threads = 1;
  const std::optional<PileRun> run = run_pile_test(scene, opt);
  ASSERT_TRUE(run.has_value());
  ASSERT_EQ(run->stop.reason, StopReason::kPhysics) << stop_reason_text(run->stop);
  EXPECT_EQ(run->stop.physics, sim::Status::kOverlap) << stop_reason_text(run->stop);
  const json file = json::parse(read_file((dir / "run" / "result.json").string()));
  EXPECT_EQ(file.at("stop").at("reason"), "physics: overlap");
  EXPECT_EQ(pile_run_from_json(file).stop.physics, sim::Status::kOverlap);
  CaseResult r;
  r.stop = run->stop;
  r.pile = run->pile;
  EXPECT_TRUE(case_result_from_json(to_json(r)).stop.is_physics());
  EXPECT_THROW(case_angle_deg(to_json(r)), std::runtime_error);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace reposetwin::experiments
