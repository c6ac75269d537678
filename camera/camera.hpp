// camera: the plain description of a camera that render/ draws with and vision/ measures with.
//
// Design note. The lab photographs the pile; the twin renders it; vision measures both. For the
// comparison to be like for like, the renderer and the measurement must agree on one camera
// model, and neither may depend on the other. This small module is that agreement: a struct of
// intrinsics and extrinsics, the projection of a world point to a pixel (the renderer must put a
// point exactly there), the inverse ray (vision uses it to undo perspective), and a JSON sidecar.
//
// Conventions (used everywhere in ReposeTwin):
//  - World frame: SI metres, z up, the base plate is the plane z = 0, the pile axis is the z axis.
//  - Camera frame: OpenCV's: x right, y down, z forward (along the viewing direction).
//  - Pixels: (u, v), u to the right, v downwards; pixel centres sit at integer coordinates, so an
//    image of width W spans u in [-0.5, W - 0.5]. The principal point defaults to the image centre
//    ((W - 1) / 2, (H - 1) / 2).
//  - Lens distortion: Brown's radial model on normalised coordinates,
//    x_d = x (1 + k1 r^2 + k2 r^4), as in OpenCV's calibrateCamera (p1 = p2 = k3 = 0).
#pragma once

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>

namespace reposetwin::camera {

enum class Projection { kPerspective, kOrthographic };

/// Lens and sensor. Square pixels.
struct Intrinsics {
  int width_px = 1920;             // image width [px]
  int height_px = 1080;            // image height [px]
  double focal_length_mm = 50.0;   // lens focal length [mm] (perspective only)
  double sensor_width_mm = 36.0;   // sensor width [mm]; full-frame by default (perspective only)
  double ortho_width_m = 0.4;      // world width spanned by the image width [m] (orthographic only)
  double k1 = 0.0;                 // radial distortion, r^2 term [-]
  double k2 = 0.0;                 // radial distortion, r^4 term [-]
  std::optional<double> cx_px;     // principal point u [px]; default (W - 1) / 2
  std::optional<double> cy_px;     // principal point v [px]; default (H - 1) / 2
};

/// Pose: where the camera stands and what it looks at.
struct Extrinsics {
  Eigen::Vector3d position{0.0, -2.0, 0.0};  // camera centre in the world [m]
  Eigen::Vector3d look_at{0.0, 0.0, 0.0};    // a point on the optical axis [m]
  Eigen::Vector3d up{0.0, 0.0, 1.0};         // world direction that appears upwards in the image
};

struct Camera {
  std::string name = "side";  // free label ("side", "top", "side_az045", ...)
  Projection projection = Projection::kPerspective;
  Intrinsics intrinsics;
  Extrinsics extrinsics;
};

/// A ray in the world: origin + t * direction, direction of unit length.
struct Ray {
  Eigen::Vector3d origin;
  Eigen::Vector3d direction;
};

/// Throws std::invalid_argument naming the field and value when the description is unusable
/// (non-positive resolution or focal length, camera at its look-at point, up parallel to the
/// viewing direction, ...). `where` prefixes the message (for example the sidecar's path).
void validate(const Camera& cam, const std::string& where = "camera");

/// Focal length in pixels (perspective) or pixels per metre (orthographic).
double focal_px(const Camera& cam);
double principal_u(const Camera& cam);
double principal_v(const Camera& cam);

/// World-to-camera rotation (rows are the camera's x, y, z axes in world coordinates).
Eigen::Matrix3d rotation_world_to_camera(const Camera& cam);

/// A world point in camera coordinates (x right, y down, z forward) [m].
Eigen::Vector3d to_camera_frame(const Camera& cam, const Eigen::Vector3d& world);

/// Applies / removes the radial distortion on normalised image coordinates.
Eigen::Vector2d distort_normalised(const Camera& cam, const Eigen::Vector2d& xy);
Eigen::Vector2d undistort_normalised(const Camera& cam, const Eigen::Vector2d& xy_distorted);

/// Projects a world point to its pixel (distortion included). For a perspective camera the point
/// must lie in front of the camera (z_cam > 0); otherwise std::nullopt.
std::optional<Eigen::Vector2d> project(const Camera& cam, const Eigen::Vector3d& world);

/// The world ray through a pixel (distortion removed).
Ray unproject(const Camera& cam, const Eigen::Vector2d& pixel);

/// Intersects the ray through `pixel` with the plane through `point` with normal `normal`.
std::optional<Eigen::Vector3d> pixel_on_plane(const Camera& cam, const Eigen::Vector2d& pixel,
                                              const Eigen::Vector3d& point,
                                              const Eigen::Vector3d& normal);

/// Size of one pixel at a world point, measured in a plane facing the camera [mm/px].
double mm_per_px_at(const Camera& cam, const Eigen::Vector3d& world);

/// A lab-like side view: level with the plate (camera height `height_m`), looking horizontally at
/// the pile axis from `distance_m`, at azimuth `azimuth_deg` about the z axis (0 = from -y).
/// The focal length is chosen so that a field `field_width_m` wide at the axis fills the image.
Camera side_view(double distance_m, double field_width_m, double height_m = 0.0,
                 double azimuth_deg = 0.0, int width_px = 1920, int height_px = 1080);

/// A lab-like top view straight down the z axis from `height_m`, image up = world +y.
Camera top_view(double height_m, double field_width_m, int width_px = 1920, int height_px = 1080);

nlohmann::json to_json(const Camera& cam);
/// Parses a camera from JSON, rejecting unknown keys; errors name `where` and the field.
Camera from_json(const nlohmann::json& j, const std::string& where = "camera");

/// Which image a sidecar is read for: its "view", when it states one, must match.
enum class SidecarView { kAny, kSide, kTop };

/// Reads a render's or the lab's sidecar JSON (its "camera" object) from a file. Strict: every
/// value the projection uses is required (the distortion and the principal point default to
/// none and the image centre), an unknown top-level field, an absurd distortion (|k| > 1) and a
/// "view" other than `expect` are refused. Throws std::invalid_argument naming the file and the
/// field.
Camera read_sidecar(const std::string& path, SidecarView expect = SidecarView::kAny);

}  // namespace reposetwin::camera
