// The pile test as a run: a tiny funnel pile that settles and is measured, the clog of a
// narrow outlet, resume after an interruption, no silent overwrite, and bad scene input.
#include "experiments/pile/pile_run.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/scene.hpp"
#include "experiments/io/scene_overrides.hpp"
#include "../../support/scratch.hpp"

namespace reposetwin::experiments {
namespace {

namespace fs = std::filesystem;

// The run's record as its result.json reads (the assertions below read the file's fields).
nlohmann::json run_json(const SceneConfig& scene, const RunOptions& opt) {
  const std::optional<PileRun> run = run_pile_test(scene, opt);
  if (!run) throw std::runtime_error("the run stopped at a limit");
  return to_json(*run);
}

/// A tiny scene: `mass` of 3-4 mm spheres through a funnel of outlet `w` (tens of particles).
std::string tiny_scene(double mass, double w, const std::string& extra = "") {
  return R"(
[scene]
name = "tiny"
seed = 3
[sample]
mass_kg = )" +
         std::to_string(mass) + R"(
material = "rock"
[sample.psd]
sieve_mm = [3.0, 3.5, 4.0]
passing_percent = [0.0, 50.0, 100.0]
[materials.rock]
density_kg_m3 = 2760.0
youngs_modulus_pa = 46.8e9
poisson_ratio = 0.19
[materials.steel]
youngs_modulus_pa = 200e9
poisson_ratio = 0.3
density_kg_m3 = 7850.0
[contacts.rock-rock]
restitution = 0.5
friction = 0.5
rolling_friction = 0.3
[contacts.rock-steel]
restitution = 0.5
friction = 0.3
rolling_friction = 0.1
[container]
kind = "funnel"
material = "steel"
bottom_diameter_m = )" +
         std::to_string(w) + R"(
top_diameter_m = 0.05
height_m = 0.04
[plate]
material = "steel"
[procedure]
lift_speed_m_s = 0.05
settle_speed_m_s = 0.01
clog_window_s = 0.3
[numerics]
softened_youngs_modulus_pa = 5e6
rayleigh_fraction = 0.3
[output]
progress_interval_s = 1000.0
)" + extra;
}

using test_support::scene_from;
using test_support::temp_dir;

TEST(PileTest, TinyPileSettlesAndIsMeasured) {
  const fs::path dir = temp_dir("tiny");
  const SceneConfig scene = scene_from(tiny_scene(0.008, 0.02), dir);
  RunOptions opt;
  opt.out_dir = (dir / "run").string();
  opt.progress = false;
  const nlohmann::json r = run_json(scene, opt);
  EXPECT_EQ(r["stop"]["reason"], "settled") << r["stop"].dump();
  EXPECT_GT(r["pile"]["theta_hd_deg"].get<double>(), 5.0);
  EXPECT_LT(r["pile"]["theta_hd_deg"].get<double>(), 60.0);
  EXPECT_GT(r["pile"]["height_m"].get<double>(), 0.0035);  // more than one layer
  // Provenance: scene, seed, time step, softened stiffness, code version.
  const auto& p = r["provenance"];
  EXPECT_EQ(p["seed"], 3);
  EXPECT_GT(p["time_step_s"].get<double>(), 0.0);
  EXPECT_EQ(p["softened_youngs_modulus_pa"], 5e6);
  EXPECT_FALSE(p["code_version"].get<std::string>().empty());
  // The PSD sample matches the mass within one particle.
  const double drawn = r["psd"]["drawn_mass_kg"], target = r["psd"]["simulated_target_mass_kg"];
  EXPECT_LT(std::abs(drawn - target), 2760.0 * 3.14159 / 6 * std::pow(4e-3, 3));
  EXPECT_TRUE(fs::exists(fs::path(opt.out_dir) / "final.vtp"));
  EXPECT_TRUE(fs::exists(fs::path(opt.out_dir) / "series.pvd"));
  // A finished result is never overwritten silently.
  EXPECT_THROW(run_pile_test(scene, opt), InputError);
}

TEST(PileTest, NarrowOutletClogsAndReportsNoPile) {
  // W / d_max = 1.25, as the paper's 10 mm funnel with 8 mm rock: particles arch and lodge.
  const fs::path dir = temp_dir("clog");
  const SceneConfig scene = scene_from(tiny_scene(0.01, 0.005), dir);
  RunOptions opt;
  opt.out_dir = (dir / "run").string();
  opt.progress = false;
  const nlohmann::json r = run_json(scene, opt);
  EXPECT_EQ(r["stop"]["reason"], "clogged") << r["stop"].dump();
  EXPECT_NE(r["stop"]["detail"].get<std::string>().find("particles lodged"), std::string::npos);
  EXPECT_EQ(r["pile"]["theta_hd_deg"], 0.0);
}

// Cohesive grains stuck to the funnel wall: the flow stops with a few grains inside. Within the
// declared max_retained_fraction they stay in the funnel and are lifted away with it (removed from
// the run and counted), and the pile settles and is measured, as in the lab; above it the same
// run is a clog. The funnel is of a material the rock sticks to (cohesion 50 kJ/m^3 on rock-clay,
// none between the grains).
TEST(PileTest, GrainsStuckToTheFunnelAreLiftedAwayWithIt) {
  const std::string sticky = R"(
[materials.clay]
youngs_modulus_pa = 1e9
poisson_ratio = 0.3
density_kg_m3 = 1800.0
[contacts.rock-clay]
restitution = 0.3
friction = 0.6
rolling_friction = 0.3
cohesion_energy_density = 50000.0
)";
  auto scene_text = [&](double fraction) {
    std::string s = tiny_scene(0.008, 0.02, sticky);
    auto put = [&s](const std::string& from, const std::string& to) {
      const auto at = s.find(from);
      EXPECT_NE(at, std::string::npos) << from;
      s.replace(at, from.size(), to);
    };
    put("kind = \"funnel\"\nmaterial = \"steel\"", "kind = \"funnel\"\nmaterial = \"clay\"");
    put("clog_window_s = 0.3", "clog_window_s = 0.3\nmax_retained_fraction = " +
                                   std::to_string(fraction));
    return s;
  };
  const fs::path dir = temp_dir("sticky");
  RunOptions opt;
  opt.progress = false;
  opt.out_dir = (dir / "lifted").string();
  const nlohmann::json r = run_json(scene_from(scene_text(0.15), dir), opt);
  EXPECT_EQ(r["stop"]["reason"], "settled") << r["stop"].dump();
  const std::int64_t n0 = r["particles"]["initial"], n1 = r["particles"]["final"];
  const std::int64_t kept = r["particles"]["retained_in_container"];
  EXPECT_GT(kept, 0) << "no grain stuck to the funnel: the test shows nothing";
  EXPECT_LE(static_cast<double>(kept), 0.15 * static_cast<double>(n0));
  EXPECT_EQ(n1 + kept, n0);
  EXPECT_GT(r["particles"]["retained_mass_kg"].get<double>(), 0.0);
  EXPECT_GT(r["pile"]["theta_hd_deg"].get<double>(), 5.0);
  EXPECT_EQ(r["procedure"]["max_retained_fraction"], 0.15);
  // Declared stricter: the same run (same bits up to the decision) is a clog of that many grains.
  opt.out_dir = (dir / "strict").string();
  const double strict = 0.5 * static_cast<double>(kept) / static_cast<double>(n0);
  const nlohmann::json c = run_json(scene_from(scene_text(strict), dir), opt);
  EXPECT_EQ(c["stop"]["reason"], "clogged") << c["stop"].dump();
  EXPECT_EQ(c["pile"]["lodged_particles"], kept);
  EXPECT_EQ(c["particles"]["retained_in_container"], 0);
}

TEST(PileTest, InterruptedRunResumesToTheSameResult) {
  const fs::path dir = temp_dir("resume");
  const SceneConfig scene = scene_from(tiny_scene(0.008, 0.02), dir);
  RunOptions full;
  full.out_dir = (dir / "full").string();
  full.progress = false;
  const nlohmann::json a = run_json(scene, full);
  RunOptions part = full;
  part.out_dir = (dir / "part").string();
  part.stop_after_steps = 2000;
  const std::optional<PileRun> stopped = run_pile_test(scene, part);
  ASSERT_FALSE(stopped.has_value()) << "the run finished before the interruption";
  part.stop_after_steps = 0;
  part.resume = true;
  const nlohmann::json b = run_json(scene, part);
  EXPECT_EQ(a["pile"]["height_m"], b["pile"]["height_m"]);
  EXPECT_EQ(a["pile"]["theta_hd_deg"], b["pile"]["theta_hd_deg"]);
  EXPECT_EQ(a["performance"]["steps"], b["performance"]["steps"]);
}

// scene.resolved.toml (written into every run folder) loads on its own from another folder: a
// sieve-table file named relative to the original scene is copied in as [sample.psd].
TEST(SceneFile, ResolvedTextLoadsFromAnyFolderWithTheSamePsd) {
  const std::string original =
      std::string(REPOSETWIN_SOURCE_DIR) + "/data/scenes/paper/table1_s1_dmax2p0_200g_reduced.toml";
  const SceneConfig a = parse_scene_file(original);
  ASSERT_NE(read_file(original).find("psd_file"), std::string::npos) << "the scene must use a file";
  EXPECT_EQ(a.resolved_toml.find("psd_file"), std::string::npos) << a.resolved_toml;
  const fs::path dir = temp_dir("resolved");
  write_file_atomic((dir / "scene.resolved.toml").string(), a.resolved_toml);
  const SceneConfig b = parse_scene_file((dir / "scene.resolved.toml").string());
  EXPECT_EQ(b.psd.spec.table.size, a.psd.spec.table.size);
  EXPECT_EQ(b.psd.spec.table.passing, a.psd.spec.table.passing);
  EXPECT_EQ(b.psd.spec.d_min, a.psd.spec.d_min);
  EXPECT_EQ(b.psd.spec.d_max, a.psd.spec.d_max);
  EXPECT_EQ(b.psd.spec.fines, a.psd.spec.fines);
  EXPECT_EQ(b.psd.assumption, a.psd.assumption);
  EXPECT_EQ(b.mass, a.mass);
  EXPECT_EQ(b.resolved_toml, a.resolved_toml);  // resolving again changes nothing
}

void expect_scene_error(const std::string& text, const std::string& needle) {
  const fs::path dir = temp_dir("bad");
  try {
    scene_from(text, dir);
    ADD_FAILURE() << "accepted a scene that should fail with " << needle;
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(needle), std::string::npos) << msg;
    EXPECT_NE(msg.find("scene.toml"), std::string::npos) << "message must name the file: " << msg;
  }
}

TEST(SceneFile, BadInputNamesFileKeyAndValue) {
  const std::string good = tiny_scene(0.008, 0.02);
  auto replace = [&](const std::string& from, const std::string& to) {
    std::string s = good;
    const auto at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return s.replace(at, from.size(), to);
  };
  expect_scene_error(good + "\n[extra]\nfoo = 1\n", "extra");
  expect_scene_error(replace("seed = 3", "seed = 3\nsede = 4"), "scene.sede");
  expect_scene_error(replace("density_kg_m3 = 2760.0", "density_kg_m3 = 0.0"), "density_kg_m3");
  expect_scene_error(
      replace("restitution = 0.5\nfriction = 0.5", "restitution = 1.5\nfriction = 0.5"),
      "restitution");
  expect_scene_error(replace("friction = 0.5", "friction = -0.2"), "friction");
  expect_scene_error(
      replace("passing_percent = [0.0, 50.0, 100.0]", "passing_percent = [0.0, 60.0, 50.0]"),
      "passing");
  expect_scene_error(
      replace("passing_percent = [0.0, 50.0, 100.0]", "passing_percent = [0.0, 50.0, 90.0]"),
      "100");
  expect_scene_error(replace("sieve_mm = [3.0, 3.5, 4.0]", "sieve_mm = [-3.0, 3.5, 4.0]"), "sieve");
  expect_scene_error(replace("mass_kg = 0.008", "mass_kg = 50.0"), "mass_kg");
  expect_scene_error(replace("bottom_diameter_m = 0.02", "bottom_diameter_m = 0.0035"), "outlet");
  expect_scene_error(replace("rayleigh_fraction = 0.3", "time_step_s = 1.0"), "time_step");
  expect_scene_error(
      replace("rolling_friction = 0.3", "rolling_friction = 0.3\nrolling_model = \"magic\""),
      "rolling_model");
  expect_scene_error(replace("clog_window_s = 0.3", "clog_window_s = 0.3\nmax_retained_fraction = 1.0"),
                     "max_retained_fraction");
}

TEST(SceneFile, EmbeddedQuickSceneParsesAndOverridesApply) {
  const SceneConfig q = load_scene("");
  EXPECT_EQ(q.name, "quick");
  EXPECT_EQ(q.file, "<embedded>");
  const SceneConfig o =
      load_scene("", {"contacts.rock-rock.rolling_friction=0.05", "scene.seed=7"});
  EXPECT_EQ(o.seed, 7u);
  EXPECT_DOUBLE_EQ(o.contacts.at({"rock", "rock"}).rolling_friction, 0.05);
  EXPECT_THROW(load_scene("", {"contacts.rock-rock.rolling_friction=\"x\""}), std::exception);
  EXPECT_THROW(load_scene("/no/such/scene.toml"), InputError);
}

}  // namespace
}  // namespace reposetwin::experiments
