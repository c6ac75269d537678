#include "render/output.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <vector>

namespace reposetwin::render {
namespace {

namespace fs = std::filesystem;

nlohmann::json vec3(const Eigen::Vector3d& v) {
  return nlohmann::json::array({v.x(), v.y(), v.z()});
}

void write_bytes_atomic(const std::string& path, const char* data, std::size_t size) {
  const fs::path target(path);
  std::error_code ec;
  if (target.has_parent_path()) fs::create_directories(target.parent_path(), ec);
  if (ec) throw std::runtime_error(path + ": cannot create folder (" + ec.message() + ")");
  const fs::path tmp =
      target.parent_path() / (target.filename().string() + ".tmp." + std::to_string(::getpid()));
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out)
      throw std::runtime_error(path + ": cannot open " + tmp.string() + " for writing (" +
                               std::strerror(errno) + ")");
    out.write(data, static_cast<std::streamsize>(size));
    out.flush();
    if (!out) {
      const int saved = errno;  // a full disk: ENOSPC
      out.close();
      fs::remove(tmp, ec);
      throw std::runtime_error(path + ": write failed (" + std::strerror(saved) + ")");
    }
  }
  fs::rename(tmp, target, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw std::runtime_error(path + ": cannot rename the temporary file into place");
  }
}

}  // namespace

Eigen::Vector3d scale_point(const Scene& scene, View view) {
  if (view == View::kTop) return Eigen::Vector3d::Zero();
  return Eigen::Vector3d(0.0, 0.0, 0.5 * std::max(pile_extent(scene).z_max_m, 0.0));
}

nlohmann::json make_sidecar(const Scene& scene, const camera::Camera& cam,
                            const RenderOptions& options, const nlohmann::json& provenance) {
  const Eigen::Vector3d point = scale_point(scene, options.view);
  nlohmann::json scale_ref = nullptr;
  if (const auto center = scale_reference_center(scene, cam, options.view)) {
    const ScaleReference& sr = scene.scale_reference;
    if (options.view == View::kSide) {
      scale_ref = {{"kind", "band_bar"},
                   {"band_mm", sr.band_mm},
                   {"count", sr.count},
                   {"width_mm", sr.width_mm},
                   {"center_m", vec3(*center)}};
    } else {
      scale_ref = {{"kind", "checker_card"},
                   {"band_mm", sr.band_mm},
                   {"squares", sr.squares},
                   {"width_mm", sr.band_mm * sr.squares},
                   {"center_m", vec3(*center)}};
    }
  }
  return {
      {"camera", camera::to_json(cam)},
      {"view", options.view == View::kSide ? "side" : "top"},
      {"image", {{"width_px", cam.intrinsics.width_px}, {"height_px", cam.intrinsics.height_px}}},
      {"mm_per_px_at_axis", camera::mm_per_px_at(cam, point)},
      {"scale_point_m", vec3(point)},
      {"scale_reference", scale_ref},
      {"look",
       {{"backdrop_gradient", scene.backdrop.gradient},
        {"plate_texture", scene.plate.texture},
        {"tint_fraction", options.tint_fraction},
        {"tone_warmth", options.tone_warmth},
        {"shadows", options.shadows},
        {"shadow_strength", options.shadow_strength},
        {"supersample", options.supersample}}},
      {"provenance", provenance}};
}

void write_render(const std::string& stem, const cv::Mat& image, const nlohmann::json& sidecar) {
  if (image.empty()) throw std::invalid_argument(stem + ".png: image is empty");
  if (image.depth() != CV_8U)
    throw std::invalid_argument(stem + ".png: image must be 8-bit, got depth " +
                                std::to_string(image.depth()));
  std::vector<unsigned char> png;
  if (!cv::imencode(".png", image, png))
    throw std::runtime_error(stem + ".png: PNG encoding failed");
  write_bytes_atomic(stem + ".png", reinterpret_cast<const char*>(png.data()), png.size());
  const std::string text = sidecar.dump(2) + "\n";
  write_bytes_atomic(stem + ".json", text.data(), text.size());
}

cv::Mat render_and_write(Renderer& renderer, const Scene& scene, const camera::Camera& cam,
                         const RenderOptions& options, const std::string& stem,
                         const nlohmann::json& provenance) {
  cv::Mat image = renderer.render(scene, cam, options);
  write_render(stem, image, make_sidecar(scene, cam, options, provenance));
  return image;
}

std::vector<camera::Camera> write_lab_views(Renderer& renderer, const Scene& scene,
                                            const std::string& prefix,
                                            const LabCameraSettings& cameras,
                                            const RenderOptions& options,
                                            const nlohmann::json& provenance) {
  const camera::Camera side = lab_side_camera(scene, cameras);
  const camera::Camera top = lab_top_camera(scene, cameras);
  RenderOptions o = options;
  o.view = View::kSide;
  render_and_write(renderer, scene, side, o, prefix + "_side", provenance);
  o.view = View::kTop;
  render_and_write(renderer, scene, top, o, prefix + "_top", provenance);
  return {side, top};
}

}  // namespace reposetwin::render
