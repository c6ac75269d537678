// Tests of vision/top_view and measure_top against footprints drawn analytically.
#include "vision/top_view.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/vision/synthetic.hpp"
#include "vision/measure.hpp"

namespace reposetwin::vision {
namespace {

TEST(TopView, CircleDiameterByFitAndByArea) {
  synthetic::TopScene t;
  const TopProfile p = measure_top_pixels(synthetic::draw_top(t));
  const double d_px = t.diameter_mm / t.mm_per_px;
  EXPECT_NEAR(p.diameter_circle_px, d_px, 0.002 * d_px);
  EXPECT_NEAR(p.diameter_area_px, d_px, 0.002 * d_px);
  EXPECT_LT(p.ellipticity, 0.005);
  EXPECT_NEAR(p.center.x, 0.5 * (t.width - 1), 0.5);
  EXPECT_NEAR(p.center.y, 0.5 * (t.height - 1), 0.5);
}

TEST(TopView, PhotoConditionsAndShading) {
  synthetic::TopScene t;
  t.look.noise_sigma = 8.0;
  t.look.blur_sigma_px = 1.5;
  t.look.pile_speckle = 0.08;
  t.shading = 0.15;
  t.look.seed = 3;
  const TopMeasurement m = measure_top(synthetic::draw_top(t));
  EXPECT_EQ(m.scale_source, ScaleSource::kCheckerCard);
  EXPECT_NEAR(m.diameter_circle_m, 0.200, 0.001);
  EXPECT_NEAR(m.diameter_area_m, 0.200, 0.001);
  EXPECT_LT(m.ellipticity, 0.01);
}

TEST(TopView, EllipseGivesEllipticityAndEqualAreaDiameter) {
  synthetic::TopScene t;
  t.diameter_mm = 200.0;
  t.minor_diameter_mm = 160.0;
  ScaleSpec spec;
  spec.mm_per_px = t.mm_per_px;
  const TopMeasurement m = measure_top(synthetic::draw_top(t), spec);
  EXPECT_NEAR(m.ellipticity, 0.2, 0.005);
  EXPECT_NEAR(m.diameter_area_m, std::sqrt(0.200 * 0.160), 0.0005);
  EXPECT_GT(m.circle_residual_m, 0.005);  // a circle does not fit an ellipse
}

TEST(TopView, KnownCameraMapsTheOutlineOntoThePlate) {
  const camera::Camera cam = camera::top_view(0.8, 0.4, 1280, 960);
  synthetic::TopScene t;
  t.camera = cam;
  t.checker_card = false;
  t.diameter_mm = 180.0;
  ScaleSpec spec;
  spec.camera = cam;
  const TopMeasurement m = measure_top(synthetic::draw_top(t), spec, {}, "top.png");
  EXPECT_TRUE(m.perspective_corrected);
  EXPECT_NEAR(m.diameter_circle_m, 0.180, 0.0004);
  EXPECT_NEAR(m.diameter_area_m, 0.180, 0.0004);
}

TEST(TopView, NoFootprintOrNoScaleIsAnError) {
  synthetic::TopScene t;
  t.diameter_mm = 0.0;  // the plate and the card only
  t.minor_diameter_mm = 0.0;
  ScaleSpec spec;
  spec.mm_per_px = 0.25;
  EXPECT_THROW(measure_top(synthetic::draw_top(t), spec, {}, "bare.png"), std::runtime_error);
  synthetic::TopScene no_card;
  no_card.checker_card = false;
  try {
    measure_top(synthetic::draw_top(no_card), {}, {}, "nocard.png");
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("nocard.png"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("scale cannot be determined"), std::string::npos);
  }
}

}  // namespace
}  // namespace reposetwin::vision
