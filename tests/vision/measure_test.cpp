// Tests of vision/measure: scale from the marker, a given mm/px or a known camera (perspective
// correction), several views combined, JSON and overlay, and clear errors for bad input.
#include "vision/measure.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <optional>

#include "tests/vision/synthetic.hpp"
#include "vision/image.hpp"

namespace reposetwin::vision {
namespace {

double theta_of(double h, double d) { return std::atan(2.0 * h / d) * 180.0 / std::numbers::pi; }

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("reposetwin_vision_" + name)).string();
}

TEST(MeasureSide, ScaleFromTheBandBar) {
  synthetic::SideScene s;
  s.height_mm = 55.0;
  s.diameter_mm = 190.0;
  const SideMeasurement m = measure_side(synthetic::draw_side(s), {}, {}, "bar.png");
  EXPECT_EQ(m.scale_source, ScaleSource::kScaleBar);
  EXPECT_FALSE(m.perspective_corrected);
  ASSERT_TRUE(m.scale_bar.has_value());
  EXPECT_NEAR(m.mm_per_px, s.mm_per_px, 0.002 * s.mm_per_px);
  EXPECT_NEAR(m.height_m, 0.055, 0.0005);
  EXPECT_NEAR(m.diameter_m, 0.190, 0.0008);
  EXPECT_NEAR(m.theta_deg, theta_of(55.0, 190.0), 0.3);
  EXPECT_GT(m.sigma_height_m, 0.0);
}

TEST(MeasureSide, GivenMillimetresPerPixel) {
  synthetic::SideScene s;
  s.scale_bar = false;
  ScaleSpec spec;
  spec.mm_per_px = s.mm_per_px;
  const SideMeasurement m = measure_side(synthetic::draw_side(s), spec);
  EXPECT_EQ(m.scale_source, ScaleSource::kMmPerPx);
  EXPECT_NEAR(m.height_m, 0.060, 0.0004);
  EXPECT_NEAR(m.diameter_m, 0.200, 0.0005);
  EXPECT_NEAR(m.flank_left_deg, theta_of(60.0, 200.0), 0.5);
  EXPECT_NEAR(m.flank_right_deg, theta_of(60.0, 200.0), 0.5);
}

TEST(MeasureSide, PerspectiveCorrectionRecoversHandD) {
  // A close camera (0.6 m) on a 200 mm pile: the toe rays graze the base circle well in front of
  // the axis, so the orthographic reading overstates D by about 1.5%.
  const camera::Camera cam = camera::side_view(0.6, 0.4, 0.0, 20.0, 1280, 720);
  synthetic::SideScene s;
  s.camera = cam;
  s.height_mm = 60.0;
  s.diameter_mm = 200.0;
  const cv::Mat img = synthetic::draw_side(s);
  ScaleSpec spec;
  spec.camera = cam;
  const SideMeasurement m = measure_side(img, spec, {}, "persp.png");
  EXPECT_TRUE(m.perspective_corrected);
  EXPECT_EQ(m.scale_source, ScaleSource::kCamera);
  EXPECT_NEAR(m.height_m, 0.060, 0.0003);
  EXPECT_NEAR(m.diameter_m, 0.200, 0.0004);
  EXPECT_NEAR(m.theta_deg, theta_of(60.0, 200.0), 0.2);
  EXPECT_NEAR(m.flank_left_deg, theta_of(60.0, 200.0), 0.3);
  EXPECT_NEAR(m.flank_right_deg, theta_of(60.0, 200.0), 0.3);
  EXPECT_NEAR(m.base_center_m.norm(), 0.0, 0.001);
  // The convenience overload gives the same.
  EXPECT_DOUBLE_EQ(measure_side_camera(img, cam).theta_deg, m.theta_deg);
  EXPECT_TRUE(m.warnings.empty());
  // A camera description that does not match the picture (here: 5 cm higher) is refused as a
  // camera mismatch: the pile stands 160 px above where that camera puts its base.
  ScaleSpec raised = spec;
  raised.camera->extrinsics.position.z() += 0.05;
  raised.camera->extrinsics.look_at.z() += 0.05;
  try {
    (void)measure_side(img, raised);
    ADD_FAILURE() << "measured through a camera 5 cm higher than the photo's";
  } catch (const Refusal& r) {
    EXPECT_EQ(r.check(), Check::kCameraConsistent) << r.what();
  }
  // The same image read orthographically at the axis scale is visibly off: the correction matters.
  ScaleSpec ortho;
  ortho.mm_per_px = camera::mm_per_px_at(cam, Eigen::Vector3d::Zero());
  const SideMeasurement o = measure_side(img, ortho);
  EXPECT_GT(o.diameter_m - 0.200, 0.002);
  EXPECT_GT(std::abs(o.theta_deg - theta_of(60.0, 200.0)), 0.3);
}

// A tripod camera looking down 10 deg at a plate narrower than the view, standing on a wider
// bench: below the plate's far edge the band shows the bench beside the plate's far corners,
// and below the plate the bench's own front edge is the photo's lowest long edge with a light
// top above it. Neither is the plate's: the plate edge is sought where the camera can put it,
// and the plate's level is read where it continues from the band's foot. A cone of 31 deg
// (H 60, D 200 mm) reads within 1 deg of atan(2H/D), as without the bench.
TEST(MeasureSide, TripodCameraOverAPlateOnABenchReadsThePile) {
  for (const double bench : {0.0, 0.6}) {
    synthetic::SideScene s;
    const double l = 0.6, aim = 0.03;
    camera::Camera cam = camera::side_view(l, 0.7, aim + l * std::tan(10.0 * std::numbers::pi / 180.0),
                                           0.0, 1280, 720);
    cam.extrinsics.look_at = Eigen::Vector3d(0.0, 0.0, aim);
    s.camera = cam;
    s.scale_bar = false;
    s.height_mm = 30.0;
    s.diameter_mm = 120.0;
    s.plate_half_size_m = 0.25;
    s.bench_half_size_m = bench;
    const cv::Mat img = synthetic::draw_side(s);
    const std::string name = bench > 0.0 ? "bench.png" : "plate.png";
    SideMeasurement m;
    try {
      m = measure_side_camera(img, cam, {}, name);
    } catch (const std::exception& e) {
      FAIL() << e.what();
    }
    EXPECT_NEAR(m.theta_deg, std::atan(2.0 * 30.0 / 120.0) * 180.0 / std::numbers::pi, 1.0)
        << name;
  }
}

TEST(MeasureSide, CameraAboveThePlateReadsHFromTheToeLine) {
  // The camera 10 mm above the plate, 0.6 m from a smooth 200 mm cone, measured as if level: the
  // plate's top face is a band from its far edge (23 px below the horizon) to its near edge
  // (55 px), and the pile stands in it with its toes (the base circle's tangent points, at depth
  // L - R^2/L) 33 px below the horizon. The plate line is the toe line, which maps to
  // z_toe = -h (1 + R^2 / (L^2 - R^2)) on the axis plane, and H reads H + h R^2 / (L^2 - R^2)
  // (+0.29 mm), not the H - h = 50 mm of the apex's height through the declared camera, nor the
  // 57 mm of the far edge (z = -h L / (L + s) = -7.1 mm). The toe line is the lowest pixel
  // within 5% of the width from each end; on this smooth cone that is below the tangent points
  // by: the synthetic cone's reach into the plate (2 px), the base ellipse's descent over 5% of
  // its width (0.44 C, C = f h R / L^2 = 5.3 px: 2.4 px), half a pixel (the pixel's bottom) and
  // up to 1.5 px of anti-aliased coverage: at most 6.4 px. The toes are carried down the flank
  // to that line, D wider by 2 x 6.4 px x cot(31 deg).
  const double h = 0.010, l = 0.6, r = 0.1;
  synthetic::SideScene s;
  s.camera = camera::side_view(l, 0.4, h, 0.0, 1280, 720);
  s.scale_bar = false;
  const cv::Mat img = synthetic::draw_side(s);
  const camera::Camera declared = camera::side_view(l, 0.4, 0.0, 0.0, 1280, 720);
  const SideMeasurement m = measure_side_camera(img, declared, {}, "raised.png");
  const double mm_px = camera::mm_per_px_at(declared, Eigen::Vector3d::Zero()) * 1e-3;  // [m/px]
  const double f_px = 1280 * l / 0.4;
  const double low_px = 2.0 + 0.44 * f_px * h * r / (l * l) + 0.5 + 1.5;
  const double z_toe = -h * (1.0 + r * r / (l * l - r * r));
  EXPECT_LT(m.plate_line_z_m, z_toe + 0.5 * mm_px);
  EXPECT_GT(m.plate_line_z_m, z_toe - low_px * mm_px);
  const double h_read = 0.060 + h * r * r / (l * l - r * r);
  EXPECT_GT(m.height_m, h_read - 0.5 * mm_px);
  EXPECT_LT(m.height_m, h_read + low_px * mm_px);
  EXPECT_NEAR(m.diameter_m, 0.200, 2.0 * low_px * mm_px / std::tan(0.54));
  // Through the true camera the same image reads the plate line on the plate (the toes, nearer
  // than the axis, map to z = -h R^2 / (L^2 - R^2) on the axis plane).
  const SideMeasurement t = measure_side_camera(img, *s.camera, {}, "raised.png");
  const double z_true = -h * r * r / (l * l - r * r);
  EXPECT_LT(t.plate_line_z_m, z_true + 0.5 * mm_px);
  EXPECT_GT(t.plate_line_z_m, z_true - low_px * mm_px);
  // Through the true camera the toe line is where the camera puts it and H the apex's height
  // above the plate: 60 mm, to a pixel.
  EXPECT_NEAR(t.height_m, 0.060, 1.0 * mm_px);
}

TEST(MeasureSide, SidecarGivesCameraAndScale) {
  const camera::Camera cam = camera::side_view(2.0, 0.4, 0.0, 0.0, 1280, 720);
  const std::string path = temp_path("sidecar.json");
  {
    std::ofstream out(path);
    out << nlohmann::json{{"camera", camera::to_json(cam)},
                          {"mm_per_px_at_axis", 0.3125},
                          {"scale_reference", {{"kind", "band_bar"}, {"band_mm", 12.0}}},
                          {"view", "side"}}
               .dump();
  }
  const ScaleSpec spec = scale_from_sidecar(path);
  ASSERT_TRUE(spec.camera.has_value());
  EXPECT_EQ(spec.camera->intrinsics.width_px, 1280);
  ASSERT_TRUE(spec.mm_per_px.has_value());
  EXPECT_DOUBLE_EQ(*spec.mm_per_px, 0.3125);
  EXPECT_DOUBLE_EQ(spec.marker.band_mm, 12.0);
  {
    std::ofstream out(path);
    out << nlohmann::json{{"camera", camera::to_json(cam)}, {"mm_per_px_at_axis", -1}}.dump();
  }
  try {
    scale_from_sidecar(path);
    FAIL() << "expected an exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("mm_per_px_at_axis"), std::string::npos) << e.what();
  }
  {
    std::ofstream out(path);
    out << R"({"view": "side"})";
  }
  EXPECT_THROW(scale_from_sidecar(path), std::invalid_argument);
  std::filesystem::remove(path);
}

TEST(MeasureSide, UnknownScaleIsAnError) {
  synthetic::SideScene s;
  s.scale_bar = false;
  try {
    measure_side(synthetic::draw_side(s), {}, {}, "noscale.png");
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("noscale.png"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("scale cannot be determined"), std::string::npos);
  }
  ScaleSpec wrong;
  wrong.camera = camera::side_view(2.0, 0.4, 0.0, 0.0, 1920, 1080);  // not this image's size
  EXPECT_THROW(measure_side(synthetic::draw_side(s), wrong), std::invalid_argument);
  ScaleSpec negative;
  negative.mm_per_px = -0.2;
  EXPECT_THROW(measure_side(synthetic::draw_side(s), negative), std::invalid_argument);
}

TEST(MeasureSide, SeveralViewsAreAveragedWithSpread) {
  std::vector<SideMeasurement> views;
  const double heights[] = {55.0, 60.0, 65.0};
  for (int i = 0; i < 3; ++i) {
    synthetic::SideScene s;
    s.height_mm = heights[i];
    s.look.noise_sigma = 4.0;
    s.look.seed = 10 + i;
    views.push_back(measure_side(synthetic::draw_side(s)));
  }
  const SideSummary sum = combine_sides(views);
  EXPECT_EQ(sum.views, 3);
  const double mean_theta =
      (theta_of(55.0, 200.0) + theta_of(60.0, 200.0) + theta_of(65.0, 200.0)) / 3.0;
  EXPECT_NEAR(sum.theta_deg.mean, mean_theta, 0.3);
  EXPECT_NEAR(sum.height_m.mean, 0.060, 0.0006);
  // The spread of 55/60/65 mm is 5 mm; of the angles about 1.3 degrees.
  EXPECT_NEAR(sum.height_m.stddev, 0.005, 0.0006);
  EXPECT_GT(sum.theta_deg.stddev, 1.0);
  EXPECT_GT(sum.theta_deg.sigma_mean, sum.theta_deg.stddev / std::sqrt(3.0) - 1e-12);
  EXPECT_EQ(combine_sides({views[0]}).theta_deg.stddev, 0.0);
  EXPECT_THROW(combine_sides({}), std::invalid_argument);
}

TEST(MeasureSide, JsonAndOverlay) {
  synthetic::SideScene s;
  const cv::Mat img = synthetic::draw_side(s);
  const SideMeasurement m = measure_side(img, {}, {}, "pile.png");
  const nlohmann::json j = to_json(m);
  for (const char* key : {"H_m", "D_m", "theta_deg", "sigma_theta_deg", "flank_left_deg",
                          "flank_right_deg", "projection", "scale", "pixels"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["projection"], "assumed orthographic");
  EXPECT_EQ(j["scale"]["source"], "scale_bar");
  EXPECT_DOUBLE_EQ(j["theta_deg"].get<double>(), m.theta_deg);
  const cv::Mat ov = draw_side_overlay(img, m);
  EXPECT_EQ(ov.size(), img.size());
  EXPECT_EQ(ov.type(), CV_8UC3);
  // The annotation changes pixels on the plate line and at the apex.
  cv::Mat diff;
  cv::absdiff(ov, img, diff);
  EXPECT_GT(cv::countNonZero(diff.reshape(1)), 1000);
  const cv::Point apex(static_cast<int>(std::lround(m.pixels.apex.x)),
                       static_cast<int>(std::lround(m.pixels.apex.y)));
  EXPECT_GT(cv::norm(diff(cv::Rect(apex.x - 8, apex.y - 8, 17, 17))), 0.0);
}

TEST(LoadImage, RejectsFilesThatAreNotImages) {
  const std::string path = temp_path("not_an_image.png");
  {
    std::ofstream out(path);
    out << "this is text, not a PNG";
  }
  try {
    load_image(path);
    FAIL() << "expected an exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
  EXPECT_THROW(load_image(temp_path("does_not_exist.png")), std::invalid_argument);
}

// The header reader against OpenCV's own decoder, on each format it reads.
TEST(LoadImage, HeaderSizeAgreesWithTheDecoder) {
  cv::Mat img(37, 53, CV_8UC3, cv::Scalar(10, 200, 90));
  for (const char* ext : {".png", ".jpg", ".bmp"}) {
    const std::string path = temp_path(std::string("header_size") + ext);
    ASSERT_TRUE(cv::imwrite(path, img)) << ext;
    const std::optional<cv::Size> size = image_header_size(path);
    ASSERT_TRUE(size.has_value()) << ext;
    EXPECT_EQ(*size, cv::imread(path).size()) << ext;
    std::filesystem::remove(path);
  }
  const std::string tiff = temp_path("header_size.tiff");
  ASSERT_TRUE(cv::imwrite(tiff, img));
  EXPECT_FALSE(image_header_size(tiff).has_value()) << "TIFF is checked after decoding";
  EXPECT_EQ(load_image(tiff).size(), img.size());
  std::filesystem::remove(tiff);
}

// A PNG whose header states 20000 x 20000 pixels is refused from its header, before any decoding
// (the rest of the file is not even a valid PNG), naming the file and the limit.
TEST(LoadImage, RefusesAnOversizedImageBeforeDecodingIt) {
  const std::string path = temp_path("huge.png");
  {
    std::ofstream out(path, std::ios::binary);
    const unsigned char header[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n', 0, 0, 0, 13,
                                    'I', 'H', 'D', 'R', 0, 0, 0x4E, 0x20, 0, 0, 0x4E, 0x20,
                                    8, 2, 0, 0, 0};
    out.write(reinterpret_cast<const char*>(header), sizeof header);
  }
  try {
    load_image(path);
    FAIL() << "expected an exception";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    EXPECT_NE(what.find("20000 x 20000"), std::string::npos) << what;
    EXPECT_NE(what.find("limit"), std::string::npos) << what;
  }
  std::filesystem::remove(path);
}

TEST(LoadImage, RefusesASliverNamingTheFile) {
  const std::string path = temp_path("sliver.png");
  ASSERT_TRUE(cv::imwrite(path, cv::Mat(1, 2000, CV_8UC3, cv::Scalar::all(128))));
  try {
    load_image(path);
    FAIL() << "expected an exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("2000 x 1"), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
}

TEST(MeasureSide, EmptyAndBlackImagesAreRejected) {
  EXPECT_THROW(measure_side(cv::Mat(), {}, {}, "empty.png"), std::invalid_argument);
  ScaleSpec spec;
  spec.mm_per_px = 0.25;
  try {
    measure_side(cv::Mat(720, 1280, CV_8UC3, cv::Scalar::all(0)), spec, {}, "black.png");
    FAIL() << "expected an exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("black.png"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("all black"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace reposetwin::vision
