// The representativeness rules against hand computations on the tiny scene: the predicted pile
// height is the cone of the simulated mass, and each rule warns exactly past its threshold.
#include "experiments/pile/representativeness.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <utility>

#include "../../support/tiny_scene.hpp"
#include "experiments/pile/run_plan.hpp"

namespace reposetwin::experiments {
namespace {

// The tiny scene with `from` replaced by `to` in its text.
SceneConfig tiny_with(const std::string& from = "", const std::string& to = "") {
  std::string text = test_support::kTinyScene;
  if (!from.empty()) text.replace(text.find(from), from.size(), to);
  return parse_scene_text(text, "tiny.toml");
}

// The tiny scene with `mass_kg` of rock in a funnel tall and wide enough to hold it.
SceneConfig tiny_of_mass(const std::string& mass_kg) {
  std::string text = test_support::kTinyScene;
  for (const auto& [from, to] :
       {std::pair<std::string, std::string>{"mass_kg = 0.006", "mass_kg = " + mass_kg},
        {"top_diameter_m = 0.05", "top_diameter_m = 0.2"},
        {"height_m = 0.04", "height_m = 0.6"}})
    text.replace(text.find(from), from.size(), to);
  return parse_scene_text(text, "tiny.toml");
}

bool warns(const Representativeness& r, RepresentativenessCheck c) {
  return !r.warnings[static_cast<std::size_t>(c)].empty();
}

TEST(Representativeness, PredictedHeightIsTheConeOfTheSimulatedMass) {
  const Representativeness r = representativeness(tiny_with());
  // 6 g of rock (2760 kg/m^3) at solid fraction 0.6: V = 3.623e-6 m^3; a cone of that volume
  // at 20 deg is H = (3 V tan^2 20 / pi)^(1/3) = 7.71 mm, at 45 deg (3 V / pi)^(1/3) = 15.1 mm.
  const double v = 0.006 / (2760.0 * 0.6);
  const double t20 = std::tan(20.0 * std::numbers::pi / 180.0);
  EXPECT_NEAR(r.height_lo_m, std::cbrt(3.0 * v * t20 * t20 / std::numbers::pi), 1e-12);
  EXPECT_NEAR(r.height_lo_m, 7.71e-3, 0.01e-3);
  EXPECT_NEAR(r.height_hi_m, 15.12e-3, 0.01e-3);
  EXPECT_DOUBLE_EQ(r.d_max_m, 4e-3);
  // 7.7 mm is below 10 d_max = 40 mm; the outlet (20 mm, 5 d_max) and the sheet (all of it
  // simulated) pass.
  EXPECT_TRUE(warns(r, RepresentativenessCheck::kPileHeight));
  EXPECT_FALSE(warns(r, RepresentativenessCheck::kOutletWidth));
  EXPECT_FALSE(warns(r, RepresentativenessCheck::kMassNotSimulated));
  EXPECT_NEAR(r.not_simulated_fraction, 0.0, 1e-12);
  EXPECT_NEAR(r.outlet_over_d_max, 5.0, 1e-12);
  const std::string w = r.warnings[0];
  for (const char* part : {"8-15 mm", "20-45 deg", "10 d_max = 40 mm", "sample.mass_kg"})
    EXPECT_NE(w.find(part), std::string::npos) << part << " in: " << w;
}

TEST(Representativeness, HeightRuleHoldsForAHighEnoughPile) {
  // H grows as the cube root of the mass: 6 g -> 7.71 mm at 20 deg; 40 mm needs 0.84 kg.
  EXPECT_TRUE(warns(representativeness(tiny_of_mass("0.8")), RepresentativenessCheck::kPileHeight));
  EXPECT_FALSE(
      warns(representativeness(tiny_of_mass("0.9")), RepresentativenessCheck::kPileHeight));
  // After the run the measured height is held to the rule too.
  const SceneConfig big = tiny_of_mass("0.9");
  const Representativeness low = representativeness(big, 0.012);
  EXPECT_TRUE(warns(low, RepresentativenessCheck::kPileHeight));
  EXPECT_NE(low.warnings[0].find("H = 12.0 mm measured (3.0 d_max)"), std::string::npos)
      << low.warnings[0];
  EXPECT_FALSE(warns(representativeness(big, 0.041), RepresentativenessCheck::kPileHeight));
}

TEST(Representativeness, OutletBelowThePapersThresholdWarns) {
  // W / d_max = 15 / 4 = 3.75 is at the threshold (no warning), 14 / 4 = 3.5 below it.
  EXPECT_FALSE(
      warns(representativeness(tiny_with("bottom_diameter_m = 0.02", "bottom_diameter_m = 0.015")),
            RepresentativenessCheck::kOutletWidth));
  const Representativeness r =
      representativeness(tiny_with("bottom_diameter_m = 0.02", "bottom_diameter_m = 0.014"));
  ASSERT_TRUE(warns(r, RepresentativenessCheck::kOutletWidth));
  EXPECT_NE(r.warnings[2].find("W / d_max = 3.50"), std::string::npos) << r.warnings[2];
  EXPECT_NE(r.warnings[2].find("3.75"), std::string::npos) << r.warnings[2];
}

TEST(Representativeness, MassNotSimulatedCountsFinesAndScalping) {
  // Sheet 1-4 mm, 50% passing 3 mm: d_min = 3 mm leaves out half the mass; d_max = 3.5 mm
  // scalps the 25% above it, and of the 75% kept two thirds are finer than 3 mm: 1 - 0.75 / 3.
  const SceneConfig fines =
      tiny_with("sieve_mm = [3.0, 3.5, 4.0]", "d_min_mm = 3.0\nsieve_mm = [1.0, 3.0, 4.0]");
  const Representativeness r = representativeness(fines);
  EXPECT_NEAR(r.not_simulated_fraction, 0.5, 1e-9);
  ASSERT_TRUE(warns(r, RepresentativenessCheck::kMassNotSimulated));
  EXPECT_NE(r.warnings[1].find("50% of the sieve sheet's mass is not simulated"), std::string::npos)
      << r.warnings[1];
  const SceneConfig both = tiny_with("sieve_mm = [3.0, 3.5, 4.0]",
                                     "d_min_mm = 3.0\nd_max_mm = 3.5\nsieve_mm = [1.0, 3.0, 4.0]");
  const Representativeness s = representativeness(both);
  EXPECT_NEAR(s.scalped_fraction, 0.25, 1e-9);
  EXPECT_NEAR(s.fines_fraction, 2.0 / 3.0, 1e-9);
  EXPECT_NEAR(s.not_simulated_fraction, 0.75, 1e-9);
}

TEST(Representativeness, ThePlanPrintsEachWarningAndTheResultKeepsThem) {
  const SceneConfig scene = tiny_with("bottom_diameter_m = 0.02", "bottom_diameter_m = 0.014");
  const RunPlan plan = plan_run(scene, 1);
  const std::string text = plan_text(plan);
  EXPECT_NE(text.find("plan: warning: the pile is low"), std::string::npos) << text;
  EXPECT_NE(text.find("plan: warning: the outlet is narrow"), std::string::npos) << text;
  EXPECT_EQ(text.find("not simulated ("), std::string::npos) << text;
  const nlohmann::json j = to_json(plan.representative);
  EXPECT_TRUE(j["warnings"].contains("pile_height"));
  EXPECT_TRUE(j["warnings"].contains("outlet_width"));
  EXPECT_FALSE(j["warnings"].contains("mass_not_simulated"));
  EXPECT_NE(j["rules"].get<std::string>().find("3.75"), std::string::npos);
}

}  // namespace
}  // namespace reposetwin::experiments
