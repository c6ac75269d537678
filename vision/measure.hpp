// vision/measure: a pile measured in metres and degrees from side and top images.
//
// Design note. The pixel measurements (side_view, top_view) know nothing of scale. This layer
// turns them into lengths in one of three ways, in this order of preference, and always says
// which one it used:
//  1. A known camera (camera::Camera, e.g. from a render's sidecar): perspective corrected. The
//     apex pixel's ray is intersected with the vertical plane through the pile axis that faces
//     the camera, giving H above the plate (z = 0). When the pile stands on the plate's visible
//     top face (side_view.hpp step 2: a camera above the plate), H is instead the height between
//     the apex and the toe line's ray below it on that plane (with the camera's true pose the toe
//     line lands on z = 0; with a camera higher than declared, as in the lab's photos measured as
//     if level, the whole picture shifts and only the difference is right: the apex's z alone
//     read 4 mm for a 14 mm pile photographed from 10 mm up). The toe pixels' rays graze the base
//     circle (they are the silhouette's tangents), so in the horizontal plane the two rays are
//     tangents from the camera to that circle: with the centre at the axis' distance from the
//     camera along their bisector, the radius is that distance times the sine of their half
//     angle. The flank angles are measured
//     on the meridian plane through each toe's tangent point (where a cone's silhouette generator
//     lies). For a top view, the outline is mapped onto the plate plane z = 0. This is exact
//     for a camera level with the plate (the lab's and the renders' side view). A camera h above
//     the plate at distance L, declared level, reads H + h R^2 / (L^2 - R^2) for a base radius R
//     once the toe line is found (it is at the toes, the base circle's tangent points, nearer
//     than the axis): +0.07 mm at h = 10 mm, L = 12 R; D does not change to first order.
//  2. A given mm per pixel at the pile axis: an orthographic view is assumed (reported so).
//  3. The scale marker of the render convention found in the image (band bar in a side view,
//     checker card in a top view): orthographic view assumed, scale from the marker's pitch.
// If none applies, the measurement throws: no number is better than an unscaled one.
// The angle theta = atan(2H/D) does not depend on the scale in the orthographic case, but H and
// D do, so a failed scale is an error rather than a partial result.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>
#include <opencv2/core.hpp>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "camera/camera.hpp"
#include "vision/admission.hpp"
#include "vision/camera_pose.hpp"
#include "vision/crest.hpp"
#include "vision/scale_marker.hpp"
#include "vision/side_view.hpp"
#include "vision/top_crest.hpp"
#include "vision/top_view.hpp"

namespace reposetwin::vision {

/// Where the scale of a measurement came from.
enum class ScaleSource { kCamera, kMmPerPx, kScaleBar, kCheckerCard };

/// "camera", "mm_per_px", "scale_bar" or "checker_card".
std::string to_string(ScaleSource source);

/// What measure_side does with a photo whose own pose contradicts its declared camera
/// (vision/camera_pose.hpp): refuse it (PoseContradiction, with the numbers), or measure it
/// through the pose the photo shows when that pose is determined (the base ellipse), reporting
/// the pose (SideMeasurement::pose, pose_used) and refusing it when it is not.
enum class PosePolicy { kRefuse, kEstimate };

/// How pixels become metres. With nothing set and `search_marker` false, measuring throws.
struct ScaleSpec {
  std::optional<camera::Camera> camera;      // known camera: perspective corrected
  std::optional<double> mm_per_px;           // given scale at the pile axis [mm/px]
  bool search_marker = true;                 // else look for the scale marker in the image
  MarkerSettings marker;                     // the marker's dimensions
  Eigen::Vector3d axis_foot{0.0, 0.0, 0.0};  // the pile axis meets the plate here [m]
  // Check the camera's pose against the photo's base ellipse (vision/camera_pose.hpp) and refuse
  // the photo, with both numbers, when they contradict.
  bool check_pose = true;
  PosePolicy pose_policy = PosePolicy::kRefuse;
  // A top view's crest stands H above the plate, nearer the camera than the plate the scale is
  // given on: with this height (the side views' H) its width is read on the plane z = H.
  std::optional<double> crest_height_m;
  std::string note;                          // recorded with the result (e.g. the sidecar's path)
};

/// Reads a render's sidecar JSON: its "camera" (camera::read_sidecar) and, when present,
/// "mm_per_px_at_axis". Throws std::invalid_argument naming the path and field.
ScaleSpec scale_from_sidecar(const std::string& path,
                             camera::SidecarView view = camera::SidecarView::kAny);

/// Thrown by measure_side when the photo's own pose contradicts its declared camera
/// (ScaleSpec::check_pose): the photo could be read, but the camera it was declared with is
/// wrong, so the caller refuses the photo rather than skip it as unreadable.
class PoseContradiction : public Refusal {
 public:
  explicit PoseContradiction(const std::string& message,
                             double measured = std::numeric_limits<double>::quiet_NaN(),
                             double limit = std::numeric_limits<double>::quiet_NaN())
      : Refusal(Check::kCameraConsistent, message, measured, limit) {}
};

/// What a side measurement's warning is about. A kind biases the measure or only informs
/// (biases_measure); a caller that must not use a biased measure (the loop, a calibration target)
/// refuses the photo on the kind, never by reading the text.
enum class SideWarningKind {
  kPlateTilted,     // the plate line is tilted in the image (a rolled camera); H and D are read
                    // perpendicular to it and hold
  kOnTopFace,       // the pile stands on the plate's visible top face: the toe line is the plate
                    // line (side_view.hpp step 2); the measure holds
  kFlanksDiffer,    // the two flanks differ by more than 3 deg: an asymmetric pile, or a camera
                    // off the pile's axis
  kCameraMismatch,  // the declared camera puts the axis foot off the detected plate line by more
                    // than its uncertainty and no top face shows to check the pose with: H, D
                    // and the angles through that camera may be biased
  kPoseEstimated,   // the photo contradicted its declared camera and was measured through the
                    // pose it shows (PosePolicy::kEstimate): the measure holds within that
                    // pose's uncertainty
};
inline constexpr int kSideWarningKinds = 5;

/// "plate_tilted", "on_top_face", "flanks_differ", "camera_mismatch", "pose_estimated".
std::string to_string(SideWarningKind kind);

/// True for the kinds whose measure may be biased (kCameraMismatch).
bool biases_measure(SideWarningKind kind);

/// One warning: its kind and the numbers in words.
struct SideWarning {
  SideWarningKind kind = SideWarningKind::kPlateTilted;
  std::string text;
};

/// A side view measured in metres and degrees.
struct SideMeasurement {
  std::string source;                  // file name or label of the image
  SideProfile pixels;                  // the pixel measurement
  double height_m = 0.0;               // pile height H [m]
  double diameter_m = 0.0;             // base diameter D at the toe line [m]
  // D's other definition, the flank lines' foot, and what a skirt (the reach beyond the foot)
  // adds to D's uncertainty (sigma_diameter_m includes it: measure.cpp's settle_diameter says
  // why); atan(2H/D) with the flank lines' foot.
  double diameter_flank_m = 0.0;             // [m]
  double sigma_diameter_definition_m = 0.0;  // [m]
  double theta_flank_foot_deg = 0.0;         // [deg]
  double theta_deg = 0.0;              // atan(2H/D) [deg]
  double sigma_height_m = 0.0;         // uncertainty of H (pixels and scale) [m]
  double sigma_diameter_m = 0.0;       // uncertainty of D (pixels and scale) [m]
  double sigma_theta_deg = 0.0;        // uncertainty of theta (pixel quantisation, fits) [deg]
  double flank_left_deg = 0.0;         // left flank angle [deg]
  double flank_right_deg = 0.0;        // right flank angle [deg]
  double sigma_flank_left_deg = 0.0;   // its uncertainty [deg]
  double sigma_flank_right_deg = 0.0;  // its uncertainty [deg]
  Crest crest;                         // the flat top in pixels (vision/crest.hpp's rule)
  double crest_width_m = 0.0;          // its width at the apex height [m]
  double sigma_crest_width_m = 0.0;    // its uncertainty [m]
  // The side camera's pose as the photo shows it (vision/camera_pose.hpp), when the declared
  // camera was checked against it (and agreed, or, with PosePolicy::kEstimate, was replaced by
  // it: pose_used).
  std::optional<PoseEstimate> pose;
  bool pose_used = false;  // measured through the estimated pose, not the declared camera
  // The photo's own camera, when its pixels (`pixels`) were read in its level view
  // (vision/level_view.hpp): a pitched, rolled or distorted camera. Unset: the photo's pixels.
  std::optional<camera::Camera> photo_camera;
  ScaleSource scale_source = ScaleSource::kMmPerPx;
  double mm_per_px = 0.0;                        // scale at the pile axis [mm/px]
  double sigma_scale_rel = 0.0;                  // relative uncertainty of the scale [-]
  bool perspective_corrected = false;            // false: an orthographic view was assumed
  std::optional<ScaleBar> scale_bar;             // the marker, when it gave the scale
  Eigen::Vector3d base_center_m{0.0, 0.0, 0.0};  // base circle centre (camera case) [m]
  double plate_line_z_m = 0.0;        // the detected plate line at the axis (camera case) [m]
  std::string note;                   // ScaleSpec::note
  std::vector<SideWarning> warnings;  // conditions met while measuring, by kind
};

/// The first warning of `m` whose kind biases the measure, if any.
std::optional<SideWarning> first_biasing_warning(const SideMeasurement& m);

/// Measures a side view (`image`: any image vision::gray_levels accepts). `where` names the
/// image in error messages. Throws std::invalid_argument / std::runtime_error as the pixel
/// measurement does, std::runtime_error when the scale cannot be determined, and
/// PoseContradiction (naming the photo, the estimated and the declared pitch) for a photo whose
/// base ellipse contradicts its declared camera.
SideMeasurement measure_side(const cv::Mat& image, const ScaleSpec& scale = {},
                             const SideSettings& settings = {}, const std::string& where = "image");

/// Convenience for renders: a side view through a known camera (perspective corrected).
SideMeasurement measure_side_camera(const cv::Mat& image, const camera::Camera& cam,
                                    const SideSettings& settings = {},
                                    const std::string& where = "image");

/// A top view measured in metres.
struct TopMeasurement {
  std::string source;
  TopProfile pixels;
  double diameter_circle_m = 0.0;        // circle-fit footprint diameter [m]
  double diameter_area_m = 0.0;          // equal-area footprint diameter [m]
  double sigma_diameter_circle_m = 0.0;  // its uncertainty [m]
  double ellipticity = 0.0;              // 1 - minor / major of the fitted ellipse [-]
  double circle_residual_m = 0.0;        // RMS radial residual of the outline [m]
  ScaleSource scale_source = ScaleSource::kMmPerPx;
  double mm_per_px = 0.0;              // scale on the plate [mm/px]
  double sigma_scale_rel = 0.0;        // relative uncertainty of the scale [-]
  bool perspective_corrected = false;  // false: an orthographic view was assumed
  std::optional<CheckerCard> checker_card;
  std::string note;
  TopCrest crest;                  // the flat top in pixels (vision/top_crest.hpp's rule)
  double crest_width_m = 0.0;      // its width, when crest.found [m]
  double sigma_crest_width_m = 0.0;
  std::string crest_plane;         // the plane its pixels were scaled on, in words
};

/// Measures a top view; scale as for measure_side (the marker is the checker card). When the
/// camera is known and `settings.seed` is unset, the seed is the projected axis foot.
TopMeasurement measure_top(const cv::Mat& image, const ScaleSpec& scale = {},
                           const TopSettings& settings = {}, const std::string& where = "image");

/// Convenience for renders: a top view through a known camera (perspective corrected).
TopMeasurement measure_top_camera(const cv::Mat& image, const camera::Camera& cam,
                                  const TopSettings& settings = {},
                                  const std::string& where = "image");

/// Mean and spread of one quantity over several views.
struct Spread {
  double mean = 0.0;
  double stddev = 0.0;      // sample standard deviation over the views (0 for one view)
  double sigma_mean = 0.0;  // uncertainty of the mean: spread / sqrt(n) and the views' own
};

/// Several side views of one pile (different azimuths) combined.
struct SideSummary {
  int views = 0;
  Spread height_m, diameter_m, theta_deg, flank_left_deg, flank_right_deg, flank_deg;
  Spread crest_width_m;  // the flat top's width [m]
};

/// Averages side measurements. Throws std::invalid_argument for an empty list.
SideSummary combine_sides(const std::vector<SideMeasurement>& views);

nlohmann::json to_json(const SideMeasurement& m);
nlohmann::json to_json(const TopMeasurement& m);
nlohmann::json to_json(const SideSummary& s);

/// The image annotated like a lab photo: plate line, apex, toe points, fitted flank lines, the
/// scale bar if used, and the numbers.
cv::Mat draw_side_overlay(const cv::Mat& image, const SideMeasurement& m);
/// The image annotated with the footprint outline, fitted circle and ellipse and the numbers.
cv::Mat draw_top_overlay(const cv::Mat& image, const TopMeasurement& m);

}  // namespace reposetwin::vision
