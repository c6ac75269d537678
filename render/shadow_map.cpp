#include "render/shadow_map.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace reposetwin::render {

Eigen::Matrix4d LightFrame::to_light() const {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  const double depth = far_z - near_z;
  m.block<1, 3>(0, 0) = f * rotation.row(0);
  m(0, 3) = cx;
  m.block<1, 3>(1, 0) = f * rotation.row(1);
  m(1, 3) = cy;
  m.block<1, 3>(2, 0) = rotation.row(2) / depth;
  m(2, 3) = -near_z / depth;
  return m;
}

LightFrame frame_light(const std::vector<Eigen::Vector3d>& centres, const std::vector<double>& radii,
                       const Eigen::Vector3d& light_direction_camera, int size) {
  if (centres.empty() || centres.size() != radii.size())
    throw std::invalid_argument("render: shadow map needs spheres with one radius each");
  LightFrame lf;
  lf.size = size;
  // The light looks along -L; any perpendicular pair completes the frame.
  const Eigen::Vector3d forward = -light_direction_camera.normalized();
  const Eigen::Vector3d helper =
      std::abs(forward.y()) < 0.9 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitX();
  const Eigen::Vector3d x = helper.cross(forward).normalized();
  const Eigen::Vector3d y = forward.cross(x);
  lf.rotation.row(0) = x.transpose();
  lf.rotation.row(1) = y.transpose();
  lf.rotation.row(2) = forward.transpose();
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (std::size_t i = 0; i < centres.size(); ++i) {
    const Eigen::Vector3d c = lf.rotation * centres[i];
    lo = lo.cwiseMin(c - Eigen::Vector3d::Constant(radii[i]));
    hi = hi.cwiseMax(c + Eigen::Vector3d::Constant(radii[i]));
  }
  const double span = std::max(hi.x() - lo.x(), hi.y() - lo.y());
  lf.f = (size - 4) / span;  // two texels of clear border on each side
  lf.cx = 0.5 * (size - 1) - lf.f * 0.5 * (lo.x() + hi.x());
  lf.cy = 0.5 * (size - 1) - lf.f * 0.5 * (lo.y() + hi.y());
  const double pad = 0.01 * (hi.z() - lo.z()) + 1e-6;
  lf.near_z = lo.z() - pad;
  lf.far_z = hi.z() + pad;
  return lf;
}

}  // namespace reposetwin::render
