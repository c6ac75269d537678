// The twin's photographs of its pile, measured the way the lab measures its photographs.
//
// Design note. A pile's angle is compared with the lab's only when both come from the same
// kind of image through the same measurement. render_and_measure() photographs the final pile
// from the side at several azimuths and from the top (render/, lab-like cameras and scale
// reference), measures every image with vision/ through its known camera (perspective
// corrected), writes each PNG with its sidecar and an annotated overlay, and combines the side
// views into a mean and spread. The pile is first centred on the camera axis, as a lab centres
// its camera on the pile.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "render/scene.hpp"

namespace reposetwin::experiments {

struct ImageSettings {
  int width_px = 1920;            // [px]
  int height_px = 1080;           // [px]
  int side_views = 4;             // side views spread over 180 degrees of azimuth [-]
  bool top_view = true;           // also the top view (footprint) [-]
  double camera_height_m = 0.0;   // side camera height above the plate (0 = level) [m]
  double distance_radii = 12.0;   // camera distance in pile radii (at least 10) [-]
  double k1 = 0.0;                // lens radial distortion of the side camera [-]
  std::uint64_t tint_seed = 1;    // particle tint seed
};

/// The render scene of a pile: the spheres moved so the footprint centre is on the camera axis,
/// on a plate wider than the footprint (1.3 x its radius), as a lab sets up its photograph.
/// `shift`, when given, receives the footprint centre that was moved to the axis [m].
render::Scene centred_pile_scene(const std::vector<Eigen::Vector3d>& positions,
                                 const std::vector<double>& radii,
                                 const std::vector<int>& materials,
                                 Eigen::Vector2d* shift = nullptr);

/// Renders and measures the pile of spheres (centres [m], radii [m], material ids) into
/// `out_dir` (side_az000.png/.json/.measured.png, ..., top.png, measurement.json) and returns
/// the measurement JSON: per-view results, the side summary (theta mean and spread), the top
/// footprint, and the settings and provenance.
nlohmann::json render_and_measure(const std::vector<Eigen::Vector3d>& positions,
                                  const std::vector<double>& radii,
                                  const std::vector<int>& materials, const std::string& out_dir,
                                  const ImageSettings& settings,
                                  const nlohmann::json& provenance = nlohmann::json::object());

/// The same for a finished run folder: reads RUN_DIR/final.vtp (or `frame`, a snapshot of the
/// run's series such as "frames/frame_00012.vtp") and result.json (provenance), writes
/// RUN_DIR/images/ (RUN_DIR/images/<frame name>/ for a frame). Throws InputError when the folder
/// holds no finished run or the frame does not exist.
nlohmann::json render_and_measure_run(const std::string& run_dir, const ImageSettings& settings,
                                      const std::string& frame = "");

}  // namespace reposetwin::experiments
