// vision/camera_pose: a side camera's elevation and pitch read from the photo itself.
//
// Design note. A lab's sidecar may say "level with the plate" for a photo taken from well above
// it, pitched down at the pile, as a person holds a camera. Measured through the declared camera
// the toe line then maps far below the plate and the apex's ray misses its true height: H, D and
// atan(2H/D) are biased by degrees. The photo shows its own pose: seen from above, the pile's
// base circle is an ellipse whose front half is the pile's lower outline on the plate's top face
// (side_view.hpp's base_front). Its semi-axes and rows fix the camera's height and pitch, given
// the declared lens and horizontal distance (which a lab knows; a raised camera keeps its
// distance):
//  1. Fit v(u) = v_c + b sqrt(1 - ((u - u_c)/a)^2) to the front outline (u_c, a from its ends,
//     v_c, b by linear least squares over |u - u_c| < 0.9 a, one pass without 3-sigma outliers,
//     all after removing the plate line's tilt).
//  2. Through the declared lens, the rows v_c (the base's tangent points, horizontal depth
//     L - R^2/L) and v_c + b (the base's front point, depth L - R) are angles delta_c, delta_f
//     below the optical axis; R = L sin(beta), beta half the angle between the rays to the
//     ellipse's ends.
//  3. The camera height h solves atan(h/(L-R)) - atan(h/(L - R^2/L)) = delta_f - delta_c
//     (bisection; the left side grows with h up to h = sqrt((L-R)(L-R^2/L)), about 45 deg);
//     the pitch is atan(h/(L - R^2/L)) - delta_c, the elevation atan(h/L).
// A level camera above the plate (the lab's 5-10 mm) has pitch 0, as declared, and is not a
// contradiction: side_view's toe line already handles it. Two things are (pose_contradiction):
// a pitch that differs from the declared one by more than max(tolerance, 3 sigma), and a toe
// line that cuts through the pile's base (the ellipse's ends well below it: side_view searches
// the plate's top face only as deep as the pile stands above the far edge, which a camera well
// above the plate, pitched down, exceeds). measure.hpp refuses such a photo with the numbers;
// posed_camera gives the camera the photo shows, for a caller that re-photographs or re-declares.
// The front outline is the pixels below the toe line that differ from the plate's level in their
// row (read at the image's outer columns), so the pile must not reach the image's sides, and
// the plate must show there. Limits: the lens (focal length, principal point) and the horizontal
// distance must be the declared ones; no roll; the pile's base must be visible (a camera above
// the plate). A level view shows no ellipse and gives no estimate.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>

#include "camera/camera.hpp"
#include "vision/side_view.hpp"

namespace reposetwin::vision {

/// The side camera's pose as the photo shows it, beside the declared one.
struct PoseEstimate {
  double elevation_deg = 0.0;        // camera above the plate, seen from the axis foot [deg]
  double pitch_deg = 0.0;            // optical axis below the horizontal [deg]
  double height_m = 0.0;             // camera height above the axis foot [m]
  double sigma_elevation_deg = 0.0;  // from the ellipse fit's standard errors [deg]
  double sigma_pitch_deg = 0.0;      // [deg]
  double declared_elevation_deg = 0.0;  // the declared camera's, for comparison [deg]
  double declared_pitch_deg = 0.0;      // [deg]
  double distance_m = 0.0;              // horizontal distance to the axis (declared) [m]
  double centre_u_px = 0.0, centre_v_px = 0.0;  // ellipse centre (tangent points' row) [px]
  double semi_major_px = 0.0, semi_minor_px = 0.0;  // a, b [px]
  double residual_px = 0.0;                        // RMS residual of the front outline's fit [px]
  int points = 0;                                  // outline columns used [-]
  // How far the ellipse's ends (its centre row) lie below the detected toe line [px], and the
  // uncertainty: more than a few pixels and the toe line cuts through the pile's base.
  double toe_line_gap_px = 0.0;
  double sigma_toe_line_gap_px = 0.0;
};

/// Estimates the pose from the pile's base ellipse. std::nullopt when the photo shows no base
/// (a level view: no plate top face, or an outline too short to fit).
std::optional<PoseEstimate> estimate_side_pose(const SideImage& prepared,
                                               const SideProfile& profile,
                                               const camera::Camera& declared,
                                               const Eigen::Vector3d& axis_foot);

/// Why a side photo cannot be measured through its declared camera, in numbers: the pitch the
/// photo shows contradicts the declared one (pitch_contradicts), or the toe line cuts through
/// the pile's base (its ellipse's ends more than max(3 px, 3 sigma) below it). Either way the
/// message gives the estimated and the declared pitch. Empty when neither.
std::string pose_contradiction(const PoseEstimate& pose, double tolerance_deg = 3.0);

/// True when the estimated pitch differs from the declared one by more than
/// max(tolerance_deg, 3 sigma).
bool pitch_contradicts(const PoseEstimate& pose, double tolerance_deg = 3.0);

/// True when the estimate is sharp enough to measure through (PosePolicy::kEstimate): pitch and
/// elevation each known to within half a degree (one sigma).
bool pose_determined(const PoseEstimate& pose);

/// The declared camera (lens, horizontal position) at the estimated height and pitch.
camera::Camera posed_camera(const camera::Camera& declared, const PoseEstimate& pose,
                            const Eigen::Vector3d& axis_foot);

nlohmann::json to_json(const PoseEstimate& pose);

}  // namespace reposetwin::vision
