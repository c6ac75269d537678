// A pile run never loses or mixes results: one process per run folder, a checkpoint continues
// only the scene and engine that wrote it, a checkpoint and its controller state from different
// moments are refused, --force deletes nothing until the new inputs have passed their checks,
// and a physics stop is written as such, with no pile measured from a broken state.
#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <string>

#include "../../support/tiny_scene.hpp"
#include "experiments/io/hash.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/scene.hpp"
#include "experiments/io/scene_overrides.hpp"
#include "experiments/pile/pile_run.hpp"
#include "experiments/pile/stop_hint.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

struct Folder {
  fs::path dir;
  std::string scene;  // the scene file
};

Folder folder(const std::string& name, const std::string& extra = "") {
  const fs::path dir = fs::temp_directory_path() / ("reposetwin_safety_" + name);
  fs::remove_all(dir);
  const std::string scene = (dir / "tiny.toml").string();
  write_file_atomic(scene, std::string(test_support::kTinyScene) + extra);
  return {dir, scene};
}

RunOptions options(const Folder& f) {
  RunOptions o;
  o.out_dir = (f.dir / "run").string();
  o.progress = false;
  o.threads = 1;
  return o;
}

std::string message_of(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(PileRunSafety, ASecondRunIntoABusyFolderIsRefused) {
  const Folder f = folder("busy");
  const RunOptions opt = options(f);
  FolderLock held(opt.out_dir, ".run.lock", "a pile run");  // the first run, still going
  const std::string what = message_of([&] { run_pile_test(load_scene(f.scene), opt); });
  EXPECT_NE(what.find("another pile run"), std::string::npos) << what;
  EXPECT_NE(what.find(opt.out_dir), std::string::npos) << what;
  EXPECT_FALSE(fs::exists(fs::path(opt.out_dir) / "result.json"));
}

TEST(PileRunSafety, AResumeWithAnotherSceneIsRefusedNamingBothHashes) {
  const Folder f = folder("other_scene");
  RunOptions opt = options(f);
  opt.stop_after_steps = 2000;
  const SceneConfig first = load_scene(f.scene);
  ASSERT_FALSE(run_pile_test(first, opt).has_value()) << "finished before the interruption";
  opt.stop_after_steps = 0;
  opt.resume = true;
  const SceneConfig other = load_scene(f.scene, {"contacts.rock-rock.friction=0.1"});
  const std::string what = message_of([&] { run_pile_test(other, opt); });
  EXPECT_NE(what.find(fnv1a_hex(first.resolved_toml)), std::string::npos) << what;
  EXPECT_NE(what.find(fnv1a_hex(other.resolved_toml)), std::string::npos) << what;
  EXPECT_FALSE(fs::exists(fs::path(opt.out_dir) / "result.json"));
  // The same scene still continues.
  EXPECT_TRUE(run_pile_test(first, opt).has_value());
}

TEST(PileRunSafety, ACheckpointAndAControllerFromDifferentStepsAreRefused) {
  const Folder f = folder("torn");
  RunOptions opt = options(f);
  const SceneConfig scene = load_scene(f.scene);
  opt.stop_after_steps = 1000;
  ASSERT_FALSE(run_pile_test(scene, opt).has_value());
  const fs::path ctrl = fs::path(opt.out_dir) / "controller.json";
  const std::string early = read_file(ctrl.string());
  opt.resume = true;
  ASSERT_FALSE(run_pile_test(scene, opt).has_value());
  const auto step_of = [](const std::string& text) {
    return "step " + std::to_string(nlohmann::json::parse(text).at("step").get<std::int64_t>());
  };
  const std::string late = read_file(ctrl.string());
  ASSERT_NE(step_of(late), step_of(early));
  write_file_atomic(ctrl.string(), early);  // killed between the checkpoint's two renames
  const std::string what = message_of([&] { run_pile_test(scene, opt); });
  EXPECT_NE(what.find(step_of(late)), std::string::npos) << what;
  EXPECT_NE(what.find(step_of(early)), std::string::npos) << what;
}

// A checkpoint damaged on disk (two bytes flipped, in the header's neighbourhood or in the
// particle arrays) is refused on resume, naming the file, and never resumed into another result;
// the undamaged file still resumes.
TEST(PileRunSafety, ACorruptedCheckpointIsRefused) {
  const Folder f = folder("corrupt");
  RunOptions opt = options(f);
  const SceneConfig scene = load_scene(f.scene);
  opt.stop_after_steps = 1000;
  ASSERT_FALSE(run_pile_test(scene, opt).has_value());
  const fs::path ckpt = fs::path(opt.out_dir) / "checkpoint.bin";
  const std::string good = read_file(ckpt.string());
  ASSERT_GT(good.size(), 1002u);
  opt.stop_after_steps = 0;
  opt.resume = true;
  for (const std::size_t at : {std::size_t{48}, std::size_t{1000}}) {
    SCOPED_TRACE(at);
    std::string bad = good;
    bad[at] = static_cast<char>(bad[at] ^ 0x5a);
    bad[at + 1] = static_cast<char>(bad[at + 1] ^ 0x01);
    write_file_atomic(ckpt.string(), bad);
    const std::string what = message_of([&] { run_pile_test(scene, opt); });
    EXPECT_NE(what.find(ckpt.string()), std::string::npos) << what;
    EXPECT_NE(what.find("checksum"), std::string::npos) << what;
    EXPECT_FALSE(fs::exists(fs::path(opt.out_dir) / "result.json"));
  }
  write_file_atomic(ckpt.string(), good);
  EXPECT_TRUE(run_pile_test(scene, opt).has_value());
}

TEST(PileRunSafety, ForceDeletesNothingWhenTheNewInputsFail) {
  const Folder good = folder("force");
  RunOptions opt = options(good);
  ASSERT_TRUE(run_pile_test(load_scene(good.scene), opt).has_value());
  const fs::path result = fs::path(opt.out_dir) / "result.json";
  const std::string before = read_file(result.string());
  // The same folder, forced, with inputs that only the run can find wrong: the packing check
  // after filling (a tolerance the parser would refuse stands for any such check).
  SceneConfig bad = load_scene(good.scene);
  bad.settings.initial_overlap_tolerance = -1.0;
  opt.force = true;
  const std::string what = message_of([&] { run_pile_test(bad, opt); });
  EXPECT_NE(what.find("initial_overlap_tolerance"), std::string::npos) << what;
  ASSERT_TRUE(fs::exists(result));
  EXPECT_EQ(read_file(result.string()), before);
  EXPECT_TRUE(fs::exists(fs::path(opt.out_dir) / "final.vtp"));
}

TEST(PileRunSafety, APhysicsStopIsWrittenWithNoPileMeasured) {
  const Folder f = folder("physics");
  std::string text = read_file(f.scene);
  const std::string stiff = "softened_youngs_modulus_pa = 5e6";
  ASSERT_NE(text.find(stiff), std::string::npos);
  text.replace(text.find(stiff), stiff.size(), "softened_youngs_modulus_pa = 1e2");
  write_file_atomic(f.scene, text);
  const std::optional<PileRun> run = run_pile_test(load_scene(f.scene), options(f));
  ASSERT_TRUE(run.has_value());
  ASSERT_TRUE(run->stop.is_physics()) << stop_reason_text(run->stop);
  EXPECT_FALSE(run->pile_ok());
  const nlohmann::json file =
      nlohmann::json::parse(read_file((f.dir / "run" / "result.json").string()));
  EXPECT_EQ(file.at("pile").at("status"), "not measured");
  EXPECT_NE(file.at("pile").at("detail").get<std::string>().find("physics"), std::string::npos);
  EXPECT_TRUE(pile_run_from_json(file).pile.not_measured);
  // The stop names the scene key that most likely caused it, with the value the scene set.
  const std::string cause = file.at("stop").at("likely_cause").get<std::string>();
  EXPECT_NE(cause.find("numerics.softened_youngs_modulus_pa = 100"), std::string::npos) << cause;
  EXPECT_EQ(pile_run_from_json(file).stop.likely_cause, cause);
}

// Every physics status maps to the keys that govern it, in the scene's own names and values.
TEST(PhysicsStopHint, NamesTheKeysThatGovernEachStatus) {
  SceneConfig scene = parse_scene_text(std::string(test_support::kTinyScene), "tiny.toml");
  EXPECT_EQ(physics_stop_hint(sim::Status::kOk, scene), "");
  EXPECT_NE(physics_stop_hint(sim::Status::kNan, scene).find("numerics.rayleigh_fraction = 0.3"),
            std::string::npos)
      << physics_stop_hint(sim::Status::kNan, scene);
  scene.settings.time_step = 1e-5;
  EXPECT_NE(physics_stop_hint(sim::Status::kNan, scene).find("numerics.time_step_s = 1e-05"),
            std::string::npos);
  const std::string overlap = physics_stop_hint(sim::Status::kOverlap, scene);
  EXPECT_NE(overlap.find("numerics.max_overlap_ratio"), std::string::npos) << overlap;
  EXPECT_NE(overlap.find("numerics.softened_youngs_modulus_pa = 5e+06"), std::string::npos)
      << overlap;
  EXPECT_NE(physics_stop_hint(sim::Status::kEscaped, scene).find("numerics.escape_distance_m"),
            std::string::npos);
}

}  // namespace
}  // namespace reposetwin::experiments
