// Every shipped scene and campaign file of the paper loads (strict parsing, existing scenes,
// overrides that apply), so a user starting a paper campaign does not fail hours in.
#include <gtest/gtest.h>

#include <filesystem>

#include "experiments/calibration/campaign_target.hpp"
#include "experiments/campaign/campaign.hpp"
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

}  // namespace
}  // namespace reposetwin::experiments
