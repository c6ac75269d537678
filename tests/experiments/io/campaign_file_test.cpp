// The campaign file read strictly: cases crossed with seeds, sweeps and calibrations, lab photos
// as a calibration target, and every bad key or value refused naming the file.
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <set>

#include "../../vision/synthetic.hpp"
#include "../campaign/campaign_fixtures.hpp"
#include "experiments/calibration/campaign_target.hpp"
#include "experiments/campaign/campaign.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;
using namespace campaign_fixtures;

std::string load_error(const fs::path& file) {
  try {
    load_campaign(file.string());
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(CampaignFile, ParsesCasesCrossedWithSeeds) {
  const ScratchDir scratch("parse_cases");
  const fs::path& dir = scratch.path;
  const auto c = load_campaign(write_campaign(dir, kCasesCampaign).string());
  EXPECT_EQ(c.name, "cases_demo");
  EXPECT_EQ(c.paper, "Fig. 8");
  EXPECT_EQ(c.scene_path, fs::absolute(dir / "scene.toml").lexically_normal().string());
  ASSERT_EQ(c.runs.size(), 4u);
  EXPECT_EQ(c.runs[0].id(), "low/seed_1");
  EXPECT_EQ(c.runs[3].id(), "high/seed_2");
  EXPECT_EQ(c.runs[3].index, 3u);
  // Common overrides apply to every case; a case's own override wins; unquoted dotted keys work.
  const auto low = build_case_scene(c.runs[0]);
  EXPECT_DOUBLE_EQ(low.number("rolling.mu_r").value(), 0.05);
  EXPECT_DOUBLE_EQ(low.number("sample.mass").value(), 0.9);
  const auto high = build_case_scene(c.runs[2]);
  EXPECT_DOUBLE_EQ(high.number("rolling.mu_r").value(), 0.2);
  EXPECT_DOUBLE_EQ(high.number("sample.mass").value(), 1.0);
  EXPECT_FALSE(c.calibration.has_value());
}

TEST(CampaignFile, ParsesSweepAndCalibration) {
  const ScratchDir scratch("parse_sweep");
  const fs::path& dir = scratch.path;
  fs::create_directories(dir / "campaigns");
  const auto file = write_campaign(dir / "campaigns", R"(
name = "mu_sweep"
scene = "../scene.toml"
seeds = 3
[sweep]
key = "rolling.mu_r"
values = [0.05, 0.1, 0.15]
[calibration]
target_deg = 33.47
target_sd_deg = 0.3
mu_r_range = [0.02, 0.4]
seeds_per_point = 2
max_simulations = 20
angle = "image_flank"
)");
  const auto c = load_campaign(file.string());
  ASSERT_EQ(c.runs.size(), 9u);
  EXPECT_EQ(c.runs[0].case_name, "mu_r_0.05");
  EXPECT_EQ(c.runs[8].id(), "mu_r_0.15/seed_3");
  EXPECT_DOUBLE_EQ(build_case_scene(c.runs[4]).number("rolling.mu_r").value(), 0.1);
  ASSERT_TRUE(c.calibration.has_value());
  EXPECT_EQ(c.calibration->key, "contacts.rock-rock.rolling_friction");  // the scene format's
  EXPECT_DOUBLE_EQ(c.calibration->target.angle_deg, 33.47);
  EXPECT_DOUBLE_EQ(c.calibration->target.sd_deg, 0.3);
  EXPECT_DOUBLE_EQ(c.calibration->settings.mu_r_lo, 0.02);
  EXPECT_DOUBLE_EQ(c.calibration->settings.mu_r_hi, 0.4);
  EXPECT_EQ(c.calibration->settings.seeds_per_point, 2);
  EXPECT_EQ(c.calibration->settings.max_simulations, 20);
  EXPECT_EQ(c.calibration->angle, AngleMeasure::kImageFlank);
}

// The lab's photos as the calibration target, measured as the renders are: atan(2H/D) for the
// image angle, the flank angle for image_flank. Two cones drawn from their geometry (60 mm high,
// 200 mm wide: flanks atan(0.6) = 30.96 deg), one with its apex rounded by a 30 mm arc tangent to
// the flanks (its top 60 - 30 (1/cos 30.96 - 1) = 55.0 mm high: atan(2H/D) 28.81 deg, flanks
// unchanged); the truth is the geometry, not the code.
TEST(CampaignFile, CalibrationTargetFromLabPhotos) {
  const ScratchDir scratch("target_photos");
  const fs::path& dir = scratch.path;
  fs::create_directories(dir / "lab");
  vision::synthetic::SideScene cone;
  cone.look.noise_sigma = 2.0;
  cv::imwrite((dir / "lab" / "sharp.png").string(), vision::synthetic::draw_side(cone));
  cone.apex_radius_mm = 30.0;
  cv::imwrite((dir / "lab" / "rounded.png").string(), vision::synthetic::draw_side(cone));
  const double flank = std::atan(0.6) * 180.0 / M_PI;
  const double rounded_h = 60.0 - 30.0 * (1.0 / std::cos(std::atan(0.6)) - 1.0);
  const double theta = 0.5 * (flank + std::atan(2.0 * rounded_h / 200.0) * 180.0 / M_PI);
  auto campaign = [&](const std::string& calibration_keys) {
    return write_campaign(dir, "name = \"photo_target\"\nscene = \"scene.toml\"\nseeds = 1\n"
                               "[calibration]\nmu_r_range = [0.05, 0.5]\n" +
                                   calibration_keys);
  };
  const std::string photos =
      "target_photos = [\"lab/sharp.png\", \"lab/rounded.png\"]\ntarget_mm_per_px = 0.25\n";

  Campaign c = load_campaign(campaign(photos).string());
  ASSERT_TRUE(c.calibration.has_value());
  EXPECT_NEAR(c.calibration->target.angle_deg, theta, 0.3);
  EXPECT_GT(c.calibration->target.sd_deg, 0.5);  // the two photos differ by 2.2 deg
  EXPECT_LT(c.calibration->target.sd_deg, 2.0);
  EXPECT_EQ(c.calibration->target_photos["views"].size(), 2u);
  EXPECT_EQ(c.calibration->target_photos["photos"][0], (dir / "lab" / "sharp.png").string());

  c = load_campaign(campaign(photos + "angle = \"image_flank\"\ntarget_sd_deg = 0.4\n").string());
  EXPECT_NEAR(c.calibration->target.angle_deg, flank, 0.3);
  EXPECT_DOUBLE_EQ(c.calibration->target.sd_deg, 0.4);  // given: it replaces the measurement's

  // Bad input names the key and the value.
  std::string e = load_error(campaign(photos + "target_deg = 30.0\n"));
  EXPECT_NE(e.find("calibration.target_photos"), std::string::npos) << e;
  EXPECT_NE(e.find("either target_deg or target_photos"), std::string::npos) << e;
  e = load_error(campaign("target_photos = \"lab/missing.png\"\ntarget_mm_per_px = 0.25\n"));
  EXPECT_NE(e.find("calibration.target_photos"), std::string::npos) << e;
  EXPECT_NE(e.find("missing.png"), std::string::npos) << e;
  e = load_error(campaign("target_photos = \"lab/sharp.png\"\ntarget_mm_per_px = -1\n"));
  EXPECT_NE(e.find("calibration.target_mm_per_px"), std::string::npos) << e;
  e = load_error(campaign("target_deg = 30.0\ntarget_mm_per_px = 0.25\n"));
  EXPECT_NE(e.find("only with target_photos"), std::string::npos) << e;
  e = load_error(campaign("target_photos = []\n"));
  EXPECT_NE(e.find("needs at least one photo"), std::string::npos) << e;
  // A photo with no scale source (no marker drawn, none declared) says how to give one.
  cone.scale_bar = false;
  cv::imwrite((dir / "lab" / "no_scale.png").string(), vision::synthetic::draw_side(cone));
  e = load_error(campaign("target_photos = \"lab/no_scale.png\"\n"));
  EXPECT_NE(e.find("calibration.target_photos"), std::string::npos) << e;
  EXPECT_NE(e.find("target_mm_per_px"), std::string::npos) << e;
}

TEST(CampaignFile, MissingSceneIsAClearError) {
  const ScratchDir scratch("missing_scene");
  const fs::path& dir = scratch.path;
  const auto e = load_error(write_campaign(dir, R"(
name = "x"
scene = "no_such_scene.toml"
seeds = [1]
[[case]]
name = "a"
)"));
  EXPECT_NE(e.find("campaign.toml"), std::string::npos) << e;
  EXPECT_NE(e.find("'scene'"), std::string::npos) << e;
  EXPECT_NE(e.find("no_such_scene.toml"), std::string::npos) << e;
  const auto e2 = load_error(write_campaign(dir, R"(
name = "x"
scene = "scene.toml"
seeds = [1]
[[case]]
name = "a"
scene = "other.toml"
)"));
  EXPECT_NE(e2.find("case[0].scene"), std::string::npos) << e2;
  EXPECT_NE(e2.find("other.toml"), std::string::npos) << e2;
  EXPECT_NE(load_error(dir / "nothing.toml").find("nothing.toml"), std::string::npos);
}

TEST(CampaignFile, BadKeysAndValuesAreRejected) {
  const ScratchDir scratch("bad_keys");
  const fs::path& dir = scratch.path;
  const std::string head = "name = \"x\"\nscene = \"scene.toml\"\nseeds = [1, 2]\n";
  struct Bad {
    std::string text, must_contain;
  };
  const std::vector<Bad> cases = {
      {head + "colour = 3\n[[case]]\nname = \"a\"\n", "colour"},
      {head + "[[case]]\nname = \"a\"\nmu = 0.1\n", "case[0].mu"},
      {head + "[[case]]\nname = \"a/b\"\n", "a/b"},
      {head + "[[case]]\nname = \"a\"\n[[case]]\nname = \"a\"\n", "not unique"},
      {head + "[[case]]\nname = \"a\"\noverrides = { \"rolling.spring.k\" = 1.0 }\n",
       "rolling.spring.k"},
      {head + "[[case]]\nname = \"a\"\noverrides = { \"rolling.mu_r\" = \"0.1\" }\n",
       "rolling.mu_r"},
      {head + "[[case]]\nname = \"a\"\n[sweep]\nkey = \"rolling.mu_r\"\nvalues = [0.1]\n",
       "not both"},
      {head + "[sweep]\nkey = \"rolling.mu_r\"\nvalues = [0.1, 0.10]\n", "not unique"},
      {head + "[sweep]\nkey = \"rolling.mu_r\"\nvalues = []\n", "sweep.values"},
      {head + "[sweep]\nkey = \"rolling.mu_r\"\nvalues = [0.1]\nstep = 2\n", "sweep.step"},
      {"name = \"x\"\nscene = \"scene.toml\"\n[[case]]\nname = \"a\"\n", "seeds"},
      {"name = \"x\"\nscene = \"scene.toml\"\nseeds = [1, 1]\n[[case]]\nname = \"a\"\n",
       "repeated"},
      {"name = \"x y\"\nscene = \"scene.toml\"\nseeds = [1]\n[[case]]\nname = \"a\"\n", "x y"},
      {"scene = \"scene.toml\"\nseeds = [1]\n[[case]]\nname = \"a\"\n", "'name'"},
      {head, "no [[case]]"},
      {head + "[calibration]\ntarget_deg = 95\nmu_r_range = [0.0, 0.3]\n", "95"},
      {head + "[calibration]\ntarget_deg = 30\nmu_r_range = [0.3, 0.1]\n", "mu_r_range"},
      {head + "[calibration]\ntarget_deg = 30\nmu_r_range = [0.0, 0.3]\nkey = \"nope.mu\"\n",
       "nope.mu"},
      {head + "[calibration]\ntarget_deg = 30\nmu_r_range = [0.0, 0.3]\nspeed = 1\n",
       "calibration.speed"},
      {head + "[calibration]\ntarget_deg = 30\nmu_r_range = [0.0, 0.3]\nangle = \"flank\"\n",
       "calibration.angle' = \"flank\""},
      {head + "[[case]\nname = \"a\"\n", "campaign.toml:"},
  };
  for (const auto& b : cases) {
    const auto e = load_error(write_campaign(dir, b.text));
    EXPECT_NE(e.find(b.must_contain), std::string::npos) << "text:\n" << b.text << "\nerror: " << e;
    EXPECT_NE(e.find("campaign.toml"), std::string::npos) << e;
  }
}

// A table written as a value is one override that replaces or creates the table whole; dotted
// keys (quoted or bare) set members, creating a table the scene format has where the scene has
// none.
TEST(CampaignFile, ATableValueIsOneOverrideAndDottedKeysAreMembers) {
  const ScratchDir scratch("table_values");
  const auto c = load_campaign(write_campaign(scratch.path, R"(
name = "tables"
scene = "scene.toml"
seeds = [1]
[[case]]
name = "whole"
overrides = { rolling = { model = "cdt" }, sample.shape = { kind = "generated", spheres = 4 } }
[[case]]
name = "members"
overrides = { rolling.model = "cdt", "sample.shape.kind" = "generated", sample.shape.spheres = 4 }
)").string());
  ASSERT_EQ(c.runs.size(), 2u);
  EXPECT_EQ(c.runs[0].overrides.size(), 2u);
  EXPECT_EQ(c.runs[1].overrides.size(), 3u);
  const auto whole = build_case_scene(c.runs[0]);
  EXPECT_EQ(whole.string("rolling.model").value(), "cdt");
  EXPECT_FALSE(whole.has("rolling.mu_r"));  // the scene's [rolling] replaced
  EXPECT_EQ(whole.number("sample.shape.spheres").value(), 4);
  EXPECT_DOUBLE_EQ(whole.number("sample.mass").value(), 0.2);
  const auto members = build_case_scene(c.runs[1]);
  EXPECT_EQ(members.string("rolling.model").value(), "cdt");
  EXPECT_DOUBLE_EQ(members.number("rolling.mu_r").value(), 0.1);  // kept
  EXPECT_EQ(members.string("sample.shape.kind").value(), "generated");
  EXPECT_EQ(members.number("sample.shape.spheres").value(), 4);
  // The case's overrides are recorded as written: the whole table as one JSON object.
  const nlohmann::json j = to_json(c.runs[0]);
  EXPECT_EQ(j.at("overrides").at("sample.shape").at("spheres"), 4) << j.dump();
}

TEST(CampaignFile, SafeNames) {
  EXPECT_TRUE(is_safe_name("mu_r_0.15"));
  EXPECT_TRUE(is_safe_name("W-40mm"));
  for (const char* n : {"", ".", "..", ".hidden", "a/b", "a b", "a\\b", "-x"})
    EXPECT_FALSE(is_safe_name(n)) << n;
  EXPECT_FALSE(is_safe_name(std::string(101, 'a')));
}

}  // namespace
}  // namespace reposetwin::experiments
