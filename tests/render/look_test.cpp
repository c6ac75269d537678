// The lab-photograph look: backdrop gradient, board grain, per-body tones and soft shadows,
// each checked against what it promises (closed-form light levels, positions from the camera
// model), plus determinism of the whole look.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <opencv2/core.hpp>

#include "camera/camera.hpp"
#include "render/renderer.hpp"
#include "render/scene.hpp"
#include "render/shadow_map.hpp"

namespace reposetwin::render {
namespace {

Renderer& renderer() {
  static Renderer r;
  return r;
}

// Straight down on the plate from 0.6 m, 0.3 m field: the plate fills the image.
camera::Camera down_camera(int w = 480, int h = 360) { return camera::top_view(0.6, 0.3, w, h); }

double grey(const cv::Mat& img, const Eigen::Vector2d& uv) {
  const cv::Vec3b p = img.at<cv::Vec3b>(static_cast<int>(std::lround(uv.y())),
                                        static_cast<int>(std::lround(uv.x())));
  return (p[0] + p[1] + p[2]) / 3.0;
}

TEST(LabLook, BackdropGradientIsLinearFromTopLeftToBottomRight) {
  Scene s;
  s.positions = {{0.0, 0.0, 0.05}};
  s.radii = {0.005};
  s.plate.enabled = false;
  s.scale_reference.enabled = false;
  s.backdrop.gradient = 0.2;
  const camera::Camera cam = camera::side_view(1.0, 0.4, 0.05, 0.0, 400, 300);
  const cv::Mat img = renderer().render(s, cam);
  const double base = s.backdrop.color.r;
  // Top-left is lighter by gradient/2, bottom-right darker by as much, the middle unchanged.
  EXPECT_NEAR(img.at<cv::Vec3b>(0, 0)[2], std::min(255.0, base * 1.1), 1.5);
  EXPECT_NEAR(img.at<cv::Vec3b>(299, 399)[2], base * 0.9, 1.5);
  EXPECT_NEAR(img.at<cv::Vec3b>(0, 399)[2], base, 1.5);
  EXPECT_NEAR(img.at<cv::Vec3b>(299, 0)[2], base, 1.5);
}

TEST(LabLook, BoardGrainVariesWithinItsBand) {
  Scene s;
  s.positions = {{0.1, 0.1, 0.002}};
  s.radii = {0.002};
  s.scale_reference.enabled = false;
  RenderOptions o;
  o.view = View::kTop;
  o.ambient = 1.0;
  o.diffuse = 0.0;
  const camera::Camera cam = down_camera();
  const cv::Mat plain = renderer().render(s, cam, o);
  s.plate.texture = 0.1;
  const cv::Mat grained = renderer().render(s, cam, o);
  cv::Mat ratio;
  cv::Mat a, b;
  plain.convertTo(a, CV_64F);
  grained.convertTo(b, CV_64F);
  cv::divide(b, a, ratio);
  const cv::Rect board(40, 40, 200, 200);  // plate only, away from the sphere
  double lo = 0, hi = 0;
  cv::minMaxLoc(ratio(board).reshape(1), &lo, &hi);
  EXPECT_GE(lo, 0.9 - 0.02);
  EXPECT_LE(hi, 1.1 + 0.02);
  cv::Scalar mean, sd;
  cv::meanStdDev(ratio(board).reshape(1), mean, sd);
  EXPECT_GT(sd[0], 0.01);  // it is a pattern, not a uniform board
  EXPECT_NEAR(mean[0], 1.0, 0.03);
}

TEST(LabLook, ClumpComponentsShareOneTone) {
  // Three equal spheres side by side in an orthographic view: the same shading at each centre.
  Scene s;
  s.positions = {{-0.02, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.02, 0.0, 0.0}};
  s.radii = {0.008, 0.008, 0.008};
  s.plate.enabled = false;
  s.scale_reference.enabled = false;
  camera::Camera cam = camera::side_view(1.0, 0.1, 0.0, 0.0, 400, 200);
  cam.projection = camera::Projection::kOrthographic;
  cam.intrinsics.ortho_width_m = 0.1;
  RenderOptions o;
  o.tint_fraction = 0.3;
  o.tone_warmth = 0.5;
  o.tint_seed = 7;
  auto centre_colour = [&](const cv::Mat& img, const Eigen::Vector3d& p) {
    const Eigen::Vector2d uv = *camera::project(cam, p);
    return img.at<cv::Vec3b>(static_cast<int>(std::lround(uv.y())),
                             static_cast<int>(std::lround(uv.x())));
  };
  s.body_ids = {5, 5, 9};
  const cv::Mat img = renderer().render(s, cam, o);
  EXPECT_EQ(centre_colour(img, s.positions[0]), centre_colour(img, s.positions[1]));
  EXPECT_NE(centre_colour(img, s.positions[0]), centre_colour(img, s.positions[2]));
  // Empty body ids: each sphere its own body, as before body ids existed.
  s.body_ids.clear();
  const cv::Mat own = renderer().render(s, cam, o);
  EXPECT_NE(centre_colour(own, s.positions[0]), centre_colour(own, s.positions[1]));
  s.body_ids = {1, 2};
  EXPECT_THROW(renderer().render(s, cam, o), std::invalid_argument);
}

TEST(LabLook, SphereCastsAShadowWhereTheLightSays) {
  // A ball hanging 40 mm over the plate, seen from above; the light comes from the camera
  // frame's (-0.35, -0.6, -1) direction. The shadow's centre is where the ray from the ball's
  // centre away from the light meets the plate.
  Scene s;
  const Eigen::Vector3d ball(0.0, 0.0, 0.04);
  s.positions = {ball};
  s.radii = {0.01};
  s.scale_reference.enabled = false;
  RenderOptions o;
  o.view = View::kTop;
  o.shadows = true;
  o.shadow_strength = 0.8;
  o.shadow_softness_m = 0.001;
  const camera::Camera cam = down_camera();
  const Eigen::Matrix3d r = camera::rotation_world_to_camera(cam);
  const Eigen::Vector3d to_light = (r.transpose() * o.light_direction_camera).normalized();
  ASSERT_GT(to_light.z(), 0.0);
  const Eigen::Vector3d on_plate = ball - ball.z() / to_light.z() * to_light;
  const Eigen::Vector3d mirrored(-on_plate.x(), -on_plate.y(), 0.0);  // lit, as far from the axis
  const cv::Mat lit = renderer().render(s, cam, [&] {
    RenderOptions no = o;
    no.shadows = false;
    return no;
  }());
  const cv::Mat shaded = renderer().render(s, cam, o);
  const Eigen::Vector2d uv = *camera::project(cam, on_plate);
  const Eigen::Vector2d uv_far = *camera::project(cam, mirrored);
  // In the umbra the direct light is cut by the strength: ambient + diffuse n.l (1 - 0.8).
  const double direct = std::max(0.0, Eigen::Vector3d::UnitZ().dot(to_light));
  const double expected = (o.ambient + o.diffuse * direct * (1.0 - o.shadow_strength)) /
                          (o.ambient + o.diffuse * direct);
  EXPECT_NEAR(grey(shaded, uv) / grey(lit, uv), expected, 0.03);
  EXPECT_NEAR(grey(shaded, uv_far), grey(lit, uv_far), 1.0);  // no shadow elsewhere
}

TEST(LabLook, SameInputSameBytes) {
  Scene s;
  for (int i = 0; i < 60; ++i) {
    const double a = 0.7 * i;
    s.positions.emplace_back(0.004 * i * std::cos(a) / 8.0, 0.004 * i * std::sin(a) / 8.0,
                             0.003 + 0.0005 * (i % 5));
    s.radii.push_back(0.003);
  }
  RenderOptions o;
  apply_lab_look(s, o);
  const camera::Camera side = lab_side_camera(s, {.width_px = 480, .height_px = 270});
  const cv::Mat a = renderer().render(s, side, o);
  const cv::Mat b = renderer().render(s, side, o);
  Renderer other;
  const cv::Mat c = other.render(s, side, o);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(a, c, cv::NORM_INF), 0.0);
}

TEST(ShadowMap, FramesEverySphereInsideTheMap) {
  const std::vector<Eigen::Vector3d> c = {{0.0, 0.0, 1.0}, {0.1, -0.05, 1.2}, {-0.03, 0.02, 0.9}};
  const std::vector<double> r = {0.01, 0.02, 0.005};
  const LightFrame lf = frame_light(c, r, Eigen::Vector3d(-0.35, -0.6, -1.0), 1024);
  const Eigen::Matrix4d m = lf.to_light();
  EXPECT_NEAR(lf.rotation.determinant(), 1.0, 1e-12);
  // The light looks along minus the direction towards it.
  EXPECT_NEAR(lf.rotation.row(2).dot(Eigen::Vector3d(-0.35, -0.6, -1.0).normalized()), -1.0,
              1e-12);
  for (std::size_t i = 0; i < c.size(); ++i) {
    for (int axis = 0; axis < 3; ++axis) {
      for (const double sgn : {-1.0, 1.0}) {
        const Eigen::Vector3d p = c[i] + sgn * r[i] * lf.rotation.row(axis).transpose();
        const Eigen::Vector4d q = m * Eigen::Vector4d(p.x(), p.y(), p.z(), 1.0);
        EXPECT_GE(q.x(), 1.0);
        EXPECT_LE(q.x(), lf.size - 2.0);
        EXPECT_GE(q.y(), 1.0);
        EXPECT_LE(q.y(), lf.size - 2.0);
        EXPECT_GT(q.z(), 0.0);
        EXPECT_LT(q.z(), 1.0);
      }
    }
  }
}

}  // namespace
}  // namespace reposetwin::render
