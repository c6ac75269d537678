// Synthetic test images for vision/: cones and footprints of known size drawn analytically.
//
// Design note. The tests must know the truth independently of the code under test, so the
// scenes are drawn from their geometry: every shape is a polygon (the cone's silhouette is the
// convex hull of its apex and base circle, projected with camera::project when a camera is
// given), filled at 4x4 supersampling and averaged down, which gives each pixel its area
// coverage like an anti-aliased render. Colours follow the shared render convention (backdrop
// grey-white, dark blue-grey plate, rock-grey pile, black/white scale bands). Optional noise,
// blur, uneven lighting, a textured backdrop and a speckled "particle" pile make the images
// harder in the ways real photos are.
#pragma once

#include <cmath>
#include <numbers>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <vector>

#include "camera/camera.hpp"

namespace reposetwin::vision::synthetic {

/// Photographic degradations shared by the scene kinds.
struct Degradation {
  double noise_sigma = 0.0;        // Gaussian pixel noise [grey levels]
  double blur_sigma_px = 0.0;      // Gaussian blur [px]
  double lighting_gradient = 0.0;  // brightness varies by +-this fraction across the image [-]
  double backdrop_texture = 0.0;   // amplitude of a smooth backdrop texture [grey levels]
  double pile_speckle = 0.0;       // per-"particle" brightness variation of the pile [-]
  int speckle_px = 5;              // size of a speckle cell [px]
  unsigned seed = 1;               // random seed
};

/// A side view of a cone on a plate, with the band scale bar.
struct SideScene {
  int width = 1280, height = 720;    // image size [px]
  double mm_per_px = 0.25;           // orthographic scale [mm/px]
  double height_mm = 60.0;           // cone height H [mm]
  double diameter_mm = 200.0;        // cone base diameter D [mm]
  double axis_u = -1.0;              // column of the cone axis [px]; < 0 = image centre
  double plate_v = 520.0;            // row of the plate line [px]
  double plate_thickness_mm = 15.0;  // plate band thickness [mm]
  // The plate's face right of the axis drawn at this fraction of the plate colour: a level view
  // facing the square plate's corner (azimuth 45 deg) shows two side faces lit differently,
  // meeting under the pile (orthographic scenes only) [-].
  double plate_right_shade = 1.0;
  double apex_radius_mm = 0.0;     // round the apex with this radius (0 = sharp) [mm]
  double top_width_mm = 0.0;       // a truncated cone: its flat top's diameter (0 = sharp) [mm]
  int strays = 0;                  // loose particles (disks) lying on the plate beyond each toe [-]
  double stray_diameter_mm = 3.0;  // their diameter [mm]
  // A monolayer of such disks lying on the plate beyond each toe, the first centred on the toe
  // (half inside the cone's foot, joined to it in the picture), centres `monolayer_pitch_mm`
  // apart, out to monolayer_mm beyond the toe (the last disk's outer edge within it). Disks
  // closer than their diameter overlap (a layer joined in the picture); farther apart, each is
  // apart from the rest. 0 = none [mm].
  double monolayer_mm = 0.0;
  double monolayer_pitch_mm = 3.0;
  // A bottom-layer particle (disk) of this diameter resting on the plate at each end of the base,
  // its outer edge at the toe, as the outermost ring of a sphere pile: near the plate it sticks
  // out of the flank with a near-vertical side. 0 = none [mm].
  double base_particle_mm = 0.0;
  double tilt_deg = 0.0;                 // whole-scene rotation about (axis_u, plate_v) [deg]
  bool pile = true;                      // draw the cone (false: the empty scene)
  bool scale_bar = true;                 // draw the band scale bar
  double bar_offset_mm = -140.0;         // lateral offset of the bar from the axis [mm]
  double band_mm = 10.0;                 // band height [mm]
  int bands = 10;                        // number of bands
  double bar_width_mm = 20.0;            // bar width [mm]
  std::optional<camera::Camera> camera;  // when set: perspective scene in metres, plate a box
  double plate_half_size_m = 0.25;       // plate half size (camera scenes) [m]
  // A bench the plate stands on (camera scenes): its top at the plate's underside, this half
  // size, 0.2 m deep, coloured kBench; 0 = none [m].
  double bench_half_size_m = 0.0;
  Degradation look;
};

/// A top view of a circular (or elliptical) footprint on the plate, with the checker card.
struct TopScene {
  int width = 1280, height = 960;           // image size [px]
  double mm_per_px = 0.25;                  // orthographic scale [mm/px]
  double diameter_mm = 200.0;               // footprint diameter (major axis) [mm]
  double minor_diameter_mm = 0.0;           // minor axis [mm]; 0 = a circle
  double center_u = -1.0, center_v = -1.0;  // footprint centre [px]; < 0 = image centre
  bool checker_card = true;                 // draw the 4x4 checker card
  double card_u = 180.0, card_v = 180.0;    // card centre [px]
  double square_mm = 10.0;                  // checker square size [mm]
  double shading = 0.0;                     // brightness ramp across the pile (+-) [-]
  std::optional<camera::Camera> camera;     // when set: footprint drawn through this camera (z = 0)
  Degradation look;
};

// BGR colours of the shared convention.
const cv::Scalar kBackdrop(220, 225, 225), kPlate(95, 80, 70), kPile(108, 115, 120),
    kBlack(20, 20, 20), kWhite(245, 245, 245), kBench(150, 165, 180);

/// Area coverage (CV_32F, 0..1) of the union of polygons given in pixel coordinates (pixel
/// centres at integers), by 4x4 supersampling.
inline cv::Mat coverage(cv::Size size, const std::vector<std::vector<cv::Point2d>>& polys) {
  constexpr int kSs = 4;
  constexpr int kShift = 8;
  cv::Mat ss(size.height * kSs, size.width * kSs, CV_8U, cv::Scalar(0));
  for (const auto& poly : polys) {
    std::vector<cv::Point> fixed;
    for (const auto& p : poly) {
      const double x = (p.x + 0.5) * kSs - 0.5, y = (p.y + 0.5) * kSs - 0.5;
      fixed.emplace_back(static_cast<int>(std::lround(x * (1 << kShift))),
                         static_cast<int>(std::lround(y * (1 << kShift))));
    }
    const cv::Point* pts = fixed.data();
    const int n = static_cast<int>(fixed.size());
    cv::fillPoly(ss, &pts, &n, 1, cv::Scalar(255), cv::LINE_8, kShift);
  }
  cv::Mat small;
  cv::resize(ss, small, size, 0, 0, cv::INTER_AREA);
  cv::Mat out;
  small.convertTo(out, CV_32F, 1.0 / 255.0);
  return out;
}

/// img = img * (1 - c) + colour * c, with an optional per-pixel brightness factor of the colour.
inline void paint(cv::Mat& img, const cv::Mat& cov, const cv::Scalar& colour,
                  const cv::Mat& factor = cv::Mat()) {
  for (int r = 0; r < img.rows; ++r) {
    cv::Vec3f* p = img.ptr<cv::Vec3f>(r);
    const float* c = cov.ptr<float>(r);
    const float* f = factor.empty() ? nullptr : factor.ptr<float>(r);
    for (int k = 0; k < img.cols; ++k) {
      if (c[k] <= 0.0f) continue;
      const float g = f ? f[k] : 1.0f;
      for (int ch = 0; ch < 3; ++ch)
        p[k][ch] = p[k][ch] * (1.0f - c[k]) + static_cast<float>(colour[ch]) * g * c[k];
    }
  }
}

/// A backdrop image (CV_32FC3) with optional smooth texture.
inline cv::Mat backdrop(cv::Size size, const Degradation& look, cv::RNG& rng) {
  cv::Mat img(size, CV_32FC3, kBackdrop);
  if (look.backdrop_texture > 0.0) {
    cv::Mat small(std::max(2, size.height / 24), std::max(2, size.width / 24), CV_32F);
    rng.fill(small, cv::RNG::NORMAL, 0.0, 1.0);
    cv::Mat tex;
    cv::resize(small, tex, size, 0, 0, cv::INTER_CUBIC);
    cv::Mat tex3;
    cv::merge(std::vector<cv::Mat>{tex, tex, tex}, tex3);
    img += tex3 * look.backdrop_texture;
  }
  return img;
}

inline cv::Mat speckle(cv::Size size, const Degradation& look, cv::RNG& rng) {
  if (look.pile_speckle <= 0.0) return cv::Mat();
  const int cell = std::max(1, look.speckle_px);
  cv::Mat small(size.height / cell + 1, size.width / cell + 1, CV_32F);
  rng.fill(small, cv::RNG::UNIFORM, 1.0 - look.pile_speckle, 1.0 + look.pile_speckle);
  cv::Mat big;
  cv::resize(small, big, cv::Size(small.cols * cell, small.rows * cell), 0, 0, cv::INTER_NEAREST);
  return big(cv::Rect(0, 0, size.width, size.height)).clone();
}

/// Lighting, blur and noise, then conversion to 8-bit BGR.
inline cv::Mat finish(cv::Mat img, const Degradation& look, cv::RNG& rng) {
  if (look.lighting_gradient != 0.0) {
    for (int r = 0; r < img.rows; ++r) {
      cv::Vec3f* p = img.ptr<cv::Vec3f>(r);
      for (int c = 0; c < img.cols; ++c) {
        const double g = 1.0 + look.lighting_gradient * (2.0 * c / img.cols - 1.0) +
                         0.5 * look.lighting_gradient * (2.0 * r / img.rows - 1.0);
        p[c] *= static_cast<float>(g);
      }
    }
  }
  if (look.blur_sigma_px > 0.0)
    cv::GaussianBlur(img, img, cv::Size(), look.blur_sigma_px, look.blur_sigma_px);
  if (look.noise_sigma > 0.0) {
    cv::Mat noise(img.size(), CV_32FC3);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, look.noise_sigma);
    img += noise;
  }
  cv::Mat out;
  img.convertTo(out, CV_8UC3);
  return out;
}

/// Projects world points to pixels with camera::project.
inline std::vector<cv::Point2d> project_all(const camera::Camera& cam,
                                            const std::vector<Eigen::Vector3d>& world) {
  std::vector<cv::Point2d> out;
  for (const auto& w : world) {
    const auto p = camera::project(cam, w);
    if (p) out.emplace_back(p->x(), p->y());
  }
  return out;
}

inline std::vector<cv::Point2d> hull(const std::vector<cv::Point2d>& pts) {
  std::vector<cv::Point2f> f(pts.begin(), pts.end());
  std::vector<cv::Point2f> h;
  cv::convexHull(f, h);
  return {h.begin(), h.end()};
}

/// How far beyond each toe the monolayer of SideScene reaches (its last disk's outer edge) [mm].
inline double monolayer_reach_mm(const SideScene& s) {
  const double rs = 0.5 * s.stray_diameter_mm;
  double reach = 0.0;
  for (double xc = 0.0; xc + rs <= s.monolayer_mm + 1e-9; xc += s.monolayer_pitch_mm)
    reach = xc + rs;
  return reach;
}

/// Draws a side scene as an 8-bit BGR image.
inline cv::Mat draw_side(const SideScene& s) {
  const cv::Size size(s.width, s.height);
  cv::RNG rng(s.look.seed);
  cv::Mat img = backdrop(size, s.look, rng);
  std::vector<std::vector<cv::Point2d>> bench, plate, plate_right, pile, black, white;
  if (!s.camera) {
    const double au = s.axis_u < 0 ? 0.5 * (s.width - 1) : s.axis_u;
    const double k = 1.0 / s.mm_per_px;
    const double t = s.tilt_deg * std::numbers::pi / 180.0;
    // Scene (x right [mm], z up [mm]) to pixels, rotated by the tilt about the axis foot.
    auto px = [&](double x, double z) {
      const double du = x * k, dv = -z * k;
      return cv::Point2d(au + du * std::cos(t) - dv * std::sin(t),
                         s.plate_v + du * std::sin(t) + dv * std::cos(t));
    };
    const double big = 4.0 * (s.width + s.height) * s.mm_per_px;
    plate.push_back(
        {px(-big, 0), px(big, 0), px(big, -s.plate_thickness_mm), px(-big, -s.plate_thickness_mm)});
    if (s.plate_right_shade != 1.0)
      plate_right.push_back(
          {px(0, 0), px(big, 0), px(big, -s.plate_thickness_mm), px(0, -s.plate_thickness_mm)});
    // The cone reaches 2 px into the plate so that it, not the plate, owns the toe row.
    const double r = 0.5 * s.diameter_mm, below = 2.0 * s.mm_per_px;
    const double rb = r * (1.0 + below / s.height_mm);
    if (s.top_width_mm > 0.0) {
      const double rt = 0.5 * s.top_width_mm;
      pile.push_back({px(-rb, -below), px(rb, -below), px(rt, s.height_mm), px(-rt, s.height_mm)});
    } else if (s.apex_radius_mm <= 0.0) {
      pile.push_back({px(-rb, -below), px(rb, -below), px(0, s.height_mm)});
    } else {
      // Apex rounded by an arc tangent to both flanks: centre on the axis rho / cos(phi) below
      // the cone's apex, tangent points at polar angles 90 deg -+ phi (the flank normals).
      const double phi = std::atan(s.height_mm / r), rho = s.apex_radius_mm;
      const double zc = s.height_mm - rho / std::cos(phi);
      std::vector<cv::Point2d> poly{px(-rb, -below), px(rb, -below)};
      for (int i = 0; i <= 180; ++i) {
        const double a = 0.5 * std::numbers::pi - phi + 2.0 * phi * i / 180.0;  // right to left
        poly.push_back(px(rho * std::cos(a), zc + rho * std::sin(a)));
      }
      pile.push_back(poly);
    }
    if (s.base_particle_mm > 0.0) {
      const double rp = 0.5 * s.base_particle_mm;
      for (double side : {-1.0, 1.0}) {
        std::vector<cv::Point2d> disk;
        for (int k = 0; k < 64; ++k)
          disk.push_back(px(side * (r - rp) + rp * std::cos(2.0 * std::numbers::pi * k / 64),
                            rp + rp * std::sin(2.0 * std::numbers::pi * k / 64)));
        pile.push_back(disk);
      }
    }
    for (int i = 0; i < s.strays; ++i) {
      const double rs = 0.5 * s.stray_diameter_mm;
      for (double side : {-1.0, 1.0}) {
        const double xc = side * (r + rs * (0.3 + 2.0 * i));  // a touching chain
        std::vector<cv::Point2d> disk;
        for (int k = 0; k < 64; ++k)
          disk.push_back(px(xc + rs * std::cos(2.0 * std::numbers::pi * k / 64),
                            rs + rs * std::sin(2.0 * std::numbers::pi * k / 64)));
        pile.push_back(disk);
      }
    }
    if (s.monolayer_mm > 0.0) {
      const double rs = 0.5 * s.stray_diameter_mm;
      for (double xc = r; xc + rs <= r + s.monolayer_mm + 1e-9; xc += s.monolayer_pitch_mm)
        for (double side : {-1.0, 1.0}) {
          std::vector<cv::Point2d> disk;
          for (int k = 0; k < 64; ++k)
            disk.push_back(px(side * xc + rs * std::cos(2.0 * std::numbers::pi * k / 64),
                              rs + rs * std::sin(2.0 * std::numbers::pi * k / 64)));
          pile.push_back(disk);
        }
    }
    if (s.scale_bar) {
      for (int i = 0; i < s.bands; ++i) {
        const double x0 = s.bar_offset_mm - 0.5 * s.bar_width_mm,
                     x1 = s.bar_offset_mm + 0.5 * s.bar_width_mm;
        std::vector<cv::Point2d> q{px(x0, i * s.band_mm), px(x1, i * s.band_mm),
                                   px(x1, (i + 1) * s.band_mm), px(x0, (i + 1) * s.band_mm)};
        (i % 2 == 0 ? black : white).push_back(q);
      }
    }
  } else {
    const camera::Camera& cam = *s.camera;
    const double L = s.plate_half_size_m, th = s.plate_thickness_mm / 1000.0;
    if (s.bench_half_size_m > 0.0) {
      std::vector<Eigen::Vector3d> b;
      for (double x : {-s.bench_half_size_m, s.bench_half_size_m})
        for (double y : {-s.bench_half_size_m, s.bench_half_size_m})
          for (double z : {-th, -th - 0.2}) b.emplace_back(x, y, z);
      bench.push_back(hull(project_all(cam, b)));
    }
    std::vector<Eigen::Vector3d> box;
    for (double x : {-L, L})
      for (double y : {-L, L})
        for (double z : {0.0, -th}) box.emplace_back(x, y, z);
    plate.push_back(hull(project_all(cam, box)));
    const double h = s.height_mm / 1000.0, r = 0.5 * s.diameter_mm / 1000.0;
    const double below = 2.0 * camera::mm_per_px_at(cam, Eigen::Vector3d(0, 0, 0)) / 1000.0;
    const double rt = 0.5 * s.top_width_mm / 1000.0;
    std::vector<Eigen::Vector3d> cone{Eigen::Vector3d(0, 0, h)};
    for (int i = 0; i < 1440; ++i) {
      const double a = 2.0 * std::numbers::pi * i / 1440;
      if (rt > 0.0) cone.emplace_back(rt * std::cos(a), rt * std::sin(a), h);
      cone.emplace_back(r * std::cos(a), r * std::sin(a), 0.0);
      const double rb = r * (1.0 + below / h);
      cone.emplace_back(rb * std::cos(a), rb * std::sin(a), -below);
    }
    pile.push_back(hull(project_all(cam, cone)));
    if (s.scale_bar) {
      // The bar stands in the vertical plane through the axis facing the camera.
      Eigen::Vector3d lateral = camera::rotation_world_to_camera(cam).row(0).transpose();
      lateral.z() = 0.0;
      lateral.normalize();
      for (int i = 0; i < s.bands; ++i) {
        const double x0 = (s.bar_offset_mm - 0.5 * s.bar_width_mm) / 1000.0,
                     x1 = (s.bar_offset_mm + 0.5 * s.bar_width_mm) / 1000.0;
        const double z0 = i * s.band_mm / 1000.0, z1 = (i + 1) * s.band_mm / 1000.0;
        (i % 2 == 0 ? black : white)
            .push_back(project_all(cam, {lateral * x0 + Eigen::Vector3d(0, 0, z0),
                                         lateral * x1 + Eigen::Vector3d(0, 0, z0),
                                         lateral * x1 + Eigen::Vector3d(0, 0, z1),
                                         lateral * x0 + Eigen::Vector3d(0, 0, z1)}));
      }
    }
  }
  if (!bench.empty()) paint(img, coverage(size, bench), kBench);
  paint(img, coverage(size, plate), kPlate);
  if (!plate_right.empty()) paint(img, coverage(size, plate_right), kPlate * s.plate_right_shade);
  if (!black.empty()) paint(img, coverage(size, black), kBlack);
  if (!white.empty()) paint(img, coverage(size, white), kWhite);
  if (s.pile) paint(img, coverage(size, pile), kPile, speckle(size, s.look, rng));
  return finish(img, s.look, rng);
}

/// Draws a top scene as an 8-bit BGR image.
inline cv::Mat draw_top(const TopScene& s) {
  const cv::Size size(s.width, s.height);
  cv::RNG rng(s.look.seed);
  cv::Mat img(size, CV_32FC3, kPlate);
  const double cu = s.center_u < 0 ? 0.5 * (s.width - 1) : s.center_u;
  const double cv_ = s.center_v < 0 ? 0.5 * (s.height - 1) : s.center_v;
  std::vector<cv::Point2d> disk;
  const double a = 0.5 * s.diameter_mm,
               b = 0.5 * (s.minor_diameter_mm > 0 ? s.minor_diameter_mm : s.diameter_mm);
  std::vector<Eigen::Vector3d> world;
  for (int i = 0; i < 1440; ++i) {
    const double t = 2.0 * std::numbers::pi * i / 1440;
    if (s.camera) {
      world.emplace_back(a / 1000.0 * std::cos(t), b / 1000.0 * std::sin(t), 0.0);
    } else {
      disk.emplace_back(cu + a / s.mm_per_px * std::cos(t), cv_ + b / s.mm_per_px * std::sin(t));
    }
  }
  if (s.camera) disk = project_all(*s.camera, world);
  if (s.checker_card) {
    std::vector<std::vector<cv::Point2d>> black, white;
    const double q = s.square_mm / s.mm_per_px;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        const double x0 = s.card_u + (i - 2) * q, y0 = s.card_v + (j - 2) * q;
        std::vector<cv::Point2d> sq{{x0, y0}, {x0 + q, y0}, {x0 + q, y0 + q}, {x0, y0 + q}};
        ((i + j) % 2 == 0 ? black : white).push_back(sq);
      }
    paint(img, coverage(size, black), kBlack);
    paint(img, coverage(size, white), kWhite);
  }
  cv::Mat factor = speckle(size, s.look, rng);
  if (s.shading != 0.0) {
    if (factor.empty()) factor = cv::Mat(size, CV_32F, cv::Scalar(1.0));
    for (int r = 0; r < s.height; ++r)
      for (int c = 0; c < s.width; ++c)
        factor.at<float>(r, c) *= static_cast<float>(
            1.0 + s.shading * std::clamp((c - cu) / (a / s.mm_per_px), -1.0, 1.0));
  }
  paint(img, coverage(size, {disk}), kPile, factor);
  return finish(img, s.look, rng);
}

}  // namespace reposetwin::vision::synthetic
