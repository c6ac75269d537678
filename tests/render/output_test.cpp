// The sidecar's keys and values against the camera model, and the files written.
#include "render/output.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "camera/camera.hpp"

namespace reposetwin::render {
namespace {

Scene small_pile() {
  Scene s;
  s.positions = {Eigen::Vector3d(0.0, 0.0, 0.04), Eigen::Vector3d(0.05, 0.0, 0.005)};
  s.radii = {0.01, 0.005};
  return s;
}

TEST(Sidecar, SideViewKeysAndScale) {
  const Scene s = small_pile();
  const camera::Camera cam = lab_side_camera(s, {.width_px = 320, .height_px = 240});
  const nlohmann::json j = make_sidecar(s, cam, RenderOptions{}, {{"seed", 42}});
  EXPECT_EQ(j["view"], "side");
  EXPECT_EQ(j["image"]["width_px"], 320);
  EXPECT_EQ(j["image"]["height_px"], 240);
  EXPECT_EQ(j["provenance"]["seed"], 42);
  EXPECT_EQ(j["camera"], camera::to_json(cam));
  // Half the pile height (max z + r = 0.05 m) on the axis.
  const Eigen::Vector3d point(0.0, 0.0, 0.025);
  EXPECT_DOUBLE_EQ(j["scale_point_m"][2].get<double>(), 0.025);
  EXPECT_DOUBLE_EQ(j["mm_per_px_at_axis"].get<double>(), camera::mm_per_px_at(cam, point));
  // Independent: 1000 * distance / focal length in px.
  EXPECT_NEAR(j["mm_per_px_at_axis"].get<double>(),
              1000.0 * cam.extrinsics.position.norm() / camera::focal_px(cam), 1e-12);
  const nlohmann::json& sr = j["scale_reference"];
  EXPECT_EQ(sr["kind"], "band_bar");
  EXPECT_EQ(sr["band_mm"], 10.0);
  EXPECT_EQ(sr["count"], 10);
  EXPECT_EQ(sr["width_mm"], 20.0);
  EXPECT_NEAR(sr["center_m"][0].get<double>(), 0.055 + 0.025, 1e-12);
  EXPECT_NEAR(sr["center_m"][2].get<double>(), 0.05, 1e-12);
}

TEST(Sidecar, TopViewAndNoScaleReference) {
  Scene s = small_pile();
  const camera::Camera cam = lab_top_camera(s, {.width_px = 320, .height_px = 240});
  RenderOptions o;
  o.view = View::kTop;
  nlohmann::json j = make_sidecar(s, cam, o);
  EXPECT_EQ(j["view"], "top");
  EXPECT_EQ(j["scale_reference"]["kind"], "checker_card");
  EXPECT_EQ(j["scale_reference"]["squares"], 4);
  EXPECT_EQ(j["scale_reference"]["width_mm"], 40.0);
  EXPECT_DOUBLE_EQ(j["mm_per_px_at_axis"].get<double>(),
                   1000.0 * cam.extrinsics.position.z() / camera::focal_px(cam));
  EXPECT_TRUE(j["provenance"].is_null());
  s.scale_reference.enabled = false;
  j = make_sidecar(s, cam, o);
  EXPECT_TRUE(j["scale_reference"].is_null());
}

TEST(WriteRender, WritesPngAndSidecarThatReadBack) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / "reposetwin_render_output_test";
  std::filesystem::remove_all(dir);
  const Scene s = small_pile();
  const camera::Camera cam = lab_side_camera(s, {.width_px = 32, .height_px = 24});
  cv::Mat img(24, 32, CV_8UC3, cv::Scalar(10, 20, 30));
  img.at<cv::Vec3b>(3, 5) = cv::Vec3b(200, 100, 50);
  const std::string stem = (dir / "sub" / "side").string();
  write_render(stem, img, make_sidecar(s, cam, RenderOptions{}, {{"scene", "x.toml"}}));
  const cv::Mat back = cv::imread(stem + ".png", cv::IMREAD_COLOR);
  ASSERT_FALSE(back.empty());
  EXPECT_EQ(cv::norm(img, back, cv::NORM_INF), 0.0);
  const camera::Camera cam_back = camera::read_sidecar(stem + ".json");
  EXPECT_EQ(camera::to_json(cam_back), camera::to_json(cam));
  std::ifstream in(stem + ".json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["provenance"]["scene"], "x.toml");
  // No temporary files are left behind.
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir / "sub")) {
    (void)e;
    ++files;
  }
  EXPECT_EQ(files, 2);
  std::filesystem::remove_all(dir);
}

TEST(WriteRender, LabViewsWriteBothViews) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / "reposetwin_render_lab_views_test";
  std::filesystem::remove_all(dir);
  Renderer renderer;
  const auto cams =
      write_lab_views(renderer, small_pile(), (dir / "pile").string(),
                      {.width_px = 160, .height_px = 120}, RenderOptions{}, {{"seed", 1}});
  ASSERT_EQ(cams.size(), 2u);
  for (const char* view : {"side", "top"}) {
    const std::string stem = (dir / (std::string("pile_") + view)).string();
    const cv::Mat img = cv::imread(stem + ".png", cv::IMREAD_COLOR);
    EXPECT_EQ(img.cols, 160);
    EXPECT_EQ(img.rows, 120);
    std::ifstream in(stem + ".json");
    const nlohmann::json j = nlohmann::json::parse(in);
    EXPECT_EQ(j["view"], view);
    EXPECT_EQ(j["provenance"]["seed"], 1);
  }
  std::filesystem::remove_all(dir);
}

TEST(WriteRender, RejectsEmptyImage) {
  try {
    write_render("/tmp/never_written", cv::Mat(), nlohmann::json::object());
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("never_written.png"), std::string::npos);
  }
}

}  // namespace
}  // namespace reposetwin::render
