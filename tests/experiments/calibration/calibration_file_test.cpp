// calibration.json as one record: a full record goes through to_json and back unchanged, every
// calibration.json the repository holds (written by earlier versions) is read, and a file that is
// not a calibration record is refused naming the file, the key as written and the value.
#include "experiments/calibration/calibration_file.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "experiments/io/input_error.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kFile = "/runs/cal1/calibration.json";

// A record with every field set to something other than its default.
CalibrationRecord full_record() {
  CalibrationRecord r;
  r.status = CalibrationStatus::kSeedNoiseLimited;
  r.message = "the seed spread alone is above the tolerance";
  r.target = {33.64, 0.8};
  r.mu_r = 0.31;
  r.mu_r_lo = 0.27;
  r.mu_r_hi = 0.36;
  r.interval_level = 0.9;
  r.interval_open_low = true;
  r.interval_open_high = false;
  r.fitted_angle_deg = 33.5;
  r.fitted_angle_halfwidth_deg = 0.4;
  r.reachable_low_deg = 24.0;
  r.reachable_high_deg = 41.5;
  r.method = CalibrationMethod::kBracket;
  r.simulations = 12;
  r.fit_method = kMonotoneFitMethod;
  r.fit.points = {{0.1, 2, 24.5, 0.5, 24.0}, {0.3, 3, 33.0, 0.7, 33.2}, {0.6, 2, 41.0, 0.2, 41.5}};
  r.fit.noise_sd_deg = 0.55;
  r.fit.noise_dof = 4;
  r.observations = {{0.1, 1, 24.1}, {0.1, 2, 24.9}, {0.3, 18446744073709551615ull, 33.0}};
  r.excluded = {{0.3, 7, 32.0}};
  r.pour_counts = {{0.6, 2, 1, 1, 0, 0, 0, 0.5, true}, {0.8, 4, 0, 2, 1, 1, 0, 0.5, false}};
  r.campaign = "/data/c.toml";
  r.campaign_name = "s1";
  r.keys = {"contacts.rock-rock.rolling_friction", "contacts.rock-plate.rolling_friction"};
  r.mu_r_range_lo = 0.05;
  r.mu_r_range_hi = 0.8;
  r.tolerance_deg = 0.5;
  r.seeds_per_point = 2;
  r.table1_sample = 3;
  r.scene = "/data/s.toml";
  r.rolling_model = {"cdt", true, "M = mu_r R* |F_n|", "R* = R1 R2 / (R1 + R2)", "w_rel"};
  r.angle_method = "vision on renders: flank lines";
  r.angle = AngleMeasure::kImageFlank;
  r.target_photos = TargetPhotosRecord{
      {"/lab/side_0.png", "/lab/side_90.png"},
      "/lab/camera.json",
      0.21,
      json{{"views", json::array({{{"theta_deg", 33.1}}})}, {"target_from", "theta_deg"}}};
  CalibratedMaterial m;
  m.scene = "/data/s.toml";
  m.scene_fnv1a = "0123456789abcdef";
  m.overrides = {{"sample.mass_kg", "0.007"}, {"sample.psd_file", "\"/data/sieve.csv\""}};
  m.keys = r.keys;
  m.mu_r = 0.31;
  m.mu_r_lo = 0.27;
  m.mu_r_hi = 0.36;
  m.target_deg = 33.64;
  m.angle = "image_flank";
  m.sieve_sheet = "/data/sieve.csv";
  r.material = m;
  r.created_utc = "2026-12-08T01:00:00Z";
  r.code_version = "0.9.0+abc1234";
  r.copied_from = "/runs/other/calibration.json";
  r.working = {{"pours", json::array({{{"mu_r", 0.6}, {"seed", 1}, {"outcome", "jam"}}})},
               {"seeds", {1, 2}},
               {"bracketed", true}};
  return r;
}

TEST(CalibrationFile, AFullRecordComesBackFieldByField) {
  const CalibrationRecord r = full_record();
  const CalibrationRecord back = calibration_record_from_json(to_json(r), kFile);
  EXPECT_EQ(back.status, r.status);
  EXPECT_EQ(back.message, r.message);
  EXPECT_EQ(back.target, r.target);
  EXPECT_EQ(back.mu_r, r.mu_r);
  EXPECT_EQ(back.mu_r_lo, r.mu_r_lo);
  EXPECT_EQ(back.mu_r_hi, r.mu_r_hi);
  EXPECT_EQ(back.interval_level, r.interval_level);
  EXPECT_EQ(back.interval_open_low, r.interval_open_low);
  EXPECT_EQ(back.interval_open_high, r.interval_open_high);
  EXPECT_EQ(back.fitted_angle_deg, r.fitted_angle_deg);
  EXPECT_EQ(back.fitted_angle_halfwidth_deg, r.fitted_angle_halfwidth_deg);
  EXPECT_EQ(back.not_calibrated, r.not_calibrated);
  EXPECT_EQ(back.reachable_low_deg, r.reachable_low_deg);
  EXPECT_EQ(back.reachable_high_deg, r.reachable_high_deg);
  EXPECT_EQ(back.method, r.method);
  EXPECT_EQ(back.simulations, r.simulations);
  EXPECT_EQ(back.fit_method, r.fit_method);
  EXPECT_EQ(back.fit, r.fit);
  EXPECT_EQ(back.observations, r.observations);
  EXPECT_EQ(back.excluded, r.excluded);
  EXPECT_EQ(back.pour_counts, r.pour_counts);
  EXPECT_EQ(back.campaign, r.campaign);
  EXPECT_EQ(back.campaign_name, r.campaign_name);
  EXPECT_EQ(back.keys, r.keys);
  EXPECT_EQ(back.mu_r_range_lo, r.mu_r_range_lo);
  EXPECT_EQ(back.mu_r_range_hi, r.mu_r_range_hi);
  EXPECT_EQ(back.tolerance_deg, r.tolerance_deg);
  EXPECT_EQ(back.seeds_per_point, r.seeds_per_point);
  EXPECT_EQ(back.table1_sample, r.table1_sample);
  EXPECT_EQ(back.scene, r.scene);
  EXPECT_EQ(back.rolling_model, r.rolling_model);
  EXPECT_EQ(back.angle_method, r.angle_method);
  EXPECT_EQ(back.angle, r.angle);
  EXPECT_EQ(back.target_photos, r.target_photos);
  EXPECT_EQ(back.material, r.material);
  EXPECT_EQ(back.created_utc, r.created_utc);
  EXPECT_EQ(back.code_version, r.code_version);
  EXPECT_EQ(back.copied_from, r.copied_from);
  EXPECT_EQ(back.working, r.working);
  EXPECT_TRUE(back == r);
  // The keys every reader before this record used are still written.
  const json j = to_json(r);
  for (const char* k : {"status",
                        "message",
                        "target",
                        "mu_r",
                        "mu_r_interval",
                        "interval_open",
                        "fitted_angle_deg",
                        "reachable_deg",
                        "simulations",
                        "fit",
                        "observations",
                        "excluded_search_observations",
                        "jam_rate_per_mu_r",
                        "method",
                        "campaign",
                        "campaign_name",
                        "key",
                        "keys",
                        "mu_r_range",
                        "tolerance_deg",
                        "seeds_per_point",
                        "table1_sample",
                        "scene",
                        "rolling_model",
                        "angle_method",
                        "angle",
                        "target_photos",
                        "material",
                        "created_utc",
                        "code_version",
                        "pours",
                        "seeds"})
    EXPECT_TRUE(j.contains(k)) << k;
  EXPECT_EQ(j.at("key"), r.keys.front());
}

// A paper run's closest point: a mu_r with a zero-width interval and no fitted angle of its own,
// under the calibration's own status; and a calibration that reached nothing.
TEST(CalibrationFile, AClosestPointAndAnUnreachedRecordComeBack) {
  CalibrationRecord r = full_record();
  r.status = CalibrationStatus::kCannotReachHigh;
  r.not_calibrated = NotCalibrated{CalibrationStatus::kCannotReachHigh, "above the range",
                                   "the usable point closest to the target"};
  r.mu_r_lo = r.mu_r_hi = *r.mu_r;
  r.fitted_angle_deg.reset();
  r.fitted_angle_halfwidth_deg = 0.0;
  r.material.reset();
  EXPECT_TRUE(calibration_record_from_json(to_json(r), kFile) == r);

  CalibrationRecord none = full_record();
  none.status = CalibrationStatus::kCannotReachLow;
  none.mu_r.reset();
  none.mu_r_lo = none.mu_r_hi = 0.0;
  none.interval_level = 0.95;
  none.interval_open_low = false;
  none.fitted_angle_deg.reset();
  none.fitted_angle_halfwidth_deg = 0.0;
  none.material.reset();
  none.target_photos.reset();
  none.table1_sample.reset();
  none.angle.reset();
  none.code_version.clear();
  none.copied_from.clear();
  const json j = to_json(none);
  EXPECT_TRUE(j.at("mu_r").is_null());
  EXPECT_TRUE(j.at("material").is_null());
  EXPECT_FALSE(j.contains("mu_r_interval"));
  EXPECT_TRUE(calibration_record_from_json(j, kFile) == none);
}

// Files as earlier versions wrote them: without "method" (the sequential driver), without
// "material", with "key" beside "keys"; the committed results hold such files.
TEST(CalibrationFile, EveryCommittedCalibrationIsRead) {
  int read = 0;
  for (const auto& e :
       fs::recursive_directory_iterator(fs::path(REPOSETWIN_SOURCE_DIR) / "results")) {
    if (e.path().filename() != "calibration.json") continue;
    const CalibrationRecord r = read_calibration_record(e.path().string());
    EXPECT_FALSE(r.keys.empty()) << e.path();
    EXPECT_FALSE(r.fit.points.empty()) << e.path();
    if (r.mu_r) {
      EXPECT_LE(r.mu_r_lo, r.mu_r_hi) << e.path();
    }
    ++read;
  }
  EXPECT_GE(read, 3);

  json old = to_json(full_record());
  for (const char* k : {"method", "material", "keys", "angle", "code_version", "target_photos",
                        "copied_from", "jam_rate_per_mu_r"})
    old.erase(k);
  const CalibrationRecord r = calibration_record_from_json(old, kFile);
  EXPECT_EQ(r.method, CalibrationMethod::kSequential);
  EXPECT_EQ(r.keys, std::vector<std::string>{"contacts.rock-rock.rolling_friction"});
  EXPECT_FALSE(r.material);
  EXPECT_FALSE(r.angle);
  EXPECT_TRUE(r.pour_counts.empty());
}

std::string refusal(const json& j) {
  try {
    calibration_record_from_json(j, kFile);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

// A file that is not a calibration record names the file, the key as written and its value.
TEST(CalibrationFile, RefusalsNameTheFileTheKeyAndTheValue) {
  const std::string f = kFile;
  EXPECT_EQ(refusal(json::object()), f + ": key \"status\": missing");
  EXPECT_EQ(refusal(json::array()).rfind(f + ": the top level = []: is array, not an object", 0),
            0u)
      << refusal(json::array());
  EXPECT_EQ(refusal(json{{"status", "calibrated"}}), f + ": key \"target\": missing");
  json good = to_json(full_record());
  json bad = good;
  bad["status"] = "done";
  EXPECT_EQ(refusal(bad).rfind(f + ": key \"status\" = \"done\": is not a calibration status "
                                   "(one of calibrated, budget_spent, seed_noise_limited, "
                                   "cannot_reach_low, cannot_reach_high)",
                               0),
            0u)
      << refusal(bad);
  bad = good;
  bad["mu_r"] = "0.31";
  EXPECT_EQ(refusal(bad), f + ": key \"mu_r\" = \"0.31\": is string, not a number");
  bad = good;
  bad.erase("mu_r_interval");
  EXPECT_EQ(refusal(bad), f + ": key \"mu_r_interval\": missing: mu_r = 0.31 carries its 95% "
                              "interval, two numbers");
  bad["mu_r_interval"] = {0.2};
  EXPECT_EQ(refusal(bad),
            f + ": key \"mu_r_interval\" = [0.2]: is an array of 1 values, not two numbers");
  // Deeper: the key as the user reads it, with the nearest known one for a misspelt key.
  bad = good;
  bad["observations"][1]["seed"] = "2";
  EXPECT_EQ(refusal(bad), f + ": key \"observations[1].seed\" = \"2\": is string, not a seed (a "
                              "whole number)");
  bad = good;
  bad["target"]["sd_dg"] = 0.5;
  EXPECT_NE(refusal(bad).find(f + ": key \"target.sd_dg\": is not a known key (value 0.5); did "
                                  "you mean sd_deg?"),
            std::string::npos)
      << refusal(bad);
  bad = good;
  bad["material"]["mu_r"] = "0.31";
  EXPECT_EQ(refusal(bad), f + ": key \"material.mu_r\" = \"0.31\": is string, not a number");
  // The driver's working at the top level is kept, not refused.
  good["bracketed"] = false;
  EXPECT_EQ(refusal(good), "(accepted)");
}

}  // namespace
}  // namespace reposetwin::experiments
