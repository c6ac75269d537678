// The one way the twin photographs a pile and measures its photographs.
//
// Design note. Every command that needs the twin's angle as the lab reads it (run, render,
// campaign, calibrate, loop) goes through photograph_pile(): the pile's spheres are centred on
// the camera axis (as a lab centres its camera on the pile), rendered from the side at several
// azimuths over 180 degrees and, if asked, from the top, and every image is measured by vision/.
// What varies between callers is settings, not code:
//  * the true camera (height, lens distortion, distance) and the camera the measurement assumes
//    (the lab's declared one; by default the true one), which is how an unknown camera height
//    or distortion biases a lab's H, D and angle;
//  * image noise and the particle tint, the scale reference in the picture, which files are
//    written (PNG, sidecar, overlay);
//  * whether one side view that vision cannot measure stops the whole measurement (a campaign
//    run must not silently lose a view) or is recorded and the others still count (a small pile
//    in the loop, whose pours are repeated when no view measures).
// It works from the spheres in memory, so a run photographs its own final state without reading
// its files back. OSMesa does not survive a fork: call it in the process that uses it.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "experiments/pile/pile_record.hpp"
#include "render/scene.hpp"
#include "vision/measure.hpp"

namespace reposetwin::experiments {

/// How a pile is photographed and measured; every field has a default (the campaign's photos).
struct PhotoSettings {
  int width_px = 1920;                      // [px]
  int height_px = 1080;                     // [px]
  int side_views = 4;                       // side views spread over 180 degrees of azimuth [-]
  bool top_view = true;                     // also the top view (footprint) [-]
  double distance_radii = 12.0;             // camera distance in pile radii [-]
  double camera_height_m = 0.0;             // true side camera height above the plate [m]
  double k1 = 0.0;                          // true lens radial distortion [-]
  // The true side cameras pitched down to look at the axis foot (as a person holds a camera
  // camera_height_m above the plate), framed without a shift lens so the pitched view keeps
  // the pile in the frame; false: level cameras [-]. With lab_cameras: each aimed at the axis
  // foot from its own position.
  bool aim_at_axis_foot = false;
  std::optional<double> declared_height_m;  // height the measurement assumes; absent: the true
  std::optional<double> declared_k1;        // distortion the measurement assumes; absent: true
  double noise_sd = 0.0;                    // Gaussian image noise, grey levels (0-255) [-]
  std::uint64_t noise_seed = 1;             // seed of the noise [-]
  std::uint64_t tint_seed = 1;              // seed of the particles' tints [-]
  bool scale_reference = true;              // draw the scale bar in the picture [-]
  bool write_photos = true;                 // write each PNG with its sidecar [-]
  bool write_overlays = true;               // write each measured view's overlay PNG [-]
  bool views_must_measure = true;           // a side view vision cannot measure is an error [-]
  bool lab_look = true;  // backdrop gradient, board grain, grain tones, soft shadows
                         // (render::apply_lab_look); false = the plain flat render [-]
  // The lab's own side cameras, one per photo (read from its sidecars, camera::read_sidecar):
  // when given, the twin photographs its pile with exactly these, like for like: the same pose,
  // lens, resolution and scale, as many side views at the same azimuths; the measurement assumes
  // them (as the lab declares them; declared_height_m / declared_k1 still override). width_px,
  // height_px, side_views, distance_radii, camera_height_m and k1 then do not apply to the side
  // views. Empty: the twin frames its own cameras from the pile's size.
  std::vector<camera::Camera> lab_cameras;
  // With lab_cameras, the cameras the measurement assumes and the sidecars carry, one per lab
  // camera, when the true cameras differ from the declared ones (the loop's measurement
  // effects: a lab camera really higher, or distorted, than its sidecar says). Empty: the lab
  // cameras themselves (declared_height_m / declared_k1 applied).
  std::vector<camera::Camera> declared_cameras;
  std::optional<camera::Camera> lab_top_camera;  // the same for the top view
  // Fixtures standing in the picture besides the plate (the funnel of a mid-run frame, at its
  // position then), on the world z axis; with any, the pile is not re-centred, since the
  // funnel's axis is the pile's [m].
  std::vector<render::Shell> shells;
  // Not empty: the picture is not of a settled pile (a mid-run frame); the sentence is stamped
  // on every overlay, so no overlay passes for a pile's measurement.
  std::string warning;
};

/// The settings as JSON, every field (the pile service keys photographs by it).
nlohmann::json to_json(const PhotoSettings& s);

/// One side view.
struct SideView {
  double azimuth_deg = 0.0;
  camera::Camera camera;                            // the camera the view was taken with
  std::string stem;                                 // "side_az045": file names stem.png, ...
  std::optional<vision::SideMeasurement> measured;  // absent: vision could not measure it
  std::string error;                                // why not (when absent)
};

/// What the photographs measured.
struct PilePhotos {
  std::vector<SideView> sides;                 // in azimuth order
  std::optional<vision::SideSummary> summary;  // over the measured side views; absent: none
  Eigen::Vector2d centre_shift = Eigen::Vector2d::Zero();  // footprint centre moved to the axis
  bool top_taken = false;
  std::optional<vision::TopMeasurement> top;  // absent when not taken or not measurable
  std::string top_error;                      // why the top view was not measurable
  std::string gl;                             // the GL implementation that rendered
};

/// The render scene of a pile: the spheres moved so that `centre` (the footprint centre) is on
/// the camera axis, on a plate wider than the footprint (1.3 x its radius), as a lab sets up its
/// photograph. Without `centre`, the footprint centre is measured (sim/pile_geometry defaults).
/// `shift`, when given, receives the centre that was moved to the axis [m]. A clump pile's
/// spheres are its components (PileSpheres), so every component is drawn as the sphere it is.
render::Scene centred_pile_scene(const PileSpheres& pile,
                                 std::optional<Eigen::Vector2d> centre = std::nullopt,
                                 Eigen::Vector2d* shift = nullptr);

/// Photographs `pile` with `settings` into `out_dir` (files only as the settings ask; sidecars
/// carry `provenance`) and measures every photograph with vision/ through the declared camera.
/// `centre` as for centred_pile_scene. Throws InputError for settings out of range, and the
/// vision error of the first side view that fails when settings.views_must_measure. With
/// settings.lab_cameras, the side views are theirs (in the order given).
PilePhotos photograph_pile(const PileSpheres& pile, const PhotoSettings& settings,
                           const std::string& out_dir, const nlohmann::json& provenance = nullptr,
                           std::optional<Eigen::Vector2d> centre = std::nullopt);

/// The bytes of `image` encoded as the extension of `path` says (PNG when it has none). Throws
/// std::runtime_error naming the path when OpenCV cannot encode it.
std::string encode_image(const std::string& path, const cv::Mat& image);

/// Writes an image (PNG, or the format of the path's extension) encoded in memory and published
/// atomically (io/files.hpp): a full disk or an unwritable folder is an error naming the
/// path, and never leaves half an image. Every image the experiments write goes through it.
void write_image_atomic(const std::string& path, const cv::Mat& image);

}  // namespace reposetwin::experiments
