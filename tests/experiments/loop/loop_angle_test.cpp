// Which angle the loop compares (issue 7; docs/loop.md): the lab's and the twin's values under
// each measure, and the twin's photographs carrying a flank angle at all.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>

#include "experiments/loop/loop.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/input_error.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

LabData two_tests() {
  LabData d;
  d.file = "/lab/data.csv";
  LabTest photo;
  photo.line = 3;
  photo.id = "with_photo";
  photo.angle_deg = 33.0;  // vision atan(2H/D) on the photos
  photo.photos = {"/lab/a.png"};
  photo.photo_measurement = {{"theta_deg", {{"mean", 33.0}}}, {"flank_deg", {{"mean", 38.5}}}};
  LabTest typed;
  typed.line = 4;
  typed.id = "typed";
  typed.angle_deg = 35.0;
  d.tests = {photo, typed};
  return d;
}

TEST(LoopAngle, LabAnglesFollowTheMeasure) {
  const LabData d = two_tests();
  const LabData image = lab_angles(d, AngleMeasure::kImage);
  EXPECT_EQ(image.tests[0].angle_deg, 33.0);
  EXPECT_EQ(image.tests[1].angle_deg, 35.0);
  EXPECT_EQ(image.tests[0].photo_measurement["compared_angle"]["measure"], "image");
  const LabData flank = lab_angles(d, AngleMeasure::kImageFlank);
  EXPECT_EQ(flank.tests[0].angle_deg, 38.5);  // the photos' flank
  EXPECT_EQ(flank.tests[1].angle_deg, 35.0);  // a typed angle stands for the flank (full cone)
  EXPECT_EQ(flank.tests[0].photo_measurement["compared_angle"]["angle_deg"], 38.5);
  EXPECT_EQ(d.tests[0].angle_deg, 33.0);  // the input is not changed
  EXPECT_EQ(lab_angles(d, AngleMeasure::kParticles).tests[0].angle_deg, 33.0);
  EXPECT_NE(lab_angle_source(AngleMeasure::kImageFlank).find("full cone"), std::string::npos);
}

TEST(LoopAngle, BadChoicesAreClearErrors) {
  LabData d = two_tests();
  try {
    lab_angles(d, AngleMeasure::kSlice);
    FAIL() << "slice accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/lab/data.csv"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("slice"), std::string::npos) << e.what();
  }
  d.tests[0].photo_measurement.erase("flank_deg");
  try {
    lab_angles(d, AngleMeasure::kImageFlank);
    FAIL() << "a photo record without a flank angle was accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("line 3"), std::string::npos) << what;
    EXPECT_NE(what.find("with_photo"), std::string::npos) << what;
    EXPECT_NE(what.find("photo"), std::string::npos) << what;
  }
}

TEST(LoopAngle, TwinAngleFollowsTheMeasure) {
  SimOutcome o;
  o.pile = true;
  o.angle_deg = 30.0;
  o.flank_deg = 36.0;
  o.positions_angle_deg = 32.0;
  EXPECT_EQ(twin_angle(o, AngleMeasure::kImage), 30.0);
  EXPECT_EQ(twin_angle(o, AngleMeasure::kImageFlank), 36.0);
  EXPECT_EQ(twin_angle(o, AngleMeasure::kParticles), 32.0);
  EXPECT_THROW(twin_angle(o, AngleMeasure::kSlice), std::runtime_error);
  o.flank_deg = std::numeric_limits<double>::quiet_NaN();  // a photograph of an older version
  EXPECT_THROW(twin_angle(o, AngleMeasure::kImageFlank), std::runtime_error);
  o.pile = false;  // no pile: angle 0, as for the other measures
  o.angle_deg = 0.0;
  EXPECT_EQ(twin_angle(o, AngleMeasure::kImageFlank), 0.0);
}

// A real photographed pile of the tiny scene carries both vision angles.
TEST(LoopAngle, PhotographsCarryTheFlankAngle) {
  const LabData data =
      read_lab_csv(std::string(REPOSETWIN_SOURCE_DIR) + "/data/loop/example.csv");
  ImageVariant img;
  img.width_px = 640;
  img.height_px = 480;
  SimCache cache((fs::temp_directory_path() /
                  ("reposetwin_loop_angle_test_" + sha256_hex(code_version()).substr(0, 16)))
                     .string(),
                 {1, false});
  const SimOutcome o =
      cache.run({make_request(data.tests[1], "contacts.{sample}-{sample}.rolling_friction", 0.3,
                              5, {}, img)})
          .at(0);
  ASSERT_TRUE(o.pile);
  EXPECT_TRUE(std::isfinite(o.flank_deg));
  EXPECT_GT(o.flank_deg, 5.0);
  EXPECT_LT(o.flank_deg, 80.0);
  EXPECT_NE(o.flank_deg, o.angle_deg);
}

}  // namespace
}  // namespace reposetwin::experiments
