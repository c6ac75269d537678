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
            {"pile", {{"status", pile_status}, {"theta_hd_deg", 27.5}}},
            {"image", {{"theta_deg", 24.25}}},
            {"run_dir", "cases/x/seed_2/run"}}}};
}

TEST(CaseAngle, ImageFirstThenParticlesAndZeroForNoPile) {
  EXPECT_DOUBLE_EQ(case_angle_deg(run_result("settled", "ok")), 24.25);
  EXPECT_DOUBLE_EQ(case_angle_deg(run_result("settled", "ok"), /*prefer_image=*/false), 27.5);
  EXPECT_DOUBLE_EQ(case_angle_deg(run_result("clogged", "no pile")), 0.0);
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
