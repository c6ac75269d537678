// renderer: offscreen pictures of a pile of spheres as the lab's cameras would take them.
//
// Design note. A pile holds 1e4 to 1e6 spheres, and the measurement wants their silhouettes
// exact, so spheres are not meshed: each is one instanced screen-space quad bounding its
// projection, and the fragment shader casts the pixel's ray at the sphere, discards misses and
// writes the hit's depth (gl_FragDepth), which is exact for any sphere size at a cost of a few
// dozen flops per covered pixel. The plate, funnel or column and the scale reference are small
// triangle meshes drawn with the same projection.
//
// The projection reproduces camera::project exactly: positions go to the camera frame on the CPU
// in double precision, and the GL projection maps u = cx + f x / z (or cx + f x) to the pixel
// whose centre is at integer u, rows top first. Lens distortion is not something a linear
// projection can do, so a distorted camera is rendered as its undistorted twin on a canvas large
// enough to hold every ray the lens sees, then warped with cv::remap through maps computed from
// camera::undistort_normalised: every point lands where camera::project puts it.
//
// Speed: the ray-cast depth defeats llvmpipe's early depth test, so every sphere drawn costs its
// full footprint. Spheres provably buried behind others (checked per pixel on the CPU against
// the discs certainly covered by nearer spheres) are not drawn: most of a pile seen from the side.
// The test suite checks that this changes no byte.
//
// The lab-photograph look (scene.hpp's apply_lab_look) adds, still in one GL pass each: a
// backdrop paper graded across the frame (a quad drawn first), a board grain on the plate
// (procedural noise in the mesh shader, shaders.hpp), a tone per grain (per body for clumps) and
// soft shadows by shadow mapping: the spheres are first drawn by the same ray-casting shader
// into a depth texture seen along the light (shadow_map.hpp), then every fragment of the main
// pass counts the lit taps of a fixed percentage-closer kernel around itself in that map.
//
// Determinism: fixed draw order, no blending, per-particle tints from a counter-based hash of
// (seed, index); llvmpipe's tiled rasterisation is deterministic, so the same input gives the
// same bytes.
#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "camera/camera.hpp"
#include "render/scene.hpp"

namespace reposetwin::render {

/// Where the time of the last render went [s], for benchmarks.
struct RenderProfile {
  double prepare_s = 0.0;   // validation, distortion maps, camera-frame transforms, colours
  double draw_s = 0.0;      // upload and rasterisation (GL, finished)
  double readback_s = 0.0;  // glReadPixels
  double warp_s = 0.0;      // distortion warp (cv::remap); 0 without distortion
  std::size_t spheres_drawn = 0;
  int shadow_map_px = 0;  // side of the shadow map drawn [px]; 0 without shadows
};

/// Owns an offscreen GL context, the shaders and the buffers; reuse one for many renders.
/// Not thread-safe: use one per thread.
class Renderer {
 public:
  /// Creates the context and compiles the shaders. Throws std::runtime_error on GL failure.
  Renderer();
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// Renders the scene through `cam` at the camera's resolution: an 8-bit BGR image, top row
  /// first. Throws std::invalid_argument on bad input (see validate(scene, cam, options)).
  cv::Mat render(const Scene& scene, const camera::Camera& cam, const RenderOptions& options = {});

  /// The timing of the last successful render.
  const RenderProfile& last_profile() const;

  /// The GL version and renderer strings, for provenance.
  std::string gl_description() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// One-shot convenience: a fresh Renderer for a single image.
cv::Mat render_image(const Scene& scene, const camera::Camera& cam,
                     const RenderOptions& options = {});

}  // namespace reposetwin::render
