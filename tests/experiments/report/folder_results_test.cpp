// What a page takes from a folder's cases (report/folder_results.hpp): in "Angles per case", a
// case whose runs gave no angle (a time limit, a jam) is shown as what it is, in its label, and
// draws no point, never one at 0 deg; the render set beside the lab photo is of the photographed
// test.
#include "experiments/report/folder_results.hpp"

#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

namespace reposetwin::experiments::report {
namespace {

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

TEST(AnglesPlot, RunsWithoutAnAngleAreNeverAZero) {
  FolderResults f;
  CaseRows a;
  a.name = "calib_rolling_friction_0.1";
  a.overrides = {{"contacts.rock-rock.rolling_friction", 0.1}};
  a.image_deg = {30.0, 32.0};
  a.particle_deg = {29.0, 31.0};
  CaseRows b;
  b.name = "calib_rolling_friction_0.5";
  b.overrides = {{"contacts.rock-rock.rolling_friction", 0.5}};
  b.without_pile = {{"time_limit", 2}};
  f.cases = {a, b};
  const std::vector<std::string> lines = lines_of(angles_plot_data(f));
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0].rfind("0 31 ", 0), 0u) << lines[0];
  // Only the flank, which no run gave, is missing.
  EXPECT_EQ(lines[0].substr(lines[0].size() - 8), " nan nan") << lines[0];
  EXPECT_EQ(lines[0].find("nan"), lines[0].size() - 7) << lines[0];
  // The second case: no number at all, NaN in every measure, and its label says why.
  std::istringstream row(lines[1]);
  std::string index, image, image_sd, particle, particle_sd;
  row >> index >> image >> image_sd >> particle >> particle_sd;
  EXPECT_EQ(image, "nan") << lines[1];
  EXPECT_EQ(particle, "nan") << lines[1];
  EXPECT_NE(lines[1].find("(no angle: 2 time_limit)\""), std::string::npos) << lines[1];
  EXPECT_EQ(lines[1].find(" 0 "), std::string::npos) << lines[1];
}

// The render set beside the lab photo is of the calibration's own test: a prediction of another
// test (another mass) at the calibrated mu_r shares the scene and mu_r, not the test.
TEST(LabPhotoPair, OnlyTheCalibrationTestsRunsStandBesideItsPhoto) {
  const std::string key = "contacts.rock-rock.rolling_friction";
  FolderResults f;
  f.calibration.emplace();
  f.calibration->keys = {key};
  f.calibration->mu_r = 0.3;
  CaseRows calib, self, other;
  calib.name = "calib_rolling_friction_0.3";
  calib.overrides = {{key, 0.3}, {"sample.mass_kg", 0.008}};
  self.name = "predict_t1_rolling_friction_0.3";
  self.overrides = {{key, 0.3}, {"sample.mass_kg", 0.008}};
  other.name = "predict_t2_rolling_friction_0.3";
  other.overrides = {{key, 0.3}, {"sample.mass_kg", 0.011}};
  f.cases = {calib, self, other};
  EXPECT_TRUE(same_test_as_calibration(f, calib));
  EXPECT_TRUE(same_test_as_calibration(f, self));
  EXPECT_FALSE(same_test_as_calibration(f, other));
  // Another mu_r of the same test is the same test.
  CaseRows calib_low = calib;
  calib_low.overrides[key] = 0.1;
  EXPECT_TRUE(same_test_as_calibration(f, calib_low));
}

}  // namespace
}  // namespace reposetwin::experiments::report
