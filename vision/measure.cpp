#include "vision/measure.hpp"

// Design note (the pose check). measure_side checks every cue a photo offers against its
// declared camera: (a) the base ellipse's pitch and toe line (camera_pose.hpp); (b) its height:
// a pose whose pitch agrees can stand higher than declared (a level camera raised), which biases
// atan(2H/D) through the toe line, so the angle is measured through the declared camera and
// through the ellipse's pose, and a difference above 0.5 deg is a contradiction; (c) without a
// top face, the detected plate line against the declared camera's axis foot, beyond max(2 px,
// 3 sigma) (a biasing warning, SideWarningKind::kCameraMismatch, which the loop refuses). With
// PosePolicy::kEstimate a contradicted photo is measured through the ellipse's pose when that
// pose is determined (pose_determined), else refused.

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

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
                               const std::string& where) {
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

// The detected plate line against the axis foot the camera predicts, when the photo shows no
// plate top face (a camera at the plate's height, or a plate face vision cannot tell from its
// edge): the gap in pixels, its uncertainty (the line's own, and a pixel of the toes' depth in
// front of the axis), and what it says of the camera in numbers: the pitch it needs at the
// declared height, or the height at the declared pitch. Empty when they agree.
std::optional<std::string> plate_line_mismatch(const SideProfile& p, const camera::Camera& cam,
                                               const Eigen::Vector3d& axis_foot) {
  const auto foot = camera::project(cam, axis_foot);
  if (!foot) return "the camera does not see the axis foot at all";
  const double line_v = p.plate.v_at(foot->x());
  const double gap = line_v - foot->y();
  const double sigma = std::hypot(p.plate.sigma_px, 1.0);
  if (std::abs(gap) <= std::max(2.0, 3.0 * sigma)) return std::nullopt;
  const Eigen::Vector3d d_foot = camera::unproject(cam, *foot).direction;
  const Eigen::Vector3d d_line =
      camera::unproject(cam, Eigen::Vector2d(foot->x(), line_v)).direction;
  // Angles below the horizontal of the two rays [rad]: the line lies lower in the image than
  // the foot when the camera is pitched more, or stands higher, than declared.
  const double below_foot = std::asin(std::clamp(-d_foot.z(), -1.0, 1.0));
  const double below_line = std::asin(std::clamp(-d_line.z(), -1.0, 1.0));
  const double dpitch = below_foot - below_line;
  const double distance = (cam.extrinsics.position.head<2>() - axis_foot.head<2>()).norm();
  const double height = cam.extrinsics.position.z() - axis_foot.z();
  const double h_at_pitch = distance * std::tan(std::atan2(height, distance) + below_line -
                                                below_foot);
  return "the camera puts the axis foot " + fixed(gap, 1) + " +- " + fixed(sigma, 1) +
         " px from the detected plate line and the photo shows no plate top face to check its "
         "pose with: the camera does not match the image (the plate line says it is pitched " +
         fixed(dpitch * kRadToDeg, 1) + " deg more than declared at the declared height, or "
         "stands " + fixed(1000.0 * h_at_pitch, 1) + " mm above the plate for a declared " +
         fixed(1000.0 * height, 1) + " mm at the declared pitch); D and the flank angles through "
         "it may be biased";
}

// A pose whose pitch agrees with the declared one can still stand higher than declared (a level
// camera raised): the toe line then reads H + h R^2 / (L^2 - R^2) (the design note), 1.8 deg
// too steep for a 14 mm pile 150 mm below a camera at 12 pile radii. The angle is measured
// through the declared camera and through the pose the photo shows; when they differ by more
// than kPoseAngleToleranceDeg the declared camera is said to contradict the photo, in numbers.
constexpr double kPoseAngleToleranceDeg = 0.5;

// The largest elevation off the declared one a photo is measured at [deg]. A camera 30 mm above
// the plate at 12 pile radii (elevation 3 deg) read a 42 mm cone of spheres 1.1 deg steeper
// than its level photo, through the declared camera and through the pose the photo shows alike
// (tests/experiments/photos/tilted_camera_test.cpp); the lab's 5-10 mm (0.6-2 deg) read within
// 0.3 deg.
constexpr double kMaxElevationDeg = 2.5;

std::string height_bias(const SideMeasurement& base, const camera::Camera& declared,
                        const PoseEstimate& pose, const Eigen::Vector3d& axis_foot,
                        const std::string& where) {
  SideMeasurement through_declared = base, through_pose = base;
  try {
    measure_through_camera(through_declared, declared, axis_foot, where);
    measure_through_camera(through_pose, posed_camera(declared, pose, axis_foot), axis_foot,
                           where);
  } catch (const std::runtime_error& e) {
    return std::string("the camera the photo shows cannot measure it (") + e.what() + ")";
  }
  const double bias = through_declared.theta_deg - through_pose.theta_deg;
  if (std::abs(bias) <= kPoseAngleToleranceDeg) return "";
  return "the pile's base ellipse says the camera stands " + fixed(1000.0 * pose.height_m, 1) +
         " +- " + fixed(1000.0 * pose.distance_m * pose.sigma_elevation_deg / kRadToDeg, 1) +
         " mm above the plate, pitched " + fixed(pose.pitch_deg, 1) + " deg (declared " +
         fixed(1000.0 * pose.distance_m * std::tan(pose.declared_elevation_deg / kRadToDeg), 1) +
         " mm, " + fixed(pose.declared_pitch_deg, 1) + " deg); through the declared camera "
         "atan(2H/D) reads " + fixed(through_declared.theta_deg, 2) + " deg, through the pose " +
         fixed(through_pose.theta_deg, 2) + " deg: a bias of " + fixed(bias, 2) +
         " deg, more than " + fixed(kPoseAngleToleranceDeg, 1) + " deg";
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

SideMeasurement measure_side(const cv::Mat& image, const ScaleSpec& scale,
                             const SideSettings& settings, const std::string& where) {
  check_input(image, scale, where);
  if (scale.camera) check_camera_size(*scale.camera, image, where);
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
  m.crest = measure_crest(p, {}, where);

  if (!scale.camera) {
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
    return m;
  }

  // Perspective correction with the known camera, once the photo's own pose agrees with it: a
  // photo taken from above and pitched down but declared level, measured through the declared
  // camera, read atan(2H/D) degrees too steep (the toe line through the middle of the pile's
  // base, D far too short); it is refused with the numbers instead, or, when asked
  // (PosePolicy::kEstimate), measured through the pose its base ellipse gives.
  camera::Camera cam = *scale.camera;
  if (scale.check_pose) {
    m.pose = estimate_side_pose(prepared, p, cam, scale.axis_foot);
    std::string why = m.pose ? pose_contradiction(*m.pose) : std::string();
    // Seen from well above the plate the toe line lies on the plate's top face, and no pose
    // measures the pile as a level photo does: refused whatever the policy.
    if (m.pose) {
      const double de = m.pose->elevation_deg - m.pose->declared_elevation_deg;
      if (std::abs(de) > std::max(kMaxElevationDeg, 3.0 * m.pose->sigma_elevation_deg))
        throw PoseContradiction(
            where + ": not measured through the declared camera: the pile's base ellipse says "
                    "the camera stands " + fixed(1000.0 * m.pose->height_m, 1) +
            " mm above the plate, elevation " + fixed(m.pose->elevation_deg, 1) + " +- " +
            fixed(m.pose->sigma_elevation_deg, 1) + " deg seen from the pile, declared " +
            fixed(m.pose->declared_elevation_deg + 0.0, 1) + " deg, and pitched " +
            fixed(m.pose->pitch_deg, 1) + " deg (declared " +
            fixed(std::abs(m.pose->declared_pitch_deg) < 0.05 ? 0.0 : m.pose->declared_pitch_deg,
                  1) +
            " deg): more than " +
            fixed(kMaxElevationDeg, 1) + " deg of elevation off the declared reads atan(2H/D) "
            "about 1 deg steep through any camera (give a level photo)" +
            (why.empty() ? std::string() : "; " + why));
    }
    if (why.empty() && m.pose && pose_determined(*m.pose))
      why = height_bias(m, cam, *m.pose, scale.axis_foot, where);
    if (!why.empty()) {
      if (scale.pose_policy == PosePolicy::kRefuse || !pose_determined(*m.pose))
        throw PoseContradiction(where + ": not measured through the declared camera: " + why);
      cam = posed_camera(cam, *m.pose, scale.axis_foot);
      m.pose_used = true;
      m.warnings.push_back({SideWarningKind::kPoseEstimated,
                            "measured through the pose the photo shows, not the declared camera: " +
                                why});
    }
  }
  // Without the plate's top face in the picture there is no base ellipse to check the pose
  // with, but the plate line is a cue of its own: a camera that puts the axis foot off it by
  // more than the line's uncertainty does not match the image.
  if (!p.far_edge)
    if (const auto miss = plate_line_mismatch(p, cam, scale.axis_foot))
      m.warnings.push_back({SideWarningKind::kCameraMismatch, *miss});
  measure_through_camera(m, cam, scale.axis_foot, where);
  return m;
}

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
  if (p.far_edge && !plate_at_axis)
    throw std::runtime_error(where + ": the plate line's ray misses the pile's axis plane");
  m.height_m = apex->z() - (p.far_edge ? m.plate_line_z_m : axis_foot.z());
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
  m.flank_left_deg =
      flank_angle_on_meridian(cam, p.left, p.plate, rl, plane_point, where + ": left flank");
  m.flank_right_deg =
      flank_angle_on_meridian(cam, p.right, p.plate, rr, plane_point, where + ": right flank");
  m.sigma_flank_left_deg = p.left.sigma_deg;
  m.sigma_flank_right_deg = p.right.sigma_deg;
  // The crest's ends lie at the apex height on the pile's silhouette plane, as the apex does.
  const auto cl = camera::pixel_on_plane(cam, ev(m.crest.left), plane_point, plane_normal);
  const auto cr = camera::pixel_on_plane(cam, ev(m.crest.right), plane_point, plane_normal);
  if (!cl || !cr) throw std::runtime_error(where + ": the crest's rays miss the pile's axis plane");
  const double crest_raw = (*cr - *cl).norm() * (m.crest.raw_width_px < 0.0 ? -1.0 : 1.0);
  m.crest_width_m = std::max(0.0, crest_raw);
  m.sigma_crest_width_m = m.crest.sigma_px * k;
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
