#include "vision/measure.hpp"

// Design note (the declared camera). A photo with a camera is read in its level view
// (level_view.hpp: pitch, roll and distortion undone by one re-projection), where the camera puts
// the pile's base: the toe line through the base circle's tangent points, iterated with the
// radius the photo shows (the tangent points' row depends on it: 4 px at 10 deg on the quick
// scene's pile). The pixels (side_view.hpp) find the pile standing on that line, against the
// backdrop above the plate's far edge and against the plate's top face below it. The photo is
// then checked against the camera by every line it shows (check_camera): a plate edge seen
// against the backdrop lies between the horizon and the toe line (exactly on the far edge's row
// when the plate's size is declared), and on the top face the pile's front lies where the camera
// puts the base's front, within a fifth of its radius. A photo that contradicts its camera is
// refused as a camera mismatch with the pitch the photo implies at the declared height; with
// PosePolicy::kEstimate it is read again through the camera re-pitched so, and measured when that
// reading agrees with its own camera (said in a kPoseEstimated warning), else refused saying
// the pose is not determined: one line cannot tell a camera raised from one pitched. A refusal
// of the pile (none found, cut) is first checked against the plate's edge: a photo declared with
// the wrong camera is searched in the wrong place, and the refusal is the camera's.

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "vision/level_view.hpp"
#include "vision/text_detail.hpp"

namespace reposetwin::vision {
namespace {

using detail::kRadToDeg;

using detail::str;

using detail::fixed;

Eigen::Vector2d ev(const cv::Point2d& p) { return {p.x, p.y}; }

void check_camera_size(const camera::Camera& cam, const cv::Mat& image, const std::string& where) {
  camera::validate(cam, where + ": camera");
  if (cam.intrinsics.width_px != image.cols || cam.intrinsics.height_px != image.rows)
    throw std::invalid_argument(where + ": camera intrinsics " + str(cam.intrinsics.width_px) +
                                "x" + str(cam.intrinsics.height_px) + " do not match the image " +
                                str(image.cols) + "x" + str(image.rows));
}

double theta_sigma_deg(double h, double d, double sh, double sd) {
  const double den = d * d + 4.0 * h * h;
  return std::hypot(2.0 * d / den * sh, 2.0 * h / den * sd) * kRadToDeg;
}

// Angle of a flank line in the camera case. A cone's generators lie in meridian planes, and the
// silhouette generator of each flank ends at the toe's tangent point, so the flank line's pixels
// are mapped onto the meridian plane through that tangent point (the vertical plane through the
// base centre and the point of the toe ray nearest to it) and the angle is measured there.
double flank_angle_on_meridian(const camera::Camera& cam, const FlankFit& f, const PlateLine& plate,
                               const camera::Ray& toe_ray, const Eigen::Vector3d& base_center,
                               const std::string& where, double* foot_radius = nullptr) {
  const double h0 = plate.height_above(f.point);
  const double dh = plate.height_above(f.point + f.direction) - h0;
  if (!(std::abs(dh) > 1e-9)) throw std::runtime_error(where + ": flank line parallel to plate");
  const cv::Point2d lo = f.point + f.direction * ((f.low_px - h0) / dh);
  const cv::Point2d hi = f.point + f.direction * ((f.high_px - h0) / dh);
  const Eigen::Vector2d d = toe_ray.direction.head<2>();
  const double t = (base_center.head<2>() - toe_ray.origin.head<2>()).dot(d) / d.squaredNorm();
  const Eigen::Vector2d radial = toe_ray.origin.head<2>() + t * d - base_center.head<2>();
  if (radial.norm() < 1e-9) throw std::runtime_error(where + ": toe ray passes through the axis");
  const Eigen::Vector3d normal(-radial.y(), radial.x(), 0.0);
  const auto wl = camera::pixel_on_plane(cam, ev(lo), base_center, normal.normalized());
  const auto wh = camera::pixel_on_plane(cam, ev(hi), base_center, normal.normalized());
  if (!wl || !wh) throw std::runtime_error(where + ": flank rays miss the meridian plane");
  const Eigen::Vector3d e = *wh - *wl;
  // The flank line's foot on the plate (z of the base centre), on the same meridian plane.
  if (foot_radius && std::abs(e.z()) > 1e-12) {
    const Eigen::Vector3d foot = *wl + e * ((base_center.z() - wl->z()) / e.z());
    *foot_radius = (foot - base_center).head<2>().norm();
  }
  return std::atan2(std::abs(e.z()), e.head<2>().norm()) * kRadToDeg;
}

void measure_through_camera(SideMeasurement& m, const camera::Camera& cam,
                            const Eigen::Vector3d& axis_foot, const std::string& where);

}  // namespace

std::string to_string(ScaleSource source) {
  switch (source) {
    case ScaleSource::kCamera:
      return "camera";
    case ScaleSource::kMmPerPx:
      return "mm_per_px";
    case ScaleSource::kScaleBar:
      return "scale_bar";
    case ScaleSource::kCheckerCard:
      return "checker_card";
  }
  return "unknown";
}

ScaleSpec scale_from_sidecar(const std::string& path, camera::SidecarView view) {
  ScaleSpec s;
  s.camera = camera::read_sidecar(path, view);
  std::ifstream in(path);
  const nlohmann::json j = nlohmann::json::parse(in);  // read_sidecar has checked it parses
  if (j.contains("mm_per_px_at_axis") && !j["mm_per_px_at_axis"].is_null()) {
    const auto& v = j["mm_per_px_at_axis"];
    if (!v.is_number() || !(v.get<double>() > 0.0))
      throw std::invalid_argument(path + ": mm_per_px_at_axis must be a positive number, got " +
                                  v.dump());
    s.mm_per_px = v.get<double>();
  }
  if (j.contains("scale_reference") && j["scale_reference"].is_object()) {
    const auto& r = j["scale_reference"];
    if (r.contains("band_mm")) {
      if (!r["band_mm"].is_number() || !(r["band_mm"].get<double>() > 0.0))
        throw std::invalid_argument(path +
                                    ": scale_reference.band_mm must be a positive number, got " +
                                    r["band_mm"].dump());
      s.marker.band_mm = r["band_mm"].get<double>();
      s.marker.square_mm = r["band_mm"].get<double>();
    }
  }
  s.note = "sidecar " + path;
  return s;
}

namespace {

/// Rejects an empty image and a non-positive or non-finite given scale.
void check_input(const cv::Mat& image, const ScaleSpec& scale, const std::string& where) {
  if (image.empty()) throw std::invalid_argument(where + ": image is empty (0 x 0 pixels)");
  if (scale.mm_per_px && !(*scale.mm_per_px > 0.0 && std::isfinite(*scale.mm_per_px)))
    throw std::invalid_argument(where + ": mm_per_px must be a positive number, got " +
                                str(*scale.mm_per_px));
}

}  // namespace

std::string to_string(SideWarningKind kind) {
  switch (kind) {
    case SideWarningKind::kPlateTilted:
      return "plate_tilted";
    case SideWarningKind::kOnTopFace:
      return "on_top_face";
    case SideWarningKind::kFlanksDiffer:
      return "flanks_differ";
    case SideWarningKind::kCameraMismatch:
      return "camera_mismatch";
    case SideWarningKind::kPoseEstimated:
      return "pose_estimated";
  }
  return "unknown";
}

bool biases_measure(SideWarningKind kind) { return kind == SideWarningKind::kCameraMismatch; }

std::optional<SideWarning> first_biasing_warning(const SideMeasurement& m) {
  for (const SideWarning& w : m.warnings)
    if (biases_measure(w.kind)) return w;
  return std::nullopt;
}

namespace {

// The conditions met while measuring that a reader should know of (SideWarningKind).
void add_side_warnings(SideMeasurement& m) {
  const SideProfile& p = m.pixels;
  if (std::abs(p.plate.tilt_deg()) > 1.0)
    m.warnings.push_back({SideWarningKind::kPlateTilted,
                          "plate line tilted by " + fixed(p.plate.tilt_deg(), 2) +
                              " deg: level the camera"});
  if (p.far_edge) {
    const double u = p.apex.x;
    m.warnings.push_back(
        {SideWarningKind::kOnTopFace,
         "the pile stands on the plate's visible top face (camera above the plate): the plate "
         "line is its toe line, " +
             fixed(p.plate.v_at(u) - p.far_edge->v_at(u), 1) + " px below the plate's far edge"});
  }
  if (std::abs(p.left.angle_deg - p.right.angle_deg) > 3.0)
    m.warnings.push_back({SideWarningKind::kFlanksDiffer,
                          "flank angles differ by " +
                              fixed(std::abs(p.left.angle_deg - p.right.angle_deg), 1) +
                              " deg: asymmetric pile or camera off the pile axis"});
}

// D by its two definitions (measure.hpp's design note): the headline is the silhouette's reach
// at the toe line; the flank lines' foot is reported beside it. Where the reach lies beyond the
// foot, a skirt of grains runs out past the flanks, a layer thin enough for blur, light or
// resolution to hide or show, and the toe then jumps between the two; half their difference
// joins D's uncertainty, so that its 95% interval reaches the foot. Where the foot lies beyond
// the reach (a rounded foot: the flank lines overshoot the outermost grain) the reach is the
// silhouette's end and nothing can move it out to the foot: no term.
void settle_diameter(SideMeasurement& m) {
  if (!(m.diameter_flank_m > 0.0) || !std::isfinite(m.diameter_flank_m)) return;
  m.sigma_diameter_definition_m = 0.5 * std::max(0.0, m.diameter_m - m.diameter_flank_m);
  m.sigma_diameter_m = std::hypot(m.sigma_diameter_m, m.sigma_diameter_definition_m);
  m.theta_flank_foot_deg = std::atan(2.0 * m.height_m / m.diameter_flank_m) * kRadToDeg;
  m.sigma_theta_deg =
      theta_sigma_deg(m.height_m, m.diameter_m, m.sigma_height_m, m.sigma_diameter_m);
}

// A side view sees the apex on the silhouette only while the camera looks at the pile from
// below its flanks' slope: from higher up the flanks face the camera, the silhouette's top is the
// base's far edge or the top's far side, and H is not on it. The flanks and atan(2H/D) read
// through a raised camera grow steeper as it nears that limit (the quick scene's 22 deg pile
// from 19 deg above its top: flanks 31 deg, atan(2H/D) 25 deg), so the camera must stand
// kViewMarginDeg below atan(2H/D) as read.
constexpr double kViewMarginDeg = 10.0;

void refuse_steep_view(const SideMeasurement& m, const camera::Camera& level,
                       const Eigen::Vector3d& axis_foot, const std::string& where) {
  if (level.projection != camera::Projection::kPerspective) return;
  const double l = (level.extrinsics.position.head<2>() - axis_foot.head<2>()).norm();
  const double h = level.extrinsics.position.z() - axis_foot.z() - m.height_m;
  const double elevation = std::atan2(h, l) * kRadToDeg;
  const double flank = m.theta_deg;
  // Seen from above the flanks, the silhouette's top is the base's far rim: the apex must stand
  // above the row where the camera puts that rim (by a twentieth of the base ellipse's
  // height), else what reads as the apex is the rim (the quick scene's 22 deg pile from 30 deg:
  // "H" 33 mm for 15, atan(2H/D) 40 deg).
  const double r = 0.5 * m.diameter_m;
  const Eigen::Vector2d away =
      (axis_foot.head<2>() - level.extrinsics.position.head<2>()).normalized();
  const auto far = camera::project(level, axis_foot + r * Eigen::Vector3d(away.x(), away.y(), 0.0));
  const auto near = camera::project(level, axis_foot - r * Eigen::Vector3d(away.x(), away.y(), 0.0));
  if (far && near && m.pixels.apex.y > far->y() - 0.05 * (near->y() - far->y()))
    throw Refusal(Check::kViewAngle,
                  where + ": the camera looks down on the pile from " + fixed(elevation, 1) +
                      " deg above its top: the silhouette's highest point (row " +
                      fixed(m.pixels.apex.y, 0) + " of the level view) is no higher than the "
                      "base's far rim (row " + fixed(far->y(), 0) + "), so it is not the apex; "
                      "photograph it from lower down",
                  elevation, flank - kViewMarginDeg);
  if (elevation > 0.0 && elevation > flank - kViewMarginDeg)
    throw Refusal(Check::kViewAngle,
                  where + ": the camera looks down on the pile from " + fixed(elevation, 1) +
                      " deg above its top, steeper than atan(2H/D) as read (" + fixed(flank, 1) +
                      " deg) less " + fixed(kViewMarginDeg, 0) +
                      " deg: the apex is not on the silhouette; photograph it from lower down",
                  elevation, flank - kViewMarginDeg);
}

// A pile at the scale: at least a grain or two tall and several wide (admission.hpp).
void refuse_small(const SideMeasurement& m, const AdmissionSettings& a, const std::string& where) {
  if (!(1000.0 * m.height_m >= a.min_height_mm) || !(1000.0 * m.diameter_m >= a.min_diameter_mm))
    throw Refusal(Check::kPilePresent,
                  where + ": no pile found: the object on the plate is " +
                      fixed(1000.0 * m.height_m, 1) + " mm tall and " +
                      fixed(1000.0 * m.diameter_m, 1) + " mm wide, less than a pile's " +
                      fixed(a.min_height_mm, 1) + " mm and " + fixed(a.min_diameter_mm, 1) + " mm",
                  1000.0 * m.height_m, a.min_height_mm);
}

// The most a camera declared level with the plate may stand above it, seen from the pile: a
// camera 30 mm above the plate at 12 pile radii (3 deg) read a 42 mm cone of spheres 1.1 deg
// steep through the toe line; the lab's 5-10 mm (0.6-2 deg) read within 0.3 deg.
constexpr double kMaxElevationDeg = 2.5;

// Where a photo's lines fall against where its declared camera puts them (the level view's rows).
struct CameraCheck {
  bool consistent = true;
  bool determined = true;   // the photo shows a line to read its pitch from
  double observed_v = 0.0;  // the line's row in the level view [px]
  double predicted_v = 0.0;  // where the camera puts it [px]
  double tolerance = 0.0;    // [px]
  double dpitch_deg = 0.0;   // the pitch the photo implies less the declared one [deg]
  std::string what;          // the line, in words
};

// Angle below the horizontal of a level view's row [rad].
double row_angle(const camera::Camera& level, double v) {
  return std::atan((v - camera::principal_v(level)) / camera::focal_px(level));
}

// The row of the base's front point (nearest the camera) for a base of `radius` [px].
double front_row(const camera::Camera& level, const Eigen::Vector3d& axis_foot, double radius) {
  const Eigen::Vector2d toward =
      (level.extrinsics.position.head<2>() - axis_foot.head<2>()).normalized();
  const auto px = camera::project(level, axis_foot + radius * Eigen::Vector3d(toward.x(),
                                                                              toward.y(), 0.0));
  return px ? px->y() : camera::principal_v(level);
}

// The photo against its camera: every line the photo shows where the camera puts it.
CameraCheck check_camera(const SideProfile& p, const camera::Camera& level,
                         const Eigen::Vector3d& axis_foot, double radius, double axis_u,
                         double tol_px, std::vector<CameraCheck> checks) {
  const double toe_v = toe_line_for(level, axis_foot, radius).v_at(axis_u);
  const double horizon = camera::principal_v(level);
  // The pile's front, where the camera sees the plate's top face deep enough to read it, is the
  // check: it is the pile's own base. An edge above it may be the plate's far edge or a bench or
  // shelf behind the plate, and is only read where the front is not.
  const double front_v = front_row(level, axis_foot, radius);
  const bool front_readable = p.far_edge && p.front_v_px && front_v - toe_v > 2.0 * tol_px;
  // A plate edge seen against the backdrop (the plate line edge-on, or the far edge above the
  // top face) lies between the horizon, where a plate without end would meet the sky, and the
  // toe line.
  const PlateLine* edge = p.plate_from_camera ? nullptr
                         : !p.far_edge         ? &p.plate
                         : p.far_edge->support > 0 ? &*p.far_edge
                                                   : nullptr;
  if (edge && !front_readable) {
    CameraCheck c;
    c.what = p.far_edge ? "the plate's far edge" : "the plate line";
    c.observed_v = edge->v_at(axis_u);
    c.tolerance = std::max(tol_px, 3.0 * std::hypot(edge->sigma_px, 0.5));
    // A camera declared level may stand up to kMaxElevationDeg higher (the lab's 5-10 mm) or be
    // pitched that much (the loop's camera probe, 2 deg): its plate edge then lies that much off
    // the horizon, and H is read from the toe line found in the photo, not the camera's.
    const double raised = toe_v - horizon <= 1.0 && !p.toe_line_predicted
                              ? camera::focal_px(level) * std::tan(kMaxElevationDeg / kRadToDeg)
                              : 0.0;
    c.predicted_v =
        std::clamp(c.observed_v, std::min(horizon, toe_v) - raised, toe_v + raised);
    checks.push_back(c);
  }
  // The front is a grain at the axis column, not the reach D/2 measures (the outermost grain
  // anywhere), and its foot is in shadow: allowed a quarter of the radius of depth (the quick
  // scene's pile and the twin's cones of spheres, seen truthfully from 0-10 deg: 4-9 px above
  // the reach's front), a quarter of the front's depth below the toe line, or twice the
  // tolerance: a gross mismatch (a pitch off by a degree: 30-100 px) is what it catches. Where the
  // front lies within twice the tolerance of the toe line (a camera nearly level) it tells
  // nothing and is not read.
  if (front_readable) {
    CameraCheck c;
    c.what = "the pile's front on the plate";
    c.observed_v = *p.front_v_px;
    c.predicted_v = front_v;
    const double per_radius = front_row(level, axis_foot, 1.25 * radius) - front_v;
    c.tolerance = std::max({2.0 * tol_px, 0.25 * (front_v - toe_v), std::abs(per_radius)});
    checks.push_back(c);
  }
  if (checks.empty()) {
    CameraCheck c;
    c.determined = false;
    return c;
  }
  for (CameraCheck& c : checks) {
    c.consistent = std::abs(c.observed_v - c.predicted_v) <= c.tolerance;
    c.dpitch_deg = (row_angle(level, c.observed_v) - row_angle(level, c.predicted_v)) * kRadToDeg;
    if (!c.consistent) return c;
  }
  return checks.back();
}

// The declared camera turned about its own horizontal axis by `dpitch_deg` (down positive).
camera::Camera repitched(const camera::Camera& cam, double dpitch_deg) {
  const Eigen::Matrix3d r = camera::rotation_world_to_camera(cam);
  const Eigen::Vector3d forward = r.row(2).transpose();
  const Eigen::Vector3d down = r.row(1).transpose();
  const double a = dpitch_deg / kRadToDeg;
  camera::Camera out = cam;
  const Eigen::Vector3d f = std::cos(a) * forward + std::sin(a) * down;
  const Eigen::Vector3d up = -(std::cos(a) * down - std::sin(a) * forward);
  out.extrinsics.look_at = cam.extrinsics.position + f;
  out.extrinsics.up = up;
  return out;
}

std::string mismatch_text(const CameraCheck& c) {
  return c.what + " lies at row " + fixed(c.observed_v, 1) + " of the photo seen level, " +
         fixed(c.observed_v - c.predicted_v, 1) + " px from row " + fixed(c.predicted_v, 1) +
         " where the declared camera puts it (tolerance " + fixed(c.tolerance, 1) +
         " px): the photo implies a camera pitched " + fixed(c.dpitch_deg, 1) +
         " deg more than declared (at the declared height)";
}

// The plate's edge the photo shows (the lowest long edge with backdrop above it, anywhere) against
// where the camera can put it: between the horizon and the toe line of the widest base the view
// holds (0.3 of the distance); std::nullopt when the photo shows no such edge.
// refuse_plate_off_camera throws PoseContradiction when it lies outside.
std::optional<CameraCheck> plate_edge_check(const SideImage& prepared, const SideSettings& set,
                                            const camera::Camera& level,
                                            const Eigen::Vector3d& axis_foot,
                                            const std::string& where) {
  const double axis_u = *set.axis_u_px - prepared.roi.x;
  const double horizon = camera::principal_v(level);
  const double lowest =
      toe_line_for(level, axis_foot, 0.3 * camera_distance_m(level, axis_foot)).v_at(*set.axis_u_px);
  const double raised = lowest - horizon <= 1.0
                            ? camera::focal_px(level) * std::tan(kMaxElevationDeg / kRadToDeg)
                            : 0.0;
  auto check_of = [&](const PlateLine& edge) {
    CameraCheck c;
    c.what = "the plate's edge";
    c.observed_v = edge.v_at(axis_u) + prepared.roi.y;
    c.predicted_v =
        std::clamp(c.observed_v, std::min(horizon, lowest) - raised, lowest + raised);
    c.tolerance =
        std::max(set.admission.camera_tolerance_px, 3.0 * std::hypot(edge.sigma_px, 0.5));
    c.consistent = std::abs(c.observed_v - c.predicted_v) <= c.tolerance;
    c.dpitch_deg = (row_angle(level, c.observed_v) - row_angle(level, c.predicted_v)) * kRadToDeg;
    return c;
  };
  // An edge where the camera can put the plate's is the plate's: a bench or table below the
  // plate shows a lower long edge with a backdrop-like top above it (the LIGGGHTS pours' bench,
  // 214 px below the plate's far edge from 100 mm above), and the lowest edge anywhere is then
  // the bench's. Only where no edge lies where the camera allows is the photo's lowest edge
  // the evidence against the camera.
  try {
    const int max_row = static_cast<int>(std::floor(
        lowest + raised + set.admission.camera_tolerance_px - prepared.roi.y));
    if (max_row >= 8) {
      const CameraCheck c =
          check_of(find_plate_line_above(prepared.flat, max_row, set, where));
      if (c.consistent) return c;
    }
  } catch (const std::runtime_error&) {
  }
  try {
    return check_of(find_plate_line(prepared.flat, set, where));
  } catch (const std::runtime_error&) {
    return std::nullopt;
  }
}

void refuse_plate_off_camera(const SideImage& prepared, const SideSettings& set,
                             const camera::Camera& level, const Eigen::Vector3d& axis_foot,
                             const std::string& where) {
  const std::optional<CameraCheck> c = plate_edge_check(prepared, set, level, axis_foot, where);
  if (c && !c->consistent)
    throw PoseContradiction(where + ": not measured through the declared camera: " +
                                mismatch_text(*c),
                            c->observed_v - c->predicted_v, c->tolerance);
}

// One reading of a photo through one camera: the level view, the toe line the camera predicts
// for the base the photo shows (iterated: the tangent points' row depends on the radius), the
// pixels, the metres, and the photo checked against the camera.
struct PosedReading {
  SideMeasurement m;
  CameraCheck check;
  camera::Camera level_camera;  // the level view's camera the pixels were read through
  bool edge_on_retry = false;   // refused for a top face that may be the plate's front face
};

// The reading of a prepared level view (read_through's loop and checks).
PosedReading read_level_view(const LevelView& view, const camera::Camera& cam,
                             const ScaleSpec& scale, SideSettings set, const SideImage& prepared,
                             const std::string& where) {
  PosedReading out;
  double radius = 0.0;
  for (int pass = 0; pass < 4; ++pass) {
    set.toe_line = toe_line_for(view.camera, scale.axis_foot, radius);
    const double toe_v = set.toe_line->v_at(*set.axis_u_px);
    set.level_toe_line = toe_v - camera::principal_v(view.camera) <= 1.0;
    if (set.level_toe_line)
      set.plate_line_lowest_v =
          toe_v + camera::focal_px(view.camera) * std::tan(kMaxElevationDeg / kRadToDeg) +
          set.admission.camera_tolerance_px;
    // The front is sought twice as deep as the camera puts it, and at least 20 px: a pile that
    // continues below that stands elsewhere than declared.
    const double front_v = front_row(view.camera, scale.axis_foot, std::max(radius, 1e-3));
    set.front_search_px = std::max(20.0, 2.0 * (front_v - toe_v) + 0.02 * view.image.rows);
    SideMeasurement m;
    m.source = where;
    m.note = scale.note;
    if (!view.identity) m.photo_camera = cam;
    try {
      m.pixels = measure_side_pixels(prepared, set, where);
    } catch (const Refusal& e) {
      // A photo declared with the wrong camera is searched for its pile in the wrong place:
      // the refusal is the camera's when the plate line says so.
      if (e.check() != Check::kCameraConsistent) refuse_plate_off_camera(prepared, set, view.camera, scale.axis_foot, where);
      throw;
    }
    add_side_warnings(m);
    m.crest = measure_crest(m.pixels, {}, where);
    measure_through_camera(m, view.camera, scale.axis_foot, where);
    out.m = std::move(m);
    const double next = 0.5 * out.m.diameter_m;
    const double moved =
        std::abs(toe_line_for(view.camera, scale.axis_foot, next).v_at(*set.axis_u_px) - toe_v);
    radius = next;
    if (moved < 0.25) break;
  }
  out.level_camera = view.camera;
  // Where the plate line is the camera's own, the plate edge the photo shows anywhere is read.
  std::vector<CameraCheck> edge;
  if (out.m.pixels.plate_from_camera)
    if (const auto c = plate_edge_check(prepared, set, view.camera, scale.axis_foot, where))
      edge.push_back(*c);
  out.check = check_camera(out.m.pixels, view.camera, scale.axis_foot, radius, *set.axis_u_px,
                           set.admission.camera_tolerance_px, edge);
  // A camera declared level whose photo shows the plate's top face (the toe line found below
  // the far edge): the base ellipse gives its pitch and elevation (camera_pose.hpp), and a pose
  // off the declared one by more than kMaxElevationDeg, or a pitch that contradicts it, is a
  // mismatch (a raised camera pitched down can put the far edge where a level one would).
  if (out.check.consistent && !out.m.pixels.toe_line_predicted) {
    if (const auto pose = estimate_side_pose(prepared, out.m.pixels, view.camera, scale.axis_foot)) {
      const double de = pose->elevation_deg - pose->declared_elevation_deg;
      const double dp = pose->pitch_deg - pose->declared_pitch_deg;
      const std::string why = pose_contradiction(*pose);
      if (!why.empty() ||
          std::abs(de) > std::max(kMaxElevationDeg, 3.0 * pose->sigma_elevation_deg)) {
        CameraCheck c;
        c.what = "the pile's base ellipse (the camera " + fixed(1000.0 * pose->height_m, 1) +
                 " mm above the plate, elevation " + fixed(pose->elevation_deg, 1) +
                 " deg, pitched " + fixed(pose->pitch_deg, 1) + " deg" +
                 (why.empty() ? std::string() : "; " + why) + ")";
        c.consistent = false;
        c.observed_v = pose->centre_v_px;
        c.predicted_v = toe_line_for(view.camera, scale.axis_foot, radius).v_at(*set.axis_u_px);
        c.tolerance = set.admission.camera_tolerance_px;
        c.dpitch_deg = dp;
        out.check = c;
        out.m.pose = *pose;
        out.edge_on_retry = out.m.pixels.far_edge.has_value() && !pitch_contradicts(*pose) &&
                            std::abs(de) <= std::max(kMaxElevationDeg,
                                                     3.0 * pose->sigma_elevation_deg);
      }
    }
  }
  return out;
}

PosedReading read_through(const cv::Mat& image, const camera::Camera& cam, const ScaleSpec& scale,
                          const SideSettings& settings, const std::string& where) {
  const LevelView view = level_view(image, cam, where);
  SideSettings set = settings;
  if (!view.identity) {
    set.valid = view.valid;
    if (!settings.roi.empty()) {  // the region of interest's corners seen level
      std::vector<cv::Point2f> corners;
      const cv::Rect& r = settings.roi;
      const double lcx = camera::principal_u(view.camera), lcy = camera::principal_v(view.camera);
      const Eigen::Matrix3d to_level = camera::rotation_world_to_camera(view.camera);
      for (const cv::Point2d q : {cv::Point2d(r.x, r.y), cv::Point2d(r.x + r.width, r.y),
                                  cv::Point2d(r.x, r.y + r.height),
                                  cv::Point2d(r.x + r.width, r.y + r.height)}) {
        const Eigen::Vector3d d = to_level * camera::unproject(cam, {q.x, q.y}).direction;
        const double f = camera::focal_px(view.camera);
        corners.emplace_back(static_cast<float>(lcx + f * d.x() / d.z()),
                             static_cast<float>(lcy + f * d.y() / d.z()));
      }
      set.roi = cv::boundingRect(corners) & cv::Rect(0, 0, view.image.cols, view.image.rows);
    }
  }
  const auto foot = camera::project(view.camera, scale.axis_foot);
  if (!foot || foot->x() < 0.0 || foot->x() > view.image.cols - 1.0)
    throw Refusal(Check::kCameraConsistent,
                  where + ": the declared camera does not see the pile's axis foot; it cannot be "
                          "the camera of this photo");
  set.axis_u_px = foot->x();
  set.camera_elevation_deg =
      std::atan2(camera_height_m(view.camera, scale.axis_foot),
                 camera_distance_m(view.camera, scale.axis_foot)) * kRadToDeg;
  const SideImage prepared = prepare_side(view.image, set, where);
  // A camera declared level whose reading found a top face the base ellipse refuses only for the
  // toe line cutting through the base (the pitch and elevation agreeing), or through which the
  // pile reached the image's sides, or grew a "neck" into it: a thick plate's front face, seen
  // from plate level, reads so (the twin's pile through a camera rolled 5 deg, or a light pile,
  // grew into the face under it and was refused as a foreign object). The plate is then read
  // edge-on, and that reading stands when it agrees with the camera; the edge-on reading runs
  // every check again, so a funnel is refused by it as well.
  const bool declared_level =
      toe_line_for(view.camera, scale.axis_foot, 0.0).v_at(*set.axis_u_px) -
          camera::principal_v(view.camera) <= 1.0;
  PosedReading out;
  std::optional<Refusal> cut;
  try {
    out = read_level_view(view, cam, scale, set, prepared, where);
  } catch (const Refusal& e) {
    if (!(declared_level && (e.check() == Check::kNotCut || e.check() == Check::kNoForeignObject)))
      throw;
    cut = e;
    out.edge_on_retry = true;
    out.check.consistent = false;
  }
  if (!out.check.consistent && out.edge_on_retry) {
    set.plate_edge_on = true;
    try {
      PosedReading edge_on = read_level_view(view, cam, scale, set, prepared, where);
      // Edge-on means on the camera's horizon, within the tolerance (not the 2.5 deg a camera
      // declared level may be off by when a top face shows it).
      const SideProfile& px = edge_on.m.pixels;
      const double u = *set.axis_u_px;
      const double off = px.plate.v_at(u) - camera::principal_v(view.camera);
      const double tol = std::max(set.admission.camera_tolerance_px,
                                  3.0 * std::hypot(px.plate.sigma_px, 0.5));
      if (edge_on.check.consistent && !px.far_edge && std::abs(off) <= tol) {
        out = std::move(edge_on);
        cut.reset();
      }
    } catch (const Refusal&) {
    }
  }
  if (cut) throw *cut;
  return out;
}

// The photo's pose as its lines imply it, for the record: the declared camera re-pitched.
PoseEstimate implied_pose(const camera::Camera& declared, const camera::Camera& used,
                          const Eigen::Vector3d& axis_foot, const CameraCheck& c) {
  auto pitch = [](const camera::Camera& cam) {
    const Eigen::Vector3d f = camera::rotation_world_to_camera(cam).row(2).transpose();
    return std::asin(std::clamp(-f.z(), -1.0, 1.0)) * kRadToDeg;
  };
  PoseEstimate e;
  e.pitch_deg = pitch(used);
  e.declared_pitch_deg = pitch(declared);
  e.distance_m = (declared.extrinsics.position.head<2>() - axis_foot.head<2>()).norm();
  e.height_m = declared.extrinsics.position.z() - axis_foot.z();
  e.elevation_deg = e.declared_elevation_deg = std::atan2(e.height_m, e.distance_m) * kRadToDeg;
  e.sigma_pitch_deg =
      std::abs(row_angle(used, c.observed_v + c.tolerance) - row_angle(used, c.observed_v)) *
      kRadToDeg;
  e.centre_v_px = c.observed_v;
  return e;
}


// A side photo through its declared camera (design note at the top): measured through it when
// the photo agrees with it; else refused as a camera mismatch with the pitch the photo implies,
// or, with PosePolicy::kEstimate, measured through the camera re-pitched to that pose when that
// reading agrees with its own camera, and refused saying why when it does not.
SideMeasurement measure_side_posed(const cv::Mat& image, const ScaleSpec& scale,
                                   const SideSettings& settings, const std::string& where) {
  const camera::Camera& declared = *scale.camera;
  PosedReading r = read_through(image, declared, scale, settings, where);
  if (scale.check_pose && (!r.check.consistent)) {
    if (scale.pose_policy == PosePolicy::kRefuse)
      throw PoseContradiction(where + ": not measured through the declared camera: " +
                                  mismatch_text(r.check),
                              r.check.observed_v - r.check.predicted_v, r.check.tolerance);
    const camera::Camera posed = repitched(declared, r.check.dpitch_deg);
    PosedReading again;
    std::string why_not;
    try {
      again = read_through(image, posed, scale, settings, where);
      if (!again.check.consistent) why_not = mismatch_text(again.check) + " even then";
    } catch (const std::exception& e) {
      why_not = e.what();
    }
    if (!why_not.empty())
      throw PoseContradiction(
          where + ": not measured through the declared camera (" + mismatch_text(r.check) +
              "), and the pose it implies is not determined: re-pitched by " +
              fixed(r.check.dpitch_deg, 1) + " deg the photo still reads inconsistent (" +
              why_not + "); a camera raised and pitched at once is not told apart by one line",
          r.check.observed_v - r.check.predicted_v, r.check.tolerance);
    again.m.pose = implied_pose(declared, posed, scale.axis_foot, r.check);
    again.m.pose_used = true;
    again.m.warnings.push_back({SideWarningKind::kPoseEstimated,
                                "measured through the pose the photo shows, not the declared "
                                "camera: " + mismatch_text(r.check)});
    r = std::move(again);
  }
  SideMeasurement& m = r.m;
  refuse_small(m, settings.admission, where);
  refuse_steep_view(m, r.level_camera, scale.axis_foot, where);
  settle_diameter(m);
  return m;
}

}  // namespace

namespace {

// No pile found in a photo mostly at the sensor's brightest level is an exposure fault, not an
// empty plate: the nuisance set's overexposed photos are 57-99% clipped and were refused as
// "no pile", every other photo of the set under 0.002%.
[[noreturn]] void refuse_no_pile_or_exposure(const Refusal& no_pile, const cv::Mat& image,
                                             const SideSettings& settings,
                                             const std::string& where) {
  cv::Mat clipped;
  try {
    clipped = prepare_side(image, settings, where).clipped;
  } catch (const std::exception&) {
  }
  const double fraction =
      clipped.empty() ? 0.0 : static_cast<double>(cv::countNonZero(clipped)) / clipped.total();
  const double limit = settings.admission.max_clipped_photo_fraction;
  if (fraction > limit)
    throw Refusal(Check::kExposure,
                  where + ": no pile found, and " + fixed(100.0 * fraction, 0) +
                      "% of the photo is at the sensor's brightest level (over-exposed): the "
                      "pile may be lost in the white; expose for the pile",
                  fraction, limit);
  throw no_pile;
}

SideMeasurement measure_side_admitted(const cv::Mat& image, const ScaleSpec& scale,
                                      const SideSettings& settings, const std::string& where);

}  // namespace

SideMeasurement measure_side(const cv::Mat& image, const ScaleSpec& scale,
                             const SideSettings& settings, const std::string& where) {
  try {
    return measure_side_admitted(image, scale, settings, where);
  } catch (const Refusal& e) {
    if (e.check() == Check::kPilePresent) refuse_no_pile_or_exposure(e, image, settings, where);
    throw;
  }
}

namespace {

SideMeasurement measure_side_admitted(const cv::Mat& image, const ScaleSpec& scale,
                                      const SideSettings& settings, const std::string& where) {
  check_input(image, scale, where);
  if (scale.camera) {
    check_camera_size(*scale.camera, image, where);
    return measure_side_posed(image, scale, settings, where);
  }
  SideMeasurement m;
  m.source = where;
  m.note = scale.note;
  SideSettings set = settings;
  const SideImage prepared = prepare_side(image, settings, where);
  if (!scale.camera && !scale.mm_per_px) {
    if (!scale.search_marker)
      throw std::runtime_error(where +
                               ": scale cannot be determined (no camera, no mm per pixel, and "
                               "the scale-bar search is off)");
    m.scale_bar = find_scale_bar_flat(prepared.flat, scale.marker);
    if (m.scale_bar) m.scale_bar->box += prepared.roi.tl();
    if (!m.scale_bar)
      throw std::runtime_error(where +
                               ": scale cannot be determined: no camera sidecar, no mm "
                               "per pixel given, and no band scale bar (at least " +
                               str(scale.marker.min_black_bands) +
                               " black bands stacked at a regular pitch) found in the image");
    // Keep the bar (and its bottom band, merged with the plate) out of the pile search.
    const int pad = static_cast<int>(std::ceil(m.scale_bar->band_px));
    cv::Rect ex = m.scale_bar->box;
    ex.x -= pad;
    ex.width += 2 * pad;
    ex.y -= pad;
    ex.height += 4 * pad;
    set.exclude.push_back(ex);
  }
  m.pixels = measure_side_pixels(prepared, set, where);
  const SideProfile& p = m.pixels;
  add_side_warnings(m);
  m.crest = measure_crest(p, {}, where);

  {
    double k;  // [m/px]
    if (scale.mm_per_px) {
      m.scale_source = ScaleSource::kMmPerPx;
      m.mm_per_px = *scale.mm_per_px;
      m.sigma_scale_rel = 0.0;
    } else {
      m.scale_source = ScaleSource::kScaleBar;
      m.mm_per_px = m.scale_bar->mm_per_px;
      m.sigma_scale_rel = m.scale_bar->sigma_rel;
    }
    k = m.mm_per_px / 1000.0;
    m.perspective_corrected = false;
    m.height_m = p.height_px * k;
    m.diameter_m = p.diameter_px * k;
    m.sigma_height_m = std::hypot(p.sigma_height_px * k, m.height_m * m.sigma_scale_rel);
    m.sigma_diameter_m = std::hypot(p.sigma_diameter_px * k, m.diameter_m * m.sigma_scale_rel);
    m.theta_deg = p.theta_deg;
    m.sigma_theta_deg = p.sigma_theta_deg;
    m.flank_left_deg = p.left.angle_deg;
    m.flank_right_deg = p.right.angle_deg;
    m.sigma_flank_left_deg = p.left.sigma_deg;
    m.sigma_flank_right_deg = p.right.sigma_deg;
    m.crest_width_m = m.crest.width_px * k;
    m.sigma_crest_width_m = std::hypot(m.crest.sigma_px * k, m.crest_width_m * m.sigma_scale_rel);
    m.diameter_flank_m = p.diameter_flank_px * k;
  }
  refuse_small(m, settings.admission, where);
  settle_diameter(m);
  return m;
}
}  // namespace

namespace {

// H, D, the flank angles and the crest of a measured silhouette through a known camera:
// perspective corrected on the vertical plane through the base centre facing the camera.
void measure_through_camera(SideMeasurement& m, const camera::Camera& cam,
                            const Eigen::Vector3d& axis_foot, const std::string& where) {
  const SideProfile& p = m.pixels;
  m.scale_source = ScaleSource::kCamera;
  m.perspective_corrected = true;
  const camera::Ray rl = camera::unproject(cam, ev(p.toe_left));
  const camera::Ray rr = camera::unproject(cam, ev(p.toe_right));
  const Eigen::Vector2d axis = axis_foot.head<2>();
  Eigen::Vector2d dl = rl.direction.head<2>(), dr = rr.direction.head<2>();
  if (dl.norm() < 1e-6 || dr.norm() < 1e-6)
    throw std::runtime_error(where + ": the camera looks straight down; not a side view");
  dl.normalize();
  dr.normalize();
  Eigen::Vector2d center;
  Eigen::Vector2d toward_camera;
  double radius;
  if (cam.projection == camera::Projection::kPerspective) {
    const Eigen::Vector2d c = cam.extrinsics.position.head<2>();
    const double dist = (c - axis).norm();
    if (dist < 1e-6)
      throw std::runtime_error(where + ": the camera stands on the pile axis; not a side view");
    const double half = 0.5 * std::acos(std::clamp(dl.dot(dr), -1.0, 1.0));
    center = c + (dl + dr).normalized() * dist;
    radius = dist * std::sin(half);
    toward_camera = (c - center).normalized();
  } else {
    const Eigen::Vector2d n(-dl.y(), dl.x());
    const double sl = n.dot(rl.origin.head<2>()), sr = n.dot(rr.origin.head<2>());
    radius = 0.5 * std::abs(sr - sl);
    center = axis + n * (0.5 * (sl + sr) - n.dot(axis));
    toward_camera = -dl;
  }
  const Eigen::Vector3d plane_point(center.x(), center.y(), axis_foot.z());
  const Eigen::Vector3d plane_normal(toward_camera.x(), toward_camera.y(), 0.0);
  const auto apex = camera::pixel_on_plane(cam, ev(p.apex), plane_point, plane_normal);
  if (!apex) throw std::runtime_error(where + ": the apex ray misses the pile's axis plane");
  const auto plate_at_axis = camera::pixel_on_plane(
      cam, Eigen::Vector2d(p.apex.x, p.plate.v_at(p.apex.x)), plane_point, plane_normal);
  m.base_center_m = plane_point;
  m.plate_line_z_m = plate_at_axis ? plate_at_axis->z() : std::nan("");
  // H above the plate the camera gives (its axis foot), or, when the pile stands on the plate's
  // visible top face (a camera above the plate), above the toe line it stands on, as the lab
  // reads its photo: with the camera's true pose that line maps to the plate (z = 0); with a
  // camera higher than declared the whole picture is shifted and only the difference holds
  // (the apex's z alone read 4 mm for a 14 mm pile photographed from 10 mm up).
  m.height_m = apex->z() - (p.far_edge && !p.toe_line_predicted ? m.plate_line_z_m : axis_foot.z());
  m.diameter_m = 2.0 * radius;
  if (!(m.height_m > 0.0))
    throw std::runtime_error(where + ": the apex maps below the plate (H = " + str(m.height_m) +
                             " m); the camera does not fit this image");
  m.mm_per_px = camera::mm_per_px_at(cam, plane_point);
  const double k = m.mm_per_px / 1000.0;
  m.sigma_scale_rel = 0.0;
  m.sigma_height_m = p.sigma_height_px * k;
  m.sigma_diameter_m = p.sigma_diameter_px * k;
  m.theta_deg = std::atan(2.0 * m.height_m / m.diameter_m) * kRadToDeg;
  m.sigma_theta_deg =
      theta_sigma_deg(m.height_m, m.diameter_m, m.sigma_height_m, m.sigma_diameter_m);
  double foot_left = 0.0, foot_right = 0.0;
  m.flank_left_deg = flank_angle_on_meridian(cam, p.left, p.plate, rl, plane_point,
                                             where + ": left flank", &foot_left);
  m.flank_right_deg = flank_angle_on_meridian(cam, p.right, p.plate, rr, plane_point,
                                              where + ": right flank", &foot_right);
  // The flank lines' foot, D's other definition, where each flank line meets the plate on its
  // meridian plane.
  m.diameter_flank_m = foot_left + foot_right;
  m.sigma_flank_left_deg = p.left.sigma_deg;
  m.sigma_flank_right_deg = p.right.sigma_deg;
  // The crest's ends lie at the apex height on the pile's silhouette plane, as the apex does.
  const auto cl = camera::pixel_on_plane(cam, ev(m.crest.left), plane_point, plane_normal);
  const auto cr = camera::pixel_on_plane(cam, ev(m.crest.right), plane_point, plane_normal);
  if (!cl || !cr) throw std::runtime_error(where + ": the crest's rays miss the pile's axis plane");
  const double crest_raw = (*cr - *cl).norm() * (m.crest.raw_width_px < 0.0 ? -1.0 : 1.0);
  m.crest_width_m = std::max(0.0, crest_raw);
  m.sigma_crest_width_m = m.crest.sigma_px * k;
  // A camera above the pile's top sees the top's far side as the silhouette's highest point,
  // not the point on the axis: a flat top of radius c puts it up to c behind the axis plane, and
  // the apex's ray meets that plane up to (h - H) c / (L + c) too high. A rounded top grazes
  // between the axis and the far rim, so the apex is read midway and half the shift joins H's
  // uncertainty (the quick scene's pile, 16 mm tall with a 19 mm crest, seen from 10 deg: 16.0
  // mm on the axis plane, 14.5 mm on the far rim's, 15.7 mm from the level photo).
  const double cam_h = cam.extrinsics.position.z() - axis_foot.z();
  if (cam.projection == camera::Projection::kPerspective && cam_h > m.height_m &&
      m.crest_width_m > 0.0) {
    const Eigen::Vector3d rim_point = plane_point - 0.5 * m.crest_width_m * plane_normal;
    if (const auto rim = camera::pixel_on_plane(cam, ev(p.apex), rim_point, plane_normal)) {
      const double h_rim = rim->z() - axis_foot.z();
      if (h_rim > 0.0) {
        m.sigma_height_m = std::hypot(m.sigma_height_m, 0.5 * (m.height_m - h_rim));
        m.height_m = 0.5 * (m.height_m + h_rim);
        m.theta_deg = std::atan(2.0 * m.height_m / m.diameter_m) * kRadToDeg;
        m.sigma_theta_deg =
            theta_sigma_deg(m.height_m, m.diameter_m, m.sigma_height_m, m.sigma_diameter_m);
      }
    }
  }
}

// Pixels mapped through the camera onto the level plane through `on_plane`, in millimetres;
// a pixel whose ray misses the plane is left out.
std::vector<cv::Point2d> on_level_plane_mm(const camera::Camera& cam,
                                           const std::vector<cv::Point2d>& pixels,
                                           const Eigen::Vector3d& on_plane) {
  std::vector<cv::Point2d> mm;
  for (const auto& q : pixels) {
    const auto w = camera::pixel_on_plane(cam, ev(q), on_plane, Eigen::Vector3d::UnitZ());
    if (w) mm.emplace_back(1000.0 * w->x(), 1000.0 * w->y());
  }
  return mm;
}

// The top view's crest (vision/top_crest.hpp) in metres. Through a camera its circle is mapped
// onto the plane of the flat top (z = crest_height_m when given, else the plate, said so);
// without one the plate's scale is used, as for the footprint.
void read_top_crest(const cv::Mat& image, const ScaleSpec& scale, const std::string& where,
                    TopMeasurement& m) {
  m.crest = measure_top_crest(image, m.pixels, {}, where);
  const double h = scale.crest_height_m.value_or(0.0);
  m.crest_plane = scale.crest_height_m ? "z = " + fixed(1e3 * h, 1) + " mm (the side views' H)"
                                       : "the plate (no crest height given)";
  if (!m.crest.found) return;
  if (!scale.camera) {
    m.crest_width_m = 2.0 * m.crest.radius_px * m.mm_per_px / 1000.0;
    m.sigma_crest_width_m = 2.0 * m.crest.sigma_radius_px * m.mm_per_px / 1000.0;
    m.crest_plane += ", orthographic view assumed";
    return;
  }
  const Eigen::Vector3d on_plane = scale.axis_foot + Eigen::Vector3d(0.0, 0.0, h);
  auto width_at = [&](double r_px) {
    std::vector<cv::Point2d> px;
    for (int i = 0; i < 72; ++i) {
      const double a = 2.0 * std::numbers::pi * i / 72.0;
      px.push_back(m.crest.center + r_px * cv::Point2d(std::cos(a), std::sin(a)));
    }
    const std::vector<cv::Point2d> mm = on_level_plane_mm(*scale.camera, px, on_plane);
    cv::Point2d c;
    double r = 0.0, rms = 0.0;
    if (mm.size() < 16 || !fit_circle(mm, c, r, rms))
      throw std::runtime_error(where + ": the crest does not map onto its plane");
    return 2.0 * r / 1000.0;
  };
  const double r = m.crest.radius_px, s = m.crest.sigma_radius_px;
  m.crest_width_m = r > 0.0 ? width_at(r) : 0.0;
  // A crest bounded from 0 (no step read) is uncertain by the whole bound.
  m.sigma_crest_width_m =
      r > s ? 0.5 * (width_at(r + s) - width_at(r - s)) : width_at(r + s) - m.crest_width_m;
}

}  // namespace

TopMeasurement measure_top(const cv::Mat& image, const ScaleSpec& scale,
                           const TopSettings& settings, const std::string& where) {
  check_input(image, scale, where);
  TopMeasurement m;
  m.source = where;
  m.note = scale.note;
  TopSettings set = settings;
  if (scale.camera) {
    check_camera_size(*scale.camera, image, where);
    if (set.seed.x < 0 || set.seed.y < 0) {
      const auto s = camera::project(*scale.camera, scale.axis_foot);
      if (!s) throw std::runtime_error(where + ": the pile axis is behind the camera");
      set.seed = cv::Point2d(s->x(), s->y());
    }
  } else if (!scale.mm_per_px) {
    if (scale.search_marker) m.checker_card = find_checker_card(image, scale.marker, where);
    if (!m.checker_card)
      throw std::runtime_error(where +
                               ": scale cannot be determined: no camera sidecar, no mm "
                               "per pixel given, and no checker card found in the image");
  }
  m.pixels = measure_top_pixels(image, set, where);
  const TopProfile& p = m.pixels;
  if (!scale.camera) {
    if (scale.mm_per_px) {
      m.scale_source = ScaleSource::kMmPerPx;
      m.mm_per_px = *scale.mm_per_px;
    } else {
      m.scale_source = ScaleSource::kCheckerCard;
      m.mm_per_px = m.checker_card->mm_per_px;
      m.sigma_scale_rel = m.checker_card->sigma_rel;
    }
    const double k = m.mm_per_px / 1000.0;
    m.diameter_circle_m = p.diameter_circle_px * k;
    m.diameter_area_m = p.diameter_area_px * k;
    m.sigma_diameter_circle_m =
        std::hypot(p.sigma_diameter_circle_px * k, m.diameter_circle_m * m.sigma_scale_rel);
    m.circle_residual_m = p.circle_residual_px * k;
    m.ellipticity = p.ellipticity;
    read_top_crest(image, scale, where, m);
    return m;
  }
  // Known camera: the outline on the plate plane, in millimetres.
  const camera::Camera& cam = *scale.camera;
  m.scale_source = ScaleSource::kCamera;
  m.perspective_corrected = true;
  const std::vector<cv::Point2d> mm = on_level_plane_mm(cam, p.outline, scale.axis_foot);
  cv::Point2d c;
  double r = 0.0, rms = 0.0;
  if (mm.size() < 16 || !fit_circle(mm, c, r, rms))
    throw std::runtime_error(where + ": the footprint outline does not map onto the plate");
  double area = 0.0;
  for (size_t i = 0; i < mm.size(); ++i) {
    const cv::Point2d& a = mm[i];
    const cv::Point2d& b = mm[(i + 1) % mm.size()];
    area += a.x * b.y - b.x * a.y;
  }
  area = 0.5 * std::abs(area);
  std::vector<cv::Point2f> f(mm.begin(), mm.end());
  const cv::RotatedRect el = cv::fitEllipse(f);
  m.mm_per_px = camera::mm_per_px_at(cam, scale.axis_foot);
  m.diameter_circle_m = 2.0 * r / 1000.0;
  m.diameter_area_m = 2.0 * std::sqrt(area / std::numbers::pi) / 1000.0;
  m.sigma_diameter_circle_m = p.sigma_diameter_circle_px * m.mm_per_px / 1000.0;
  m.circle_residual_m = rms / 1000.0;
  m.ellipticity =
      1.0 - std::min(el.size.width, el.size.height) / std::max(el.size.width, el.size.height);
  read_top_crest(image, scale, where, m);
  return m;
}

SideMeasurement measure_side_camera(const cv::Mat& image, const camera::Camera& cam,
                                    const SideSettings& settings, const std::string& where) {
  ScaleSpec spec;
  spec.camera = cam;
  return measure_side(image, spec, settings, where);
}

TopMeasurement measure_top_camera(const cv::Mat& image, const camera::Camera& cam,
                                  const TopSettings& settings, const std::string& where) {
  ScaleSpec spec;
  spec.camera = cam;
  return measure_top(image, spec, settings, where);
}

SideSummary combine_sides(const std::vector<SideMeasurement>& views) {
  if (views.empty()) throw std::invalid_argument("combine_sides: no side views given");
  SideSummary s;
  s.views = static_cast<int>(views.size());
  auto spread = [&](auto value, auto sigma) {
    Spread out;
    const double n = static_cast<double>(views.size());
    double sum = 0.0, s2 = 0.0;
    for (const auto& v : views) {
      sum += value(v);
      s2 += sigma(v) * sigma(v);
    }
    out.mean = sum / n;
    double ss = 0.0;
    for (const auto& v : views) ss += (value(v) - out.mean) * (value(v) - out.mean);
    out.stddev = n > 1 ? std::sqrt(ss / (n - 1)) : 0.0;
    out.sigma_mean = std::sqrt(out.stddev * out.stddev / n + s2 / (n * n));
    return out;
  };
  s.height_m = spread([](const SideMeasurement& v) { return v.height_m; },
                      [](const SideMeasurement& v) { return v.sigma_height_m; });
  s.diameter_m = spread([](const SideMeasurement& v) { return v.diameter_m; },
                        [](const SideMeasurement& v) { return v.sigma_diameter_m; });
  s.theta_deg = spread([](const SideMeasurement& v) { return v.theta_deg; },
                       [](const SideMeasurement& v) { return v.sigma_theta_deg; });
  s.flank_left_deg = spread([](const SideMeasurement& v) { return v.flank_left_deg; },
                            [](const SideMeasurement& v) { return v.sigma_flank_left_deg; });
  s.flank_right_deg = spread([](const SideMeasurement& v) { return v.flank_right_deg; },
                             [](const SideMeasurement& v) { return v.sigma_flank_right_deg; });
  s.crest_width_m = spread([](const SideMeasurement& v) { return v.crest_width_m; },
                           [](const SideMeasurement& v) { return v.sigma_crest_width_m; });
  s.flank_deg =
      spread([](const SideMeasurement& v) { return 0.5 * (v.flank_left_deg + v.flank_right_deg); },
             [](const SideMeasurement& v) {
               return 0.5 * std::hypot(v.sigma_flank_left_deg, v.sigma_flank_right_deg);
             });
  return s;
}

}  // namespace reposetwin::vision
