// prepare: the CPU side of a render, before any GL call: sphere colours, the undistorted canvas
// with its distortion maps, and the occlusion culling of buried spheres.
//
// Design note. These are plain functions of the scene, the camera and the options, kept apart
// from the GL code in renderer.cpp so that each reads on its own; the renderer calls them in
// this order and uploads what they return.
#pragma once

#include <Eigen/Core>
#include <array>
#include <opencv2/core.hpp>
#include <vector>

#include "camera/camera.hpp"
#include "render/scene.hpp"

namespace reposetwin::render::detail {

/// The colour of each sphere (linear 0-1 RGB) for the options' shading.
std::vector<std::array<float, 3>> sphere_colors(const Scene& scene, const RenderOptions& options);

/// The canvas drawn on: the image itself, or for a distorted lens its undistorted twin large
/// enough to hold every ray the lens sees, with the maps from output pixels to canvas pixels.
struct Canvas {
  int width = 0;
  int height = 0;
  double cx = 0.0;  // principal point on the canvas [px]
  double cy = 0.0;
  cv::Mat map_u;  // (H x W) CV_32F: canvas u for each output pixel; empty without distortion
  cv::Mat map_v;
};

/// The canvas for this camera. Throws std::invalid_argument for a lens model that folds or
/// needs too large a canvas.
Canvas make_canvas(const camera::Camera& cam);

/// Which spheres (camera-frame centres, radii; `drawn` = not clipped) can show a pixel: 0 for
/// those provably hidden behind nearer spheres (see prepare.cpp).
std::vector<char> visible_spheres(const std::vector<Eigen::Vector3d>& centres,
                                  const std::vector<double>& radii, const std::vector<char>& drawn,
                                  double f, double cx, double cy, bool ortho, int width, int height,
                                  double depth_range);

}  // namespace reposetwin::render::detail
