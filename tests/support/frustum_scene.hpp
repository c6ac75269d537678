// A flat-topped pile of known shape for render-and-measure tests: a frustum fixture
// (render::Shell, the funnel's mesh) standing on the plate, its crest width 2 r_top exactly.
// Shared by the crest tests of photos/ (vision on renders) and loop/ (a lab photo's crest).
#pragma once

#include <Eigen/Core>

#include "render/scene.hpp"

namespace reposetwin::test_support {

/// A scene of the frustum alone: height `h`, foot radius `r_bottom`, top radius `r_top` [m], on
/// the plate, no scale marker. One sphere hides inside it (a scene needs one).
inline render::Scene frustum_scene(double h, double r_bottom, double r_top) {
  render::Scene scene;
  scene.positions = {Eigen::Vector3d(0.0, 0.0, 0.005)};
  scene.radii = {0.002};
  scene.material_ids = {0};
  scene.scale_reference.enabled = false;
  render::Shell shell;
  shell.z_bottom_m = 0.0;
  shell.z_top_m = h;
  shell.r_bottom_m = r_bottom;
  shell.r_top_m = r_top;
  shell.color = {108, 115, 120};
  scene.shells = {shell};
  return scene;
}

}  // namespace reposetwin::test_support
