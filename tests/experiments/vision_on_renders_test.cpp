// Vision on the twin's own renders of piles placed by hand, so the truth is the geometry placed:
// the plate is z = 0, the apex top is at the cone's height, and the outermost sphere's reach
// sets the footprint. The photographs are taken the way the loop takes them
// (experiments/loop_sim.cpp photograph_pile): the pile centred on a plate 1.3 x its radius, no
// scale bar, 960 x 720 px, 12 pile radii away, and measured through the camera the lab declares
// (level with the plate) even when the true camera stands higher.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "../support/cone_pile.hpp"
#include "experiments/pile_images.hpp"
#include "render/renderer.hpp"
#include "render/scene.hpp"
#include "vision/measure.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;
using test_support::kConePi;
using test_support::Spheres;

constexpr double kA = 1.75e-3;  // sphere radius: 3.5 mm spheres, as the loop's piles [m]
constexpr double kH0 = 14e-3;   // dense cone height (apex top) [m]
constexpr double kR0 = 24e-3;   // dense cone base radius (bottom layer's reach) [m]

// The dense cone (tests/support/cone_pile.hpp: H = kH0, reach kR0) with, when `rings` > 0, a
// sparse monolayer around it: rings of single spheres resting on the plate (z = a), 4a apart
// radially and about 4a apart around each ring, so about one diameter of plate shows between
// neighbours. The outermost ring's centres are at radius *r1 [m].
Spheres cone_with_monolayer(int rings, double* r1 = nullptr) {
  Spheres s = test_support::make_cone(kH0, kR0, 0.0, 0.0, kA, 11, 0.3);
  sim::Rng rng(23);
  double rho = kR0 - kA;
  for (int k = 0; k < rings; ++k) {
    rho += 4.0 * kA;
    test_support::add_ring(s, 0.0, 0.0, rho, kA, kA, 4.0 * kA, rng);
  }
  if (r1) *r1 = rho;
  return s;
}

struct Photo {
  cv::Mat image;
  camera::Camera truth;     // where the camera stood
  camera::Camera declared;  // what the measurement is told: level with the plate
};

// Renders the side view at azimuth 0 with the camera `height_m` above the plate.
Photo photograph(const Spheres& s, double height_m) {
  std::vector<Eigen::Vector3d> x(s.x.begin(), s.x.end());
  render::Scene scene = centred_pile_scene(x, s.r, std::vector<int>(s.r.size(), 0));
  scene.scale_reference.enabled = false;
  render::LabCameraSettings cams;
  cams.width_px = 960;
  cams.height_px = 720;
  cams.distance_radii = 12.0;
  cams.side_height_m = height_m;
  Photo p;
  p.truth = render::lab_side_camera(scene, cams);
  p.declared = p.truth;
  p.declared.extrinsics.position.z() = 0.0;
  p.declared.extrinsics.look_at.z() = 0.0;
  static render::Renderer renderer;
  p.image = renderer.render(scene, p.truth, {});
  return p;
}

vision::SideMeasurement measure(const Photo& p, const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / "reposetwin_vision_on_renders";
  fs::create_directories(dir);
  const std::string path = (dir / (name + ".png")).string();
  cv::imwrite(path, p.image);
  const vision::SideMeasurement m = vision::measure_side_camera(p.image, p.declared, {}, path);
  cv::imwrite((dir / (name + ".measured.png")).string(), vision::draw_side_overlay(p.image, m));
  std::printf("%s: plate line z %.2f mm, H %.2f mm, D %.2f mm, theta %.2f deg\n", name.c_str(),
              1e3 * m.plate_line_z_m, 1e3 * m.height_m, 1e3 * m.diameter_m, m.theta_deg);
  return m;
}

TEST(VisionOnRenders, SparseMonolayerEdgeBelongsToThePile) {
  double r1 = 0.0;
  const Spheres s = cone_with_monolayer(4, &r1);
  const vision::SideMeasurement m = measure(photograph(s, 0.0), "sparse_edge");
  const double d_true = 2.0 * (r1 + kA);
  EXPECT_NEAR(m.plate_line_z_m, 0.0, 0.3 * kA);
  EXPECT_NEAR(m.height_m, kH0, 0.03 * kH0);
  EXPECT_NEAR(m.diameter_m, d_true, 0.05 * d_true);
}

TEST(VisionOnRenders, RaisedCameraReadsHFromTheToeLine) {
  const Spheres s = cone_with_monolayer(0);
  for (double h : {0.0, 0.005, 0.010}) {
    const vision::SideMeasurement m =
        measure(photograph(s, h), "raised_" + std::to_string(static_cast<int>(1e3 * h)) + "mm");
    EXPECT_NEAR(m.height_m, kH0, 0.03 * kH0) << h;
    EXPECT_NEAR(m.diameter_m, 2.0 * kR0, 0.03 * 2.0 * kR0) << h;
  }
}

}  // namespace
}  // namespace reposetwin::experiments
