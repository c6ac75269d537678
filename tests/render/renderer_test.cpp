// Rendered pixels checked against the camera model and closed forms: no stored images.
#include "render/renderer.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "camera/camera.hpp"
#include "render/gl_context.hpp"
#include "render/scene.hpp"

namespace reposetwin::render {
namespace {

using camera::Camera;
using camera::Projection;

// A 320 x 240 perspective camera at `position` looking at `look_at`, z up.
Camera small_camera(const Eigen::Vector3d& position, const Eigen::Vector3d& look_at,
                    double focal_mm = 24.0) {
  Camera cam;
  cam.intrinsics.width_px = 320;
  cam.intrinsics.height_px = 240;
  cam.intrinsics.focal_length_mm = focal_mm;
  cam.intrinsics.sensor_width_mm = 36.0;
  cam.extrinsics.position = position;
  cam.extrinsics.look_at = look_at;
  cam.extrinsics.up = Eigen::Vector3d(0, 0, 1);
  return cam;
}

// One sphere, no fixtures, flat colour (ambient only), so every covered pixel differs from the
// backdrop by the same amount.
Scene one_sphere(const Eigen::Vector3d& c, double r) {
  Scene s;
  s.positions = {c};
  s.radii = {r};
  s.plate.enabled = false;
  s.scale_reference.enabled = false;
  return s;
}

RenderOptions flat() {
  RenderOptions o;
  o.ambient = 1.0;
  o.diffuse = 0.0;
  o.tint_fraction = 0.0;
  return o;
}

struct Blob {
  double area = 0.0;  // [px^2], coverage-weighted
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
};

// Coverage of each pixel = its blue-channel departure from the backdrop over the full contrast
// (exact for an unlit sphere, including pixels blended by the distortion warp).
Blob measure(const cv::Mat& img, const Scene& scene, const RenderOptions& o) {
  const double bg = scene.backdrop.color.b;
  const double fg = o.particle_color.b;
  Blob b;
  for (int v = 0; v < img.rows; ++v) {
    for (int u = 0; u < img.cols; ++u) {
      const double w = std::clamp((bg - img.at<cv::Vec3b>(v, u)[0]) / (bg - fg), 0.0, 1.0);
      b.area += w;
      b.centroid += w * Eigen::Vector2d(u, v);
    }
  }
  b.centroid /= b.area;
  return b;
}

// The exact image of a sphere under a pinhole camera: the conic cut by the plane z = 1 from the
// cone of rays tangent to the sphere, (X . c)^2 = cos^2(alpha) |X|^2 |c|^2, X = (x, y, 1).
// Returns its centre [px] and the radius of the circle of equal area [px].
std::pair<Eigen::Vector2d, double> exact_ellipse(const Camera& cam, const Eigen::Vector3d& world,
                                                 double r) {
  const Eigen::Vector3d c = camera::to_camera_frame(cam, world);
  const Eigen::Matrix3d q =
      c * c.transpose() - (c.squaredNorm() - r * r) * Eigen::Matrix3d::Identity();
  // The conic x^T A x + 2 b^T x + k = 0 in normalised coordinates (sign chosen so the inside is
  // positive: q(X) > 0 inside the cone).
  const Eigen::Matrix2d a = -q.topLeftCorner<2, 2>();
  const Eigen::Vector2d b = -q.topRightCorner<2, 1>();
  const double k = -q(2, 2);
  const Eigen::Vector2d x0 = -a.inverse() * b;
  const double rhs = b.dot(a.inverse() * b) - k;
  const double area_n = M_PI * rhs / std::sqrt(a.determinant());
  const double f = camera::focal_px(cam);
  const Eigen::Vector2d centre(camera::principal_u(cam) + f * x0.x(),
                               camera::principal_v(cam) + f * x0.y());
  return {centre, f * std::sqrt(area_n / M_PI)};
}

class RendererTest : public ::testing::Test {
 protected:
  static Renderer& renderer() {
    static Renderer r;
    return r;
  }
};

TEST_F(RendererTest, ContextIsOpenGl45Core) {
  const std::string d = renderer().gl_description();
  EXPECT_EQ(d.rfind("4.5", 0), 0u) << d;
  EXPECT_NE(d.find("Core"), std::string::npos) << d;
}

TEST_F(RendererTest, ImageHasCameraResolutionAndBackdrop) {
  const Scene s = one_sphere(Eigen::Vector3d(0, 0, 0), 0.01);
  const Camera cam = small_camera(Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 0, 0));
  const cv::Mat img = renderer().render(s, cam, flat());
  ASSERT_EQ(img.cols, 320);
  ASSERT_EQ(img.rows, 240);
  ASSERT_EQ(img.type(), CV_8UC3);
  const cv::Vec3b corner = img.at<cv::Vec3b>(0, 0);  // BGR
  EXPECT_EQ(corner, cv::Vec3b(220, 225, 225));
}

TEST_F(RendererTest, SphereOnAxisMatchesProjectionPerspective) {
  const Eigen::Vector3d c(0.003, 0.0, 0.002);
  const double r = 0.05;
  const Scene s = one_sphere(c, r);
  const Camera cam = small_camera(Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 0, 0), 50.0);
  const RenderOptions o = flat();
  const Blob blob = measure(renderer().render(s, cam, o), s, o);
  const Eigen::Vector2d p = *camera::project(cam, c);
  EXPECT_NEAR(blob.centroid.x(), p.x(), 0.5);
  EXPECT_NEAR(blob.centroid.y(), p.y(), 0.5);
  // On the axis the outline is a circle of radius f tan(alpha), sin(alpha) = r / distance.
  const double d = camera::to_camera_frame(cam, c).norm();
  const double expected_r = camera::focal_px(cam) * r / std::sqrt(d * d - r * r);
  EXPECT_NEAR(std::sqrt(blob.area / M_PI), expected_r, 0.5);
  EXPECT_GT(expected_r, 20.0);
}

TEST_F(RendererTest, SphereOffAxisMatchesExactEllipsePerspective) {
  // Far off the axis the outline is an ellipse whose centre lies outward of project(centre).
  const Eigen::Vector3d c(0.45, 0.0, -0.3);
  const double r = 0.08;
  const Scene s = one_sphere(c, r);
  const Camera cam = small_camera(Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 0, 0));
  const RenderOptions o = flat();
  const Blob blob = measure(renderer().render(s, cam, o), s, o);
  const auto [centre, radius] = exact_ellipse(cam, c, r);
  EXPECT_NEAR(blob.centroid.x(), centre.x(), 0.5);
  EXPECT_NEAR(blob.centroid.y(), centre.y(), 0.5);
  EXPECT_NEAR(std::sqrt(blob.area / M_PI), radius, 0.5);
  // And the projected centre is not far from it (the sphere is where the model says).
  const Eigen::Vector2d p = *camera::project(cam, c);
  EXPECT_NEAR((blob.centroid - p).norm(), (centre - p).norm(), 0.5);
}

TEST_F(RendererTest, SphereMatchesProjectionOrthographic) {
  const Eigen::Vector3d c(0.06, 0.02, -0.04);
  const double r = 0.03;
  const Scene s = one_sphere(c, r);
  Camera cam = small_camera(Eigen::Vector3d(0.0, -1.0, 0.0), Eigen::Vector3d(0, 0, 0));
  cam.projection = Projection::kOrthographic;
  cam.intrinsics.ortho_width_m = 0.4;
  cam.intrinsics.cx_px = 150.25;  // an off-centre principal point must be honoured too
  const RenderOptions o = flat();
  const Blob blob = measure(renderer().render(s, cam, o), s, o);
  const Eigen::Vector2d p = *camera::project(cam, c);
  EXPECT_NEAR(blob.centroid.x(), p.x(), 0.5);
  EXPECT_NEAR(blob.centroid.y(), p.y(), 0.5);
  EXPECT_NEAR(std::sqrt(blob.area / M_PI), camera::focal_px(cam) * r, 0.5);
}

TEST_F(RendererTest, SupersampledSphereKeepsCentroidAndArea) {
  // Anti-aliased by 3 x 3 supersampling: same centroid and area, and partial edge pixels.
  const Eigen::Vector3d c(0.021, 0.0, -0.013);
  const double r = 0.03;
  const Scene s = one_sphere(c, r);
  const Camera cam = small_camera(Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 0, 0), 50.0);
  RenderOptions o = flat();
  o.supersample = 3;
  const cv::Mat img = renderer().render(s, cam, o);
  ASSERT_EQ(img.cols, 320);
  const Blob blob = measure(img, s, o);
  const auto [centre, radius] = exact_ellipse(cam, c, r);
  EXPECT_NEAR(blob.centroid.x(), centre.x(), 0.2);
  EXPECT_NEAR(blob.centroid.y(), centre.y(), 0.2);
  EXPECT_NEAR(std::sqrt(blob.area / M_PI), radius, 0.2);
  int partial = 0;
  for (int v = 0; v < img.rows; ++v)
    for (int u = 0; u < img.cols; ++u) {
      const int b = img.at<cv::Vec3b>(v, u)[0];
      if (b > 110 && b < 218) ++partial;
    }
  EXPECT_GT(partial, 20);
}

TEST_F(RendererTest, PrincipalPointShiftsTheImage) {
  const Eigen::Vector3d c(0.0, 0.0, 0.0);
  const Scene s = one_sphere(c, 0.03);
  Camera cam = small_camera(Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 0, 0), 50.0);
  cam.intrinsics.cx_px = 120.0;
  cam.intrinsics.cy_px = 140.0;
  const RenderOptions o = flat();
  const Blob blob = measure(renderer().render(s, cam, o), s, o);
  EXPECT_NEAR(blob.centroid.x(), 120.0, 0.5);
  EXPECT_NEAR(blob.centroid.y(), 140.0, 0.5);
}

TEST_F(RendererTest, OverlappingSpheresOccludeInDepthOrder) {
  // Sphere 0 (material 0, orange) is nearer; sphere 1 (material 1, blue) behind it, larger.
  const Camera cam = small_camera(Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 0, 0), 50.0);
  RenderOptions o;
  o.shading = Shading::kByMaterial;
  for (const bool near_first : {true, false}) {
    Scene s;
    s.plate.enabled = false;
    s.scale_reference.enabled = false;
    const Eigen::Vector3d near_c(-0.02, -0.1, 0.0), far_c(0.03, 0.1, 0.0);
    s.positions = near_first ? std::vector<Eigen::Vector3d>{near_c, far_c}
                             : std::vector<Eigen::Vector3d>{far_c, near_c};
    s.radii = near_first ? std::vector<double>{0.05, 0.08} : std::vector<double>{0.08, 0.05};
    s.material_ids = near_first ? std::vector<int>{0, 1} : std::vector<int>{1, 0};
    const cv::Mat img = renderer().render(s, cam, o);
    // The near sphere's centre pixel is also inside the far sphere's outline: it must be orange
    // (R > B); the far sphere's centre is outside the near one's outline: blue (B > R).
    const Eigen::Vector2d pn = *camera::project(cam, near_c);
    const Eigen::Vector2d pf = *camera::project(cam, far_c);
    const cv::Vec3b at_near = img.at<cv::Vec3b>(std::lround(pn.y()), std::lround(pn.x()));
    const cv::Vec3b at_far = img.at<cv::Vec3b>(std::lround(pf.y()), std::lround(pf.x() + 10));
    EXPECT_GT(at_near[2], at_near[0] + 50) << "near_first=" << near_first;
    EXPECT_GT(at_far[0], at_far[2] + 50) << "near_first=" << near_first;
    // The overlap really exists: the far sphere's outline reaches the near centre.
    const auto [fc, fr] = exact_ellipse(cam, far_c, 0.08);
    ASSERT_LT((fc - pn).norm(), fr - 3.0);
  }
}

Scene random_pile(int n, std::uint64_t seed) {
  Scene s;
  std::uint64_t x = seed;
  auto next = [&x]() {
    x = x * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(x >> 11) * 0x1.0p-53;
  };
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * M_PI * next();
    const double rho = 0.1 * std::sqrt(next());
    const double z = (0.1 - rho) * 0.7 * next();
    s.positions.emplace_back(rho * std::cos(a), rho * std::sin(a), z + 0.004);
    s.radii.push_back(0.002 + 0.002 * next());
    s.material_ids.push_back(i % 3);
  }
  return s;
}

TEST_F(RendererTest, SameInputRendersBitIdentically) {
  const Scene s = random_pile(3000, 7);
  const Camera side = lab_side_camera(s, {.width_px = 320, .height_px = 240});
  RenderOptions o;
  const cv::Mat a = renderer().render(s, side, o);
  const cv::Mat b = renderer().render(s, side, o);
  Renderer fresh;
  const cv::Mat c = fresh.render(s, side, o);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(a, c, cv::NORM_INF), 0.0);
  // The comparison can fail: another tint seed changes the picture.
  o.tint_seed = 2;
  EXPECT_GT(cv::norm(a, renderer().render(s, side, o), cv::NORM_INF), 0.0);
}

TEST_F(RendererTest, OcclusionCullingChangesNoPixel) {
  // A dense pile seen from the side and from above: culling must skip many buried spheres and
  // leave every byte as it was.
  const Scene s = random_pile(6000, 11);
  for (const View view : {View::kSide, View::kTop}) {
    const Camera cam = view == View::kSide ? lab_side_camera(s, {.width_px = 480, .height_px = 270})
                                           : lab_top_camera(s, {.width_px = 480, .height_px = 270});
    RenderOptions o;
    o.view = view;
    o.occlusion_culling = false;
    const cv::Mat all = renderer().render(s, cam, o);
    EXPECT_EQ(renderer().last_profile().spheres_drawn, s.positions.size());
    o.occlusion_culling = true;
    const cv::Mat culled = renderer().render(s, cam, o);
    // From the side most of this pile is buried; from above its grains are 1 to 3 px wide, too
    // small for certain cover, so some but fewer are skipped.
    EXPECT_LT(renderer().last_profile().spheres_drawn,
              view == View::kSide ? s.positions.size() * 3 / 4 : s.positions.size())
        << (view == View::kSide ? "side" : "top");
    EXPECT_EQ(cv::norm(all, culled, cv::NORM_INF), 0.0);
  }
}

TEST_F(RendererTest, PhotoTintStaysWithinItsBand) {
  // 7 x 5 separated spheres, unlit: each centre pixel is the rock grey times (1 + t),
  // |t| <= tint_fraction, and the tints do differ.
  Scene s;
  s.plate.enabled = false;
  s.scale_reference.enabled = false;
  for (int i = 0; i < 7; ++i)
    for (int j = 0; j < 5; ++j) {
      s.positions.emplace_back(-0.15 + 0.05 * i, 0.0, -0.1 + 0.05 * j);
      s.radii.push_back(0.015);
    }
  const Camera cam = small_camera(Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 0, 0));
  RenderOptions o = flat();
  o.tint_fraction = 0.08;
  const cv::Mat img = renderer().render(s, cam, o);
  double lo = 2.0, hi = 0.0;
  for (const Eigen::Vector3d& p : s.positions) {
    const Eigen::Vector2d uv = *camera::project(cam, p);
    const cv::Vec3b px = img.at<cv::Vec3b>(std::lround(uv.y()), std::lround(uv.x()));
    const double k = px[2] / 120.0;  // red channel of (120, 115, 108)
    EXPECT_NEAR(px[0] / 108.0, k, 0.02);
    lo = std::min(lo, k);
    hi = std::max(hi, k);
  }
  EXPECT_GE(lo, 0.92 - 0.01);
  EXPECT_LE(hi, 1.08 + 0.01);
  EXPECT_GT(hi - lo, 0.05);
}

TEST_F(RendererTest, ColourBySizeRunsFromPurpleToYellow) {
  Scene s;
  s.plate.enabled = false;
  s.scale_reference.enabled = false;
  s.positions = {Eigen::Vector3d(-0.1, 0, 0), Eigen::Vector3d(0.1, 0, 0)};
  s.radii = {0.01, 0.04};
  const Camera cam = small_camera(Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 0, 0));
  RenderOptions o = flat();
  o.shading = Shading::kBySize;
  const cv::Mat img = renderer().render(s, cam, o);
  const Eigen::Vector2d small = *camera::project(cam, s.positions[0]);
  const Eigen::Vector2d large = *camera::project(cam, s.positions[1]);
  // Viridis: (68, 1, 84) at the low end, (253, 231, 37) at the high end (BGR below).
  const cv::Vec3b ps = img.at<cv::Vec3b>(std::lround(small.y()), std::lround(small.x()));
  const cv::Vec3b pl = img.at<cv::Vec3b>(std::lround(large.y()), std::lround(large.x()));
  EXPECT_NEAR(ps[0], 84, 3);
  EXPECT_NEAR(ps[1], 1, 3);
  EXPECT_NEAR(ps[2], 68, 3);
  EXPECT_NEAR(pl[0], 37, 3);
  EXPECT_NEAR(pl[1], 231, 3);
  EXPECT_NEAR(pl[2], 253, 3);
}

bool is_backdrop(const cv::Vec3b& p) { return p == cv::Vec3b(220, 225, 225); }

TEST_F(RendererTest, PlateLineLevelCameraSitsWhereTheModelPutsIt) {
  Scene s = one_sphere(Eigen::Vector3d(0, 0, 0.01), 0.01);
  s.plate.enabled = true;
  const Camera cam = camera::side_view(2.0, 0.8, 0.0, 0.0, 320, 240);
  const cv::Mat img = renderer().render(s, cam, RenderOptions{});
  const int u = 100;  // a column through the plate, clear of the sphere
  int first = -1, last = -1;
  for (int v = 0; v < img.rows; ++v) {
    if (!is_backdrop(img.at<cv::Vec3b>(v, u))) {
      if (first < 0) first = v;
      last = v;
    }
  }
  ASSERT_GE(first, 0);
  // Top edge: the plate's top face, edge-on, at z = 0; bottom edge: the front face's lower edge.
  const double x = camera::unproject(cam, Eigen::Vector2d(u, 0)).direction.x() /
                   camera::unproject(cam, Eigen::Vector2d(u, 0)).direction.y() * 1.75;
  const double top = camera::project(cam, Eigen::Vector3d(x, -0.25, 0.0))->y();
  const double bottom = camera::project(cam, Eigen::Vector3d(x, -0.25, -0.015))->y();
  EXPECT_NEAR(first - 0.5, top, 0.5);
  EXPECT_NEAR(last + 0.5, bottom, 0.5);
  EXPECT_GT(bottom - top, 3.0);
}

TEST_F(RendererTest, PlateBackEdgeRaisedCameraSitsWhereTheModelPutsIt) {
  Scene s = one_sphere(Eigen::Vector3d(0, 0, 0.01), 0.01);
  s.plate.enabled = true;
  const Camera cam = small_camera(Eigen::Vector3d(0.1, -1.5, 0.3), Eigen::Vector3d(0, 0, 0), 35.0);
  const cv::Mat img = renderer().render(s, cam, RenderOptions{});
  // The far edge of the plate top (y = +0.25, z = 0) is a straight image line.
  const Eigen::Vector2d a = *camera::project(cam, Eigen::Vector3d(-0.25, 0.25, 0.0));
  const Eigen::Vector2d b = *camera::project(cam, Eigen::Vector3d(0.25, 0.25, 0.0));
  for (const int u : {60, 100, 220, 260}) {
    if (u < a.x() + 2 || u > b.x() - 2) continue;
    int first = -1;
    for (int v = 0; v < img.rows && first < 0; ++v)
      if (!is_backdrop(img.at<cv::Vec3b>(v, u))) first = v;
    const double expected = a.y() + (b.y() - a.y()) * (u - a.x()) / (b.x() - a.x());
    EXPECT_NEAR(first - 0.5, expected, 0.5) << "column " << u;
  }
}

TEST_F(RendererTest, PlateHidesTheSunkenHalfOfASphere) {
  // A sphere centred on the plate's top face, seen from above the plate: its image must end
  // where the plate plane cuts it, at the circle's nearest point (mesh and impostor depths agree).
  const Eigen::Vector3d c(0.05, 0.0, 0.0);
  const double r = 0.04;
  Scene s = one_sphere(c, r);
  s.plate.enabled = true;
  const Camera cam = small_camera(Eigen::Vector3d(0, -1, 0.3), Eigen::Vector3d(0, 0, 0), 50.0);
  const RenderOptions o = flat();  // unlit: sphere (120, 115, 108), plate (70, 80, 95)
  const cv::Mat img = renderer().render(s, cam, o);
  const Eigen::Vector2d pc = *camera::project(cam, c);
  const int u = static_cast<int>(std::lround(pc.x()));
  int first_plate = -1;
  for (int v = static_cast<int>(std::lround(pc.y())); v < img.rows && first_plate < 0; ++v) {
    if (img.at<cv::Vec3b>(v, u) == cv::Vec3b(95, 80, 70)) first_plate = v;
  }
  ASSERT_GT(first_plate, 0);
  EXPECT_EQ(img.at<cv::Vec3b>(first_plate - 1, u), cv::Vec3b(108, 115, 120));
  const double cut = camera::project(cam, Eigen::Vector3d(c.x(), c.y() - r, 0.0))->y();
  EXPECT_NEAR(first_plate - 0.5, cut, 0.5);
  // Unhidden, the outline would reach much lower.
  EXPECT_GT(exact_ellipse(cam, c, r).first.y() + exact_ellipse(cam, c, r).second, cut + 5.0);
}

TEST_F(RendererTest, DistortionMovesAPointWhereProjectSays) {
  const Eigen::Vector3d c(0.42, 0.0, -0.28);
  const double r = 0.012;
  const Scene s = one_sphere(c, r);
  Camera cam = small_camera(Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 0, 0));
  cam.intrinsics.k1 = -0.2;
  cam.intrinsics.k2 = 0.03;
  const RenderOptions o = flat();
  const Blob blob = measure(renderer().render(s, cam, o), s, o);
  // The expected centre: the exact undistorted outline's centre, moved by the lens model.
  Camera pinhole = cam;
  pinhole.intrinsics.k1 = pinhole.intrinsics.k2 = 0.0;
  const auto [centre, radius] = exact_ellipse(pinhole, c, r);
  const double f = camera::focal_px(cam);
  const Eigen::Vector2d pp(camera::principal_u(cam), camera::principal_v(cam));
  const Eigen::Vector2d expected = pp + f * camera::distort_normalised(cam, (centre - pp) / f);
  EXPECT_NEAR(blob.centroid.x(), expected.x(), 0.5);
  EXPECT_NEAR(blob.centroid.y(), expected.y(), 0.5);
  EXPECT_NEAR((expected - *camera::project(cam, c)).norm(), 0.0, 0.5);
  // The lens moved it by several pixels, so the check has teeth.
  EXPECT_GT((blob.centroid - *camera::project(pinhole, c)).norm(), 5.0);
}

TEST_F(RendererTest, DistortedImageKeepsBackdropInTheCorners) {
  // Barrel distortion pulls a wider field in: the corners must be rendered, not left black.
  Scene s = one_sphere(Eigen::Vector3d(0, 0, 0), 0.02);
  Camera cam = small_camera(Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 0, 0));
  cam.intrinsics.k1 = -0.1;
  const cv::Mat img = renderer().render(s, cam, RenderOptions{});
  EXPECT_TRUE(is_backdrop(img.at<cv::Vec3b>(0, 0)));
  EXPECT_TRUE(is_backdrop(img.at<cv::Vec3b>(239, 319)));
  // A lens model that folds before the image corner (r_d = r (1 + k1 r^2) peaks at 0.77 for
  // k1 = -0.25, below the corner's 0.94) cannot be rendered: a clear error, not garbage.
  cam.intrinsics.k1 = -0.25;
  try {
    renderer().render(s, cam, RenderOptions{});
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("k1/k2"), std::string::npos) << e.what();
  }
}

TEST_F(RendererTest, ScaleBarBandsSitWhereTheModelPutsThem) {
  Scene s = random_pile(200, 3);
  const Camera cam = camera::side_view(1.5, 0.3, 0.05, 0.0, 320, 240);
  RenderOptions o;
  const cv::Mat img = renderer().render(s, cam, o);
  const Eigen::Vector3d centre = *scale_reference_center(s, cam, View::kSide);
  for (int k = 0; k < 10; ++k) {
    const Eigen::Vector3d mid(centre.x(), centre.y(), 0.01 * (k + 0.5));
    const Eigen::Vector2d p = *camera::project(cam, mid);
    const cv::Vec3b px = img.at<cv::Vec3b>(std::lround(p.y()), std::lround(p.x()));
    EXPECT_EQ(px, k % 2 == 0 ? cv::Vec3b(20, 20, 20) : cv::Vec3b(245, 245, 245)) << "band " << k;
  }
  // Just above the bar: backdrop.
  const Eigen::Vector2d above = *camera::project(cam, Eigen::Vector3d(centre.x(), 0, 0.104));
  EXPECT_TRUE(is_backdrop(img.at<cv::Vec3b>(std::lround(above.y()), std::lround(above.x()))));
}

TEST_F(RendererTest, CheckerCardSquaresSitWhereTheModelPutsThem) {
  Scene s = random_pile(200, 3);
  const Camera cam = camera::top_view(1.0, 0.35, 320, 240);
  RenderOptions o;
  o.view = View::kTop;
  const cv::Mat img = renderer().render(s, cam, o);
  const Eigen::Vector3d c = *scale_reference_center(s, cam, View::kTop);
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      const Eigen::Vector3d mid(c.x() - 0.02 + 0.01 * (i + 0.5), c.y() - 0.02 + 0.01 * (j + 0.5),
                                c.z());
      const Eigen::Vector2d p = *camera::project(cam, mid);
      const cv::Vec3b px = img.at<cv::Vec3b>(std::lround(p.y()), std::lround(p.x()));
      EXPECT_EQ(px, (i + j) % 2 == 0 ? cv::Vec3b(20, 20, 20) : cv::Vec3b(245, 245, 245))
          << "square " << i << "," << j;
    }
  }
}

TEST_F(RendererTest, ShellIsDrawnAroundTheAxis) {
  Scene s = one_sphere(Eigen::Vector3d(0, 0, 0.01), 0.01);
  s.shells.push_back(Shell{.z_bottom_m = 0.1, .z_top_m = 0.2, .r_bottom_m = 0.02, .r_top_m = 0.06});
  const Camera cam = camera::side_view(2.0, 0.6, 0.0, 0.0, 320, 240);
  const cv::Mat img = renderer().render(s, cam, RenderOptions{});
  // Inside the frustum's outline at mid height: not backdrop; just outside it: backdrop.
  const Eigen::Vector2d in = *camera::project(cam, Eigen::Vector3d(0.035, 0.0, 0.15));
  const Eigen::Vector2d out = *camera::project(cam, Eigen::Vector3d(0.05, 0.0, 0.15));
  EXPECT_FALSE(is_backdrop(img.at<cv::Vec3b>(std::lround(in.y()), std::lround(in.x()))));
  EXPECT_TRUE(is_backdrop(img.at<cv::Vec3b>(std::lround(out.y()), std::lround(out.x()))));
}

TEST_F(RendererTest, BadInputThrows) {
  const Scene s = one_sphere(Eigen::Vector3d(0, 0, 0.05), 0.05);
  Camera cam = small_camera(Eigen::Vector3d(0, -1, 0.05), Eigen::Vector3d(0, 0, 0.05));
  auto message = [&](const Scene& scene, const Camera& c) {
    try {
      renderer().render(scene, c, RenderOptions{});
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  Camera bad = cam;
  bad.intrinsics.width_px = 0;
  EXPECT_NE(message(s, bad).find("width_px"), std::string::npos) << message(s, bad);
  bad = cam;
  bad.intrinsics.height_px = -3;
  EXPECT_NE(message(s, bad).find("height_px"), std::string::npos) << message(s, bad);
  bad = cam;
  bad.extrinsics.position = Eigen::Vector3d(0.01, 0, 0.06);  // inside the sphere
  bad.extrinsics.look_at = Eigen::Vector3d(0.01, 1, 0.06);
  EXPECT_NE(message(s, bad).find("inside sphere 0"), std::string::npos) << message(s, bad);
  Scene two = s;
  two.positions.push_back(Eigen::Vector3d(0.3, 0, 0.05));
  two.radii.push_back(0.01);
  bad = cam;
  bad.extrinsics.position = Eigen::Vector3d(0, -0.2, 0.05);  // between spheres, inside the pile
  EXPECT_NE(message(two, bad).find("bounding cylinder"), std::string::npos) << message(two, bad);
  bad = cam;
  bad.extrinsics.look_at = Eigen::Vector3d(0, -2, 0.05);  // looking away
  EXPECT_NE(message(s, bad).find("behind the camera"), std::string::npos) << message(s, bad);
  bad = cam;
  bad.extrinsics.look_at = Eigen::Vector3d(1, 0, 0.05);  // looking 45 degrees aside
  EXPECT_NE(message(s, bad).find("outside the image"), std::string::npos) << message(s, bad);
  Scene empty = s;
  empty.positions.clear();
  empty.radii.clear();
  EXPECT_NE(message(empty, cam).find("scene.positions is empty"), std::string::npos);
  Scene negative = s;
  negative.radii[0] = -0.01;
  EXPECT_NE(message(negative, cam).find("scene.radii[0]"), std::string::npos);
  Scene mismatch = s;
  mismatch.radii.push_back(0.01);
  EXPECT_NE(message(mismatch, cam).find("scene.radii has 2 entries"), std::string::npos);
}

}  // namespace
}  // namespace reposetwin::render
