// The twin's photographs of its pile, measured the way the lab measures its photographs.
//
// Design note. A pile's angle is compared with the lab's only when both come from the same
// kind of image through the same measurement. render_and_measure() photographs the final pile
// with photographs.hpp's one pipeline (side views at several azimuths and the top, lab-like
// cameras and scale reference, every image measured by vision/ through its known camera),
// writes each PNG with its sidecar and an annotated overlay, and records it all in
// measurement.json, the file a campaign run, `reposetwin render` and the reports share.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "experiments/photos/photographs.hpp"

namespace reposetwin::experiments {

/// The campaign's photographs: photographs.hpp's settings with their defaults (the true camera
/// is the declared one, every file written, every side view must be measured).
using ImageSettings = PhotoSettings;

/// Photographs the pile (photographs.hpp, with the settings above: every side view must be
/// measured) into `out_dir` (side_az000.png/.json/.measured.png, ..., top.png,
/// measurement.json) and returns the measurement JSON: per-view results, the side summary
/// (theta mean and spread), the top footprint, and the settings and provenance. `centre` is the
/// pile's footprint centre when the caller has measured it (a run's PileMeasure).
/// `after_photographs` is called once the images are written and before measurement.json is
/// (a run folder records its stage there: pile/run_state.hpp).
nlohmann::json render_and_measure(const PileSpheres& pile, const std::string& out_dir,
                                  const ImageSettings& settings,
                                  const nlohmann::json& provenance = nlohmann::json::object(),
                                  std::optional<Eigen::Vector2d> centre = std::nullopt,
                                  const std::function<void()>& after_photographs = {});

/// The same for spheres given as three arrays (centres [m], radii [m], material ids).
nlohmann::json render_and_measure(const std::vector<Eigen::Vector3d>& positions,
                                  const std::vector<double>& radii,
                                  const std::vector<int>& materials, const std::string& out_dir,
                                  const ImageSettings& settings,
                                  const nlohmann::json& provenance = nlohmann::json::object());

/// The same for a run just finished in this process: its final spheres are photographed from
/// memory into RUN_DIR/images (a run read back from its files, which has none, from final.vtp).
/// Throws InputError when the run formed no pile.
nlohmann::json render_and_measure_run(const PileRun& run, const std::string& run_dir,
                                      const ImageSettings& settings,
                                      const std::function<void()>& after_photographs = {});

/// The same for a finished run folder: reads RUN_DIR/final.vtp (or `frame`, a snapshot of the
/// run's series such as "frames/frame_00012.vtp") and result.json (provenance), writes
/// RUN_DIR/images/ (RUN_DIR/images/<frame name>/ for a frame). Throws InputError when the folder
/// holds no finished run or the frame does not exist.
nlohmann::json render_and_measure_run(const std::string& run_dir, const ImageSettings& settings,
                                      const std::string& frame = "",
                                      const std::function<void()>& after_photographs = {});

}  // namespace reposetwin::experiments
