#include "render/scene.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace reposetwin::render {
namespace {

[[noreturn]] void fail(const std::string& field, const std::string& what) {
  throw std::invalid_argument("render: " + field + " " + what);
}

template <typename T>
std::string str(const T& v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

std::string str(const Eigen::Vector3d& v) {
  std::ostringstream os;
  os << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return os.str();
}

void require_positive(double v, const std::string& field) {
  if (!(v > 0.0) || !std::isfinite(v)) fail(field, "must be positive and finite, got " + str(v));
}

void validate_color_fraction(double v, const std::string& field) {
  if (!(v >= 0.0) || !(v <= 1.0)) fail(field, "must be in [0, 1], got " + str(v));
}

}  // namespace

PileExtent pile_extent(const Scene& scene) {
  if (scene.positions.empty()) fail("scene.positions", "is empty: nothing to render");
  PileExtent e;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  e.radius_m = 0.0;
  for (std::size_t i = 0; i < scene.positions.size(); ++i) {
    const Eigen::Vector3d& p = scene.positions[i];
    const double r = i < scene.radii.size() ? scene.radii[i] : 0.0;
    lo = lo.cwiseMin(p - Eigen::Vector3d::Constant(r));
    hi = hi.cwiseMax(p + Eigen::Vector3d::Constant(r));
    e.radius_m = std::max(e.radius_m, std::hypot(p.x(), p.y()) + r);
  }
  e.z_min_m = lo.z();
  e.z_max_m = hi.z();
  e.center_m = 0.5 * (lo + hi);
  return e;
}

void validate(const Scene& scene) {
  const std::size_t n = scene.positions.size();
  if (n == 0) fail("scene.positions", "is empty: nothing to render");
  if (scene.radii.size() != n) {
    fail("scene.radii",
         "has " + str(scene.radii.size()) + " entries but scene.positions has " + str(n));
  }
  if (!scene.material_ids.empty() && scene.material_ids.size() != n) {
    fail("scene.material_ids",
         "has " + str(scene.material_ids.size()) + " entries but scene.positions has " + str(n));
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!scene.positions[i].allFinite())
      fail("scene.positions[" + str(i) + "]", "must be finite, got " + str(scene.positions[i]));
    const double r = scene.radii[i];
    if (!(r > 0.0) || !std::isfinite(r)) require_positive(r, "scene.radii[" + str(i) + "]");
  }
  if (!scene.body_ids.empty() && scene.body_ids.size() != n) {
    fail("scene.body_ids",
         "has " + str(scene.body_ids.size()) + " entries but scene.positions has " + str(n));
  }
  if (!(scene.plate.texture >= 0.0 && scene.plate.texture <= 0.5))
    fail("scene.plate.texture", "must be in [0, 0.5], got " + str(scene.plate.texture));
  require_positive(scene.plate.texture_scale_m, "scene.plate.texture_scale_m");
  if (!(scene.backdrop.gradient >= 0.0 && scene.backdrop.gradient <= 0.5))
    fail("scene.backdrop.gradient", "must be in [0, 0.5], got " + str(scene.backdrop.gradient));
  for (std::size_t i = 0; i < scene.material_ids.size(); ++i) {
    if (scene.material_ids[i] < 0)
      fail("scene.material_ids[" + str(i) + "]",
           "must be non-negative, got " + str(scene.material_ids[i]));
  }
  if (scene.plate.enabled) {
    require_positive(scene.plate.half_size_m, "scene.plate.half_size_m");
    require_positive(scene.plate.thickness_m, "scene.plate.thickness_m");
  }
  for (std::size_t i = 0; i < scene.shells.size(); ++i) {
    const Shell& s = scene.shells[i];
    const std::string w = "scene.shells[" + str(i) + "]";
    if (!(s.z_top_m > s.z_bottom_m) || !std::isfinite(s.z_top_m) || !std::isfinite(s.z_bottom_m))
      fail(w + ".z_top_m", "must be finite and above z_bottom_m = " + str(s.z_bottom_m) + ", got " +
                               str(s.z_top_m));
    if (!(s.r_bottom_m >= 0.0) || !std::isfinite(s.r_bottom_m))
      fail(w + ".r_bottom_m", "must be non-negative, got " + str(s.r_bottom_m));
    if (!(s.r_top_m >= 0.0) || !std::isfinite(s.r_top_m))
      fail(w + ".r_top_m", "must be non-negative, got " + str(s.r_top_m));
    if (s.r_bottom_m == 0.0 && s.r_top_m == 0.0)
      fail(w + ".r_top_m", "and r_bottom_m are both 0: the shell has no surface");
  }
  const ScaleReference& sr = scene.scale_reference;
  if (sr.enabled) {
    require_positive(sr.band_mm, "scene.scale_reference.band_mm");
    require_positive(sr.width_mm, "scene.scale_reference.width_mm");
    require_positive(sr.thickness_mm, "scene.scale_reference.thickness_mm");
    require_positive(sr.card_thickness_mm, "scene.scale_reference.card_thickness_mm");
    if (sr.count < 1)
      fail("scene.scale_reference.count", "must be at least 1, got " + str(sr.count));
    if (sr.squares < 1)
      fail("scene.scale_reference.squares", "must be at least 1, got " + str(sr.squares));
    if (sr.offset_m && !std::isfinite(*sr.offset_m))
      fail("scene.scale_reference.offset_m", "must be finite, got " + str(*sr.offset_m));
    if (sr.card_center_m && !sr.card_center_m->allFinite())
      fail("scene.scale_reference.card_center_m", "must be finite");
  }
}

void validate(const Scene& scene, const camera::Camera& cam, const RenderOptions& options) {
  validate(scene);
  camera::validate(cam, "render: camera");
  validate_color_fraction(options.tint_fraction, "options.tint_fraction");
  if (options.supersample < 1 || options.supersample > 8)
    fail("options.supersample", "must be in [1, 8], got " + str(options.supersample));
  validate_color_fraction(options.tone_warmth, "options.tone_warmth");
  validate_color_fraction(options.shadow_strength, "options.shadow_strength");
  if (!(options.shadow_softness_m >= 0.0) || !std::isfinite(options.shadow_softness_m))
    fail("options.shadow_softness_m", "must be non-negative, got " + str(options.shadow_softness_m));
  if (options.shadow_map_px != 0 && (options.shadow_map_px < 64 || options.shadow_map_px > 8192))
    fail("options.shadow_map_px", "must be 0 (chosen from the image) or in [64, 8192], got " +
                                       str(options.shadow_map_px));
  validate_color_fraction(options.ambient, "options.ambient");
  validate_color_fraction(options.diffuse, "options.diffuse");
  if (!options.light_direction_camera.allFinite() || options.light_direction_camera.norm() < 1e-12)
    fail("options.light_direction_camera", "must be a finite non-zero vector");

  const Eigen::Vector3d& eye = cam.extrinsics.position;
  for (std::size_t i = 0; i < scene.positions.size(); ++i) {
    if ((eye - scene.positions[i]).norm() <= scene.radii[i]) {
      fail("camera.extrinsics.position", str(eye) + " is inside sphere " + str(i) + " (centre " +
                                             str(scene.positions[i]) + ", radius " +
                                             str(scene.radii[i]) + " m)");
    }
  }
  const PileExtent pile = pile_extent(scene);
  if (std::hypot(eye.x(), eye.y()) < pile.radius_m && eye.z() >= pile.z_min_m &&
      eye.z() <= pile.z_max_m) {
    fail("camera.extrinsics.position",
         str(eye) + " is inside the pile's bounding cylinder (radius " + str(pile.radius_m) +
             " m, z from " + str(pile.z_min_m) + " to " + str(pile.z_max_m) + " m)");
  }
  const Eigen::Vector3d c = camera::to_camera_frame(cam, pile.center_m);
  if (cam.projection == camera::Projection::kPerspective && c.z() <= 0.0) {
    fail("camera.extrinsics.look_at", str(cam.extrinsics.look_at) +
                                          " looks away from the pile: its centre " +
                                          str(pile.center_m) + " is behind the camera");
  }
  const std::optional<Eigen::Vector2d> uv = camera::project(cam, pile.center_m);
  const double w = cam.intrinsics.width_px;
  const double h = cam.intrinsics.height_px;
  if (!uv || !(uv->x() >= -0.5 && uv->x() <= w - 0.5 && uv->y() >= -0.5 && uv->y() <= h - 0.5)) {
    fail("camera.extrinsics.look_at",
         str(cam.extrinsics.look_at) + " looks away from the pile: its centre " +
             str(pile.center_m) + " projects outside the image" +
             (uv ? " at (" + str(uv->x()) + ", " + str(uv->y()) + ") px" : std::string()));
  }
}

void apply_lab_look(Scene& scene, RenderOptions& options) {
  // Figures chosen by eye against the lab's photographs, each small enough that vision's
  // flat field, Otsu split and coverage edges read the pile as they read the plain renders
  // (tests/experiments/photos measure the same cones both ways).
  scene.backdrop.gradient = 0.12;
  scene.plate.texture = 0.06;
  options.tint_fraction = 0.16;
  options.tone_warmth = 0.35;
  options.shadows = true;
}

int shadow_map_side(const RenderOptions& options, int width_px, int height_px) {
  if (options.shadow_map_px > 0) return options.shadow_map_px;
  int side = 512;
  while (side < std::max(width_px, height_px) && side < 2048) side *= 2;
  return side;
}

std::optional<Eigen::Vector3d> scale_reference_center(const Scene& scene, const camera::Camera& cam,
                                                      View view) {
  const ScaleReference& sr = scene.scale_reference;
  if (!sr.enabled) return std::nullopt;
  const double pile_radius = pile_extent(scene).radius_m;
  if (view == View::kTop) {
    const Eigen::Vector2d xy = sr.card_center_m.value_or(Eigen::Vector2d(pile_radius + 0.035, 0.0));
    return Eigen::Vector3d(xy.x(), xy.y(), 1e-3 * sr.card_thickness_mm);
  }
  // The image's horizontal direction, flattened onto the plate.
  Eigen::Vector3d e = camera::rotation_world_to_camera(cam).row(0).transpose();
  e.z() = 0.0;
  if (e.norm() < 1e-9)
    fail("camera", "cannot hold a side-view scale bar: its image has no horizontal direction");
  e.normalize();
  const double offset = sr.offset_m.value_or(pile_radius + 0.025);
  return Eigen::Vector3d(offset * e.x(), offset * e.y(), 0.5e-3 * sr.band_mm * sr.count);
}

camera::Camera lab_side_camera(const Scene& scene, const LabCameraSettings& settings) {
  validate(scene);
  if (!(settings.distance_radii >= 10.0))
    fail("settings.distance_radii", "must be at least 10, got " + str(settings.distance_radii));
  if (!(settings.margin >= 1.0))
    fail("settings.margin", "must be at least 1, got " + str(settings.margin));
  if (settings.width_px <= 0)
    fail("settings.width_px", "must be positive, got " + str(settings.width_px));
  if (settings.height_px <= 0)
    fail("settings.height_px", "must be positive, got " + str(settings.height_px));
  const PileExtent pile = pile_extent(scene);
  const double distance = settings.distance_radii * pile.radius_m;
  const ScaleReference& sr = scene.scale_reference;
  double half_width = pile.radius_m;
  double top = pile.z_max_m;
  double bottom = std::min(pile.z_min_m, scene.plate.enabled ? -scene.plate.thickness_m : 0.0);
  if (sr.enabled) {
    const double offset = sr.offset_m.value_or(pile.radius_m + 0.025);
    half_width = std::max(half_width, std::abs(offset) + 0.5e-3 * sr.width_mm);
    top = std::max(top, 1e-3 * sr.band_mm * sr.count);
  }
  for (const Shell& shell : scene.shells) {  // a funnel in the picture is in it whole
    half_width = std::max({half_width, shell.r_bottom_m, shell.r_top_m});
    top = std::max(top, shell.z_top_m);
  }
  const double aspect = static_cast<double>(settings.width_px) / settings.height_px;
  // The pile's front is nearer than the axis by up to a pile radius: it looks that much larger.
  const double near_factor = distance / (distance - pile.radius_m);
  const double h = settings.side_height_m;
  if (!settings.shift_lens) {
    const double half_height = std::max(top - h, h - bottom);
    const double field =
        settings.margin * near_factor * std::max(2.0 * half_width, 2.0 * half_height * aspect);
    return camera::side_view(distance, field, h, settings.azimuth_deg, settings.width_px,
                             settings.height_px);
  }
  // Vertical extent as tangents of the viewing angle: the pile's top at its front, the bar's at
  // the axis, and the plate's underside at its near edge (which looks lowest).
  const double near_plate = scene.plate.enabled
                                ? std::max(distance - scene.plate.half_size_m, 0.25 * distance)
                                : distance - pile.radius_m;
  const double t_top = std::max((pile.z_max_m - h) / (distance - pile.radius_m), (top - h) / distance);
  const double t_bottom = std::min((bottom - h) / near_plate, (pile.z_min_m - h) / distance);
  const double field = settings.margin * std::max(near_factor * 2.0 * half_width,
                                                  distance * (t_top - t_bottom) * aspect);
  camera::Camera cam = camera::side_view(distance, field, h, settings.azimuth_deg,
                                         settings.width_px, settings.height_px);
  // Image rows grow downwards: the middle of the extent goes to the middle row.
  cam.intrinsics.cy_px =
      0.5 * (settings.height_px - 1) + camera::focal_px(cam) * 0.5 * (t_top + t_bottom);
  return cam;
}

camera::Camera lab_top_camera(const Scene& scene, const LabCameraSettings& settings) {
  validate(scene);
  if (!(settings.distance_radii >= 10.0))
    fail("settings.distance_radii", "must be at least 10, got " + str(settings.distance_radii));
  if (!(settings.margin >= 1.0))
    fail("settings.margin", "must be at least 1, got " + str(settings.margin));
  if (settings.width_px <= 0)
    fail("settings.width_px", "must be positive, got " + str(settings.width_px));
  if (settings.height_px <= 0)
    fail("settings.height_px", "must be positive, got " + str(settings.height_px));
  const PileExtent pile = pile_extent(scene);
  double top = std::max(pile.z_max_m, 0.0);
  for (const Shell& shell : scene.shells) top = std::max(top, shell.z_top_m);
  const double height = top + settings.distance_radii * pile.radius_m;
  const ScaleReference& sr = scene.scale_reference;
  const double aspect = static_cast<double>(settings.width_px) / settings.height_px;
  const double near_factor = height / (height - top);
  // The pile's footprint and the card on the plate, as a box (x_lo, y_lo, x_hi, y_hi) [m].
  Eigen::Vector4d box(-pile.radius_m, -pile.radius_m, pile.radius_m, pile.radius_m);
  if (sr.enabled) {
    const Eigen::Vector2d c =
        sr.card_center_m.value_or(Eigen::Vector2d(pile.radius_m + 0.035, 0.0));
    const double half_card = 0.5e-3 * sr.band_mm * sr.squares;
    box.head<2>() = box.head<2>().cwiseMin(c - Eigen::Vector2d::Constant(half_card));
    box.tail<2>() = box.tail<2>().cwiseMax(c + Eigen::Vector2d::Constant(half_card));
  }
  for (const Shell& shell : scene.shells) {
    const double r = std::max(shell.r_bottom_m, shell.r_top_m);
    box.head<2>() = box.head<2>().cwiseMin(Eigen::Vector2d::Constant(-r));
    box.tail<2>() = box.tail<2>().cwiseMax(Eigen::Vector2d::Constant(r));
  }
  if (!settings.shift_lens) {
    const double half_extent = box.cwiseAbs().maxCoeff();
    const double field = settings.margin * near_factor * 2.0 * half_extent * std::max(1.0, aspect);
    return camera::top_view(height, field, settings.width_px, settings.height_px);
  }
  const double field = settings.margin * near_factor *
                       std::max(box.z() - box.x(), (box.w() - box.y()) * aspect);
  camera::Camera cam = camera::top_view(height, field, settings.width_px, settings.height_px);
  // The box's centre to the image centre (the principal point moves with the image).
  const Eigen::Vector3d mid(0.5 * (box.x() + box.z()), 0.5 * (box.y() + box.w()), 0.0);
  const Eigen::Vector2d uv = *camera::project(cam, mid);
  cam.intrinsics.cx_px = camera::principal_u(cam) + 0.5 * (settings.width_px - 1) - uv.x();
  cam.intrinsics.cy_px = camera::principal_v(cam) + 0.5 * (settings.height_px - 1) - uv.y();
  return cam;
}

}  // namespace reposetwin::render
