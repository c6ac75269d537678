// output: a render's PNG and its JSON sidecar (camera, scale, scale reference, provenance).
//
// Design note. A measurement on a render must be checkable against the particles, so every image
// travels with a sidecar that says how it was taken (the camera, in camera::to_json's form, which
// vision reads back with camera::read_sidecar), how large a pixel is at the pile's axis, and
// where the scale reference stands; keys per notes/marker.md. Both files are written to a
// temporary name and renamed into place, so a reader never sees half a file.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "camera/camera.hpp"
#include "render/renderer.hpp"
#include "render/scene.hpp"

namespace reposetwin::render {

/// The point where the sidecar's scale (mm per pixel) is taken: (0, 0, 0) for the top view; on
/// the axis at half the pile height (max(z + r) / 2, or z = 0 for a pile below the plate) for the
/// side view [m].
Eigen::Vector3d scale_point(const Scene& scene, View view);

/// The sidecar for a render of `scene` through `cam`: keys "camera", "view", "image",
/// "mm_per_px_at_axis", "scale_point_m", "scale_reference" (object or null) and "provenance"
/// (passed through unchanged; null when not given).
nlohmann::json make_sidecar(const Scene& scene, const camera::Camera& cam,
                            const RenderOptions& options,
                            const nlohmann::json& provenance = nullptr);

/// Writes `image` to STEM.png and `sidecar` to STEM.json, each atomically (temporary file in the
/// same folder, then rename). Creates missing parent folders. Throws std::runtime_error naming
/// the path on failure, std::invalid_argument for an empty or non-8-bit image.
void write_render(const std::string& stem, const cv::Mat& image, const nlohmann::json& sidecar);

/// Renders `scene` through `cam` and writes STEM.png and STEM.json (make_sidecar + write_render).
/// Returns the image.
cv::Mat render_and_write(Renderer& renderer, const Scene& scene, const camera::Camera& cam,
                         const RenderOptions& options, const std::string& stem,
                         const nlohmann::json& provenance = nullptr);

/// Renders the lab's two views of the scene (lab_side_camera, lab_top_camera) and writes
/// PREFIX_side.png/.json and PREFIX_top.png/.json; `options.view` is set per view. Returns the
/// two cameras used, side first.
std::vector<camera::Camera> write_lab_views(Renderer& renderer, const Scene& scene,
                                            const std::string& prefix,
                                            const LabCameraSettings& cameras = {},
                                            const RenderOptions& options = {},
                                            const nlohmann::json& provenance = nullptr);

}  // namespace reposetwin::render
