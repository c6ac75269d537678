// vision/level_view: a side photo from any declared camera, seen as a level camera sees it.
//
// Design note. A lab's camera on a tripod looks slightly down at the pile (pitch 5-30 deg) and
// is seldom perfectly level about its axis (roll of a few degrees); its lens distorts a little.
// Side-view measurement (side_view.hpp) reads lines that are horizontal for a level camera: the
// plate's far edge, the toe line through the base circle's tangent points. Rather than teach
// every step about pitch, roll and distortion, the photo is re-projected once onto the image of
// a level camera at the same centre (a rotation about the camera centre is a homography, exact
// for every depth), its lens free of distortion and of the same focal length. Every later step
// then meets the geometry it was written for, and every distance the camera predicts in the
// level image is a plain function of depth and height:
//   v = cy + f (h - z) / d     for a point at height z and horizontal depth d along the axis,
// with h the camera's height. In particular the base circle's tangent points, at depth
// L - R^2 / L for a circle of radius R seen from horizontal distance L, lie on one horizontal
// line (the toe line) whose row the camera fixes: "the pile's base where the declared camera
// predicts it" (toe_line_for). A camera with no pitch, no roll and no distortion is returned as
// it is, byte for byte, so every level photo reads exactly as before.
// The level image is larger than the photo where the rotation fans it out; its pixels that come
// from outside the photo are marked invalid (`valid`), and a pile that reaches them is cut by
// the photo's border. Limits: the camera must look at least 10 deg away from straight down
// (pitch below 80 deg) and see the axis foot.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <string>

#include "camera/camera.hpp"
#include "vision/side_view.hpp"

namespace reposetwin::vision {

/// A photo re-projected onto a level camera at the same centre.
struct LevelView {
  cv::Mat image;             // the photo as the level camera sees it (same type as the photo)
  cv::Mat valid;             // CV_8U: 255 where the level pixel comes from inside the photo
  camera::Camera camera;     // the level camera: no pitch, no roll, no distortion
  camera::Camera declared;   // the photo's own camera
  double pitch_deg = 0.0;    // the declared optical axis below the horizontal [deg]
  double roll_deg = 0.0;     // the declared camera's roll about its axis [deg]
  bool identity = true;      // the photo needed no re-projection (level, no distortion)
};

/// The level view of `image` taken through `declared`. Throws std::invalid_argument naming
/// `where` for a camera that looks too steeply down (pitch of 80 deg or more) or up, or whose
/// level image would exceed four times the photo's pixels.
LevelView level_view(const cv::Mat& image, const camera::Camera& declared,
                     const std::string& where = "image");

/// A pixel of the level image back in the photo (for overlays drawn on the photo).
cv::Point2d to_photo(const LevelView& view, const cv::Point2d& level_px);

/// The toe line the camera predicts in a level image: the row of the base circle's tangent
/// points for a base of radius `radius_m` centred on `axis_foot` (the two points projected, the
/// line through them). `sigma_px` is set to `sigma_px_in`.
PlateLine toe_line_for(const camera::Camera& level, const Eigen::Vector3d& axis_foot,
                       double radius_m, double sigma_px_in = 0.5);

/// Height of the level camera above the axis foot [m] and its horizontal distance to it [m].
double camera_height_m(const camera::Camera& level, const Eigen::Vector3d& axis_foot);
double camera_distance_m(const camera::Camera& level, const Eigen::Vector3d& axis_foot);

}  // namespace reposetwin::vision
