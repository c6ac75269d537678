#include "camera/camera.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>
#include <sstream>
#include <stdexcept>
#include <tuple>
#include <utility>

namespace reposetwin::camera {
namespace {

// The largest image side a sidecar may declare [px]: the largest camera sensors are about 15,000
// pixels wide; the bound keeps a typo (10^12) from wrapping an int.
constexpr std::int64_t kMaxSidePx = 100000;

[[noreturn]] void fail(const std::string& where, const std::string& field, const std::string& what) {
  throw std::invalid_argument(where + ": " + field + " " + what);
}

std::string str(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

void reject_unknown(const nlohmann::json& j, const std::set<std::string>& known,
                    const std::string& where) {
  if (!j.is_object()) fail(where, "", "must be a JSON object");
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (!known.count(it.key())) fail(where, it.key(), "is not a known key");
  }
}

Eigen::Vector3d vec3(const nlohmann::json& j, const std::string& where, const std::string& field) {
  if (!j.is_array() || j.size() != 3) fail(where, field, "must be an array of 3 numbers");
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    if (!j[i].is_number()) fail(where, field, "must be an array of 3 numbers");
    v[i] = j[i].get<double>();
  }
  return v;
}

double number(const nlohmann::json& j, const std::string& where, const std::string& field) {
  if (!j.is_number()) fail(where, field, "must be a number, got " + j.dump());
  return j.get<double>();
}

}  // namespace

void validate(const Camera& cam, const std::string& where) {
  const Intrinsics& in = cam.intrinsics;
  if (in.width_px <= 0) fail(where, "intrinsics.width_px", "must be positive, got " + str(in.width_px));
  if (in.height_px <= 0)
    fail(where, "intrinsics.height_px", "must be positive, got " + str(in.height_px));
  if (cam.projection == Projection::kPerspective) {
    if (!(in.focal_length_mm > 0.0))
      fail(where, "intrinsics.focal_length_mm", "must be positive, got " + str(in.focal_length_mm));
    if (!(in.sensor_width_mm > 0.0))
      fail(where, "intrinsics.sensor_width_mm", "must be positive, got " + str(in.sensor_width_mm));
  } else {
    if (!(in.ortho_width_m > 0.0))
      fail(where, "intrinsics.ortho_width_m", "must be positive, got " + str(in.ortho_width_m));
    if (in.k1 != 0.0 || in.k2 != 0.0)
      fail(where, "intrinsics.k1/k2", "must be 0 for an orthographic camera");
  }
  if (!std::isfinite(in.k1) || !std::isfinite(in.k2)) fail(where, "intrinsics.k1/k2", "must be finite");
  const Extrinsics& ex = cam.extrinsics;
  if (!ex.position.allFinite()) fail(where, "extrinsics.position", "must be finite");
  if (!ex.look_at.allFinite()) fail(where, "extrinsics.look_at", "must be finite");
  const Eigen::Vector3d f = ex.look_at - ex.position;
  if (f.norm() < 1e-12) fail(where, "extrinsics.look_at", "coincides with the camera position");
  if (ex.up.norm() < 1e-12) fail(where, "extrinsics.up", "must be a non-zero vector");
  if (f.normalized().cross(ex.up.normalized()).norm() < 1e-9)
    fail(where, "extrinsics.up", "is parallel to the viewing direction");
}

double focal_px(const Camera& cam) {
  const Intrinsics& in = cam.intrinsics;
  if (cam.projection == Projection::kPerspective)
    return in.focal_length_mm / in.sensor_width_mm * in.width_px;
  return in.width_px / in.ortho_width_m;
}

double principal_u(const Camera& cam) {
  return cam.intrinsics.cx_px.value_or(0.5 * (cam.intrinsics.width_px - 1));
}

double principal_v(const Camera& cam) {
  return cam.intrinsics.cy_px.value_or(0.5 * (cam.intrinsics.height_px - 1));
}

Eigen::Matrix3d rotation_world_to_camera(const Camera& cam) {
  const Extrinsics& ex = cam.extrinsics;
  const Eigen::Vector3d z = (ex.look_at - ex.position).normalized();
  const Eigen::Vector3d x = z.cross(ex.up).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d r;
  r.row(0) = x.transpose();
  r.row(1) = y.transpose();
  r.row(2) = z.transpose();
  return r;
}

Eigen::Vector3d to_camera_frame(const Camera& cam, const Eigen::Vector3d& world) {
  return rotation_world_to_camera(cam) * (world - cam.extrinsics.position);
}

Eigen::Vector2d distort_normalised(const Camera& cam, const Eigen::Vector2d& xy) {
  const double r2 = xy.squaredNorm();
  const double k = 1.0 + cam.intrinsics.k1 * r2 + cam.intrinsics.k2 * r2 * r2;
  return xy * k;
}

Eigen::Vector2d undistort_normalised(const Camera& cam, const Eigen::Vector2d& xy_distorted) {
  if (cam.intrinsics.k1 == 0.0 && cam.intrinsics.k2 == 0.0) return xy_distorted;
  // Fixed-point iteration x = x_d / (1 + k1 r^2 + k2 r^4), as OpenCV's undistortPoints does.
  Eigen::Vector2d xy = xy_distorted;
  for (int it = 0; it < 50; ++it) {
    const double r2 = xy.squaredNorm();
    const double k = 1.0 + cam.intrinsics.k1 * r2 + cam.intrinsics.k2 * r2 * r2;
    const Eigen::Vector2d next = xy_distorted / k;
    if ((next - xy).norm() < 1e-15) return next;
    xy = next;
  }
  return xy;
}

std::optional<Eigen::Vector2d> project(const Camera& cam, const Eigen::Vector3d& world) {
  const Eigen::Vector3d pc = to_camera_frame(cam, world);
  const double f = focal_px(cam);
  if (cam.projection == Projection::kOrthographic) {
    return Eigen::Vector2d(principal_u(cam) + f * pc.x(), principal_v(cam) + f * pc.y());
  }
  if (pc.z() <= 0.0) return std::nullopt;
  const Eigen::Vector2d xy = distort_normalised(cam, Eigen::Vector2d(pc.x(), pc.y()) / pc.z());
  return Eigen::Vector2d(principal_u(cam) + f * xy.x(), principal_v(cam) + f * xy.y());
}

Ray unproject(const Camera& cam, const Eigen::Vector2d& pixel) {
  const Eigen::Matrix3d rt = rotation_world_to_camera(cam).transpose();
  const double f = focal_px(cam);
  const Eigen::Vector2d n((pixel.x() - principal_u(cam)) / f, (pixel.y() - principal_v(cam)) / f);
  if (cam.projection == Projection::kOrthographic) {
    return Ray{cam.extrinsics.position + rt * Eigen::Vector3d(n.x(), n.y(), 0.0),
               rt.col(2).normalized()};
  }
  const Eigen::Vector2d u = undistort_normalised(cam, n);
  return Ray{cam.extrinsics.position, (rt * Eigen::Vector3d(u.x(), u.y(), 1.0)).normalized()};
}

std::optional<Eigen::Vector3d> pixel_on_plane(const Camera& cam, const Eigen::Vector2d& pixel,
                                              const Eigen::Vector3d& point,
                                              const Eigen::Vector3d& normal) {
  const Ray ray = unproject(cam, pixel);
  const double denom = ray.direction.dot(normal);
  if (std::abs(denom) < 1e-12) return std::nullopt;
  const double t = (point - ray.origin).dot(normal) / denom;
  if (t <= 0.0) return std::nullopt;
  return ray.origin + t * ray.direction;
}

double mm_per_px_at(const Camera& cam, const Eigen::Vector3d& world) {
  if (cam.projection == Projection::kOrthographic) return 1000.0 / focal_px(cam);
  return 1000.0 * to_camera_frame(cam, world).z() / focal_px(cam);
}

Camera side_view(double distance_m, double field_width_m, double height_m, double azimuth_deg,
                 int width_px, int height_px) {
  Camera cam;
  cam.name = "side";
  cam.projection = Projection::kPerspective;
  cam.intrinsics.width_px = width_px;
  cam.intrinsics.height_px = height_px;
  cam.intrinsics.sensor_width_mm = 36.0;
  cam.intrinsics.focal_length_mm = distance_m / field_width_m * cam.intrinsics.sensor_width_mm;
  const double a = azimuth_deg * std::numbers::pi / 180.0;
  cam.extrinsics.position = Eigen::Vector3d(distance_m * std::sin(a), -distance_m * std::cos(a),
                                            height_m);
  cam.extrinsics.look_at = Eigen::Vector3d(0.0, 0.0, height_m);
  cam.extrinsics.up = Eigen::Vector3d(0.0, 0.0, 1.0);
  return cam;
}

Camera top_view(double height_m, double field_width_m, int width_px, int height_px) {
  Camera cam;
  cam.name = "top";
  cam.projection = Projection::kPerspective;
  cam.intrinsics.width_px = width_px;
  cam.intrinsics.height_px = height_px;
  cam.intrinsics.sensor_width_mm = 36.0;
  cam.intrinsics.focal_length_mm = height_m / field_width_m * cam.intrinsics.sensor_width_mm;
  cam.extrinsics.position = Eigen::Vector3d(0.0, 0.0, height_m);
  cam.extrinsics.look_at = Eigen::Vector3d(0.0, 0.0, 0.0);
  cam.extrinsics.up = Eigen::Vector3d(0.0, 1.0, 0.0);
  return cam;
}

nlohmann::json to_json(const Camera& cam) {
  const Intrinsics& in = cam.intrinsics;
  nlohmann::json ji = {{"width_px", in.width_px},
                       {"height_px", in.height_px},
                       {"focal_length_mm", in.focal_length_mm},
                       {"sensor_width_mm", in.sensor_width_mm},
                       {"ortho_width_m", in.ortho_width_m},
                       {"k1", in.k1},
                       {"k2", in.k2},
                       {"cx_px", principal_u(cam)},
                       {"cy_px", principal_v(cam)}};
  auto v = [](const Eigen::Vector3d& x) { return nlohmann::json::array({x.x(), x.y(), x.z()}); };
  return {{"name", cam.name},
          {"projection",
           cam.projection == Projection::kPerspective ? "perspective" : "orthographic"},
          {"intrinsics", ji},
          {"extrinsics",
           {{"position", v(cam.extrinsics.position)},
            {"look_at", v(cam.extrinsics.look_at)},
            {"up", v(cam.extrinsics.up)}}}};
}

Camera from_json(const nlohmann::json& j, const std::string& where) {
  reject_unknown(j, {"name", "projection", "intrinsics", "extrinsics"}, where);
  Camera cam;
  if (j.contains("name")) {
    if (!j["name"].is_string()) fail(where, "name", "must be a string");
    cam.name = j["name"].get<std::string>();
  }
  if (j.contains("projection")) {
    const std::string p = j["projection"].is_string() ? j["projection"].get<std::string>() : "";
    if (p == "perspective") {
      cam.projection = Projection::kPerspective;
    } else if (p == "orthographic") {
      cam.projection = Projection::kOrthographic;
    } else {
      fail(where, "projection",
           "must be \"perspective\" or \"orthographic\", got " + j["projection"].dump());
    }
  }
  if (j.contains("intrinsics")) {
    const nlohmann::json& ji = j["intrinsics"];
    const std::string w = where + ": intrinsics";
    reject_unknown(ji,
                   {"width_px", "height_px", "focal_length_mm", "sensor_width_mm", "ortho_width_m",
                    "k1", "k2", "cx_px", "cy_px"},
                   w);
    Intrinsics& in = cam.intrinsics;
    // Checked before the conversion to int: 10^12 would wrap to a negative width.
    auto integer = [&](const char* key, int& out) {
      if (!ji.contains(key)) return;
      const nlohmann::json& v = ji[key];
      if (!v.is_number_integer()) fail(w, key, "must be an integer, got " + v.dump());
      const std::int64_t n = v.get<std::int64_t>();  // above 2^63 wraps negative: refused too
      if (n < 1 || n > kMaxSidePx)
        fail(w, key, "must be from 1 to " + std::to_string(kMaxSidePx) + " pixels, got " + v.dump());
      out = v.get<int>();
    };
    integer("width_px", in.width_px);
    integer("height_px", in.height_px);
    if (ji.contains("focal_length_mm")) in.focal_length_mm = number(ji["focal_length_mm"], w, "focal_length_mm");
    if (ji.contains("sensor_width_mm")) in.sensor_width_mm = number(ji["sensor_width_mm"], w, "sensor_width_mm");
    if (ji.contains("ortho_width_m")) in.ortho_width_m = number(ji["ortho_width_m"], w, "ortho_width_m");
    if (ji.contains("k1")) in.k1 = number(ji["k1"], w, "k1");
    if (ji.contains("k2")) in.k2 = number(ji["k2"], w, "k2");
    if (ji.contains("cx_px")) in.cx_px = number(ji["cx_px"], w, "cx_px");
    if (ji.contains("cy_px")) in.cy_px = number(ji["cy_px"], w, "cy_px");
  }
  if (j.contains("extrinsics")) {
    const nlohmann::json& je = j["extrinsics"];
    const std::string w = where + ": extrinsics";
    reject_unknown(je, {"position", "look_at", "up"}, w);
    if (je.contains("position")) cam.extrinsics.position = vec3(je["position"], w, "position");
    if (je.contains("look_at")) cam.extrinsics.look_at = vec3(je["look_at"], w, "look_at");
    if (je.contains("up")) cam.extrinsics.up = vec3(je["up"], w, "up");
  }
  validate(cam, where);
  return cam;
}

namespace {

// A sidecar's top-level keys: the camera and what a render writes beside it.
const std::set<std::string> kSidecarKeys = {"camera",          "view",  "image",
                                            "mm_per_px_at_axis", "scale_point_m",
                                            "scale_reference", "look",  "provenance", "plate"};
// The largest radial distortion coefficient a sidecar may declare: a real lens's k1 is within
// +-0.5 (the loop's synthetic lenses are held there too); 1e6 is a typo, not a lens.
constexpr double kMaxDistortion = 1.0;

// Every value the projection uses must be in the file: a missing focal length or intrinsics
// block would otherwise take a default camera's and measure a wrong H without a word. The
// distortion (k1, k2: none) and the principal point (cx_px, cy_px: the image centre) have
// neutral defaults and may be left out.
void require_complete(const nlohmann::json& cam, const std::string& where) {
  if (!cam.is_object()) fail(where, "", "must be a JSON object");
  auto need = [&](const nlohmann::json& j, const std::string& block, const char* key) {
    if (!j.is_object() || !j.contains(key))
      fail(where, block + key,
           "is missing (a sidecar gives every value its projection uses: projection, "
           "intrinsics.width_px, height_px, focal_length_mm and sensor_width_mm, or "
           "ortho_width_m, extrinsics.position, look_at, up)");
  };
  need(cam, "", "projection");
  need(cam, "", "intrinsics");
  need(cam, "", "extrinsics");
  const nlohmann::json& in = cam["intrinsics"];
  need(in, "intrinsics.", "width_px");
  need(in, "intrinsics.", "height_px");
  if (cam["projection"] == "orthographic") {
    need(in, "intrinsics.", "ortho_width_m");
  } else {
    need(in, "intrinsics.", "focal_length_mm");
    need(in, "intrinsics.", "sensor_width_mm");
  }
  for (const char* key : {"position", "look_at", "up"}) need(cam["extrinsics"], "extrinsics.", key);
}

}  // namespace

Camera read_sidecar(const std::string& path, SidecarView expect) {
  std::error_code ec;
  if (std::filesystem::exists(path, ec) && !std::filesystem::is_regular_file(path, ec))
    throw std::invalid_argument(path + ": camera sidecar is not a regular file");
  std::ifstream in(path);
  if (!in) throw std::invalid_argument(path + ": cannot open camera sidecar");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    // The library's text without its "[json.exception.parse_error.101] " tag.
    std::string why = e.what();
    const std::size_t tag = why.find("] ");
    if (why.rfind("[json.", 0) == 0 && tag != std::string::npos) why.erase(0, tag + 2);
    throw std::invalid_argument(path + ": not valid JSON (" + why + ")");
  }
  if (!j.is_object() || !j.contains("camera"))
    throw std::invalid_argument(path + ": field \"camera\" is missing");
  for (auto it = j.begin(); it != j.end(); ++it)
    if (!kSidecarKeys.count(it.key()))
      throw std::invalid_argument(path + ": field \"" + it.key() +
                                  "\" is not a sidecar field (known: camera, view, image, "
                                  "mm_per_px_at_axis, scale_point_m, scale_reference, look, "
                                  "provenance, plate)");
  // The plate, when declared: a square board centred on the axis, top at z = 0. A lab may
  // record it beside the camera; vision finds the pile's base from the camera alone (a bench or
  // shelf behind the plate made its far edge no line to check against), so it is only checked
  // here, so that a typo is an error.
  if (j.contains("plate")) {
    const nlohmann::json& pl = j["plate"];
    if (!pl.is_object()) throw std::invalid_argument(path + ": plate must be an object");
    for (auto it = pl.begin(); it != pl.end(); ++it) {
      if (it.key() != "size_m" && it.key() != "thickness_m")
        throw std::invalid_argument(path + ": plate." + it.key() +
                                    " is not a plate field (known: size_m, thickness_m)");
      if (!it.value().is_number() || !(it.value().get<double>() > 0.0) ||
          !std::isfinite(it.value().get<double>()))
        throw std::invalid_argument(path + ": plate." + it.key() +
                                    " must be a positive number of metres, got " +
                                    it.value().dump());
    }
  }
  if (j.contains("view")) {
    const nlohmann::json& v = j["view"];
    if (v != "side" && v != "top")
      throw std::invalid_argument(path + ": view must be \"side\" or \"top\", got " + v.dump());
    const char* wanted = expect == SidecarView::kSide ? "side"
                         : expect == SidecarView::kTop ? "top"
                                                       : nullptr;
    if (wanted && v != wanted)
      throw std::invalid_argument(path + ": view = " + v.dump() + ", but it is given for a " +
                                  wanted + " image; give the " + wanted + " view's sidecar");
  }
  require_complete(j["camera"], path + ": camera");
  Camera cam = from_json(j["camera"], path + ": camera");
  // A sidecar's principal point lies near the image (pixel centres span [-0.5, W - 0.5]). A
  // shift lens moves it off the image, as does the twin's own pitched camera that keeps the
  // pile framed (loop-synth's camera case: cy -58 px on a 720 px image); more than an image's
  // size off is a typo that would still project, to the wrong pixels.
  const Intrinsics& ci = cam.intrinsics;
  for (const auto& [name, c, size] : {std::tuple{"intrinsics.cx_px", ci.cx_px, ci.width_px},
                                      std::tuple{"intrinsics.cy_px", ci.cy_px, ci.height_px}})
    if (c && !(*c >= -0.5 - size && *c <= 2.0 * size - 0.5))
      fail(path + ": camera", name,
           "= " + str(*c) + " must lie within one image size of the image, in [" +
               str(-0.5 - size) + ", " + str(2.0 * size - 0.5) + "]");
  for (const auto& [name, k] : {std::pair{"intrinsics.k1", cam.intrinsics.k1},
                                std::pair{"intrinsics.k2", cam.intrinsics.k2}})
    if (!(std::abs(k) <= kMaxDistortion))
      fail(path + ": camera", name,
           "= " + str(k) + " must be within +-" + str(kMaxDistortion) +
               " (a real lens's radial distortion is within +-0.5)");
  return cam;
}

}  // namespace reposetwin::camera
