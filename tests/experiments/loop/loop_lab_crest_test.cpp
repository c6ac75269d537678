// The lab's crest from its own photos: a row with photos and no crest_mm takes the flat-top width
// vision measures on them (with the views' uncertainty), a typed crest_mm wins over the photos',
// and a row with neither carries no crest at all (loop.json as without the feature).
//
// The lab's photos are renders of a known flat top: a frustum fixture (render::Shell, 40 mm across
// its top, 120 mm at its foot, 30 mm high) on the plate, photographed level from 0.6 and 0.5 m
// at azimuths 20 and 110 deg, each with a lab-style camera sidecar. Its crest width is the closed
// form 2 r_top = 40 mm; CrestRender.FrustumFixtureGivesItsTopWidth reads one such view within
// 1 mm, the tolerance here. No simulation.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "../../support/frustum_scene.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/loop/loop_data.hpp"
#include "render/renderer.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

const std::string kScene = std::string(REPOSETWIN_SOURCE_DIR) + "/data/loop/tiny_scene.toml";
constexpr double kH = 0.03, kRb = 0.06, kRt = 0.02;  // frustum height, foot and top radii [m]

// Renders the frustum through a level camera `l` metres away at azimuth `az` and writes
// DIR/NAME.png with its sidecar DIR/NAME.json as a lab writes one (the camera only).
std::string frustum_photo(const fs::path& dir, const std::string& name, double l, double az) {
  const render::Scene scene = test_support::frustum_scene(kH, kRb, kRt);
  const camera::Camera cam = camera::side_view(l, 0.2, 0.0, az, 960, 720);
  fs::create_directories(dir);
  cv::imwrite((dir / (name + ".png")).string(), render::render_image(scene, cam, {}));
  std::ofstream(dir / (name + ".json")) << nlohmann::json{{"camera", camera::to_json(cam)}}.dump(2);
  return name + ".png";
}

TEST(LoopLabCrest, PhotoCrestIsReadAndATypedOneWins) {
  const fs::path dir = fs::temp_directory_path() / "reposetwin_loop_lab_crest_test";
  fs::remove_all(dir);
  const std::string photos = frustum_photo(dir, "frustum_az020", 0.6, 20.0) + ";" +
                             frustum_photo(dir, "frustum_az110", 0.5, 110.0);
  const fs::path csv = dir / "lab.csv";
  write_file_atomic(csv.string(),
                    "id,role,scene,angle_deg,crest_mm,photo\n"
                    "from_photo,calibrate," +
                        kScene + ",,," + photos +
                        "\n"
                        "typed,calibrate," +
                        kScene + ",,12.5," + photos +
                        "\n"
                        "plain,validate," +
                        kScene + ",30,,\n");
  const LabData data = read_lab_csv(csv.string());
  ASSERT_EQ(data.tests.size(), 3u);

  // The photos' crest, within 1 mm of the closed form, with the views' uncertainty.
  const LabTest& p = data.tests[0];
  ASSERT_TRUE(p.crest_mm.has_value());
  EXPECT_NEAR(*p.crest_mm, 2e3 * kRt, 1.0);
  EXPECT_EQ(p.crest_source, "photo");
  const nlohmann::json& crest = p.photo_measurement.at("crest_width_m");
  ASSERT_TRUE(p.crest_sigma_mm.has_value());
  EXPECT_DOUBLE_EQ(*p.crest_sigma_mm, 1e3 * crest.at("sigma_mean").get<double>());
  EXPECT_GT(*p.crest_sigma_mm, 0.0);
  EXPECT_LT(*p.crest_sigma_mm, 1.0);  // two clean views of one rim
  const nlohmann::json jp = to_json(p);
  EXPECT_EQ(jp.at("crest_source"), "photo");
  EXPECT_DOUBLE_EQ(jp.at("crest_mm").get<double>(), *p.crest_mm);
  EXPECT_DOUBLE_EQ(jp.at("crest_sigma_mm").get<double>(), *p.crest_sigma_mm);
  std::printf("frustum photos: crest %.3f +- %.3f mm (views' sd %.3f mm; closed form %.1f mm)\n",
              *p.crest_mm, *p.crest_sigma_mm, 1e3 * crest.at("stddev").get<double>(), 2e3 * kRt);

  // Typed wins over the same photos, which still record their own reading.
  const LabTest& t = data.tests[1];
  ASSERT_TRUE(t.crest_mm.has_value());
  EXPECT_DOUBLE_EQ(*t.crest_mm, 12.5);
  EXPECT_EQ(t.crest_source, "typed");
  EXPECT_FALSE(t.crest_sigma_mm.has_value());
  EXPECT_EQ(to_json(t).at("crest_source"), "typed");
  EXPECT_FALSE(to_json(t).contains("crest_sigma_mm"));
  EXPECT_NEAR(1e3 * t.photo_measurement.at("crest_width_m").at("mean").get<double>(), *p.crest_mm,
              1e-9);
  // The photos' H and D replace nothing typed here, and read the frustum (angle atan(2H/D)).
  EXPECT_NEAR(*t.diameter_mm, 2e3 * kRb, 1.5);

  // Neither photos nor a crest: no crest field of any kind.
  const LabTest& n = data.tests[2];
  EXPECT_FALSE(n.crest_mm.has_value());
  EXPECT_TRUE(n.crest_source.empty());
  const nlohmann::json jn = to_json(n);
  for (const char* k : {"crest_mm", "crest_source", "crest_sigma_mm"})
    EXPECT_FALSE(jn.contains(k)) << k;
}

}  // namespace
}  // namespace reposetwin::experiments
