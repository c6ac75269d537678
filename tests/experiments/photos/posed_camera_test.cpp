// Truthfully declared cameras as a lab sets them up: on a tripod, pitched down 0-30 deg at the
// pile, rolled up to +-5 deg, from plate level to well above the pile. Cones of spheres are
// photographed by the twin's renderer and each photo is measured through its own (true) camera
// (vision/level_view.hpp, measure.hpp): it must read within 1 deg of the same pile's level photo,
// or be refused where the camera looks down on the pile more steeply than a side view allows
// (admission.hpp's view-angle check; from higher still the flanks or the border the photo then
// shows refuse it first) and nowhere else.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "../../support/cone_photo_scene.hpp"
#include "experiments/photos/photographs.hpp"
#include "render/renderer.hpp"
#include "render/scene.hpp"
#include "vision/measure.hpp"

namespace reposetwin::experiments {
namespace {
using test_support::Spheres;

constexpr double kA = 1.75e-3;  // sphere radius [m]
constexpr double kDeg = 3.14159265358979323846 / 180.0;

struct Cone {
  double h, r;  // apex height and base radius [m]
};

render::Scene cone_scene(const Cone& c) { return test_support::cone_photo_scene(c.h, c.r, kA); }

// The lab's level side camera at plate height, 12 pile radii away (the reference photo).
camera::Camera level_camera(const render::Scene& scene) {
  return test_support::cone_photo_camera(scene);
}

// A tripod camera at the level camera's horizontal place, `height` above the plate, aimed down
// `pitch_deg` through its lens centre at the pile, rolled by `roll_deg` about its axis. The lens
// is centred (no shift), so the aim keeps the pile in the frame.
camera::Camera tripod(const camera::Camera& level, double height, double pitch_deg,
                      double roll_deg) {
  camera::Camera c = level;
  c.intrinsics.cx_px.reset();
  c.intrinsics.cy_px.reset();
  c.extrinsics.position.z() = height;
  Eigen::Vector3d flat = level.extrinsics.look_at - level.extrinsics.position;
  flat.z() = 0.0;
  flat.normalize();
  const double p = pitch_deg * kDeg, r = roll_deg * kDeg;
  const Eigen::Vector3d forward = std::cos(p) * flat - std::sin(p) * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d up0 = std::sin(p) * flat + std::cos(p) * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d right = forward.cross(up0);
  c.extrinsics.look_at = c.extrinsics.position + forward;
  c.extrinsics.up = std::cos(r) * up0 + std::sin(r) * right;
  return c;
}

struct Reading {
  bool measured = false;
  double theta_deg = 0.0;
  vision::Check check = vision::Check::kCount;
  std::string why;
};

Reading read(const cv::Mat& image, const camera::Camera& cam, const std::string& name) {
  vision::ScaleSpec spec;
  spec.camera = cam;
  spec.search_marker = false;
  Reading r;
  try {
    const vision::SideMeasurement m = vision::measure_side(image, spec, {}, name);
    r.measured = true;
    r.theta_deg = m.theta_deg;
  } catch (const vision::Refusal& e) {
    r.check = e.check();
    r.why = e.what();
  } catch (const std::exception& e) {
    r.why = e.what();
  }
  return r;
}

// Measured (640 x 480, 12 pile radii): see the printed table; every photo of pitch up to 20 deg
// is measured, the 30 deg ones of the flatter cone are refused as looking down on it.
TEST(PosedCamera, TruthfulTripodCamerasReadAsTheLevelPhoto) {
  static render::Renderer renderer;
  int measured = 0, refused = 0;
  for (const Cone& cone : {Cone{22e-3, 42e-3}, Cone{30e-3, 42e-3}}) {
    const render::Scene scene = cone_scene(cone);
    const camera::Camera level = level_camera(scene);
    const Reading ref = read(renderer.render(scene, level, {}), level, "level");
    ASSERT_TRUE(ref.measured) << ref.why;
    const double distance =
        (level.extrinsics.position.head<2>() - Eigen::Vector2d::Zero()).norm();
    for (double pitch : {0.0, 5.0, 10.0, 20.0, 30.0})
      for (double roll : {-5.0, 0.0, 5.0}) {
        // Aimed at the pile's mid height: from plate level (at pitch 0, half the pile's height
        // up) to well above the pile (0.3 m at 30 deg).
        std::vector<double> heights = {0.5 * cone.h + distance * std::tan(pitch * kDeg)};
        for (double h : heights) {
          const camera::Camera cam = tripod(level, h, pitch, roll);
          char name[96];
          std::snprintf(name, sizeof name, "H%.0f p%.0f r%+.0f h%.0fmm", 1e3 * cone.h, pitch, roll,
                        1e3 * h);
          const cv::Mat photo = renderer.render(scene, cam, {});
          const Reading t = read(photo, cam, name);
          const double elevation = std::atan2(h - cone.h, distance) / kDeg;
          if (t.measured) {
            ++measured;
            std::printf("%s: %.2f deg (level %.2f)\n", name, t.theta_deg, ref.theta_deg);
            EXPECT_NEAR(t.theta_deg, ref.theta_deg, 1.0) << name;
          } else {
            ++refused;
            std::printf("%s: refused: %s\n", name, t.why.c_str());
            // A truthful photo is refused only from well above the pile (the view-angle check,
            // or, from higher still, the flanks or the border it then shows).
            EXPECT_GT(elevation, ref.theta_deg - 12.0) << name << ": " << t.why;
          }
          if (pitch <= 10.0) EXPECT_TRUE(t.measured) << name << ": " << t.why;
        }
      }
  }
  std::printf("posed cameras: %d measured, %d refused\n", measured, refused);
}

// A photo taken pitched 12 deg down from above, its sidecar declaring the level camera at the
// plate, is refused as a camera mismatch (not as "no pile"), and the same for a level photo
// whose sidecar declares the tripod's pitch.
TEST(PosedCamera, ContradictedSidecarIsACameraMismatch) {
  static render::Renderer renderer;
  const Cone cone{22e-3, 42e-3};
  const render::Scene scene = cone_scene(cone);
  const camera::Camera level = level_camera(scene);
  const double distance = level.extrinsics.position.head<2>().norm();
  const camera::Camera pitched =
      tripod(level, 0.5 * cone.h + distance * std::tan(12.0 * kDeg), 12.0, 0.0);
  const Reading a = read(renderer.render(scene, pitched, {}), level, "pitched, declared level");
  EXPECT_FALSE(a.measured);
  EXPECT_EQ(a.check, vision::Check::kCameraConsistent) << a.why;
  const Reading b = read(renderer.render(scene, level, {}), pitched, "level, declared pitched");
  EXPECT_FALSE(b.measured);
  EXPECT_EQ(b.check, vision::Check::kCameraConsistent) << b.why;
}

}  // namespace
}  // namespace reposetwin::experiments
