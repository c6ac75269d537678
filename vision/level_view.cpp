#include "vision/level_view.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "vision/text_detail.hpp"

namespace reposetwin::vision {
namespace {

using detail::kRadToDeg;
using detail::str;

// Steeper than this the camera looks down on the pile rather than at its side [deg].
constexpr double kMaxPitchDeg = 80.0;
// A camera this close to level, unrolled and undistorted, is used as it is.
constexpr double kLevelTolerance = 1e-9;
// The level image may hold at most this many times the photo's pixels.
constexpr double kMaxGrowth = 4.0;

// The level camera at `declared`'s centre: its axis the declared axis's horizontal direction.
camera::Camera level_camera(const camera::Camera& declared) {
  camera::Camera level = declared;
  const Eigen::Vector3d forward =
      camera::rotation_world_to_camera(declared).row(2).transpose();
  Eigen::Vector3d flat(forward.x(), forward.y(), 0.0);
  flat.normalize();
  level.extrinsics.look_at = declared.extrinsics.position + flat;
  level.extrinsics.up = Eigen::Vector3d::UnitZ();
  level.intrinsics.k1 = 0.0;
  level.intrinsics.k2 = 0.0;
  return level;
}

// Pixel of a direction given in a camera's frame, without distortion; false behind the camera.
bool pinhole(double f, double cx, double cy, const Eigen::Vector3d& c, Eigen::Vector2d& px) {
  if (!(c.z() > 1e-6)) return false;
  px = {cx + f * c.x() / c.z(), cy + f * c.y() / c.z()};
  return true;
}

}  // namespace

LevelView level_view(const cv::Mat& image, const camera::Camera& declared,
                     const std::string& where) {
  LevelView out;
  out.declared = declared;
  const Eigen::Matrix3d rd = camera::rotation_world_to_camera(declared);
  const Eigen::Vector3d forward = rd.row(2).transpose(), right = rd.row(0).transpose();
  out.pitch_deg = std::asin(std::clamp(-forward.z(), -1.0, 1.0)) * kRadToDeg;
  out.roll_deg = std::asin(std::clamp(right.z(), -1.0, 1.0)) * kRadToDeg;
  if (declared.projection != camera::Projection::kPerspective) {
    out.image = image;
    out.valid = cv::Mat(image.size(), CV_8U, cv::Scalar(255));
    out.camera = declared;
    return out;
  }
  if (!(std::abs(out.pitch_deg) < kMaxPitchDeg))
    throw std::invalid_argument(where + ": the camera is pitched " + str(out.pitch_deg) +
                                " deg; a side view is taken within " + str(kMaxPitchDeg) +
                                " deg of level");
  const bool level = std::abs(forward.z()) < kLevelTolerance &&
                     std::abs(right.z()) < kLevelTolerance && declared.intrinsics.k1 == 0.0 &&
                     declared.intrinsics.k2 == 0.0;
  if (level) {
    out.image = image;
    out.valid = cv::Mat(image.size(), CV_8U, cv::Scalar(255));
    out.camera = declared;
    return out;
  }
  out.identity = false;
  camera::Camera lv = level_camera(declared);
  const Eigen::Matrix3d rl = camera::rotation_world_to_camera(lv);
  const double f = camera::focal_px(declared);
  const double cx = camera::principal_u(declared), cy = camera::principal_v(declared);
  const int w = image.cols, h = image.rows;
  // The photo's border seen by the level camera: its bounding box is the level image.
  double u0 = 1e300, u1 = -1e300, v0 = 1e300, v1 = -1e300;
  auto border_point = [&](double u, double v) {
    const camera::Ray ray = camera::unproject(declared, Eigen::Vector2d(u, v));
    Eigen::Vector2d px;
    if (!pinhole(f, 0.0, 0.0, rl * ray.direction, px)) return;
    u0 = std::min(u0, px.x());
    u1 = std::max(u1, px.x());
    v0 = std::min(v0, px.y());
    v1 = std::max(v1, px.y());
  };
  for (int i = 0; i <= 64; ++i) {
    const double u = -0.5 + w * i / 64.0, v = -0.5 + h * i / 64.0;
    border_point(u, -0.5);
    border_point(u, h - 0.5);
    border_point(-0.5, v);
    border_point(w - 0.5, v);
  }
  const int lw = static_cast<int>(std::ceil(u1 - u0)), lh = static_cast<int>(std::ceil(v1 - v0));
  if (!(lw > 0 && lh > 0) || static_cast<double>(lw) * lh > kMaxGrowth * w * h)
    throw std::invalid_argument(where + ": the camera's pitch " + str(out.pitch_deg) +
                                " deg and roll " + str(out.roll_deg) +
                                " deg fan the photo out beyond " + str(kMaxGrowth) +
                                " times its size seen level; not a side view");
  // Same focal length in pixels on the new width, principal point where the box begins.
  lv.intrinsics.sensor_width_mm = declared.intrinsics.sensor_width_mm * lw / w;
  lv.intrinsics.width_px = lw;
  lv.intrinsics.height_px = lh;
  lv.intrinsics.cx_px = -0.5 - u0;
  lv.intrinsics.cy_px = -0.5 - v0;
  const double lcx = *lv.intrinsics.cx_px, lcy = *lv.intrinsics.cy_px;
  // Each level pixel's ray in the photo (rotation, then the declared lens's distortion).
  const Eigen::Matrix3d level_to_photo = rd * rl.transpose();
  cv::Mat map_u(lh, lw, CV_32F), map_v(lh, lw, CV_32F);
  out.valid = cv::Mat(lh, lw, CV_8U, cv::Scalar(0));
  for (int r = 0; r < lh; ++r) {
    float* mu = map_u.ptr<float>(r);
    float* mv = map_v.ptr<float>(r);
    uchar* ok = out.valid.ptr<uchar>(r);
    for (int c = 0; c < lw; ++c) {
      const Eigen::Vector3d d = level_to_photo * Eigen::Vector3d((c - lcx) / f, (r - lcy) / f, 1.0);
      mu[c] = mv[c] = -1e6f;
      if (!(d.z() > 1e-6)) continue;
      const Eigen::Vector2d xy =
          camera::distort_normalised(declared, Eigen::Vector2d(d.x() / d.z(), d.y() / d.z()));
      const double u = cx + f * xy.x(), v = cy + f * xy.y();
      mu[c] = static_cast<float>(u);
      mv[c] = static_cast<float>(v);
      if (u >= -0.5 && u <= w - 0.5 && v >= -0.5 && v <= h - 0.5) ok[c] = 255;
    }
  }
  cv::remap(image, out.image, map_u, map_v, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  out.camera = lv;
  return out;
}

cv::Point2d to_photo(const LevelView& view, const cv::Point2d& level_px) {
  if (view.identity) return level_px;
  const camera::Ray ray = camera::unproject(view.camera, Eigen::Vector2d(level_px.x, level_px.y));
  const auto px = camera::project(view.declared, ray.origin + ray.direction);
  if (!px) return level_px;
  return {px->x(), px->y()};
}

PlateLine toe_line_for(const camera::Camera& level, const Eigen::Vector3d& axis_foot,
                       double radius_m, double sigma_px_in) {
  const Eigen::Vector2d c = level.extrinsics.position.head<2>(), a = axis_foot.head<2>();
  const double l = (a - c).norm();
  const double r = std::clamp(radius_m, 0.0, 0.95 * l);
  const Eigen::Vector2d u = (a - c) / l, n(-u.y(), u.x());
  const double depth = l - r * r / l, side = r * std::sqrt(l * l - r * r) / l;
  const Eigen::Vector2d p0 = c + depth * u - side * n, p1 = c + depth * u + side * n;
  auto px = [&](const Eigen::Vector2d& p) {
    const auto q = camera::project(level, Eigen::Vector3d(p.x(), p.y(), axis_foot.z()));
    if (!q) throw std::runtime_error("the camera does not see the pile's base");
    return *q;
  };
  Eigen::Vector2d q0 = px(p0), q1 = px(p1);
  if (radius_m <= 0.0 || std::abs(q1.x() - q0.x()) < 1.0) {
    // No width yet: the row of the axis foot, level.
    const Eigen::Vector2d q = px(a);
    q0 = q - Eigen::Vector2d(1.0, 0.0);
    q1 = q + Eigen::Vector2d(1.0, 0.0);
  }
  PlateLine line;
  line.b = (q1.y() - q0.y()) / (q1.x() - q0.x());
  line.a = q0.y() - line.b * q0.x();
  line.sigma_px = sigma_px_in;
  line.support = 2;
  return line;
}

double camera_height_m(const camera::Camera& level, const Eigen::Vector3d& axis_foot) {
  return level.extrinsics.position.z() - axis_foot.z();
}

double camera_distance_m(const camera::Camera& level, const Eigen::Vector3d& axis_foot) {
  return (level.extrinsics.position.head<2>() - axis_foot.head<2>()).norm();
}

}  // namespace reposetwin::vision
