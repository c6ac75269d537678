// The grain-shape candidate: a request turns every grain into a rod of four spheres of the
// requested elongation, the scene accepts it, a scene with shapes of its own refuses it, and it
// is tried only when named. A size-dependent rolling resistance is refused on tests that all
// simulate one size distribution, and only then.
#include "experiments/loop/loop_effects.hpp"

#include <gtest/gtest.h>

#include "experiments/io/scene_overrides.hpp"
#include "experiments/loop/loop_sim.hpp"

namespace reposetwin::experiments {
namespace {

const std::string kScene = std::string(REPOSETWIN_SOURCE_DIR) + "/data/loop/small_scene.toml";

LabTest small_test() {
  LabTest t;
  t.id = "m15";
  t.role = Role::kCalibrate;
  t.scene_path = kScene;
  t.overrides = {{"sample.mass_kg", "0.015"}};
  return t;
}

TEST(LoopEffects, GrainShapeMakesEveryGrainARodOfFourSpheres) {
  const CandidateEffect& e = find_effect("grain_shape");
  EXPECT_TRUE(e.opt_in);
  EXPECT_EQ(e.off, 1.0);
  const LabTest t = small_test();
  EXPECT_EQ(effect_unavailable(t, e), "");
  const SimRequest r = make_request(t, "contacts.{sample}-{sample}.rolling_friction", 0.2, 1,
                                    {{&e, 1.8}}, ImageVariant{});
  const SceneConfig s = load_scene(t.scene_path, resolved_overrides(r));
  ASSERT_EQ(s.shapes.size(), 1u);
  EXPECT_EQ(s.shapes[0].elongation, 1.8);
  EXPECT_EQ(s.shapes[0].spheres, kShapeSpheres);
  // Off, the scene is the spheres it was.
  const SimRequest off =
      make_request(t, "contacts.{sample}-{sample}.rolling_friction", 0.2, 1, {}, ImageVariant{});
  EXPECT_TRUE(load_scene(t.scene_path, resolved_overrides(off)).shapes.empty());
}

TEST(LoopEffects, AScenesOwnShapesRefuseTheShapeCandidate) {
  LabTest t = small_test();
  t.overrides.push_back(
      {"sample.shape", "{name = \"rod\", kind = \"generated\", elongation = 1.5, spheres = 4}"});
  EXPECT_NE(effect_unavailable(t, find_effect("grain_shape")).find("its own grain shapes"),
            std::string::npos);
}

// Masses, plates and lift speeds do not tell rolling_size from mu_r: one size distribution in
// every test. Another d_max or d_min does, and so does another sieve table.
TEST(LoopEffects, RollingSizeNeedsTestsOfDifferentSizes) {
  const CandidateEffect& e = find_effect("rolling_size");
  LabTest a = small_test();
  LabTest b = small_test();
  b.id = "m35_wood";
  b.overrides = {{"sample.mass_kg", "0.035"}, {"procedure.lift_speed_m_s", "0.1"}};
  const std::string why = effect_unidentifiable({a, b}, e);
  EXPECT_NE(why.find("same size distribution (3-4 mm)"), std::string::npos) << why;
  // The others have no such condition.
  EXPECT_EQ(effect_unidentifiable({a, b}, find_effect("plate_friction")), "");
  LabTest c = b;
  c.overrides.push_back({"sample.d_min_mm", "3.5"});
  EXPECT_EQ(effect_unidentifiable({a, b, c}, e), "");
  LabTest d = b;
  d.overrides.push_back(
      {"sample.psd", "{sieve_mm = [3.0, 3.5, 4.0], passing_percent = [0.0, 30.0, 100.0]}"});
  EXPECT_EQ(effect_unidentifiable({a, d}, e), "");
  EXPECT_EQ(effect_unidentifiable({a}, e), "");  // one test: nothing to compare
}


// The restitution candidate drives the sample's own pair (not the plate's, which the pile-top
// study found moves nothing), is off at the scene's declared value, and is tried only when named.
TEST(LoopEffects, RestitutionSetsTheSamplesOwnPairFromItsDeclaredValue) {
  const CandidateEffect& e = find_effect("restitution");
  EXPECT_TRUE(e.opt_in);
  EXPECT_TRUE(e.off_from_scene);
  const LabTest t = small_test();
  EXPECT_EQ(scene_value(t, e.key), 0.5);  // small_scene.toml's rock-rock restitution
  EXPECT_EQ(effect_unavailable(t, e), "");
  const SimRequest r = make_request(t, "contacts.{sample}-{sample}.rolling_friction", 0.2, 1,
                                    {{&e, 0.3}}, ImageVariant{});
  const SceneConfig s = load_scene(t.scene_path, resolved_overrides(r));
  const SceneConfig declared = load_scene(t.scene_path, resolved_overrides(make_request(
      t, "contacts.{sample}-{sample}.rolling_friction", 0.2, 1, {}, ImageVariant{})));
  ASSERT_EQ(s.contacts.size(), declared.contacts.size());
  EXPECT_EQ(s.contacts.at({"rock", "rock"}).restitution, 0.3);
  for (const auto& [pair, params] : s.contacts)
    if (pair != std::make_pair(std::string("rock"), std::string("rock")))
      EXPECT_EQ(params.restitution, declared.contacts.at(pair).restitution)
          << pair.first << "-" << pair.second;
}

}  // namespace
}  // namespace reposetwin::experiments
