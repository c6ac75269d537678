// Scene fuzz, by property: every number, integer, string, boolean and array key the reference
// lists (`reposetwin keys`) is set, one at a time, to values from a hostile set, on the tiny
// scene and on the paper's scenes, the way `reposetwin run SCENE --set KEY=VALUE` reads them
// (load_scene, then plan_run as the run's plan gate calls it). The property, for every mutation:
//  - either the scene is refused with an InputError whose message names the file and the key as
//    written (a crash or any other exception type fails the test),
//  - or it is accepted and its plan is usable: a finite, positive time step; a positive particle
//    count; a positive number of steps, at most 1e11, equal to ceil(simulated time / dt); a
//    finite, positive simulated time no longer than max_time; a finite wall time; and at most
//    1e4 frames. And the time step depends only on the materials simulated: adding a material
//    no grain or wall uses, with absurd values, leaves dt unchanged to the bit.
// Deterministic: every key of the tiny scene gets every value; each paper scene gets a fixed
// number of (key, value) draws from a seeded generator (no std:: distribution, whose output
// differs between standard libraries).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <random>
#include <string>
#include <typeinfo>
#include <vector>

#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/scene.hpp"
#include "experiments/io/scene_keys.hpp"
#include "experiments/io/scene_overrides.hpp"
#include "experiments/pile/run_plan.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

const fs::path kSource = REPOSETWIN_SOURCE_DIR;

// The reference's keys of a kind expanded to the scene's own names: <name> to each material,
// <a>-<b> to each contact pair, [<k>] to each shape of a mix as an override writes it
// (sample.shapes.<k>.elongation).
std::vector<std::string> concrete_keys(const SceneConfig& scene, const std::string& type) {
  std::vector<std::string> out;
  for (const SceneKey& k : scene_keys()) {
    if (k.type != type) continue;
    const std::size_t name = k.key.find("<name>");
    const std::size_t pair = k.key.find("<a>-<b>");
    const std::size_t shape = k.key.find("[<k>]");
    if (shape != std::string::npos) {
      const std::size_t n = scene.shapes.size();
      for (std::size_t i = 0; n > 1 && i < n; ++i)
        out.push_back(k.key.substr(0, shape) + "." + std::to_string(i) + k.key.substr(shape + 5));
    } else if (name != std::string::npos) {
      for (const sim::Material& m : scene.materials)
        out.push_back(k.key.substr(0, name) + m.name + k.key.substr(name + 6));
    } else if (pair != std::string::npos) {
      for (const auto& [ab, params] : scene.contacts)
        out.push_back(k.key.substr(0, pair) + ab.first + "-" + ab.second + k.key.substr(pair + 7));
    } else {
      out.push_back(k.key);
    }
  }
  return out;
}

std::string number_text(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  std::string s = buf;
  if (s.find_first_of(".eninf") == std::string::npos) s += ".0";
  return s;
}

// The hostile values of a key of `type` whose value in the scene (or default) is `current`.
std::vector<std::string> hostile_values(const std::string& type, std::optional<double> current) {
  if (type == "number" || type == "integer") {
    std::vector<std::string> v = {"0",   "0.0",  "-1",  "-1.0", "1e-300", "1e300",
                                  "inf", "-inf", "nan", "9223372036854775807",
                                  "-9223372036854775808", "99999999999999999999", "1e19",
                                  "0.5", "\"junk\"", "true", "[1.0, 2.0]", "{ a = 1 }", ""};
    if (current && *current != 0.0) {
      for (double f : {1e-12, 1e-6, 1e6, 1e12, -1.0}) v.push_back(number_text(*current * f));
    }
    return v;
  }
  if (type == "string")
    return {"\"\"", "\"zzz\"", "\"\\u0000\"", "\"a\\u0000b\"", "\"" + std::string(5000, 'x') + "\"",
            "42", "true", "[\"a\"]", "nan", "\"../../../etc/passwd\"", "\"ro-ck\"", "\" \""};
  if (type == "boolean") return {"1", "\"yes\"", "nan", "[true]"};
  if (type == "array of numbers")
    return {"[]",           "[nan]",          "[inf, 1.0]",         "[1.0]",
            "[\"a\", \"b\"]", "[-1.0, 2.0, 3.0]", "[3.0, 2.0, 1.0]",    "[1e300, 1e301, 1e302]",
            "[1e-300, 2e-300, 3e-300]", "[0.0, 0.0, 0.0]", "[1.0, nan, 3.0]", "5.0"};
  return {};
}

struct Mutation {
  fs::path scene;
  std::string key;
  std::string value;
  // The table the --set creates, when the scene has no table for the key (sample.shape on a
  // scene of spheres, sample.psd on a scene with a psd_file): a refusal may name it instead.
  std::string created_table;
};

// Checks one mutation; returns "" when the property holds, else what broke it.
std::string check(const Mutation& m) {
  const std::string set = m.key + "=" + m.value;
  std::optional<SceneConfig> scene;
  try {
    scene = load_scene(m.scene.string(), {set});
  } catch (const InputError& e) {
    const std::string what = e.what();
    if (what.find(m.key) == std::string::npos &&
        (m.created_table.empty() || what.find(m.created_table) == std::string::npos))
      return "refused without the key: " + what;
    if (what.find(m.scene.filename().string()) == std::string::npos)
      return "refused without the file: " + what;
    return "";
  } catch (const std::exception& e) {
    return std::string("another exception (") + typeid(e).name() + "): " + e.what();
  }
  RunPlan plan;
  try {
    plan = plan_run(*scene, 1);
  } catch (const std::exception& e) {
    return std::string("accepted, but its plan throws: ") + e.what();
  }
  const double dt = plan.time_step_s;
  if (!(std::isfinite(dt) && dt > 0)) return "accepted with dt " + number_text(dt);
  if (!(plan.particles > 0)) return "accepted with " + std::to_string(plan.particles) + " particles";
  if (!(plan.steps > 0 && plan.steps <= 100'000'000'000LL))
    return "accepted with " + std::to_string(plan.steps) + " steps";
  if (!(std::isfinite(plan.simulated_time_s) && plan.simulated_time_s > 0 &&
        plan.simulated_time_s <= scene->procedure.max_time))
    return "accepted with simulated time " + number_text(plan.simulated_time_s);
  if (plan.steps != std::llround(std::ceil(plan.simulated_time_s / dt)))
    return "accepted with steps not simulated time / dt";
  if (!(std::isfinite(scene->procedure.max_time / dt) && scene->procedure.max_time / dt <= 1e11))
    return "accepted with " + number_text(scene->procedure.max_time / dt) + " steps to max_time";
  if (!(std::isfinite(plan.wall_s) && plan.wall_s >= 0))
    return "accepted with wall time " + number_text(plan.wall_s);
  const double every = scene->output.frame_interval;
  if (!(every >= 0 && std::isfinite(every)) ||
      (every > 0 && !(scene->procedure.max_time / every <= 1e4)))
    return "accepted with frame interval " + number_text(every);
  // An unused material changes nothing the run simulates.
  try {
    const SceneConfig with_unused =
        load_scene(m.scene.string(), {set, "materials.zzz_unused.density_kg_m3=1.0",
                                      "materials.zzz_unused.youngs_modulus_pa=1e12",
                                      "materials.zzz_unused.poisson_ratio=0.49"});
    const double dt2 = plan_run(with_unused, 1).time_step_s;
    if (dt2 != dt)
      return "an unused material changes dt from " + number_text(dt) + " to " + number_text(dt2);
  } catch (const std::exception& e) {
    return std::string("accepted, but not with an unused material: ") + e.what();
  }
  return "";
}

// Runs the mutations, reporting every broken one (at most 40 printed).
void run_all(const std::vector<Mutation>& mutations) {
  int broken = 0;
  for (const Mutation& m : mutations) {
    const std::string why = check(m);
    if (why.empty()) continue;
    if (++broken <= 40)
      ADD_FAILURE() << m.scene.filename().string() << " --set " << m.key << "="
                    << m.value.substr(0, 60) << ": " << why.substr(0, 400);
  }
  EXPECT_EQ(broken, 0) << "of " << mutations.size() << " mutations";
  ::testing::Test::RecordProperty("mutations", static_cast<int>(mutations.size()));
}

std::vector<Mutation> all_mutations(const fs::path& scene_path) {
  const SceneConfig base = parse_scene_file(scene_path.string());
  const SceneDoc doc(scene_path.string());
  std::vector<Mutation> out;
  for (const char* type : {"number", "integer", "string", "boolean", "array of numbers"})
    for (const std::string& key : concrete_keys(base, type))
      for (const std::string& v : hostile_values(type, doc.number(key))) {
        const std::string table = key.substr(0, key.rfind('.'));
        out.push_back({scene_path, key, v, doc.has(table) ? std::string() : table});
      }
  return out;
}

TEST(SceneFuzz, EveryKeyOfTheTinySceneWithEveryHostileValue) {
  const std::vector<Mutation> all = all_mutations(kSource / "data/loop/tiny_scene.toml");
  ASSERT_GT(all.size(), 800u);
  run_all(all);
}

// A mix of three grain shapes (one of each kind) on the tiny scene: the keys of every shape, as
// `--set sample.shapes.<k>.KEY=VALUE` writes them, with hostile values; a refusal names the key
// so spelt. (All 450 passed when this was written, in 23 s.)
TEST(SceneFuzz, EveryKeyOfAShapeMixWithEveryHostileValue) {
  const fs::path dir = fs::temp_directory_path() / "reposetwin_scene_fuzz_shapes";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::string text = read_file((kSource / "data/loop/tiny_scene.toml").string());
  text += R"(
[[sample.shapes]]
name = "rod"
kind = "generated"
mass_fraction = 0.4
elongation = 2.0
spheres = 3

[[sample.shapes]]
name = "block"
kind = "blocky"
mass_fraction = 0.4
elongation = 1.5
flatness = 1.2
angularity = 0.5

[[sample.shapes]]
name = "pair"
kind = "template"
mass_fraction = 0.2
offsets = [[0.0, 0.0, 0.0], [0.6, 0.0, 0.0]]
radii = [0.5, 0.5]
)";
  const fs::path scene = dir / "shape_mix.toml";
  write_file_atomic(scene.string(), text);
  ASSERT_EQ(parse_scene_file(scene.string()).shapes.size(), 3u);
  // The scene's other keys are the tiny scene's, fuzzed above. A clump scene costs about 100
  // times a sphere scene to read and plan, so the unit set takes 150 seeded draws of the
  // shape keys' mutations, every key's first value among them.
  std::vector<Mutation> shape_keys, drawn;
  for (const Mutation& m : all_mutations(scene))
    if (m.key.rfind("sample.shapes.", 0) == 0) shape_keys.push_back(m);
  ASSERT_GT(shape_keys.size(), 400u) << "every shape's keys are mutated";
  std::mt19937_64 rng(20261206);
  for (std::size_t i = 0; i < shape_keys.size(); ++i)
    if (i == 0 || shape_keys[i].key != shape_keys[i - 1].key) drawn.push_back(shape_keys[i]);
  while (drawn.size() < 150) drawn.push_back(shape_keys[rng() % shape_keys.size()]);
  run_all(drawn);
}

TEST(SceneFuzz, PaperScenesWithSeededDraws) {
  constexpr int kDrawsPerScene = 120;
  std::mt19937_64 rng(20261206);
  std::vector<Mutation> drawn;
  std::vector<fs::path> scenes;
  for (const auto& entry : fs::directory_iterator(kSource / "data/scenes/paper"))
    if (entry.path().extension() == ".toml") scenes.push_back(entry.path());
  std::sort(scenes.begin(), scenes.end());
  scenes.push_back(kSource / "data/scenes/quick.toml");
  ASSERT_GE(scenes.size(), 10u);
  for (const fs::path& s : scenes) {
    const std::vector<Mutation> all = all_mutations(s);
    for (int i = 0; i < kDrawsPerScene; ++i) drawn.push_back(all[rng() % all.size()]);
  }
  run_all(drawn);
}

}  // namespace
}  // namespace reposetwin::experiments
