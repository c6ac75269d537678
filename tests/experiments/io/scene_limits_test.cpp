// Values outside physical or numerical limits are refused when the scene is read, naming the
// file and the key as the user wrote it, before anything runs (each row was once accepted and
// failed later, or ran to a wrong answer).
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "../../support/tiny_scene.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/scene.hpp"
#include "experiments/io/scene_overrides.hpp"
#include "sim/psd.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

struct Row {
  std::string set;  // --set text
  std::string key;  // what the message must name
};

class SceneLimits : public ::testing::TestWithParam<Row> {};

TEST_P(SceneLimits, IsRefusedNamingTheFileAndTheKey) {
  const fs::path path = fs::temp_directory_path() / "reposetwin_scene_limits" / "tiny.toml";
  write_file_atomic(path.string(),
                    std::string(test_support::kTinyScene) + "[measure]\nsectors = 36\n");
  ASSERT_NO_THROW(load_scene(path.string()));
  try {
    load_scene(path.string(), {GetParam().set});
    FAIL() << GetParam().set << " was accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path.string()), std::string::npos) << what;
    EXPECT_NE(what.find(GetParam().key), std::string::npos) << what;
  }
}

INSTANTIATE_TEST_SUITE_P(
    BadValues, SceneLimits,
    ::testing::Values(Row{"sample.d_min_mm=-1.0", "sample.d_min_mm"},
                      Row{"sample.d_min_mm=0.0", "sample.d_min_mm"},
                      Row{"sample.d_max_mm=-4.0", "sample.d_max_mm"},
                      Row{"sample.mass_kg=1e-9", "sample.mass_kg"},
                      Row{"procedure.lift_speed_m_s=1e6", "procedure.lift_speed_m_s"},
                      Row{"numerics.gravity_m_s2=1e30", "numerics.gravity_m_s2"},
                      Row{"numerics.gravity_m_s2=nan", "numerics.gravity_m_s2"},
                      Row{"numerics.initial_overlap_tolerance=-1.0",
                          "numerics.initial_overlap_tolerance"},
                      Row{"numerics.rayleigh_fraction=0.8", "numerics.rayleigh_fraction"},
                      Row{"numerics.max_rayleigh_fraction=0.9", "max_rayleigh_fraction"},
                      Row{"measure.sectors=0", "measure.sectors"},
                      // Issue 41: non-finite, out of range, or an unbounded plan.
                      Row{"numerics.softened_youngs_modulus_pa=1e200",
                          "numerics.softened_youngs_modulus_pa"},
                      Row{"numerics.softened_youngs_modulus_pa=nan",
                          "numerics.softened_youngs_modulus_pa"},
                      Row{"numerics.time_step_s=nan", "numerics.time_step_s"},
                      Row{"numerics.time_step_s=0.01", "numerics.time_step_s"},
                      Row{"procedure.fill_settle_max_s=-1.0", "procedure.fill_settle_max_s"},
                      Row{"procedure.settle_speed_m_s=inf", "procedure.settle_speed_m_s"},
                      Row{"procedure.max_time_s=1e9", "procedure.max_time_s"},
                      Row{"output.frame_interval_s=1e-9", "output.frame_interval_s"},
                      Row{"output.progress_interval_s=-1.0", "output.progress_interval_s"},
                      Row{"materials.rock.density_kg_m3=1e-300", "materials.rock.density_kg_m3"},
                      Row{"container.height_m=inf", "container.height_m"},
                      Row{"procedure.lattice_gap=1e6", "procedure.lattice_gap"},
                      Row{"numerics.threads=100000", "numerics.threads"},
                      Row{"measure.slice_azimuths=1000000000", "measure.slice_azimuths"},
                      Row{"sample.shape={kind='generated', elongation=1e9, spheres=4}",
                          "sample.shape.elongation"}));

// Every plan a scene that is read can make is finite and bounded: the time step from the
// materials, the steps up to the time limit. A stiffness at the limit still reads.
TEST(SceneBounds, AStiffnessAtItsLimitGivesAFiniteBoundedStepCount) {
  const fs::path path = fs::temp_directory_path() / "reposetwin_scene_bounds" / "tiny.toml";
  write_file_atomic(path.string(), test_support::kTinyScene);
  const SceneConfig s = load_scene(path.string(), {"numerics.softened_youngs_modulus_pa=1e13"});
  const sim::ResolvedPsd psd = sim::resolve_psd(s.psd.spec);
  const auto [r_min, r_max] = grain_radius_range(s, psd.d_min, psd.d_max);
  const double dt = build_model(s, r_min, r_max).dt;
  EXPECT_GT(dt, 0.0);
  EXPECT_LE(s.procedure.max_time / dt, 1e11);
}

// A material nothing is made of changes nothing: the time step comes from the grains' and the
// walls' materials (it once moved dt from 5.68e-5 to 5.41e-5 s).
TEST(SceneBounds, AnUnusedMaterialDoesNotChangeTheTimeStep) {
  const fs::path path = fs::temp_directory_path() / "reposetwin_scene_bounds" / "tiny.toml";
  write_file_atomic(path.string(), test_support::kTinyScene);
  auto dt_of = [&](const std::vector<std::string>& sets) {
    const SceneConfig s = load_scene(path.string(), sets);
    const sim::ResolvedPsd psd = sim::resolve_psd(s.psd.spec);
  const auto [r_min, r_max] = grain_radius_range(s, psd.d_min, psd.d_max);
    return build_model(s, r_min, r_max).dt;
  };
  const double dt = dt_of({});
  EXPECT_EQ(dt_of({"materials.zzz.density_kg_m3=2500"}), dt);
  EXPECT_EQ(dt_of({"materials.zzz.density_kg_m3=10.0"}), dt);
  // A used material does: the grains made lighter shorten the step as sqrt(density).
  EXPECT_NEAR(dt_of({"materials.rock.density_kg_m3=690.0"}) / dt, 0.5, 1e-9);
}

// A material whose name holds a dash is found in a contact's name: "ro-ck-ro-ck" is ro-ck on
// ro-ck, the one reading that names two declared materials.
TEST(SceneBounds, AMaterialNamedWithADashIsReadInContacts) {
  std::string text = test_support::kTinyScene;
  for (std::size_t at; (at = text.find("rock")) != std::string::npos;) text.replace(at, 4, "ro-ck");
  const fs::path path = fs::temp_directory_path() / "reposetwin_scene_bounds" / "dash.toml";
  write_file_atomic(path.string(), text);
  const SceneConfig s = load_scene(path.string());
  EXPECT_TRUE(s.contacts.count({"ro-ck", "ro-ck"}));
  EXPECT_EQ(s.contacts.size(), 1u);
}

// Of two --set of one key, the message names the one whose value was read: the last.
TEST(SceneBounds, TheLastSetOfAKeyIsTheOneNamed) {
  const fs::path path = fs::temp_directory_path() / "reposetwin_scene_bounds" / "tiny.toml";
  write_file_atomic(path.string(), test_support::kTinyScene);
  try {
    load_scene(path.string(),
               {"contacts.rock-rock.friction=0.4", "contacts.rock-rock.friction=-1.0"});
    FAIL() << "a negative friction was accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("--set contacts.rock-rock.friction=-1.0"), std::string::npos) << what;
    EXPECT_EQ(what.find("friction=0.4"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace reposetwin::experiments
