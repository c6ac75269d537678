// A campaign over grain-shape keys: a sweep of [sample.shape] elongation at a fixed number of
// spheres runs end to end on the tiny rod scene, each case named by its value and each case's
// result.json saying which shape it ran; cases give a sphere scene its shape table; and the k-th
// of [[sample.shapes]] is overridden by its index, checked against the scene before anything
// runs.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "../../support/tiny_scene.hpp"
#include "experiments/calibration/campaign_target.hpp"
#include "experiments/campaign/case_runner.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/scene_overrides.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("reposetwin_shape_campaign_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// The tiny scene with `shape_toml` for its grains, and a campaign `campaign_toml` beside it.
Campaign campaign_in(const fs::path& dir, const std::string& shape_toml,
                     const std::string& campaign_toml) {
  write_file_atomic((dir / "scene.toml").string(),
                    std::string(test_support::kTinyScene) + shape_toml);
  write_file_atomic((dir / "c.toml").string(), campaign_toml);
  return load_campaign((dir / "c.toml").string());
}

RunnerSettings one_worker() {
  RunnerSettings r;
  r.workers = 1;
  r.progress = false;
  r.rank.reset();
  return r;
}

nlohmann::json read_json(const fs::path& file) {
  return nlohmann::json::parse(read_file(file.string()));
}

TEST(ShapeCampaign, ASweepOverElongationRunsEachShapeAndSaysSo) {
  const fs::path dir = fresh_dir("sweep");
  const Campaign c = campaign_in(dir, test_support::kTinyRods,
                                 "name = \"rod_elongation\"\nscene = \"scene.toml\"\nseeds = [3]\n"
                                 "overrides = { \"sample.mass_kg\" = 0.004 }\n"
                                 "[sweep]\nkey = \"sample.shape.elongation\"\n"
                                 "values = [1.0, 1.5, 2.0]\n");
  ASSERT_EQ(c.runs.size(), 3u);
  const double values[] = {1.0, 1.5, 2.0};
  const char* names[] = {"elongation_1", "elongation_1.5", "elongation_2"};
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(c.runs[k].case_name, names[k]);
    EXPECT_EQ(c.runs[k].relative_dir(), std::string("cases/") + names[k] + "/seed_3");
  }
  CaseRunSettings rs;
  rs.images = false;
  const fs::path out = dir / "out";
  const auto summary = run_campaign(c, out.string(), pile_case_fn(rs), one_worker());
  EXPECT_EQ(summary.finished, 3);
  for (std::size_t k = 0; k < 3; ++k) {
    const fs::path case_dir = out / "cases" / names[k] / "seed_3";
    ASSERT_TRUE(fs::exists(case_dir / "result.json")) << case_dir;
    const nlohmann::json j = read_json(case_dir / "result.json");
    const nlohmann::json& r = j.at("result");
    EXPECT_EQ(r.at("stop").at("reason"), "settled") << r.at("stop").dump();
    ASSERT_TRUE(r.contains("shape")) << names[k] << ": the case's result does not say its shape";
    const nlohmann::json& shape = r.at("shape").at("shapes").at(0);
    EXPECT_EQ(shape.at("name"), "rod");
    EXPECT_EQ(shape.at("components"), 4);
    EXPECT_DOUBLE_EQ(shape.at("elongation").get<double>(), values[k]) << names[k];
    // Round ends (roundness 1): the body built has the asked L/I.
    EXPECT_NEAR(shape.at("measured_elongation").get<double>(), values[k], 1e-9) << names[k];
    // The typed result reads it back, and the pile run's own result.json agrees.
    const CaseResult back = case_result_from_json(j);
    ASSERT_TRUE(back.shape.has_value());
    EXPECT_DOUBLE_EQ(back.shape->shapes.at(0).elongation, values[k]);
    const nlohmann::json run = read_json(case_dir / "run" / "result.json");
    EXPECT_EQ(run.at("shape"), r.at("shape"));
  }
  // The longer the rod of the same four spheres and sieve size, the more volume per grain, so
  // the fewer grains in the same mass.
  const auto grains = [&](std::size_t k) {
    return read_json(out / "cases" / names[k] / "seed_3" / "result.json")
        .at("result").at("shape").at("bodies_initial").get<std::int64_t>();
  };
  EXPECT_GT(grains(0), grains(1));
  EXPECT_GT(grains(1), grains(2));
  fs::remove_all(dir);
}

// A campaign over a sphere scene whose cases add the shape table: one case of spheres, one rod
// given as a whole table, one given key by key (each creates [sample.shape], which the scene
// lacks). Each case's result says what it ran: no shape for the spheres, the rod and its
// elongation for the others.
TEST(ShapeCampaign, CasesGiveASphereSceneItsGrainShape) {
  const fs::path dir = fresh_dir("sphere_scene");
  const Campaign c = campaign_in(
      dir, "",
      "name = \"shapes\"\nscene = \"scene.toml\"\nseeds = [3]\n"
      "overrides = { \"sample.mass_kg\" = 0.004 }\n"
      "[[case]]\nname = \"spheres\"\n"
      "[[case]]\nname = \"rod_e1.5\"\n"
      "overrides = { sample.shape = { name = \"rod\", kind = \"generated\", elongation = 1.5, "
      "spheres = 4 } }\n"
      "[[case]]\nname = \"rod_e2\"\n"
      "overrides = { \"sample.shape.name\" = \"rod\", \"sample.shape.kind\" = \"generated\", "
      "\"sample.shape.elongation\" = 2.0, \"sample.shape.spheres\" = 4 }\n");
  ASSERT_EQ(c.runs.size(), 3u);
  // The whole table is one override; the dotted keys are four.
  EXPECT_EQ(c.runs[1].overrides.size(), 2u);
  EXPECT_EQ(c.runs[2].overrides.size(), 5u);
  check_pile_cases(c);
  CaseRunSettings rs;
  rs.images = false;
  const fs::path out = dir / "out";
  const auto summary = run_campaign(c, out.string(), pile_case_fn(rs), one_worker());
  EXPECT_EQ(summary.finished, 3);
  const auto result_of = [&](const std::string& name) {
    return read_json(out / "cases" / name / "seed_3" / "result.json").at("result");
  };
  const nlohmann::json spheres = result_of("spheres");
  EXPECT_EQ(spheres.at("stop").at("reason"), "settled");
  EXPECT_FALSE(spheres.contains("shape")) << spheres.at("shape").dump();
  EXPECT_FALSE(read_json(out / "cases" / "spheres" / "seed_3" / "run" / "result.json")
                   .contains("shape"));
  const std::pair<const char*, double> rods[] = {{"rod_e1.5", 1.5}, {"rod_e2", 2.0}};
  for (const auto& [name, elongation] : rods) {
    const nlohmann::json r = result_of(name);
    EXPECT_EQ(r.at("stop").at("reason"), "settled") << name;
    ASSERT_TRUE(r.contains("shape")) << name << ": the case's result does not say its shape";
    const nlohmann::json& shape = r.at("shape").at("shapes").at(0);
    EXPECT_EQ(shape.at("name"), "rod") << name;
    EXPECT_EQ(shape.at("kind"), "generated") << name;
    EXPECT_EQ(shape.at("components"), 4) << name;
    EXPECT_DOUBLE_EQ(shape.at("elongation").get<double>(), elongation) << name;
  }
  fs::remove_all(dir);
}

// A misspelt key in a case's shape table is refused before anything runs, naming the campaign
// file, the case, the key as the scene reads it and the value; a table the scene format does not
// have is refused as the campaign loads.
TEST(ShapeCampaign, AMisspeltShapeKeyInACaseIsRefused) {
  const fs::path dir = fresh_dir("typo");
  write_file_atomic((dir / "scene.toml").string(), test_support::kTinyScene);
  write_file_atomic((dir / "typo.toml").string(),
                    "name = \"typo\"\nscene = \"scene.toml\"\nseeds = [1]\n"
                    "[[case]]\nname = \"rod\"\n"
                    "overrides = { sample.shape = { kind = \"generated\", elongaton = 1.5, "
                    "spheres = 4 } }\n");
  try {
    check_pile_cases(load_campaign((dir / "typo.toml").string()));
    FAIL() << "a misspelt shape key was accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    for (const char* part : {"typo.toml", "case rod", "sample.shape.elongaton", "1.5"})
      EXPECT_NE(what.find(part), std::string::npos) << part << " not in: " << what;
  }
  write_file_atomic((dir / "table.toml").string(),
                    "name = \"table\"\nscene = \"scene.toml\"\nseeds = [1]\n"
                    "[[case]]\nname = \"rod\"\n"
                    "overrides = { \"sample.shap.elongation\" = 1.5 }\n");
  try {
    (void)load_campaign((dir / "table.toml").string());
    FAIL() << "an override into a table no scene has was accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    for (const char* part : {"table.toml", "case rod", "sample.shap.elongation", "1.5"})
      EXPECT_NE(what.find(part), std::string::npos) << part << " not in: " << what;
  }
  fs::remove_all(dir);
}

TEST(ShapeCampaign, CasesOverrideTheKthShapeOfAMixByIndex) {
  const fs::path dir = fresh_dir("mix");
  const std::string mix =
      "[[sample.shapes]]\nname = \"rod\"\nkind = \"generated\"\nelongation = 1.5\nspheres = 4\n"
      "mass_fraction = 0.5\n[[sample.shapes]]\nname = \"slab\"\nkind = \"generated\"\n"
      "flatness = 1.5\nspheres = 4\nmass_fraction = 0.5\n";
  const Campaign c = campaign_in(
      dir, mix,
      "name = \"mix\"\nscene = \"scene.toml\"\nseeds = [1]\n"
      "[[case]]\nname = \"long_rods\"\noverrides = { \"sample.shapes.0.elongation\" = 2 }\n"
      "[[case]]\nname = \"six_sphere_slabs\"\n"
      "overrides = { \"sample.shapes.1.spheres\" = 6, \"sample.shapes.1.flatness\" = 1.8 }\n");
  ASSERT_EQ(c.runs.size(), 2u);
  const SceneConfig a = build_case_scene(c.runs[0]).config();
  ASSERT_EQ(a.shapes.size(), 2u);
  EXPECT_DOUBLE_EQ(a.shapes[0].elongation, 2.0);
  EXPECT_DOUBLE_EQ(a.shapes[1].flatness, 1.5);
  const SceneConfig b = build_case_scene(c.runs[1]).config();
  EXPECT_DOUBLE_EQ(b.shapes[0].elongation, 1.5);
  EXPECT_EQ(b.shapes[1].spheres, 6);
  EXPECT_DOUBLE_EQ(b.shapes[1].flatness, 1.8);

  // A case that asks for a shape the scene does not have, or one the reader refuses, fails at
  // load time with the campaign file, the key and the value.
  for (const std::string& bad : {std::string("\"sample.shapes.2.elongation\" = 2.0"),
                                 std::string("\"sample.shapes.0.elongation\" = 0.5")}) {
    write_file_atomic((dir / "bad.toml").string(),
                      "name = \"bad\"\nscene = \"scene.toml\"\nseeds = [1]\n[[case]]\n"
                      "name = \"x\"\noverrides = { " + bad + " }\n");
    try {
      // An index past the mix fails as the campaign loads; a value the shape reader refuses,
      // when the campaign command reads the cases' scenes (check_pile_cases) before running.
      check_pile_cases(load_campaign((dir / "bad.toml").string()));
      FAIL() << bad << " was accepted";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("bad.toml"), std::string::npos) << what;
      EXPECT_NE(what.find("elongation"), std::string::npos) << what;
      EXPECT_NE(what.find(bad.find("2.0") != std::string::npos ? "2" : "0.5"), std::string::npos)
          << what;
    }
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace reposetwin::experiments
