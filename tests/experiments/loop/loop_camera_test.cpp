// The twin photographs its piles with the lab's declared camera: a lab test whose photo comes
// with a camera sidecar (another distance, height, azimuth and resolution than the twin's own
// framing) is read from its CSV, its request carries that camera, and the loop's photograph of
// a cone of spheres placed by hand has the lab's sidecar, and its plate line and pile axis where
// the lab's camera projects them (closed-form pinhole projection), within 1 px. No simulation.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <opencv2/imgcodecs.hpp>

#include "../../support/cone_pile.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/loop/loop_data.hpp"
#include "experiments/loop/loop_effects.hpp"
#include "experiments/loop/loop_sim.hpp"
#include "experiments/photos/photographs.hpp"
#include "vision/measure.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

const std::string kScene = std::string(REPOSETWIN_SOURCE_DIR) + "/data/loop/tiny_scene.toml";

constexpr double kA = 1.75e-3;  // sphere radius [m]
constexpr double kH = 14e-3;    // cone height (apex top) [m]
constexpr double kR = 24e-3;    // cone base reach [m]

// The lab's camera: 0.40 m away (the twin's own framing would stand 12 pile radii, 0.29 m,
// away), from azimuth 30 deg, 800 x 600 px (the twin's 960 x 720), 80 mm of field at the axis,
// level with the plate through a lens whose principal point is off the image centre (the
// plate low in the frame and the pile left of centre), so every part of the pose and lens shows
// in where the plate and the axis land. Level, the plate's whole top face projects on the
// principal row, so the plate line's row has a closed form free of which plate edge vision
// takes for it (a raised camera sees a band of top face a few pixels deep).
constexpr double kL = 0.40, kAz = 30.0, kCx = 372.0, kCy = 415.0;
camera::Camera lab_camera() {
  camera::Camera c = camera::side_view(kL, 0.08, 0.0, kAz, 800, 600);
  c.intrinsics.cx_px = kCx;
  c.intrinsics.cy_px = kCy;
  return c;
}

// The silhouette's axis column: the mean over the rows of the flank band (20-80% of H) of the
// middle between the left and right edges (a rotationally symmetric pile's axis). The apex
// column is no estimate: the top sphere's flat crown spans tens of columns.
double silhouette_axis_column(const vision::SideProfile& p) {
  std::map<long, double> right;
  for (const cv::Point2d& q : p.right_edge) right[std::lround(q.y)] = q.x;
  const double v_plate = p.plate.v_at(p.apex.x);
  double sum = 0.0;
  int n = 0;
  for (const cv::Point2d& q : p.left_edge) {
    const double up = (v_plate - q.y) / p.height_px;
    const auto it = right.find(std::lround(q.y));
    if (up < 0.2 || up > 0.8 || it == right.end()) continue;
    sum += 0.5 * (q.x + it->second);
    ++n;
  }
  return n > 0 ? sum / n : std::nan("");
}

struct Cone {
  std::vector<Eigen::Vector3d> x;
  std::vector<double> r;
  std::vector<int> m;
};

Cone cone() {
  const test_support::Spheres s = test_support::make_cone(kH, kR, 0.0, 0.0, kA, 11, 0.3);
  return {{s.x.begin(), s.x.end()}, s.r, std::vector<int>(s.r.size(), 0)};
}

// The lab's photo of the cone with its camera, and the sidecar beside it; returns the photo's
// path relative to `dir`.
std::string lab_photo(const Cone& c, const fs::path& dir) {
  PhotoSettings s;
  s.lab_cameras = {lab_camera()};
  s.top_view = false;
  s.scale_reference = false;
  s.write_overlays = false;
  const PilePhotos p = photograph_pile(PileSpheres{c.x, c.r, c.m}, s, (dir / "lab").string());
  return "lab/" + p.sides.at(0).stem + ".png";
}

TEST(LoopCamera, TwinPhotographsWithTheLabsDeclaredCamera) {
  const fs::path dir = fs::temp_directory_path() / "reposetwin_loop_camera_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const Cone c = cone();
  const std::string photo = lab_photo(c, dir);
  write_file_atomic((dir / "lab.csv").string(),
                    "id,role,scene,photo\nlab1,calibrate," + kScene + "," + photo + "\n");
  const LabData data = read_lab_csv((dir / "lab.csv").string());
  ASSERT_EQ(data.tests.at(0).cameras.size(), 1u);

  // Through the loop's path: the request's image settings, then its photograph.
  ImageVariant v = make_request(data.tests[0], "contacts.{sample}-{sample}.rolling_friction", 0.1,
                                1, {}, ImageVariant{})
                       .image;
  ASSERT_EQ(v.lab_cameras.size(), 1u);
  const auto key = [](const ImageVariant& x) { return to_json(photo_settings(x)); };
  EXPECT_NE(key(v), key(ImageVariant{}));
  // --own-cameras: the twin's own framing, the key of a test without sidecars.
  ImageVariant own;
  own.use_lab_cameras = false;
  EXPECT_EQ(key(make_request(data.tests[0], "contacts.{sample}-{sample}.rolling_friction", 0.1,
                             1, {}, own)
                    .image),
            key(ImageVariant{}));
  ImageVariant other = v;
  other.lab_cameras[0].extrinsics.position.z() += 1e-3;
  EXPECT_NE(key(v), key(other)) << "a photo through another camera must not be reused";
  v.keep_photos = true;
  const fs::path twin = dir / "twin";
  const nlohmann::json rec = photograph_pile(c.x, c.r, c.m, v, twin.string());
  ASSERT_FALSE(rec.contains("error")) << rec.dump();
  ASSERT_EQ(rec.at("views").size(), 1u);
  const std::string stem = fs::path(rec["views"][0]["photo"].get<std::string>()).stem().string();

  // The twin photo's sidecar is the lab's camera, and the image has the lab's resolution.
  const camera::Camera got = camera::read_sidecar((twin / (stem + ".json")).string());
  EXPECT_EQ(camera::to_json(got).dump(), camera::to_json(lab_camera()).dump());
  const cv::Mat image = cv::imread((twin / (stem + ".png")).string());
  ASSERT_EQ(image.cols, 800);
  ASSERT_EQ(image.rows, 600);

  // Closed form: a pinhole at (L sin az, -L cos az, 0) looking level at the axis. A world
  // point P is at depth z_c = (P - C) . forward, x_c = (P - C) . right, y_c = -(P - C)_z, and
  // projects to (cx + f x_c / z_c, cy + f y_c / z_c), f = focal / sensor width x image width.
  // Every point of the axis has x_c = 0 (u = cx), every point of the plate y_c = 0 (v = cy).
  const camera::Intrinsics& in = lab_camera().intrinsics;
  const double f = in.focal_length_mm / in.sensor_width_mm * in.width_px;
  const double az = kAz * M_PI / 180.0;
  const Eigen::Vector3d cam(kL * std::sin(az), -kL * std::cos(az), 0.0);
  const Eigen::Vector3d forward(-std::sin(az), std::cos(az), 0.0),
      right(std::cos(az), std::sin(az), 0.0);
  auto project = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d d = p - cam;
    return Eigen::Vector2d(kCx + f * d.dot(right) / d.dot(forward),
                           kCy + f * -d.z() / d.dot(forward));
  };
  const Eigen::Vector2d foot = project(Eigen::Vector3d::Zero());
  const Eigen::Vector2d top = project(Eigen::Vector3d(0.0, 0.0, kH));
  EXPECT_NEAR(top.x(), foot.x(), 1e-9);
  const vision::SideMeasurement m = vision::measure_side_camera(image, got);
  const vision::SideProfile& px = m.pixels;
  const double u_axis = silhouette_axis_column(px);
  const double u_toes = 0.5 * (px.toe_left.x + px.toe_right.x);
  const double v_plate = px.plate.v_at(foot.x());
  EXPECT_NEAR(u_axis, foot.x(), 1.0);
  EXPECT_NEAR(u_toes, foot.x(), 1.0);
  EXPECT_NEAR(v_plate, foot.y(), 1.0);
  // The apex, H above the foot, lands f H / L above the plate row.
  EXPECT_NEAR(v_plate - px.height_px, top.y(), 1.5);
  std::printf(
      "axis column: closed form %.2f, silhouette %.2f, toes' middle %.2f; plate row at "
      "the axis: closed form %.2f, detected %.2f; apex row closed form %.2f, detected "
      "%.2f px\n",
      foot.x(), u_axis, u_toes, foot.y(), v_plate, top.y(), v_plate - px.height_px);
  // And the twin measures the cone it was given through the lab's camera.
  EXPECT_NEAR(m.height_m, kH, 0.5e-3);
}

// The camera_pose candidate at h: the request's true camera is raised by h and pitched down so
// its optical axis meets the axis foot, pitch atan(h / L) at the horizontal distance L of the
// twin's framing (12 pile radii), while the measurement and the sidecar assume it level. Vision
// reads the pitch back from the pile's base ellipse in the photo within 1 deg.
TEST(LoopCamera, CameraPosePitchesAtTheAxisFootAndVisionReadsThePitch) {
  const fs::path dir = fs::temp_directory_path() / "reposetwin_loop_camera_pose_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  write_file_atomic((dir / "lab.csv").string(),
                    "id,role,scene,angle_deg\nlab1,calibrate," + kScene + ",30\n");
  const LabData data = read_lab_csv((dir / "lab.csv").string());
  const CandidateEffect& e = find_effect("camera_pose");
  EXPECT_EQ(e.kind, EffectKind::kMeasurement);
  // The off value is the base model's level camera.
  const ImageVariant off =
      make_request(data.tests[0], "contacts.{sample}-{sample}.rolling_friction", 0.1, 1,
                   {{&e, 0.0}}, ImageVariant{})
          .image;
  EXPECT_EQ(to_json(photo_settings(off)), to_json(photo_settings(ImageVariant{})));
  const Cone c = cone();
  // At the registry's probe (2 deg of pitch) vision measures the photos through the level
  // camera (so the candidate has a fingerprint); at 5 deg it refuses them with the pitch it
  // read (the candidate is then reported unavailable at that probe).
  for (double h : {e.probe, 0.025}) {
    ImageVariant v = make_request(data.tests[0], "contacts.{sample}-{sample}.rolling_friction", 0.1,
                                  1, {{&e, h}}, ImageVariant{})
                         .image;
    EXPECT_TRUE(v.aim_at_axis_foot);
    EXPECT_DOUBLE_EQ(v.camera_height_m, h);
    EXPECT_DOUBLE_EQ(v.declared_height_m, 0.0);
    v.keep_photos = true;
    const fs::path out = dir / ("h" + std::to_string(static_cast<int>(1e3 * h + 0.5)));
    const PilePhotos photos =
        photograph_pile(PileSpheres{c.x, c.r, c.m}, photo_settings(v), out.string());
    ASSERT_EQ(photos.sides.size(), 2u);
    for (const SideView& view : photos.sides) {
      const camera::Camera& truth = view.camera;
      const Eigen::Vector3d& p = truth.extrinsics.position;
      const double l = p.head<2>().norm();
      EXPECT_NEAR(p.z(), h, 1e-12);
      // The twin's framing: 12 pile radii (the cone's reach) from the axis.
      EXPECT_NEAR(l, 12.0 * kR, 0.05 * 12.0 * kR);
      // Aimed at the axis foot: the foot lies on the optical axis.
      const Eigen::Vector3d f = (truth.extrinsics.look_at - p).normalized();
      EXPECT_LT((-p - (-p).dot(f) * f).norm(), 1e-12);
      const double pitch = std::atan2(-f.z(), f.head<2>().norm()) * 180.0 / M_PI;
      const double closed = std::atan(h / l) * 180.0 / M_PI;
      EXPECT_NEAR(pitch, closed, 1e-9);
      // The measurement and the sidecar assume the same camera level with the plate.
      const std::string base = (out / view.stem).string();
      const camera::Camera declared = camera::read_sidecar(base + ".json");
      EXPECT_DOUBLE_EQ(declared.extrinsics.position.z(), 0.0);
      EXPECT_DOUBLE_EQ(declared.extrinsics.look_at.z(), 0.0);
      // Vision's pose estimate from the photo's base ellipse.
      const cv::Mat image = cv::imread(base + ".png");
      const vision::SideImage prepared = vision::prepare_side(image, {}, base);
      const vision::SideProfile px = vision::measure_side_pixels(prepared, {}, base);
      const auto pose = vision::estimate_side_pose(prepared, px, declared, Eigen::Vector3d::Zero());
      ASSERT_TRUE(pose) << base;
      std::printf(
          "h %.0f mm, az %.0f: pitch closed form %.3f deg, vision %.3f +- %.3f deg; "
          "measured: %s\n",
          1e3 * h, view.azimuth_deg, closed, pose->pitch_deg, pose->sigma_pitch_deg,
          view.measured ? "yes" : view.error.c_str());
      EXPECT_NEAR(pose->pitch_deg, closed, 1.0) << base;
      if (h == e.probe) {
        EXPECT_TRUE(view.measured.has_value()) << view.error;
      } else {
        EXPECT_NE(view.error.find("not measured through the declared camera"), std::string::npos)
            << view.error;
      }
    }
  }
}

}  // namespace
}  // namespace reposetwin::experiments
