// shadow_map: the light's orthographic view used for the renderer's soft shadows.
//
// Design note. The lab's light is directional and fixed relative to the camera (RenderOptions),
// so its view is an orthographic projection along the light, framed on the spheres (the only
// shadow casters: the fixtures are few, and a pile's shadows are what a photograph shows).
// Framing on the casters alone is enough: a receiver outside their footprint along the light
// can be shadowed by nothing, and the shader reads texels outside the map as lit. This header
// is plain geometry (no GL), so a test can check the mapping without a context.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace reposetwin::render {

/// The light's view: camera-frame point p goes to texel (u, v) = (cx + f (R p).x,
/// cy + f (R p).y) and depth ((R p).z - near) / (far - near) in [0, 1].
struct LightFrame {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // camera frame to light frame
  double f = 1.0;        // texels per metre [1/m]
  double cx = 0.0;       // [texel]
  double cy = 0.0;       // [texel]
  double near_z = 0.0;   // light-frame depth of depth 0 [m]
  double far_z = 1.0;    // light-frame depth of depth 1 [m]
  int size = 2048;       // map side [texel]
  /// The affine map camera frame -> (u, v, depth), row-major 4 x 4.
  Eigen::Matrix4d to_light() const;
};

/// Frames the light's view on the spheres (camera-frame centres [m], radii [m]), with the light
/// towards `light_direction_camera` (camera frame, need not be unit) and a map of `size` texels.
/// Requires at least one sphere.
LightFrame frame_light(const std::vector<Eigen::Vector3d>& centres, const std::vector<double>& radii,
                       const Eigen::Vector3d& light_direction_camera, int size);

}  // namespace reposetwin::render
