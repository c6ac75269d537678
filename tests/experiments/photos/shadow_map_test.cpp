// The shadow map's side follows the image (render/scene.hpp, shadow_map_px = 0, the default):
// 1024 px for the loop's 960 x 720 photos instead of 2048, a quarter of the fragments in the
// shadow pass.
// The claim that this changes no measurement is checked against the map it replaces: the same
// lab-look cone photographed with both maps reads the same H, D and atan(2H/D) within a small
// part of a pixel, and the slope of the cone it was built with.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "../../support/cone_pile.hpp"
#include "experiments/photos/photographs.hpp"
#include "render/renderer.hpp"
#include "vision/measure.hpp"

namespace reposetwin::experiments {
namespace {

TEST(PhotoShadowMap, SideFollowsTheImageUnlessSet) {
  render::RenderOptions o;
  EXPECT_EQ(o.shadow_map_px, 0);  // the default: chosen from the image
  EXPECT_EQ(render::shadow_map_side(o, 320, 240), 512);
  EXPECT_EQ(render::shadow_map_side(o, 960, 720), 1024);
  EXPECT_EQ(render::shadow_map_side(o, 1024, 768), 1024);
  EXPECT_EQ(render::shadow_map_side(o, 1920, 1080), 2048);
  EXPECT_EQ(render::shadow_map_side(o, 4000, 3000), 2048);
  o.shadow_map_px = 300;
  EXPECT_EQ(render::shadow_map_side(o, 960, 720), 300);
}

TEST(PhotoShadowMap, TheImagesMapMeasuresAsTheLargeOne) {
  constexpr double kH = 14e-3, kR = 24e-3;
  const test_support::Spheres s = test_support::make_cone(kH, kR, 0.0, 0.0, 1.75e-3, 11, 0.3);
  render::Scene scene =
      centred_pile_scene({{s.x.begin(), s.x.end()}, s.r, std::vector<int>(s.r.size(), 0)});
  scene.scale_reference.enabled = false;
  render::RenderOptions o;
  render::apply_lab_look(scene, o);
  o.shadow_map_px = 0;  // chosen from the image
  const camera::Camera cam = render::lab_side_camera(scene, {.width_px = 960, .height_px = 720});
  render::Renderer renderer;
  const cv::Mat auto_map = renderer.render(scene, cam, o);
  EXPECT_EQ(renderer.last_profile().shadow_map_px, 1024);
  render::RenderOptions large = o;
  large.shadow_map_px = 2048;
  const cv::Mat large_map = renderer.render(scene, cam, large);
  EXPECT_EQ(renderer.last_profile().shadow_map_px, 2048);
  EXPECT_GT(cv::norm(auto_map, large_map, cv::NORM_INF), 0.0);  // the shadows differ a little
  const vision::SideMeasurement a = vision::measure_side_camera(auto_map, cam, {}, "auto");
  const vision::SideMeasurement b = vision::measure_side_camera(large_map, cam, {}, "large");
  // A pixel is about 0.16 mm on this pile (48 mm across about 300 px).
  EXPECT_NEAR(a.height_m, b.height_m, 0.05e-3);
  EXPECT_NEAR(a.diameter_m, b.diameter_m, 0.05e-3);
  EXPECT_NEAR(a.theta_deg, b.theta_deg, 0.05);
  // Both read the cone they were built from (its slope atan(H/R), 30.3 deg; the grains' tops
  // and toe round it by a degree or two).
  const double slope = std::atan(kH / kR) * 180.0 / std::numbers::pi;
  EXPECT_NEAR(a.theta_deg, slope, 3.0);
}

}  // namespace
}  // namespace reposetwin::experiments
