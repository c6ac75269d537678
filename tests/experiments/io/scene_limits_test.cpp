// Values outside physical or numerical limits are refused when the scene is read, naming the
// file and the key as the user wrote it, before anything runs (each row was once accepted and
// failed later, or ran to a wrong answer).
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "../../support/tiny_scene.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/scene_overrides.hpp"

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
                      Row{"measure.sectors=0", "measure.sectors"}));

}  // namespace
}  // namespace reposetwin::experiments
