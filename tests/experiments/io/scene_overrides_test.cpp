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
  // A word where the scene has a number is read as a word, and the type rule refuses it.
  const std::string word = message_of(path, "sample.mass_kg=abc");
  EXPECT_NE(word.find("--set"), std::string::npos) << word;
  EXPECT_NE(word.find("sample.mass_kg"), std::string::npos) << word;
  EXPECT_NE(word.find("abc"), std::string::npos) << word;
  EXPECT_NE(word.find("floating-point"), std::string::npos) << word;
  // Text that starts like a TOML string or array and is not one is a typo in it.
  const std::string open_quote = message_of(path, "scene.name=\"tiny");
  EXPECT_NE(open_quote.find("not a TOML value"), std::string::npos) << open_quote;
  const std::string open_array = message_of(path, "sample.psd.sieve_mm=[3.0, 3.5");
  EXPECT_NE(open_array.find("not a TOML value"), std::string::npos) << open_array;
  const std::string empty = message_of(path, "sample.mass_kg=");
  EXPECT_NE(empty.find("the value is empty"), std::string::npos) << empty;
  EXPECT_NE(empty.find("sample.mass_kg"), std::string::npos) << empty;
}

TEST(SceneOverrides, AStringKeyTakesABareWord) {
  const SceneConfig s =
      load_scene(scene_file(), {"contacts.rock-rock.rolling_model=cdt", "scene.name=my pile"});
  EXPECT_EQ(s.name, "my pile");
  ASSERT_FALSE(s.contacts.empty());
  EXPECT_EQ(s.contacts.begin()->second.rolling_model, sim::RollingModel::kCdt);
  // The quoted form means the same.
  const SceneConfig q = load_scene(scene_file(), {"contacts.rock-rock.rolling_model=\"cdt\""});
  EXPECT_EQ(q.contacts.begin()->second.rolling_model, sim::RollingModel::kCdt);
}

TEST(SceneOverrides, ASetCreatesAMissingTableAndTheParserStillJudgesIt) {
  // The tiny scene has no [output] table: --set makes it, and the value arrives.
  const SceneConfig s = load_scene(scene_file(), {"output.frame_interval_s=0.25"});
  EXPECT_DOUBLE_EQ(s.output.frame_interval, 0.25);
  // A misspelt table is created too, and then refused by the strict parser, which says the
  // key came from --set and suggests the table meant.
  const std::string what = message_of(scene_file(), "outptu.frame_interval_s=0.25");
  EXPECT_NE(what.find("outptu"), std::string::npos) << what;
  EXPECT_NE(what.find("did you mean output"), std::string::npos) << what;
  EXPECT_NE(what.find("(set by --set outptu.frame_interval_s=0.25)"), std::string::npos) << what;
}

TEST(SceneOverrides, AnUnknownKeyFromSetSaysSoWithTheValueAsTyped) {
  const std::string what = message_of(scene_file(), "numerics.dt_fractio=1e-30");
  EXPECT_NE(what.find("numerics.dt_fractio"), std::string::npos) << what;
  EXPECT_NE(what.find("(set by --set numerics.dt_fractio=1e-30)"), std::string::npos) << what;
  EXPECT_NE(what.find("value 1e-30"), std::string::npos) << what;
  EXPECT_EQ(what.find("1.0000000000000001e-30"), std::string::npos) << what;
  // A bad value set on a known key is named as set too.
  const std::string range = message_of(scene_file(), "sample.mass_kg=-1");
  EXPECT_NE(range.find("(set by --set sample.mass_kg=-1)"), std::string::npos) << range;
}

// Changes the working directory for one scope (a --set path is the shell's, not the scene's).
struct InDirectory {
  explicit InDirectory(const fs::path& d) : old(fs::current_path()) { fs::current_path(d); }
  ~InDirectory() { fs::current_path(old); }
  fs::path old;
};

TEST(SceneOverrides, APsdFileFromSetReplacesTheInlineTableRelativeToTheShell) {
  const std::string scene = scene_file();
  const fs::path here = fs::temp_directory_path() / "reposetwin_scene_overrides" / "shell";
  fs::create_directories(here / "psd");
  write_file_atomic((here / "psd" / "coarse.toml").string(),
                    "[psd]\nsieve_mm = [3.5, 4.0]\npassing_percent = [0.0, 100.0]\n");
  InDirectory cd(here);
  const SceneConfig s = load_scene(scene, {"sample.psd_file=psd/coarse.toml"});
  // The file's table, not the scene's: the smallest sieve is 3.5 mm where the scene has 3.0.
  ASSERT_FALSE(s.psd.spec.table.size.empty());
  EXPECT_DOUBLE_EQ(s.psd.spec.table.size.front(), 3.5e-3);
  // A path that is not there is named as the user's, resolved where they stand.
  const std::string what = message_of(scene, "sample.psd_file=psd/missing.toml");
  EXPECT_NE(what.find((here / "psd" / "missing.toml").string()), std::string::npos) << what;
  EXPECT_NE(what.find("(set by --set sample.psd_file=psd/missing.toml)"), std::string::npos)
      << what;
}

}  // namespace
}  // namespace reposetwin::experiments
