// The top view's crest (vision/top_crest.hpp) on piles drawn from their geometry: a truncated
// cone of known top radius seen from above, each pixel shaded by Lambert's law from the cone's
// own normal under a light psi off the view, and speckled by grains (discs of random
// brightness) so that the shading is no cleaner than a photo's. The closed form: the crest's
// radius is the cone's top radius.
#include "vision/top_crest.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <string>

#include "vision/top_view.hpp"

namespace reposetwin::vision {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

struct ConeTop {
  double radius_px = 240.0;   // footprint radius R [px]
  double top_px = 60.0;       // flat top radius r_t [px]
  double slope_deg = 35.0;    // flank slope theta [deg]
  double light_deg = 35.0;    // light off the view axis psi [deg]
  double light_az_deg = 210;  // light's azimuth in the image [deg]
  double speckle = 0.25;      // grains' brightness spread (fraction) [-]
  unsigned seed = 7;
};

// The top view: plate blue-grey, the cone grey under the light, grains as discs of 3-7 px with a
// brightness factor each, and pixel noise.
cv::Mat draw_cone_top(const ConeTop& c) {
  const int w = 800, h = 640;
  const cv::Point2d o(400.0, 320.0);
  const double t = c.slope_deg * kDeg, psi = c.light_deg * kDeg, al = c.light_az_deg * kDeg;
  const cv::Vec3d light(std::sin(psi) * std::cos(al), std::sin(psi) * std::sin(al), std::cos(psi));
  cv::Mat grains(h, w, CV_32F, cv::Scalar(1.0f));
  cv::RNG rng(c.seed);
  for (int i = 0; i < 30000; ++i) {
    const cv::Point p(rng.uniform(0, w), rng.uniform(0, h));
    cv::circle(grains, p, rng.uniform(3, 8),
               cv::Scalar(1.0 + c.speckle * (rng.uniform(0.0, 2.0) - 1.0)), cv::FILLED);
  }
  cv::Mat img(h, w, CV_8UC3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double dx = x - o.x, dy = y - o.y, r = std::hypot(dx, dy);
      cv::Vec3d bgr(95.0, 80.0, 70.0);  // the plate
      if (r < c.radius_px) {
        const double s = r > c.top_px ? t : 0.0;
        const double phi = std::atan2(dy, dx);
        const cv::Vec3d n(std::sin(s) * std::cos(phi), std::sin(s) * std::sin(phi), std::cos(s));
        const double lit = 40.0 + 170.0 * std::max(0.0, n.dot(light));
        const double g = lit * grains.at<float>(y, x) + rng.gaussian(3.0);
        bgr = cv::Vec3d(0.92 * g, 0.98 * g, g);
      }
      for (int k = 0; k < 3; ++k) img.at<cv::Vec3b>(y, x)[k] = cv::saturate_cast<uchar>(bgr[k]);
    }
  return img;
}

// The crest read with the drawn footprint (the footprint's own segmentation is top_view's
// test; the renders of tests/experiments/photos/ run the two together).
TopCrest read(const ConeTop& c) {
  const cv::Mat img = draw_cone_top(c);
  TopProfile p;
  p.center = {400.0, 320.0};
  p.diameter_circle_px = 2.0 * c.radius_px;
  return measure_top_crest(img, p, {}, "cone_top.png");
}

TEST(TopCrest, TruncatedConesGiveTheirTopRadius) {
  for (double top : {45.0, 70.0, 95.0})
    for (unsigned seed : {7u, 8u}) {
      ConeTop c;
      c.top_px = top;
      c.seed = seed;
      const TopCrest got = read(c);
      std::printf("top %.0f px seed %u: crest %.1f +- %.1f px, light %.0f deg, P %.1f +- %.2f\n",
                  top, seed, got.radius_px, got.sigma_radius_px, got.light_azimuth_deg,
                  got.flank_amplitude, got.flank_sigma);
      ASSERT_TRUE(got.found) << got.reason;
      EXPECT_NEAR(got.radius_px, top, std::max(4.0, 2.5 * got.sigma_radius_px));
      EXPECT_LT(got.sigma_radius_px, 8.0);
      // The light is found where it was put (image azimuth 210 deg = -150).
      EXPECT_NEAR(got.light_azimuth_deg, -150.0, 10.0);
    }
}

TEST(TopCrest, AFullConeHasNoFlatTop) {
  ConeTop c;
  c.top_px = 0.0;
  const TopCrest got = read(c);
  std::printf("full cone: crest %.1f +- %.1f px\n", got.radius_px, got.sigma_radius_px);
  ASSERT_TRUE(got.found) << got.reason;
  EXPECT_LT(got.radius_px, 6.0 + 2.0 * got.sigma_radius_px);
}

TEST(TopCrest, ALightAlongTheViewLeavesTheCrestUnread) {
  ConeTop c;
  c.light_deg = 0.0;
  const TopCrest got = read(c);
  std::printf("light along the view: %s\n", got.reason.c_str());
  EXPECT_FALSE(got.found);
  EXPECT_NE(got.reason.find("along the view"), std::string::npos) << got.reason;
}

// Grains so coarse and bright-spread that the shading's step drowns: the crest goes unread
// with the numbers, or, if read, the answer's uncertainty covers the truth.
TEST(TopCrest, ANoisyStepIsRefusedOrHonestlyUncertain) {
  ConeTop c;
  c.top_px = 70.0;
  c.speckle = 0.9;
  c.light_deg = 8.0;
  const TopCrest got = read(c);
  std::printf("noisy: found %d, crest %.1f +- %.1f px; %s\n", got.found, got.radius_px,
              got.sigma_radius_px, got.reason.c_str());
  if (got.found)
    EXPECT_NEAR(got.radius_px, c.top_px, 3.0 * got.sigma_radius_px + 4.0);
  else
    EXPECT_FALSE(got.reason.empty());
}

TEST(TopCrest, AnEmptyFootprintIsRefused) {
  const cv::Mat img(100, 100, CV_8UC3, cv::Scalar(90, 90, 90));
  EXPECT_THROW(measure_top_crest(img, TopProfile{}, {}, "x.png"), std::invalid_argument);
}

}  // namespace
}  // namespace reposetwin::vision
