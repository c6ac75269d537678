// The admission checks (vision/admission.hpp): each planted failure is refused by its own check,
// with the value it measured, and a photo that passes them all is measured. Scenes are drawn
// from their geometry (synthetic.hpp), so the truth is known without the code under test.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <string>

#include "synthetic.hpp"
#include "vision/measure.hpp"

namespace reposetwin::vision {
namespace {

// What measuring a picture gave: a number, or the check that refused it.
struct Outcome {
  bool measured = false;
  Check check = Check::kCount;
  std::string why;
  SideMeasurement m;
};

Outcome measure(const cv::Mat& img, const ScaleSpec& spec) {
  Outcome o;
  try {
    o.m = measure_side(img, spec, {}, "photo");
    o.measured = true;
  } catch (const Refusal& r) {
    o.check = r.check();
    o.why = r.what();
  }
  return o;
}

// A level camera at the plate, 0.6 m from the axis, and a 60 x 200 mm cone drawn through it.
synthetic::SideScene camera_scene() {
  synthetic::SideScene s;
  s.camera = camera::side_view(0.6, 0.4, 0.0, 0.0, 1280, 720);
  s.scale_bar = false;
  return s;
}

ScaleSpec through(const synthetic::SideScene& s) {
  ScaleSpec spec;
  spec.camera = *s.camera;
  spec.search_marker = false;
  return spec;
}

TEST(Admission, CheckNamesAreTheRecordsWords) {
  EXPECT_EQ(to_string(Check::kPilePresent), "no_pile");
  EXPECT_EQ(to_string(Check::kFlankLimits), "flank_limits");
  EXPECT_EQ(to_string(Check::kNotCut), "cut_by_border");
  EXPECT_EQ(to_string(Check::kNoForeignObject), "foreign_object");
  EXPECT_EQ(to_string(Check::kExposure), "exposure");
  EXPECT_EQ(to_string(Check::kCameraConsistent), "camera_mismatch");
  EXPECT_EQ(to_string(Check::kViewAngle), "view_too_steep");
}

TEST(Admission, ACleanConeIsMeasured) {
  const synthetic::SideScene s = camera_scene();
  const Outcome o = measure(synthetic::draw_side(s), through(s));
  ASSERT_TRUE(o.measured) << o.why;
  EXPECT_NEAR(o.m.height_m, 0.060, 0.0005);
}

// The empty plate with the scale bar standing on it was read as a 45 deg pile of the bar's foot:
// through its camera nothing stands on the pile's axis. (Without a camera an object under 60 px
// tall is not shape-checked: side_view.cpp's kTaperMinHeightPx.)
TEST(Admission, EmptyPlateWithScaleBarIsNoPile) {
  synthetic::SideScene c = camera_scene();
  c.pile = false;
  c.scale_bar = true;
  const Outcome b = measure(synthetic::draw_side(c), through(c));
  EXPECT_FALSE(b.measured);
  EXPECT_EQ(b.check, Check::kPilePresent) << b.why;
}

// A box standing on the plate where the pile should be does not narrow upwards.
TEST(Admission, ABoxIsNoPile) {
  synthetic::SideScene s = camera_scene();
  s.pile = false;
  cv::Mat img = synthetic::draw_side(s);
  const auto foot = camera::project(*s.camera, Eigen::Vector3d::Zero());
  const int u = static_cast<int>(foot->x()), v = static_cast<int>(foot->y());
  cv::rectangle(img, cv::Rect(u - 60, v - 120, 120, 120), cv::Scalar(108, 115, 120), cv::FILLED);
  const Outcome o = measure(img, through(s));
  EXPECT_FALSE(o.measured);
  EXPECT_EQ(o.check, Check::kPilePresent) << o.why;
}

// A cone steeper than any granular pile (70 deg) is refused by the flank check.
TEST(Admission, SeventyDegreeFlanksAreOutsideThePhysicalLimits) {
  synthetic::SideScene s = camera_scene();
  s.height_mm = 0.5 * 60.0 * std::tan(70.0 * std::numbers::pi / 180.0);
  s.diameter_mm = 60.0;
  const Outcome o = measure(synthetic::draw_side(s), through(s));
  EXPECT_FALSE(o.measured);
  EXPECT_EQ(o.check, Check::kFlankLimits) << o.why;
}

// The funnel's outlet hanging just above the apex, apart from it or resting in it.
TEST(Admission, FunnelAboveTheApexIsAForeignObject) {
  for (const int gap_px : {6, -4}) {
    synthetic::SideScene s = camera_scene();
    cv::Mat img = synthetic::draw_side(s);
    const auto apex = camera::project(*s.camera, Eigen::Vector3d(0.0, 0.0, 0.060));
    const int u = static_cast<int>(apex->x()), v = static_cast<int>(apex->y()) - gap_px;
    const std::vector<cv::Point> funnel = {{u - 20, v}, {u + 20, v}, {u + 80, 0}, {u - 80, 0}};
    cv::fillConvexPoly(img, funnel, cv::Scalar(60, 62, 66));
    const Outcome o = measure(img, through(s));
    EXPECT_FALSE(o.measured) << "gap " << gap_px;
    EXPECT_EQ(o.check, Check::kNoForeignObject) << "gap " << gap_px << ": " << o.why;
  }
}

// A pile reaching the image's side is cut; an object at the image's side that is not the pile
// is not (the pile is the blob standing on the declared camera's axis).
TEST(Admission, OnlyThePilesOwnSilhouetteCountsForTheBorder) {
  synthetic::SideScene s = camera_scene();
  s.axis_u = 120.0;  // drawn off-axis only in orthographic scenes: use a wide cone instead
  s.axis_u = -1.0;
  s.diameter_mm = 430.0;
  s.height_mm = 90.0;
  const Outcome cut = measure(synthetic::draw_side(s), through(s));
  EXPECT_FALSE(cut.measured);
  EXPECT_EQ(cut.check, Check::kNotCut) << cut.why;

  synthetic::SideScene small = camera_scene();
  small.diameter_mm = 120.0;
  small.height_mm = 35.0;
  cv::Mat img = synthetic::draw_side(small);
  const auto foot = camera::project(*small.camera, Eigen::Vector3d::Zero());
  const int v = static_cast<int>(foot->y());
  // A large box at the image's right edge, standing behind the plate line (its foot hidden).
  cv::rectangle(img, cv::Rect(img.cols - 220, v - 260, 220, 258), cv::Scalar(70, 60, 55),
                cv::FILLED);
  const Outcome ok = measure(img, through(small));
  ASSERT_TRUE(ok.measured) << ok.why;
  EXPECT_NEAR(ok.m.height_m, 0.035, 0.0005);
}

// A photo exposed for the shadows: the top of the pile washed out to white.
TEST(Admission, WashedOutTopIsAnExposureRefusal) {
  synthetic::SideScene s = camera_scene();
  cv::Mat img = synthetic::draw_side(s);
  cv::Mat f;
  img.convertTo(f, CV_32FC3);
  const auto apex = camera::project(*s.camera, Eigen::Vector3d(0.0, 0.0, 0.060));
  const double v_apex = apex->y();
  for (int r = 0; r < f.rows; ++r) {
    // Gain 2.6 above the pile's top third, falling to 1 at its middle.
    const double t = std::clamp((r - (v_apex + 40.0)) / 60.0, 0.0, 1.0);
    f.row(r) *= 2.6 - 1.6 * t;
  }
  cv::Mat out;
  f.convertTo(out, CV_8UC3);
  const Outcome o = measure(out, through(s));
  EXPECT_FALSE(o.measured) << "H " << o.m.height_m << " level " << o.m.pixels.pile_level;
  EXPECT_EQ(o.check, Check::kExposure) << o.why;
}


// A photo over-exposed as a whole (gain 3: the backdrop, the plate and most of the pile at the
// sensor's brightest level) shows no pile to find; that is its exposure, not an empty plate. The
// empty plate exposed well stays "no pile".
TEST(Admission, NoPileInAnOverExposedPhotoIsAnExposureRefusal) {
  synthetic::SideScene s = camera_scene();
  cv::Mat bright;
  synthetic::draw_side(s).convertTo(bright, CV_8UC3, 3.0);
  const Outcome o = measure(bright, through(s));
  EXPECT_FALSE(o.measured) << "H " << o.m.height_m;
  EXPECT_EQ(o.check, Check::kExposure) << o.why;
  s.pile = false;
  const Outcome empty = measure(synthetic::draw_side(s), through(s));
  EXPECT_FALSE(empty.measured);
  EXPECT_EQ(empty.check, Check::kPilePresent) << empty.why;
}

}  // namespace
}  // namespace reposetwin::vision
