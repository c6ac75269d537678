// Tests of vision/top_view on grainy footprints whose grey level matches the plate's: a disc of
// rock-grey dots (with dark gaps between them) on a plate of about the same luminance, the case
// where grey-level segmentation leaks into the plate and colour or texture must find the pile.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "vision/top_view.hpp"

namespace reposetwin::vision {
namespace {

struct GrainDisc {
  int width = 800, height = 600;       // image size [px]
  double radius_px = 150.0;            // footprint radius, to the grains' outer edge [px]
  double grain_px = 4.0;               // grain radius [px]
  cv::Scalar plate{95, 80, 70};        // BGR plate colour (dark blue-grey)
  cv::Scalar rock{108, 115, 120};      // BGR rock colour, fully lit
  cv::Scalar gap{38, 36, 35};          // BGR shadow between grains
  double lit_lo = 0.5, lit_hi = 0.95;  // brightness factor range of the grains [-]
  double noise_sigma = 3.0;            // pixel noise [grey levels]
  int seed = 7;
};

// Grey level (OpenCV BGR2GRAY weights) of a BGR colour.
double luminance(const cv::Scalar& c) { return 0.114 * c[0] + 0.587 * c[1] + 0.299 * c[2]; }

// Draws the disc: a shadow disc, then grains centred within radius - grain radius, so the
// outer envelope of the grains is the footprint circle.
cv::Mat draw_grains(const GrainDisc& g) {
  cv::RNG rng(g.seed);
  cv::Mat img(g.height, g.width, CV_32FC3, g.plate);
  const cv::Point2d c(0.5 * (g.width - 1), 0.5 * (g.height - 1));
  const double r_in = g.radius_px - g.grain_px;
  constexpr int kSub = 4;  // sub-pixel drawing shift (1/16 px)
  auto fixed = [](double v) { return static_cast<int>(std::lround(v * (1 << kSub))); };
  cv::circle(img, cv::Point(fixed(c.x), fixed(c.y)), fixed(r_in), g.gap, cv::FILLED, cv::LINE_AA,
             kSub);
  const int n = static_cast<int>(2.5 * r_in * r_in / (g.grain_px * g.grain_px));
  for (int i = 0; i < n; ++i) {
    const double rho = r_in * std::sqrt(rng.uniform(0.0, 1.0));
    const double phi = rng.uniform(0.0, 2.0 * 3.14159265358979323846);
    const double f = rng.uniform(g.lit_lo, g.lit_hi);
    const cv::Point p(fixed(c.x + rho * std::cos(phi)), fixed(c.y + rho * std::sin(phi)));
    cv::circle(img, p, fixed(g.grain_px * 0.9), g.rock * f, cv::FILLED, cv::LINE_AA, kSub);
  }
  cv::Mat noise(img.size(), CV_32FC3);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, g.noise_sigma);
  img += noise;
  cv::Mat out;
  img.convertTo(out, CV_8UC3);
  return out;
}

TEST(TopTexture, GrainsOnAPlateOfTheSameLuminanceAreFoundByColour) {
  GrainDisc g;
  // The premise: the plate's luminance lies within the grains' own spread.
  ASSERT_GT(luminance(g.plate), luminance(g.rock) * g.lit_lo);
  ASSERT_LT(luminance(g.plate), luminance(g.rock) * g.lit_hi);
  const TopProfile p = measure_top_pixels(draw_grains(g), {}, "grains.png");
  EXPECT_NE(p.cue, "grey level");
  const double d = 2.0 * g.radius_px;
  EXPECT_NEAR(p.diameter_circle_px, d, 0.03 * d);
  EXPECT_NEAR(p.diameter_area_px, d, 0.03 * d);
  EXPECT_NEAR(p.center.x, 0.5 * (g.width - 1), 2.0);
  EXPECT_NEAR(p.center.y, 0.5 * (g.height - 1), 2.0);
}

TEST(TopTexture, NeutralGrainsOnANeutralPlateAreFoundByTexture) {
  GrainDisc g;
  g.plate = cv::Scalar(80, 80, 80);
  g.rock = cv::Scalar(115, 115, 115);
  g.gap = cv::Scalar(36, 36, 36);
  const TopProfile p = measure_top_pixels(draw_grains(g), {}, "grey_grains.png");
  EXPECT_EQ(p.cue, "texture (local grey-level deviation)");
  const double d = 2.0 * g.radius_px;
  EXPECT_NEAR(p.diameter_circle_px, d, 0.03 * d);
  EXPECT_NEAR(p.diameter_area_px, d, 0.03 * d);
}

TEST(TopTexture, AUniformPlateIsStillNoFootprint) {
  GrainDisc g;
  g.radius_px = 0.0;
  g.grain_px = 0.0;
  cv::Mat img(g.height, g.width, CV_8UC3, g.plate);
  cv::rectangle(img, cv::Rect(0, 0, 40, g.height), cv::Scalar(220, 225, 225), cv::FILLED);
  try {
    measure_top_pixels(img, {}, "bare.png");
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bare.png"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace reposetwin::vision
