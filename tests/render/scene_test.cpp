// Scene data, validation, lab cameras and fixture geometry: closed forms, no GL.
#include "render/scene.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "camera/camera.hpp"
#include "render/fixtures.hpp"

namespace reposetwin::render {
namespace {

Scene two_spheres() {
  Scene s;
  s.positions = {Eigen::Vector3d(0.03, 0.04, 0.01), Eigen::Vector3d(-0.01, 0.0, 0.05)};
  s.radii = {0.01, 0.002};
  return s;
}

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no exception";
}

TEST(PileExtent, BoundingCylinderOfTheSpheres) {
  const PileExtent e = pile_extent(two_spheres());
  EXPECT_DOUBLE_EQ(e.radius_m, 0.05 + 0.01);  // hypot(0.03, 0.04) + r
  EXPECT_DOUBLE_EQ(e.z_min_m, 0.0);
  EXPECT_DOUBLE_EQ(e.z_max_m, 0.052);
  EXPECT_NEAR(e.center_m.z(), 0.026, 1e-15);
  EXPECT_NE(message_of([] { pile_extent(Scene{}); }).find("scene.positions is empty"),
            std::string::npos);
}

TEST(Validate, NamesTheFieldAndValue) {
  Scene s = two_spheres();
  EXPECT_NO_THROW(validate(s));
  s.positions[1].x() = std::nan("");
  EXPECT_NE(message_of([&] { validate(s); }).find("scene.positions[1]"), std::string::npos);
  s = two_spheres();
  s.radii[0] = 0.0;
  EXPECT_NE(message_of([&] { validate(s); }).find("scene.radii[0] must be positive"),
            std::string::npos);
  s = two_spheres();
  s.material_ids = {0};
  EXPECT_NE(message_of([&] { validate(s); }).find("scene.material_ids has 1 entries"),
            std::string::npos);
  s = two_spheres();
  s.shells.push_back(Shell{.z_bottom_m = 0.2, .z_top_m = 0.1});
  EXPECT_NE(message_of([&] { validate(s); }).find("scene.shells[0].z_top_m"), std::string::npos);
  s = two_spheres();
  s.plate.thickness_m = -1.0;
  EXPECT_NE(message_of([&] { validate(s); }).find("scene.plate.thickness_m"), std::string::npos);
  s = two_spheres();
  s.scale_reference.count = 0;
  EXPECT_NE(message_of([&] { validate(s); }).find("scene.scale_reference.count"),
            std::string::npos);
}

TEST(Validate, OptionsAreChecked) {
  const Scene s = two_spheres();
  const camera::Camera cam = lab_side_camera(s, {.width_px = 320, .height_px = 240});
  RenderOptions o;
  EXPECT_NO_THROW(validate(s, cam, o));
  o.ambient = 1.5;
  EXPECT_NE(message_of([&] { validate(s, cam, o); }).find("options.ambient"), std::string::npos);
  o = RenderOptions{};
  o.supersample = 0;
  EXPECT_NE(
      message_of([&] { validate(s, cam, o); }).find("options.supersample must be in [1, 8], got 0"),
      std::string::npos);
  o = RenderOptions{};
  o.light_direction_camera.setZero();
  EXPECT_NE(message_of([&] { validate(s, cam, o); }).find("options.light_direction_camera"),
            std::string::npos);
}

// Every listed world point must project inside the image.
void expect_in_view(const camera::Camera& cam, const std::vector<Eigen::Vector3d>& points) {
  for (const Eigen::Vector3d& p : points) {
    const auto uv = camera::project(cam, p);
    ASSERT_TRUE(uv.has_value());
    EXPECT_GE(uv->x(), 0.0) << p.transpose();
    EXPECT_LE(uv->x(), cam.intrinsics.width_px - 1.0) << p.transpose();
    EXPECT_GE(uv->y(), 0.0) << p.transpose();
    EXPECT_LE(uv->y(), cam.intrinsics.height_px - 1.0) << p.transpose();
  }
}

Scene cone_of_spheres() {
  // A ring of spheres at the base and one at the top: radius 0.1 m, height 0.06 m.
  Scene s;
  for (int k = 0; k < 36; ++k) {
    const double a = 2.0 * M_PI * k / 36.0;
    s.positions.emplace_back(0.098 * std::cos(a), 0.098 * std::sin(a), 0.002);
    s.radii.push_back(0.002);
  }
  s.positions.emplace_back(0.0, 0.0, 0.058);
  s.radii.push_back(0.002);
  return s;
}

TEST(LabCameras, SideViewIsLevelFarAndFramesPileAndBar) {
  const Scene s = cone_of_spheres();
  const camera::Camera cam = lab_side_camera(s);
  EXPECT_EQ(cam.name, "side");
  EXPECT_DOUBLE_EQ(cam.extrinsics.position.z(), 0.0);  // level with the plate
  EXPECT_DOUBLE_EQ(cam.extrinsics.look_at.z(), 0.0);   // looking horizontally
  EXPECT_GE(std::hypot(cam.extrinsics.position.x(), cam.extrinsics.position.y()),
            10.0 * pile_extent(s).radius_m);
  const Eigen::Vector3d bar = *scale_reference_center(s, cam, View::kSide);
  expect_in_view(cam, {{-0.1, -0.1, 0.0},
                       {0.1, -0.1, 0.0},
                       {0.0, 0.0, 0.06},
                       {0.0, -0.25, -0.015},
                       {bar.x() + 0.01, 0.0, 0.1},
                       {bar.x() + 0.01, 0.0, 0.0}});
  // The pile is not lost in the frame: it spans at least half the image's width budget.
  const double span =
      camera::project(cam, {0.1, 0, 0})->x() - camera::project(cam, {-0.1, 0, 0})->x();
  EXPECT_GT(span, 0.4 * cam.intrinsics.width_px);
  // The default bar stands clear of the pile, to its right in the image.
  EXPECT_NEAR(bar.x(), 0.1 + 0.025, 1e-12);
  EXPECT_NEAR(bar.z(), 0.05, 1e-12);
}

TEST(LabCameras, SideViewAzimuthKeepsTheBarBesideThePile) {
  const Scene s = cone_of_spheres();
  const camera::Camera cam = lab_side_camera(s, {.azimuth_deg = 90.0});
  const Eigen::Vector3d bar = *scale_reference_center(s, cam, View::kSide);
  // The bar lies in the plane through the axis facing the camera: same depth as the axis.
  EXPECT_NEAR(camera::to_camera_frame(cam, bar).z(),
              camera::to_camera_frame(cam, Eigen::Vector3d(0, 0, bar.z())).z(), 1e-12);
  EXPECT_GT(camera::project(cam, bar)->x(), camera::principal_u(cam) + 10.0);
}

TEST(LabCameras, TopViewLooksStraightDownAndFramesPileAndCard) {
  const Scene s = cone_of_spheres();
  const camera::Camera cam = lab_top_camera(s);
  EXPECT_EQ(cam.name, "top");
  const Eigen::Matrix3d r = camera::rotation_world_to_camera(cam);
  EXPECT_NEAR(r.row(2).dot(Eigen::Vector3d(0, 0, -1)), 1.0, 1e-12);
  EXPECT_GE(cam.extrinsics.position.z() - 0.06, 10.0 * pile_extent(s).radius_m - 1e-12);
  const Eigen::Vector3d card = *scale_reference_center(s, cam, View::kTop);
  expect_in_view(cam, {{-0.1, 0.0, 0.0},
                       {0.1, 0.0, 0.0},
                       {0.0, 0.1, 0.0},
                       {0.0, -0.1, 0.0},
                       {card.x() + 0.02, card.y() + 0.02, 0.0},
                       {card.x() + 0.02, card.y() - 0.02, 0.0}});
}

TEST(LabCameras, RejectsTooCloseADistance) {
  const Scene s = cone_of_spheres();
  EXPECT_NE(message_of([&] {
              lab_side_camera(s, {.distance_radii = 5.0});
            }).find("settings.distance_radii"),
            std::string::npos);
  EXPECT_NE(message_of([&] { lab_top_camera(s, {.width_px = 0}); }).find("settings.width_px"),
            std::string::npos);
  EXPECT_NE(message_of([&] { lab_side_camera(Scene{}); }).find("scene.positions is empty"),
            std::string::npos);
}

TEST(Fixtures, BarBandsAlternateFromBlackAtTheBottom) {
  Scene s = cone_of_spheres();
  s.plate.enabled = false;
  const camera::Camera cam = lab_side_camera(s);
  const TriangleMesh m = build_fixtures(s, cam, View::kSide);
  ASSERT_EQ(m.positions.size(), 10u * 36u);  // 10 boxes of 12 triangles
  for (int k = 0; k < 10; ++k) {
    double z_lo = 1e9, z_hi = -1e9;
    for (int i = 0; i < 36; ++i) {
      z_lo = std::min(z_lo, m.positions[36 * k + i].z());
      z_hi = std::max(z_hi, m.positions[36 * k + i].z());
    }
    EXPECT_NEAR(z_lo, 0.01 * k, 1e-12);
    EXPECT_NEAR(z_hi, 0.01 * (k + 1), 1e-12);
    EXPECT_EQ(m.colors[36 * k].r, k % 2 == 0 ? 20 : 245);
    EXPECT_EQ(m.lit[36 * k], 0);
  }
  // Front face in the plane through the axis (camera-frame depth of the axis), 2 mm deep.
  const double axis_depth = camera::to_camera_frame(cam, Eigen::Vector3d::Zero()).z();
  double d_lo = 1e9, d_hi = -1e9;
  for (const Eigen::Vector3d& p : m.positions) {
    d_lo = std::min(d_lo, camera::to_camera_frame(cam, p).z());
    d_hi = std::max(d_hi, camera::to_camera_frame(cam, p).z());
  }
  EXPECT_NEAR(d_lo, axis_depth, 1e-12);
  EXPECT_NEAR(d_hi - d_lo, 0.002, 1e-12);
}

TEST(Fixtures, ShellRimsHaveTheirRadii) {
  TriangleMesh m;
  add_shell(m, Shell{.z_bottom_m = 0.1, .z_top_m = 0.3, .r_bottom_m = 0.01, .r_top_m = 0.07}, 64);
  ASSERT_EQ(m.positions.size(), 64u * 6u);
  for (std::size_t i = 0; i < m.positions.size(); ++i) {
    const Eigen::Vector3d& p = m.positions[i];
    const double rho = std::hypot(p.x(), p.y());
    if (std::abs(p.z() - 0.1) < 1e-12) {
      EXPECT_NEAR(rho, 0.01, 1e-12);
    } else {
      EXPECT_NEAR(p.z(), 0.3, 1e-12);
      EXPECT_NEAR(rho, 0.07, 1e-12);
    }
    // Normals are perpendicular to the generator (0.06 out per 0.2 up).
    const Eigen::Vector3d gen(0.06 * p.x() / rho, 0.06 * p.y() / rho, 0.2);
    EXPECT_NEAR(m.normals[i].dot(gen), 0.0, 1e-12);
  }
}

}  // namespace
}  // namespace reposetwin::render
