// Every shipped scene and campaign file of the paper, and the shape study, loads (strict
// parsing, existing scenes, overrides that apply), so a user starting a campaign does not fail
// hours in.
#include <gtest/gtest.h>

#include <filesystem>

#include "experiments/calibration/campaign_target.hpp"
#include "experiments/campaign/campaign.hpp"
#include "experiments/campaign/case_runner.hpp"
#include "experiments/io/scene.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

TEST(PaperFiles, EverySceneParses) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(fs::path(REPOSETWIN_SOURCE_DIR) / "data/scenes/paper")) {
    if (e.path().extension() != ".toml") continue;
    EXPECT_NO_THROW(parse_scene_file(e.path().string())) << e.path();
    ++n;
  }
  EXPECT_GE(n, 13);
  EXPECT_NO_THROW(parse_scene_file(std::string(REPOSETWIN_SOURCE_DIR) + "/data/scenes/quick.toml"));
}

TEST(PaperFiles, EveryCampaignLoads) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(fs::path(REPOSETWIN_SOURCE_DIR) / "experiments/paper")) {
    if (e.path().extension() != ".toml") continue;
    if (e.path().filename() == "index.toml") continue;  // the paper index (paper_index_test.cpp)
    const Campaign c = load_campaign(e.path().string());
    EXPECT_FALSE(c.paper.empty()) << e.path();
    for (const CaseSpec& run : c.runs) EXPECT_NO_THROW(build_case_scene(run)) << run.id();
    ++n;
  }
  EXPECT_GE(n, 8);
}

// Issue 20's first shape study: two samples x (spheres, rods L/I 1.5 and 2) x two mu_r, three
// seeds each, every case's scene read as its run will read it, the rods' shape table added to
// the sphere scenes by the case.
TEST(PaperFiles, TheShapeStudyRunsTheShapesItNames) {
  const Campaign c = load_campaign(std::string(REPOSETWIN_SOURCE_DIR) +
                                   "/experiments/studies/clump_shapes_s3_s4.toml");
  EXPECT_EQ(c.runs.size(), 36u);
  EXPECT_NO_THROW(check_pile_cases(c));
  int rods = 0;
  for (const CaseSpec& run : c.runs) {
    if (run.seed != 1) continue;
    SCOPED_TRACE(run.case_name);
    const SceneDoc doc = build_case_scene(run);
    const SceneConfig scene = doc.config();
    const bool s3 = run.case_name.rfind("s3_", 0) == 0;
    EXPECT_DOUBLE_EQ(scene.mass, s3 ? 0.7 : 0.9);
    const double mu = run.case_name.ends_with("mu0.1") ? 0.1 : 0.4;
    EXPECT_DOUBLE_EQ(doc.number("contacts.rock-rock.rolling_friction").value(), mu);
    EXPECT_DOUBLE_EQ(doc.number("contacts.rock-plate.rolling_friction").value(), mu);
    if (run.case_name.find("spheres") != std::string::npos) {
      EXPECT_TRUE(scene.shapes.empty());
      continue;
    }
    ++rods;
    ASSERT_EQ(scene.shapes.size(), 1u);
    EXPECT_EQ(scene.shapes[0].spheres, 4);
    EXPECT_DOUBLE_EQ(scene.shapes[0].elongation,
                     run.case_name.find("e1.5") != std::string::npos ? 1.5 : 2.0);
  }
  EXPECT_EQ(rods, 8);
}

}  // namespace
}  // namespace reposetwin::experiments
