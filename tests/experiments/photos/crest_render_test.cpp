// The crest through the renderer: a frustum fixture (render::Shell, the funnel's mesh) standing on
// the plate, photographed level with the plate, measured by vision through the camera. Its top
// width is the closed form 2 r_top; seen from below its top rim's near point is the highest
// (H = h L / (L - r_top), as for the analytic frustum of tests/vision/crest_test.cpp), and its
// foot is the base circle (D = 2 r_bottom).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "../../support/frustum_scene.hpp"
#include <opencv2/imgcodecs.hpp>
#include "render/renderer.hpp"
#include "render/scene.hpp"
#include "vision/measure.hpp"

namespace reposetwin {
namespace {

TEST(CrestRender, FrustumFixtureGivesItsTopWidth) {
  constexpr double kH = 0.03, kRb = 0.06, kRt = 0.02, kL = 0.6;  // [m]
  const render::Scene scene = test_support::frustum_scene(kH, kRb, kRt);
  const camera::Camera cam = camera::side_view(kL, 0.2, 0.0, 20.0, 960, 720);
  const cv::Mat image = render::render_image(scene, cam, {});
  const vision::SideMeasurement m = vision::measure_side_camera(image, cam, {}, "frustum.png");
  std::printf("frustum: crest %.2f mm (%.1f px), H %.2f mm, D %.2f mm\n", 1e3 * m.crest_width_m,
              m.crest.width_px, 1e3 * m.height_m, 1e3 * m.diameter_m);
  // 256 facets: the rim's polygon is within 2 r_top (1 - cos(pi/256)) of the circle, nothing at
  // this scale (0.21 mm/px); the crest within 1 mm (5 px), H within 0.3 mm, D within 1 mm.
  EXPECT_NEAR(1e3 * m.crest_width_m, 2e3 * kRt, 1.0);
  EXPECT_NEAR(m.height_m, kH * kL / (kL - kRt), 0.3e-3);
  EXPECT_NEAR(m.diameter_m, 2.0 * kRb, 1e-3);
}

// The crest from above: the same frustum, capped (a flat disc at its top rim), photographed
// from straight above under the renderer's light (35 deg off the view), measured by vision
// through the camera with the crest's height given. Its top width is 2 r_top; the cap's plane is
// h above the plate, so read on the plate plane it would come out L / (L - h) too wide.
TEST(CrestRender, FrustumFromAboveGivesItsTopWidthFromTheShading) {
  constexpr double kH = 0.03, kRb = 0.07, kRt = 0.02, kL = 0.6;  // [m]
  render::Scene scene = test_support::frustum_scene(kH, kRb, kRt);
  // Light rock, so that its side turned from the light stays far off the plate's grey and the
  // footprint is the whole base (the crest's rings are centred on it).
  scene.shells.front().color = {235, 228, 215};
  render::Shell cap = scene.shells.front();
  cap.z_bottom_m = kH - 1e-5;  // a cone 10 um tall: the disc of the top
  cap.r_bottom_m = 0.0;
  cap.r_top_m = kRt;
  scene.shells.push_back(cap);
  const camera::Camera cam = camera::top_view(kL, 0.3, 960, 720);
  const cv::Mat image = render::render_image(scene, cam, {});
  cv::imwrite("/tmp/tc/frustum_top.png", image);
  vision::ScaleSpec spec;
  spec.camera = cam;
  spec.crest_height_m = kH;
  const vision::TopMeasurement m = vision::measure_top(image, spec, {}, "frustum_top.png");
  spec.crest_height_m.reset();
  const vision::TopMeasurement on_plate = vision::measure_top(image, spec, {}, "frustum_top.png");
  std::printf("frustum from above: crest %.2f +- %.2f mm (%.1f px, light %.0f deg), on the plate "
              "plane %.2f mm\n",
              1e3 * m.crest_width_m, 1e3 * m.sigma_crest_width_m, m.crest.radius_px,
              m.crest.light_azimuth_deg, 1e3 * on_plate.crest_width_m);
  ASSERT_TRUE(m.crest.found) << m.crest.reason;
  EXPECT_NEAR(1e3 * m.crest_width_m, 2e3 * kRt, std::max(1.0, 2.0 * 1e3 * m.sigma_crest_width_m));
  EXPECT_LT(m.sigma_crest_width_m, 1.5e-3);
  EXPECT_NEAR(on_plate.crest_width_m / m.crest_width_m, kL / (kL - kH), 1e-3);
}

// A flat monolayer of grains (80 or 25 spheres of 3.5 mm lying on the plate, spread evenly over
// a disc 90 mm across, 2.5 or 5 diameters apart), photographed as the loop photographs its
// piles: it is no heap with an angle. With 80 the grains at different depths overlap into one
// strip one grain tall, which reads as the flat heap it is (measured 5.5-6.8 deg, under 10);
// with 25 they stand apart in the picture in 4-12 similar blobs, and the photo is refused as
// grains lying flat (the largest blob alone read as a pile would be a few grains' steep heap).
TEST(CrestRender, FlatMonolayerReadsFlatOrIsRefused) {
  constexpr double kA = 1.75e-3;
  for (int n : {80, 25}) {
  render::Scene scene;
  for (int i = 0; i < n; ++i) {
    const double r = 0.045 * std::sqrt((i + 0.5) / n), t = 2.399963 * i;  // sunflower spiral
    scene.positions.emplace_back(r * std::cos(t), r * std::sin(t), kA);
    scene.radii.push_back(kA);
    scene.material_ids.push_back(0);
  }
  scene.scale_reference.enabled = false;
  scene.plate.half_size_m = std::max(scene.plate.half_size_m, 1.3 * 0.047);
  render::LabCameraSettings cams;
  cams.width_px = 960;
  cams.height_px = 720;
  for (double az : {0.0, 45.0, 90.0}) {
    cams.azimuth_deg = az;
    const camera::Camera cam = render::lab_side_camera(scene, cams);
    const cv::Mat image = render::render_image(scene, cam, {});
    try {
      const vision::SideMeasurement m = vision::measure_side_camera(image, cam, {}, "layer.png");
      std::printf("monolayer n %d az %.0f: theta %.2f deg, H %.2f mm, D %.1f mm, crest %.1f mm\n", n, az,
                  m.theta_deg, 1e3 * m.height_m, 1e3 * m.diameter_m, 1e3 * m.crest_width_m);
      EXPECT_LT(m.theta_deg, 10.0) << az;
    } catch (const std::runtime_error& e) {
      const std::string what = e.what();
      std::printf("monolayer n %d az %.0f: refused: %s\n", n, az, what.c_str());
      // A layer is no pile: grains apart ("no heap") or one layer touching ("does not narrow").
      EXPECT_TRUE(what.find("no heap") != std::string::npos ||
                  what.find("does not narrow upwards") != std::string::npos)
          << what;
    }
  }
  }
}

}  // namespace
}  // namespace reposetwin
