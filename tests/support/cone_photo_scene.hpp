// A cone of spheres standing on the lab's plate, ready to photograph: the shared scene of the
// camera-pose render tests (tilted, posed and camera_pose tests in tests/experiments/photos).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "cone_pile.hpp"
#include "experiments/photos/photographs.hpp"
#include "render/scene.hpp"

namespace reposetwin::test_support {

/// Spheres of radius `a` [m] packed into a cone of apex height `h` and base radius `r` [m] on the
/// axis, on the lab's plate, no scale reference drawn.
inline render::Scene cone_photo_scene(double h, double r, double a) {
  const Spheres s = make_cone(h, r, 0.0, 0.0, a, 11, 0.3);
  std::vector<Eigen::Vector3d> x(s.x.begin(), s.x.end());
  render::Scene scene =
      experiments::centred_pile_scene({x, s.r, std::vector<int>(s.r.size(), 0)});
  scene.scale_reference.enabled = false;
  return scene;
}

/// The lab's level side camera at plate height, 640 x 480, 12 pile radii away, margin 1.6: the
/// camera-pose tests' reference. `shift_lens` false centres the lens on the horizon, so a camera
/// pitched from it keeps the pile in the frame.
inline camera::Camera cone_photo_camera(const render::Scene& scene, bool shift_lens = true) {
  render::LabCameraSettings cams;
  cams.width_px = 640;
  cams.height_px = 480;
  cams.distance_radii = 12.0;
  cams.margin = 1.6;
  cams.shift_lens = shift_lens;
  return render::lab_side_camera(scene, cams);
}

}  // namespace reposetwin::test_support
