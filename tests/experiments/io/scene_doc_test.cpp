// The typed overrides and the scene document behind them: an Override's text reads back to the
// same value (floats to the bit), a campaign's list keeps one value per key in key order (a
// whole table before its members), result files record the values as JSON numbers and strings,
// and SceneDoc answers single values by key path and builds the one SceneConfig.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "../../support/tiny_scene.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/overrides.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/scene_overrides.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

std::string scene_file() {
  const fs::path p = fs::temp_directory_path() / "reposetwin_scene_doc" / "tiny.toml";
  write_file_atomic(p.string(), test_support::kTinyScene);
  return p.string();
}

TEST(SceneDoc, NumberOverridesReadBackToTheSameBits) {
  for (double v : {0.39896802757437844, 0.1, 1.0, 1e-20, 0.30000000000000004}) {
    const Override o = number_override("sample.mass_kg", v);
    EXPECT_EQ(o.key, "sample.mass_kg");
    EXPECT_EQ(overrides_to_json({o})["sample.mass_kg"].get<double>(), v) << o.value;
    EXPECT_NE(o.value.find_first_of(".e"), std::string::npos) << o.value;  // a TOML float
  }
  EXPECT_EQ(overrides_to_json({string_override("0", "a.b=\"x\"")})["0"], "a.b=\"x\"");
}

TEST(SceneDoc, SetOverrideKeepsOneValuePerKeyInKeyOrder) {
  std::vector<Override> list;
  set_override(list, {"rolling.mu_r", "0.3"});
  set_override(list, {"sample.mass", "1"});
  set_override(list, {"rolling", "{ model = 'cdt' }"});
  set_override(list, {"rolling.mu_r", "0.2"});  // replaces, does not add
  ASSERT_EQ(list.size(), 3u);
  EXPECT_EQ(list[0].key, "rolling");
  EXPECT_EQ(list[1], (Override{"rolling.mu_r", "0.2"}));
  EXPECT_EQ(list[2].key, "sample.mass");
  const nlohmann::json j = overrides_to_json(list);
  EXPECT_EQ(j["rolling"]["model"], "cdt");
  EXPECT_EQ(j["sample.mass"], 1);
  EXPECT_TRUE(is_toml_value("[1, 2.5]"));
  EXPECT_FALSE(is_toml_value("cdt"));
}

TEST(SceneDoc, AnswersByKeyPathAndBuildsTheScene) {
  const std::string path = scene_file();
  SceneDoc doc(path, std::vector<Override>{number_override("sample.mass_kg", 0.007)}, "test");
  EXPECT_EQ(doc.number("sample.mass_kg"), 0.007);
  EXPECT_FALSE(doc.number("sample.nosuch").has_value());
  EXPECT_TRUE(doc.has("sample"));
  EXPECT_FALSE(doc.has("nosuch"));
  EXPECT_FALSE(doc.string("sample.mass_kg").has_value());  // a number is not a string
  doc.set_seed(42);
  const SceneConfig s = doc.config();
  EXPECT_EQ(s.seed, 42u);
  EXPECT_DOUBLE_EQ(s.mass, 0.007);
  EXPECT_EQ(s.file, path);
}

TEST(SceneDoc, ABadOverrideNamesTheOriginAndTheKey) {
  try {
    SceneDoc(scene_file(), std::vector<Override>{{"nosuch.table.key", "1.0"}}, "campaign.toml, case a");
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("campaign.toml, case a"), std::string::npos) << what;
    EXPECT_NE(what.find("nosuch.table.key"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace reposetwin::experiments
