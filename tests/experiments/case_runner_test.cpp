// The angle a calibration takes from one run: the image angle, the particle angle, 0 for "no
// pile", and never an angle from a run that a physics failure stopped.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <stdexcept>

#include "experiments/case_runner.hpp"

namespace reposetwin::experiments {
namespace {

nlohmann::json run_result(const std::string& reason, const std::string& pile_status) {
  return {{"result",
           {{"stop", {{"reason", reason}, {"detail", "largest overlap 0.2009 exceeds 0.2"}}},
            {"pile",
             {{"status", pile_status}, {"theta_hd_deg", 27.5}, {"slice_angle_mean_deg", 31.75}}},
            {"image", {{"theta_deg", 24.25}, {"flank_deg", 29.5}}},
            {"run_dir", "cases/x/seed_2/run"}}}};
}

TEST(CaseAngle, ImageFirstThenParticlesAndZeroForNoPile) {
  EXPECT_DOUBLE_EQ(case_angle_deg(run_result("settled", "ok")), 24.25);
  EXPECT_DOUBLE_EQ(case_angle_deg(run_result("settled", "ok"), AngleMeasure::kParticles), 27.5);
  EXPECT_DOUBLE_EQ(case_angle_deg(run_result("clogged", "no pile")), 0.0);
  EXPECT_TRUE(case_made_no_pile(run_result("clogged", "no pile")));
  EXPECT_TRUE(case_made_no_pile(run_result("clogged", "no pile")["result"]));
  EXPECT_FALSE(case_made_no_pile(run_result("settled", "ok")));
}

TEST(CaseAngle, EachMeasureReadsItsOwnField) {
  const nlohmann::json r = run_result("settled", "ok");
  EXPECT_DOUBLE_EQ(case_angle_deg(r, AngleMeasure::kImageFlank), 29.5);
  EXPECT_DOUBLE_EQ(case_angle_deg(r, AngleMeasure::kSlice), 31.75);
  EXPECT_DOUBLE_EQ(case_angle_deg(run_result("clogged", "no pile"), AngleMeasure::kSlice), 0.0);
  // Without photographs the flank angle does not exist; it is never replaced by another angle.
  nlohmann::json bare = r;
  bare["result"].erase("image");
  EXPECT_DOUBLE_EQ(case_angle_deg(bare, AngleMeasure::kImage), 27.5);
  EXPECT_THROW(case_angle_deg(bare, AngleMeasure::kImageFlank), std::runtime_error);
}

TEST(CaseAngle, MeasureNamesRoundTripAndAnUnknownNameIsRejected) {
  for (AngleMeasure m : {AngleMeasure::kImage, AngleMeasure::kImageFlank, AngleMeasure::kParticles,
                         AngleMeasure::kSlice})
    EXPECT_EQ(parse_angle_measure(angle_measure_name(m), "here"), m);
  try {
    parse_angle_measure("protractor", "c.toml: key 'calibration.angle'");
    FAIL() << "an unknown angle name was accepted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("c.toml"), std::string::npos) << what;
    EXPECT_NE(what.find("protractor"), std::string::npos) << what;
    EXPECT_NE(what.find("image_flank"), std::string::npos) << what;
  }
}

TEST(CaseAngle, APhysicsFailureHasNoAngle) {
  try {
    case_angle_deg(run_result("physics: overlap", "ok"));
    FAIL() << "a run stopped on overlap gave an angle";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("physics: overlap"), std::string::npos) << what;
    EXPECT_NE(what.find("cases/x/seed_2/run"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace reposetwin::experiments
