// The crest through the renderer: a frustum fixture (render::Shell, the funnel's mesh) standing on
// the plate, photographed level with the plate, measured by vision through the camera. Its top
// width is the closed form 2 r_top; seen from below its top rim's near point is the highest
// (H = h L / (L - r_top), as for the analytic frustum of tests/vision/crest_test.cpp), and its
// foot is the base circle (D = 2 r_bottom).
#include <gtest/gtest.h>

#include <cstdio>

#include "render/renderer.hpp"
#include "render/scene.hpp"
#include "vision/measure.hpp"

namespace reposetwin {
namespace {

TEST(CrestRender, FrustumFixtureGivesItsTopWidth) {
  constexpr double kH = 0.03, kRb = 0.06, kRt = 0.02, kL = 0.6;  // [m]
  render::Scene scene;
  scene.positions = {Eigen::Vector3d(0.0, 0.0, 0.005)};  // one sphere, hidden inside the shell
  scene.radii = {0.002};
  scene.material_ids = {0};
  scene.scale_reference.enabled = false;
  render::Shell shell;
  shell.z_bottom_m = 0.0;
  shell.z_top_m = kH;
  shell.r_bottom_m = kRb;
  shell.r_top_m = kRt;
  shell.color = {108, 115, 120};
  scene.shells = {shell};
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

}  // namespace
}  // namespace reposetwin
