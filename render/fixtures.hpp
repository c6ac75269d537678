// fixtures: triangle meshes of the lab fixtures (base plate, funnel or column, scale reference).
//
// Design note. The fixtures are few and simple (boxes and one frustum), so they are built on the
// CPU in the world frame, in double precision, as plain triangle lists; the renderer moves them
// to the camera frame and draws them with the projection it uses for the spheres. Keeping the
// geometry apart from GL lets a test check it (for example that the bar's bands have the stated
// heights) without a context.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "camera/camera.hpp"
#include "render/scene.hpp"

namespace reposetwin::render {

/// A triangle list: vertices 3k, 3k+1, 3k+2 form triangle k.
struct TriangleMesh {
  std::vector<Eigen::Vector3d> positions;  // (3t) vertex positions, world frame [m]
  std::vector<Eigen::Vector3d> normals;    // (3t) unit normals (faces are drawn two-sided)
  std::vector<Rgb> colors;                 // (3t) base colour
  std::vector<std::uint8_t> lit;           // (3t) 1 = shaded by the light, 0 = drawn as is,
                                           // 2 = shaded, with the board's grain
};

/// Appends a box with centre `center`, unit axes `a`, `b`, `c` (orthogonal) and half sizes
/// `half` along them [m].
void add_box(TriangleMesh& mesh, const Eigen::Vector3d& center, const Eigen::Vector3d& a,
             const Eigen::Vector3d& b, const Eigen::Vector3d& c, const Eigen::Vector3d& half,
             Rgb color, bool lit);

/// Appends the lateral surface of an axisymmetric shell, `segments` facets around.
void add_shell(TriangleMesh& mesh, const Shell& shell, int segments = 256);

/// All fixtures of the scene for this camera and view: the plate, the shells and the view's
/// scale reference (bar or card, per marker.md).
TriangleMesh build_fixtures(const Scene& scene, const camera::Camera& cam, View view);

}  // namespace reposetwin::render
