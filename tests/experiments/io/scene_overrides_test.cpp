// Typed overrides at the file edge: "dotted.key=value" from --set (or a loop row) is parsed into
// an Override once, applied to the scene, and the strict scene parser reads the result; a text
// without '=' or a key the scene does not know is refused, naming where it came from and the key.
#include "experiments/io/scene_overrides.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "../../support/tiny_scene.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/overrides.hpp"
#include "experiments/io/provenance.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

std::string scene_file() {
  const fs::path p = fs::temp_directory_path() / "reposetwin_scene_overrides" / "tiny.toml";
  write_file_atomic(p.string(), test_support::kTinyScene);
  return p.string();
}

std::string message_of(const std::string& path, const std::string& set) {
  try {
    load_scene(path, {set});
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(SceneOverrides, AValueReachesTheSceneAndKeepsItsType) {
  const SceneConfig s = load_scene(scene_file(), {"sample.mass_kg=0.009", "scene.seed=11"});
  EXPECT_DOUBLE_EQ(s.mass, 0.009);
  EXPECT_EQ(s.seed, 11u);
}

TEST(SceneOverrides, AMissingEqualsIsRefusedNamingTheFlagAndTheText) {
  const std::string what = message_of(scene_file(), "sample.mass_kg");
  EXPECT_NE(what.find("--set"), std::string::npos) << what;
  EXPECT_NE(what.find("sample.mass_kg"), std::string::npos) << what;
  EXPECT_NE(what.find("dotted.key=value"), std::string::npos) << what;
  EXPECT_THROW(parse_override("=0.1", "data.csv line 3"), InputError);
  EXPECT_THROW(parse_override("no_equals", "data.csv line 3"), InputError);
  const Override o = parse_override("contacts.rock-rock.friction=0.4", "--set");
  EXPECT_EQ(o.key, "contacts.rock-rock.friction");
  EXPECT_EQ(o.value, "0.4");
}

TEST(SceneOverrides, AnUnknownKeyIsRefusedNamingTheFileAndTheKey) {
  const std::string path = scene_file();
  const std::string what = message_of(path, "sample.masss_kg=0.01");
  EXPECT_NE(what.find(path), std::string::npos) << what;
  EXPECT_NE(what.find("masss_kg"), std::string::npos) << what;
  const std::string missing_table = message_of(path, "samples.mass_kg=0.01");
  EXPECT_NE(missing_table.find("samples"), std::string::npos) << missing_table;
  const std::string not_toml = message_of(path, "sample.mass_kg=abc");
  EXPECT_NE(not_toml.find("not a TOML value"), std::string::npos) << not_toml;
  EXPECT_NE(not_toml.find("sample.mass_kg"), std::string::npos) << not_toml;
}

}  // namespace
}  // namespace reposetwin::experiments
