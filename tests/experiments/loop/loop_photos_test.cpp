// The loop keeps, for each test, the lab's photo and one twin photo of the same test with both
// overlays, for the page: on the tiny scene, a lab photo with a camera sidecar (a cone of
// spheres photographed by hand) gets a twin photo through that camera, at its scale and
// resolution, copied into OUT/photos/<id>/ and named in loop.json; a test with a typed angle
// gets the twin's photo alone (through the twin's own framing). Each costs one photograph job
// and no pile run (the pile is the baseline's). On a cache carried without PNGs or particles the
// loop still finishes, and the page says why a twin photo is missing.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "../../support/cone_pile.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/loop/loop.hpp"
#include "experiments/loop/loop_data.hpp"
#include "experiments/loop/loop_records.hpp"
#include "experiments/photos/photographs.hpp"
#include "experiments/report/loop_report.hpp"
#include "experiments/report/page_check.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

const std::string kScene = std::string(REPOSETWIN_SOURCE_DIR) + "/data/loop/tiny_scene.toml";

// The lab's camera: 0.30 m away from azimuth 20 deg, 640 x 480 px, 96 mm of field at the axis
// (the twin's own framing would differ in all three).
camera::Camera lab_camera() { return camera::side_view(0.30, 0.096, 0.0, 20.0, 640, 480); }

// A cone of 3.5 mm spheres (H 12 mm, base reach 22 mm) photographed through the lab camera,
// with its sidecar beside it; returns the photo's path relative to `dir`.
std::string lab_photo(const fs::path& dir) {
  const test_support::Spheres c = test_support::make_cone(12e-3, 22e-3, 0.0, 0.0, 1.75e-3, 11, 0.3);
  PhotoSettings s;
  s.lab_cameras = {lab_camera()};
  s.top_view = false;
  s.scale_reference = false;
  s.write_overlays = false;
  const PilePhotos p =
      photograph_pile(PileSpheres{{c.x.begin(), c.x.end()}, c.r, std::vector<int>(c.r.size(), 0)},
                      s, (dir / "lab").string());
  return "lab/" + p.sides.at(0).stem + ".png";
}

TEST(LoopPhotos, LoopJsonNamesTheLabAndTwinPhotosOfEachTestWithPhotos) {
  const fs::path dir = fs::temp_directory_path() / "reposetwin_loop_photos_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string photo = lab_photo(dir);
  // Two tests of one pile: one with the lab's photo, one with a typed angle (no photo).
  write_file_atomic((dir / "lab.csv").string(),
                    "id,role,scene,photo,angle_deg\n"
                    "pic,calibrate," +
                        kScene + "," + photo +
                        ",\n"
                        "typed,validate," +
                        kScene + ",,27\n");
  const LabData data = read_lab_csv((dir / "lab.csv").string());
  LoopSettings s;
  s.mu_grid = {0.1, 0.3};
  s.seeds = {1, 2};
  s.at_bound = GridBound::kRefuse;
  s.max_pours = 2;
  s.progress = false;
  s.page = write_loop_html;
  s.cache_dir = (dir / "cache").string();
  const fs::path out = dir / "loop";
  const json loop = run_loop(data, out.string(), s);

  ASSERT_EQ(loop.at("photo_pairs").size(), 2u) << "one per test";
  const json& p = loop["photo_pairs"][0];
  EXPECT_EQ(p["id"], "pic");
  const json& typed = loop["photo_pairs"][1];
  EXPECT_EQ(typed["id"], "typed");
  EXPECT_TRUE(typed["lab"].is_null()) << "the lab gave no photo of this test";
  ASSERT_FALSE(typed["twin"].is_null()) << typed.dump();
  EXPECT_TRUE(fs::exists(out / typed["twin"]["overlay"].get<std::string>()));
  EXPECT_NE(typed["twin"]["width_px"], 640)
      << "the twin's own framing, not the other test's lab camera";
  ASSERT_FALSE(p["twin"].is_null()) << p.dump();
  for (const char* who : {"lab", "twin"})
    for (const char* f : {"photo", "overlay"}) {
      const fs::path file = out / p[who][f].get<std::string>();
      EXPECT_TRUE(fs::exists(file)) << file;
      const cv::Mat img = cv::imread(file.string());
      EXPECT_EQ(img.cols, p[who]["width_px"].get<int>()) << file;
      EXPECT_EQ(img.rows, p[who]["height_px"].get<int>()) << file;
    }
  EXPECT_NE(p["lab"]["overlay"], p["twin"]["overlay"]);
  // Through the lab's camera: its resolution, and its scale at the axis (the same lens at the
  // same distance; the piles' sizes differ, hence the scale's axis point a little).
  EXPECT_EQ(p["twin"]["width_px"], 640);
  EXPECT_EQ(p["twin"]["height_px"], 480);
  const double lab_mm = p["lab"]["mm_per_px"], twin_mm = p["twin"]["mm_per_px"];
  EXPECT_NEAR(lab_mm, 0.096e3 / 640, 0.01 * lab_mm);
  EXPECT_NEAR(twin_mm, lab_mm, 1e-3 * lab_mm);
  // The twin pile is the baseline's: a grid point and a pour that made the first seed's pile.
  EXPECT_TRUE(p["mu_r"] == 0.1 || p["mu_r"] == 0.3) << p["mu_r"];
  EXPECT_EQ(p["seed"].get<std::uint64_t>() % kRepourSeedStride, 1u);
  // 2 tests x 2 grid points x 2 seeds photographed (the test with a lab camera through it, the
  // other through the twin's own), and one photo a test for the page; the piles are shared.
  EXPECT_EQ(loop["simulations"]["pile_runs_started"].get<int>(), 4);
  EXPECT_EQ(loop["simulations"]["photos_started"].get<int>(), 10);
  // The page places both overlays.
  const std::string html = read_file((out / "index.html").string());
  EXPECT_NE(html.find("src='photos/pic/lab.measured.png'"), std::string::npos);
  EXPECT_NE(html.find("src='photos/pic/twin.measured.png'"), std::string::npos);
  EXPECT_NE(html.find("src='photos/typed/twin.measured.png'"), std::string::npos);
  // And opens in a copied folder: every image and link relative and present, no machine path.
  for (const report::PageProblem& q : report::page_problems(out / "index.html"))
    ADD_FAILURE() << report::to_string(q.kind) << ": " << q.what;
  // The loop.json the page was read from reads back into its LoopRecord and writes the same
  // JSON: the lab's photos, their measurement and cameras, the photo pairs, every record.
  const json back = to_json(loop_record_from_json(loop, (out / "loop.json").string()));
  EXPECT_EQ(back, loop) << json::diff(loop, back).dump(1).substr(0, 2000);

  // Again on the same cache: nothing is simulated or photographed anew.
  s.force = true;
  const json again = run_loop(data, out.string(), s);
  EXPECT_EQ(again["simulations"]["pile_runs_started"].get<int>(), 0);
  EXPECT_EQ(again["simulations"]["photos_started"].get<int>(), 0);
  EXPECT_EQ(again["photo_pairs"][0]["twin"], p["twin"]);

  // A cache carried to another machine keeps the photograph's result.json, not its PNGs
  // (scripts/collect_results.sh): the loop still finishes, and the page says why that twin
  // photo is missing and how to make it again.
  fs::remove(typed["twin"]["source"].get<std::string>());
  const json carried = run_loop(data, out.string(), s);
  EXPECT_EQ(carried["simulations"]["photos_started"].get<int>(), 0);
  EXPECT_EQ(carried["photo_pairs"][0]["twin"], p["twin"]);
  EXPECT_TRUE(carried["photo_pairs"][1]["twin"].is_null());
  EXPECT_NE(
      carried["photo_pairs"][1]["note"].get<std::string>().find("a cache collected without images"),
      std::string::npos)
      << carried["photo_pairs"][1].dump();
  // Nor are the piles' particles carried: a page photo not yet taken of a collected pile cannot
  // be taken. The loop still finishes, the pair saying why.
  fs::remove_all(fs::path(typed["twin"]["source"].get<std::string>()).parent_path());
  for (const auto& e : fs::recursive_directory_iterator(dir / "cache"))
    if (e.path().filename() == "final.vtp") fs::remove(e.path());
  const json bare = run_loop(data, out.string(), s);
  EXPECT_TRUE(bare["photo_pairs"][1]["twin"].is_null());
  EXPECT_FALSE(bare["photo_pairs"][1]["note"].get<std::string>().empty())
      << bare["photo_pairs"][1].dump();
  std::printf("without particles: %s\n", bare["photo_pairs"][1]["note"].get<std::string>().c_str());
  std::printf("lab %.4f mm/px, twin %.4f mm/px at mu_r %.2f seed %llu; lab %.2f deg, twin %.2f\n",
              lab_mm, twin_mm, p["mu_r"].get<double>(),
              static_cast<unsigned long long>(p["seed"].get<std::uint64_t>()),
              p["lab"]["angle_deg"].get<double>(), p["twin"]["angle_deg"].get<double>());
}

}  // namespace
}  // namespace reposetwin::experiments
