// The optional contact effects as scene keys of [contacts.a-b]: cohesion_energy_density,
// rolling_size_exponent, rolling_reference_diameter_m. They parse into sim::PairParams, reach the
// engine's pair constants, are written into the resolved scene, can be set with --set, and bad
// values are errors naming the file, the key and the value. Absent keys leave a run unchanged.
#include <gtest/gtest.h>
#include <toml++/toml.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "../../support/tiny_scene.hpp"
#include "experiments/io/scene.hpp"
#include "experiments/io/scene_overrides.hpp"
#include "experiments/io/input_error.hpp"
#include "sim/world.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

/// The tiny scene with `lines` added to its [contacts.rock-rock] table.
std::string scene_with(const std::string& lines) {
  std::string text = test_support::kTinyScene;
  const std::string anchor = "rolling_friction = 0.3\n";
  const auto at = text.find(anchor);
  EXPECT_NE(at, std::string::npos);
  return text.insert(at + anchor.size(), lines);
}

const std::string kFile = "effects_scene.toml";

SceneConfig parse(const std::string& lines) { return parse_scene_text(scene_with(lines), kFile); }

/// The message of the InputError that parsing `lines` throws ("" if none).
std::string error_of(const std::string& lines) {
  try {
    parse(lines);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

const sim::PairParams& rock_rock(const SceneConfig& s) { return s.contacts.at({"rock", "rock"}); }

TEST(SceneEffects, KeysParseIntoThePairAndReachTheEngine) {
  const SceneConfig s = parse(
      "cohesion_energy_density = 2.5e4\nrolling_size_exponent = -0.5\n"
      "rolling_reference_diameter_m = 0.0035\n");
  EXPECT_EQ(rock_rock(s).cohesion_energy_density, 2.5e4);
  EXPECT_EQ(rock_rock(s).rolling_size_exponent, -0.5);
  EXPECT_EQ(rock_rock(s).rolling_reference_diameter, 0.0035);
  const sim::Model m = build_model(s, 1.5e-3, 2e-3);
  const sim::ContactConstants& c = m.table.c(0, 0);
  EXPECT_TRUE(c.cohesive);
  EXPECT_EQ(c.cohesion_energy_density, 2.5e4);
  EXPECT_TRUE(c.size_dependent_rolling);
  EXPECT_EQ(c.rolling_size_exponent, -0.5);
  EXPECT_EQ(c.rolling_reference_diameter, 0.0035);
}

TEST(SceneEffects, AbsentKeysMeanOffAndTheResolvedSceneStatesThem) {
  const SceneConfig off = parse("");
  EXPECT_EQ(rock_rock(off).cohesion_energy_density, 0.0);
  EXPECT_EQ(rock_rock(off).rolling_size_exponent, 0.0);
  const sim::Model m = build_model(off, 1.5e-3, 2e-3);
  EXPECT_FALSE(m.table.c(0, 0).cohesive);
  EXPECT_FALSE(m.table.c(0, 0).size_dependent_rolling);
  const toml::table resolved = toml::parse(off.resolved_toml);
  EXPECT_EQ(resolved["contacts"]["rock-rock"]["cohesion_energy_density"].value<double>(), 0.0);
  EXPECT_EQ(resolved["contacts"]["rock-rock"]["rolling_size_exponent"].value<double>(), 0.0);
  EXPECT_EQ(resolved["contacts"]["rock-rock"]["rolling_reference_diameter_m"].value<double>(), 0.0);
  // A set value is written as read, and the resolved scene parses back to the same pair.
  const SceneConfig on = parse(
      "cohesion_energy_density = 1200\nrolling_size_exponent = 0.25\n"
      "rolling_reference_diameter_m = 0.004\n");
  const toml::table r2 = toml::parse(on.resolved_toml);
  EXPECT_EQ(r2["contacts"]["rock-rock"]["cohesion_energy_density"].value<double>(), 1200.0);
  EXPECT_EQ(r2["contacts"]["rock-rock"]["rolling_size_exponent"].value<double>(), 0.25);
  EXPECT_EQ(r2["contacts"]["rock-rock"]["rolling_reference_diameter_m"].value<double>(), 0.004);
  const SceneConfig again = parse_scene_text(on.resolved_toml, kFile);
  EXPECT_EQ(rock_rock(again).cohesion_energy_density, 1200.0);
  EXPECT_EQ(rock_rock(again).rolling_size_exponent, 0.25);
  EXPECT_EQ(rock_rock(again).rolling_reference_diameter, 0.004);
}

TEST(SceneEffects, BadValuesNameTheFileTheKeyAndTheValue) {
  const std::string neg = error_of("cohesion_energy_density = -5.0\n");
  EXPECT_NE(neg.find(kFile), std::string::npos) << neg;
  EXPECT_NE(neg.find("contacts.rock-rock.cohesion_energy_density"), std::string::npos) << neg;
  EXPECT_NE(neg.find("-5"), std::string::npos) << neg;
  const std::string no_ref = error_of("rolling_size_exponent = 0.5\n");
  EXPECT_NE(no_ref.find(kFile), std::string::npos) << no_ref;
  EXPECT_NE(no_ref.find("contacts.rock-rock.rolling_reference_diameter_m"), std::string::npos)
      << no_ref;
  EXPECT_NE(no_ref.find("= 0"), std::string::npos) << no_ref;
  const std::string neg_ref =
      error_of("rolling_size_exponent = 0.5\nrolling_reference_diameter_m = -0.002\n");
  EXPECT_NE(neg_ref.find("rolling_reference_diameter_m = -0.002"), std::string::npos) << neg_ref;
  const std::string text = error_of("rolling_size_exponent = \"big\"\n");
  EXPECT_NE(text.find("contacts.rock-rock.rolling_size_exponent"), std::string::npos) << text;
  EXPECT_NE(text.find("big"), std::string::npos) << text;
  const std::string nan = error_of("cohesion_energy_density = nan\n");
  EXPECT_NE(nan.find("cohesion_energy_density = nan"), std::string::npos) << nan;
  // Unknown keys are still rejected, typos of the new ones included.
  const std::string typo = error_of("cohesion_energy = 10.0\n");
  EXPECT_NE(typo.find("contacts.rock-rock.cohesion_energy"), std::string::npos) << typo;
  // A reference diameter alone (exponent 0) is allowed and unused.
  EXPECT_EQ(error_of("rolling_reference_diameter_m = 0.003\n"), "");
}

TEST(SceneEffects, SetOverridesTheKeysOfAPair) {
  const fs::path dir = fs::temp_directory_path() / "reposetwin_test_scene_effects";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path file = dir / "scene.toml";
  std::ofstream(file) << scene_with("");
  const SceneConfig s =
      load_scene(file.string(), {"contacts.rock-rock.cohesion_energy_density=150",
                                 "contacts.rock-rock.rolling_size_exponent=-1.0",
                                 "contacts.rock-rock.rolling_reference_diameter_m=3.5e-3"});
  EXPECT_EQ(rock_rock(s).cohesion_energy_density, 150.0);
  EXPECT_EQ(rock_rock(s).rolling_size_exponent, -1.0);
  EXPECT_EQ(rock_rock(s).rolling_reference_diameter, 3.5e-3);
  try {
    load_scene(file.string(), {"contacts.rock-rock.cohesion_energy_density=-1.0"});
    ADD_FAILURE() << "a negative cohesion through --set must be refused";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(file.string()), std::string::npos) << what;
    EXPECT_NE(what.find("cohesion_energy_density = -1"), std::string::npos) << what;
  }
  fs::remove_all(dir);
}

/// The state hash of a few spheres dropped onto the plate of `scene`'s model.
std::uint64_t drop_hash(const SceneConfig& scene) {
  sim::World w(build_model(scene, 1.5e-3, 2e-3));
  for (int k = 0; k < 8; ++k) {
    const double r = (k % 2) ? 2e-3 : 1.5e-3;
    w.add_particle(sim::Vec3(1.1e-3 * (k % 3), 0.9e-3 * (k % 2), (2.0 + 4.2 * k) * 1e-3), r, 0);
  }
  for (int s = 0; s < 2000; ++s) w.step();
  return sim::state_hash(w.state());
}

TEST(SceneEffects, ExplicitZerosRunBitIdenticallyToAbsentKeys) {
  const std::uint64_t absent = drop_hash(parse(""));
  EXPECT_EQ(drop_hash(parse("cohesion_energy_density = 0.0\nrolling_size_exponent = 0.0\n"
                            "rolling_reference_diameter_m = 0.003\n")),
            absent);
  EXPECT_NE(drop_hash(parse("cohesion_energy_density = 1e4\n")), absent)
      << "the run must be able to see cohesion";
}

}  // namespace
}  // namespace reposetwin::experiments
