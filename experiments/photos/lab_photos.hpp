// A lab's side photographs of one pile test, measured with vision/ as the twin's renders are.
//
// Design note. The same measurement reads a lab photo and a render, so the lab's angle and the
// twin's are compared like for like; this is the one place that turns a user's photo files into
// measured H, D, atan(2H/D) and flank angles, for every command that takes photos (the loop's
// measured-data CSV, a calibration campaign's target). The scale of a photo comes, in this order,
// from a camera sidecar JSON given for all photos, from a declared mm per pixel at the pile axis
// (orthographic view assumed), from a render-style sidecar STEM.json next to each photo, and last
// from the scale reference vision finds in the image. A photo that cannot be read, or that has no
// scale from any source, is an error naming the field that gave it; with several photos of one
// test, one that vision cannot measure is recorded (`unmeasured`) and the others still count. A
// photo whose pose contradicts its declared camera (vision/camera_pose.hpp: a camera pitched
// down at the pile, declared level) is refused with both pitches, whatever the other photos
// show: its camera is declared wrong, and so, most likely, are those of the same setup. So is a
// photo vision measured with a warning whose kind may bias the measure (vision::biases_measure:
// the declared camera puts the axis foot off the detected plate line), by its kind, with vision's
// numbers.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "vision/measure.hpp"

namespace reposetwin::experiments {

/// Where the photos came from, for error messages: each text names the file and the field,
/// e.g. "data.csv line 4 (test m7), column photo" or "cal.toml: key 'calibration.target_photos'".
struct LabPhotoFields {
  std::string photo;           // where the photos are listed
  std::string camera;          // where a camera sidecar for all photos is given
  std::string mm_per_px;       // where the scale is given
  std::string camera_name;     // short names of the last two, for the hint when a photo has
  std::string mm_per_px_name;  // no scale ("photo_camera", "mm_per_px")
};

/// How the photos' scale is known (both empty: each photo's own sidecar, else the scale marker).
struct LabPhotoScale {
  std::string camera_json;            // camera sidecar JSON for every photo (render convention)
  std::optional<double> mm_per_px;    // scale at the pile axis [mm/px], > 0
};

/// The photos' measurement: their combination over views and the JSON record of every view.
struct LabPhotoMeasurement {
  vision::SideSummary summary;  // means and spreads over the measured photos
  nlohmann::json record;        // summary, "views" (one per measured photo), "unmeasured"
  // The lab's camera of every photo that has one (a common camera sidecar or the photo's own),
  // in photo order: what PhotoSettings::lab_cameras takes, so the twin photographs like for like.
  std::vector<camera::Camera> cameras;
  // Vision's overlay (H and D lines, toe line, apex) of every measured photo, in the order of
  // record["views"]; empty unless asked for (the loop's page shows one per test).
  std::vector<cv::Mat> overlays;
};

/// Measures the side photos (paths as given) of one pile test. Uses one OpenCV thread, so that a
/// worker pool may fork afterwards. Throws InputError naming `fields` for an unreadable photo, a
/// bad scale, a photo without any scale, a photo whose pose contradicts its declared camera, or
/// when no photo could be measured. With `draw_overlays`, also draws each measured photo's
/// overlay (LabPhotoMeasurement::overlays).
LabPhotoMeasurement measure_lab_photos(const std::vector<std::string>& photos,
                                       const LabPhotoScale& scale, const LabPhotoFields& fields,
                                       bool draw_overlays = false);

}  // namespace reposetwin::experiments
