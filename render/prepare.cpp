#include "render/prepare.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

namespace reposetwin::render::detail {
namespace {
// ---------------------------------------------------------------------------------------------
// Colours.

// SplitMix64: a counter-based hash, so particle i's tint depends only on (seed, i).
std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Distinct colours for materials (Okabe-Ito palette, readable by colour-blind readers).
constexpr std::array<Rgb, 8> kMaterialPalette = {{{230, 159, 0},
                                                  {86, 180, 233},
                                                  {0, 158, 115},
                                                  {240, 228, 66},
                                                  {0, 114, 178},
                                                  {213, 94, 0},
                                                  {204, 121, 167},
                                                  {120, 115, 108}}};

}  // namespace

std::vector<std::array<float, 3>> sphere_colors(const Scene& scene, const RenderOptions& options) {
  const std::size_t n = scene.positions.size();
  std::vector<std::array<float, 3>> colors(n);
  auto to_float = [](Rgb c) {
    return std::array<float, 3>{c.r / 255.0f, c.g / 255.0f, c.b / 255.0f};
  };
  switch (options.shading) {
    case Shading::kPhoto: {
      const std::array<float, 3> base = to_float(options.particle_color);
      const std::uint64_t seed_hash = splitmix64(options.tint_seed);
      // A brown of the grey's brightness (Rec. 601 weights 0.299, 0.587, 0.114 keep it).
      const std::array<float, 3> warm = {1.18f, 0.98f, 0.74f};
      for (std::size_t i = 0; i < n; ++i) {
        // One tone per body: a clump's components share their body's hash.
        const std::uint64_t key =
            scene.body_ids.empty() ? i : static_cast<std::uint64_t>(scene.body_ids[i]);
        const std::uint64_t h = splitmix64(seed_hash ^ key);
        const double u = static_cast<double>(h >> 11) * 0x1.0p-53;
        const float k = static_cast<float>(1.0 + options.tint_fraction * (2.0 * u - 1.0));
        float w = 0.0f;
        if (options.tone_warmth > 0.0)
          w = static_cast<float>(options.tone_warmth *
                                 (static_cast<double>(splitmix64(h) >> 11) * 0x1.0p-53));
        for (int c = 0; c < 3; ++c)
          colors[i][c] = std::min(base[c] * k * (1.0f + w * (warm[c] - 1.0f)), 1.0f);
      }
      break;
    }
    case Shading::kBySize: {
      const auto [lo, hi] = std::minmax_element(scene.radii.begin(), scene.radii.end());
      cv::Mat ramp(256, 1, CV_8UC1);
      for (int i = 0; i < 256; ++i) ramp.at<std::uint8_t>(i) = static_cast<std::uint8_t>(i);
      cv::Mat lut;
      cv::applyColorMap(ramp, lut, cv::COLORMAP_VIRIDIS);  // BGR
      const double span = *hi - *lo;
      for (std::size_t i = 0; i < n; ++i) {
        const double t = span > 0.0 ? (scene.radii[i] - *lo) / span : 0.5;
        const cv::Vec3b bgr = lut.at<cv::Vec3b>(static_cast<int>(std::lround(255.0 * t)));
        colors[i] = to_float(Rgb{bgr[2], bgr[1], bgr[0]});
      }
      break;
    }
    case Shading::kByMaterial:
      for (std::size_t i = 0; i < n; ++i) {
        const int m = scene.material_ids.empty() ? 0 : scene.material_ids[i];
        colors[i] =
            to_float(kMaterialPalette[static_cast<std::size_t>(m) % kMaterialPalette.size()]);
      }
      break;
  }
  return colors;
}

// ---------------------------------------------------------------------------------------------
// Distortion: the undistorted canvas and the maps from output pixels to canvas pixels.



Canvas make_canvas(const camera::Camera& cam) {
  Canvas c;
  const int w = cam.intrinsics.width_px;
  const int h = cam.intrinsics.height_px;
  const double f = camera::focal_px(cam);
  const double cx = camera::principal_u(cam);
  const double cy = camera::principal_v(cam);
  if (cam.intrinsics.k1 == 0.0 && cam.intrinsics.k2 == 0.0) {
    c.width = w;
    c.height = h;
    c.cx = cx;
    c.cy = cy;
    return c;
  }
  std::vector<double> us(static_cast<std::size_t>(w) * h), vs(us.size());
  double u_lo = std::numeric_limits<double>::infinity(), u_hi = -u_lo, v_lo = u_lo, v_hi = -u_lo;
  double worst = 0.0;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const Eigen::Vector2d xd((u - cx) / f, (v - cy) / f);
      const Eigen::Vector2d xu = camera::undistort_normalised(cam, xd);
      worst = std::max(worst, (camera::distort_normalised(cam, xu) - xd).norm() * f);
      const double cu = cx + f * xu.x(), cv_ = cy + f * xu.y();
      us[static_cast<std::size_t>(v) * w + u] = cu;
      vs[static_cast<std::size_t>(v) * w + u] = cv_;
      u_lo = std::min(u_lo, cu);
      u_hi = std::max(u_hi, cu);
      v_lo = std::min(v_lo, cv_);
      v_hi = std::max(v_hi, cv_);
    }
  }
  const std::string field = "camera.intrinsics.k1/k2 (" + std::to_string(cam.intrinsics.k1) + ", " +
                            std::to_string(cam.intrinsics.k2) + ")";
  if (!(worst < 1e-3) || !std::isfinite(u_lo + u_hi + v_lo + v_hi)) {
    throw std::invalid_argument("render: " + field +
                                " cannot be inverted over the image (the lens model folds)");
  }
  const double u0 = std::floor(u_lo) - 2.0, v0 = std::floor(v_lo) - 2.0;
  const double cw = std::ceil(u_hi) + 3.0 - u0, ch = std::ceil(v_hi) + 3.0 - v0;
  if (cw > std::min(4.0 * w, 16384.0) || ch > std::min(4.0 * h, 16384.0)) {
    throw std::invalid_argument("render: " + field +
                                " is too strong: the undistorted field would need a " +
                                std::to_string(cw) + " x " + std::to_string(ch) + " px canvas");
  }
  c.width = static_cast<int>(cw);
  c.height = static_cast<int>(ch);
  c.cx = cx - u0;
  c.cy = cy - v0;
  c.map_u.create(h, w, CV_32F);
  c.map_v.create(h, w, CV_32F);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * w + u;
      c.map_u.at<float>(v, u) = static_cast<float>(us[i] - u0);
      c.map_v.at<float>(v, u) = static_cast<float>(vs[i] - v0);
    }
  }
  return c;
}

// ---------------------------------------------------------------------------------------------
// Occlusion culling. Most spheres of a pile are buried: drawing them costs fragment work (the
// ray-cast depth defeats early depth tests) and changes no pixel. Per pixel we record the
// smallest "back" depth z + r of the spheres that certainly cover its centre: the ray through it
// hits such a sphere no deeper than that. The image of a sphere contains the disc of radius
// f r / z about its projected centre (the image of its cross-section facing the camera), shrunk
// here by a safety margin for the shader's float arithmetic. A sphere whose bounding box (with
// the drawn quad's margin) holds only pixels with a recorded depth clearly below its front
// z - r wins no depth test anywhere, so leaving it out gives the same bytes; a test checks that.

namespace {

struct PixelBox {
  double u_lo, u_hi, v_lo, v_hi;
};

// The bounding box of a sphere's image on the canvas [px], as the vertex shader computes it.
PixelBox sphere_box(const Eigen::Vector3d& c, double r, double f, double cx, double cy,
                    bool ortho) {
  if (ortho) {
    return {cx + f * (c.x() - r), cx + f * (c.x() + r), cy + f * (c.y() - r), cy + f * (c.y() + r)};
  }
  const double d = c.z() * c.z() - r * r;
  const double qx = std::sqrt(c.x() * c.x() + d), qy = std::sqrt(c.y() * c.y() + d);
  return {cx + f * (c.x() * c.z() - r * qx) / d, cx + f * (c.x() * c.z() + r * qx) / d,
          cy + f * (c.y() * c.z() - r * qy) / d, cy + f * (c.y() * c.z() + r * qy) / d};
}

}  // namespace

std::vector<char> visible_spheres(const std::vector<Eigen::Vector3d>& centres,
                                  const std::vector<double>& radii, const std::vector<char>& drawn,
                                  double f, double cx, double cy, bool ortho, int width, int height,
                                  double depth_range) {
  constexpr double kMarginPx = 0.02;     // inner disc shrink [px]
  constexpr double kDepthMargin = 1e-5;  // depth gap required to cull, relative to the larger
                                         // of the sphere's depth and the depth range [-]
  std::vector<float> occluder(static_cast<std::size_t>(width) * height,
                              std::numeric_limits<float>::infinity());
  const std::size_t n = centres.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (!drawn[i]) continue;
    const Eigen::Vector3d& c = centres[i];
    const double scale = ortho ? f : f / c.z();
    const double u0 = cx + scale * c.x(), v0 = cy + scale * c.y();
    const double rho = scale * radii[i] * (1.0 - 1e-4) - kMarginPx;
    if (rho <= 0.0) continue;
    // Rounded up, so a float compared below is never nearer than the true back depth.
    const float back = std::nextafter(static_cast<float>(c.z() + radii[i]),
                                      std::numeric_limits<float>::infinity());
    const int v_lo = std::max(static_cast<int>(std::ceil(v0 - rho)), 0);
    const int v_hi = std::min(static_cast<int>(std::floor(v0 + rho)), height - 1);
    for (int v = v_lo; v <= v_hi; ++v) {
      const double w = std::sqrt(std::max(rho * rho - (v - v0) * (v - v0), 0.0));
      const int u_lo = std::max(static_cast<int>(std::ceil(u0 - w)), 0);
      const int u_hi = std::min(static_cast<int>(std::floor(u0 + w)), width - 1);
      float* row = occluder.data() + static_cast<std::size_t>(v) * width;
      for (int u = u_lo; u <= u_hi; ++u) row[u] = std::min(row[u], back);
    }
  }
  std::vector<char> visible(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (!drawn[i]) continue;
    const PixelBox b = sphere_box(centres[i], radii[i], f, cx, cy, ortho);
    const double front_exact = centres[i].z() - radii[i];
    const double front_d =
        front_exact - kDepthMargin * std::max(std::abs(front_exact), depth_range);
    const float front = static_cast<float>(front_d);
    // The drawn quad's one-pixel margin, plus one for rounding.
    const int u_lo = std::max(static_cast<int>(std::floor(b.u_lo - 2.0)), 0);
    const int u_hi = std::min(static_cast<int>(std::ceil(b.u_hi + 2.0)), width - 1);
    const int v_lo = std::max(static_cast<int>(std::floor(b.v_lo - 2.0)), 0);
    const int v_hi = std::min(static_cast<int>(std::ceil(b.v_hi + 2.0)), height - 1);
    bool hidden = u_lo <= u_hi && v_lo <= v_hi;  // off the canvas: leave it to the clipper
    for (int v = v_lo; v <= v_hi && hidden; ++v) {
      const float* row = occluder.data() + static_cast<std::size_t>(v) * width;
      for (int u = u_lo; u <= u_hi; ++u) {
        if (!(row[u] < front)) {
          hidden = false;
          break;
        }
      }
    }
    visible[i] = hidden ? 0 : 1;
  }
  return visible;
}


}  // namespace reposetwin::render::detail
