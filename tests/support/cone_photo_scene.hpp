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

}  // namespace reposetwin::test_support
