// The pile test with clumps: a tiny pour of four-sphere rods fills, lifts, settles and forms a
// pile measured from the component spheres; its result names the shape and counts bodies and
// components; the snapshot carries body ids; a run cut off and resumed ends bit-identically, as
// does a run on two threads;
// a resume against other templates is refused; and a scene of one-sphere clumps gives the sphere
// engine's pile exactly.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "../../support/scratch.hpp"
#include "../../support/tiny_scene.hpp"
#include "experiments/io/scene.hpp"
#include "experiments/io/vtk_output.hpp"
#include "experiments/pile/pile_run.hpp"

namespace reposetwin::experiments {
namespace {

namespace fs = std::filesystem;

/// Tens of 3-4 mm grains through a 20 mm funnel (as tests/experiments/pile/pile_run_test.cpp).
std::string scene_text(const std::string& shape, double mass = 0.006) {
  return R"(
[scene]
name = "tiny-clumps"
seed = 5
[sample]
mass_kg = )" +
         std::to_string(mass) +
         R"(
material = "rock"
[sample.psd]
sieve_mm = [3.0, 3.5, 4.0]
passing_percent = [0.0, 50.0, 100.0]
[materials.rock]
density_kg_m3 = 2760.0
youngs_modulus_pa = 46.8e9
poisson_ratio = 0.19
[contacts.rock-rock]
restitution = 0.5
friction = 0.5
rolling_friction = 0.3
[container]
kind = "funnel"
material = "rock"
bottom_diameter_m = 0.02
top_diameter_m = 0.05
height_m = 0.04
[plate]
material = "rock"
[procedure]
lift_speed_m_s = 0.05
settle_speed_m_s = 0.01
clog_window_s = 0.3
[numerics]
softened_youngs_modulus_pa = 5e6
rayleigh_fraction = 0.3
[output]
progress_interval_s = 1000.0
)" + shape;
}

using test_support::scene_from;
// Clump runs get folders of their own beside the sphere tests'.
fs::path temp_dir(const std::string& name) { return test_support::temp_dir("clump_" + name); }

PileRun run(const SceneConfig& scene, const fs::path& out, std::int64_t stop_after = 0,
            bool resume = false, int threads = 1) {
  RunOptions opt;
  opt.threads = threads;
  opt.out_dir = out.string();
  opt.progress = false;
  opt.stop_after_steps = stop_after;
  opt.resume = resume;
  const std::optional<PileRun> r = run_pile_test(scene, opt);
  if (!r) throw std::runtime_error("the run stopped at its step limit");
  return *r;
}

TEST(PileClumps, ATinyPourOfRodsFormsAPileAndResumesBitIdentically) {
  const fs::path dir = temp_dir("rods");
  const SceneConfig scene = scene_from(scene_text(test_support::kTinyRods), dir);
  const PileRun a = run(scene, dir / "full");
  EXPECT_EQ(a.stop.reason, StopReason::kSettled) << a.stop.detail;
  ASSERT_TRUE(a.pile_ok()) << a.pile.detail;
  EXPECT_GT(a.pile.theta_hd_deg, 5.0);
  EXPECT_LT(a.pile.theta_hd_deg, 60.0);
  EXPECT_GT(a.pile.height_m, 0.0035);  // more than one layer of grains
  ASSERT_TRUE(a.shape.has_value());
  const ShapeRecord& s = *a.shape;
  ASSERT_EQ(s.shapes.size(), 1u);
  EXPECT_EQ(s.shapes[0].name, "rod");
  EXPECT_EQ(s.shapes[0].components, 4);
  EXPECT_NEAR(s.shapes[0].measured_elongation, 1.5, 1e-9);
  EXPECT_EQ(s.bodies_initial, a.particles.initial);
  EXPECT_EQ(s.bodies_initial, a.psd.count);
  EXPECT_EQ(s.components_initial, 4 * s.bodies_initial);
  EXPECT_EQ(s.bodies_final + a.particles.retained_in_container, s.bodies_initial);
  EXPECT_EQ(s.components_final, 4 * s.bodies_final);
  EXPECT_EQ(static_cast<std::int64_t>(a.final_spheres.x.size()), s.components_final);
  ASSERT_EQ(a.final_spheres.body.size(), a.final_spheres.x.size());
  // The result file carries the shape and reads back.
  const PileRun back = pile_run_from_json(to_json(a));
  ASSERT_TRUE(back.shape.has_value());
  EXPECT_EQ(back.shape->components_final, s.components_final);
  // The snapshot: one point per component with its body's id.
  const SnapshotParticles snap = read_vtp((dir / "full" / "final.vtp").string());
  ASSERT_EQ(snap.body.size(), snap.x.size());
  EXPECT_EQ(snap.body, a.final_spheres.body);
  for (std::int64_t id : snap.body) EXPECT_GE(id, 0);

  // Cut off mid-run, resumed: the same pile, the same component positions, bit for bit.
  EXPECT_THROW(run(scene, dir / "part", 1500), std::runtime_error);
  const PileRun b = run(scene, dir / "part", 0, true);
  EXPECT_EQ(a.pile.height_m, b.pile.height_m);
  EXPECT_EQ(a.pile.theta_hd_deg, b.pile.theta_hd_deg);
  EXPECT_EQ(a.performance.steps, b.performance.steps);
  EXPECT_EQ(a.final_spheres.x, b.final_spheres.x);
  EXPECT_EQ(a.final_spheres.body, b.final_spheres.body);
}

// The same rod pour on two threads ends in the same bits as on one.
TEST(PileClumps, TwoThreadsGiveTheSameRodPile) {
  const fs::path dir = temp_dir("threads");
  const SceneConfig scene = scene_from(scene_text(test_support::kTinyRods), dir);
  const PileRun a = run(scene, dir / "one", 0, false, 1), b = run(scene, dir / "two", 0, false, 2);
  EXPECT_EQ(a.performance.steps, b.performance.steps);
  EXPECT_EQ(a.pile.theta_hd_deg, b.pile.theta_hd_deg);
  EXPECT_EQ(a.final_spheres.x, b.final_spheres.x);
}

// The controller keeps the templates' fingerprint: a checkpoint whose clumps another build of
// the templates would not reproduce is refused on resume (here the fingerprint is edited).
TEST(PileClumps, AResumeWithOtherTemplatesIsRefused) {
  const fs::path dir = temp_dir("fingerprint");
  const SceneConfig scene = scene_from(scene_text(test_support::kTinyRods), dir);
  EXPECT_THROW(run(scene, dir / "run", 300), std::runtime_error);
  const fs::path ctl = dir / "run" / "controller.json";
  nlohmann::json j = nlohmann::json::parse(std::ifstream(ctl));
  ASSERT_FALSE(j.at("templates_fnv1a").get<std::string>().empty());
  j["templates_fnv1a"] = "0000000000000000";
  std::ofstream(ctl) << j.dump();
  try {
    run(scene, dir / "run", 0, true);
    FAIL() << "the resume was not refused";
  } catch (const ResumeError& e) {
    EXPECT_NE(std::string(e.what()).find("clump templates"), std::string::npos) << e.what();
  }
}

// A one-sphere clump is the sphere: the same sample, fill, flow and pile.
TEST(PileClumps, OneSphereClumpsGiveTheSphereEnginesPile) {
  const fs::path dir = temp_dir("one_sphere");
  fs::create_directories(dir / "s");
  fs::create_directories(dir / "c");
  const SceneConfig spheres = scene_from(scene_text(""), dir / "s");
  const SceneConfig ones =
      scene_from(scene_text("[sample.shape]\nkind = \"template\"\noffsets = [[0.0, 0.0, 0.0]]\n"
                            "radii = [0.5]\n"),
                 dir / "c");
  const PileRun a = run(spheres, dir / "s" / "run"), b = run(ones, dir / "c" / "run");
  EXPECT_FALSE(a.shape.has_value());
  ASSERT_TRUE(b.shape.has_value());
  EXPECT_EQ(a.stop.reason, b.stop.reason);
  EXPECT_EQ(a.particles.initial, b.particles.initial);
  EXPECT_EQ(a.particles.final, b.particles.final);
  EXPECT_EQ(a.performance.steps, b.performance.steps);
  EXPECT_EQ(a.pile.height_m, b.pile.height_m);
  EXPECT_EQ(a.pile.base_diameter_m, b.pile.base_diameter_m);
  EXPECT_EQ(a.pile.theta_hd_deg, b.pile.theta_hd_deg);
  EXPECT_EQ(a.pile.slice_angle_mean_deg, b.pile.slice_angle_mean_deg);
  EXPECT_EQ(a.final_spheres.x, b.final_spheres.x);
}

}  // namespace
}  // namespace reposetwin::experiments
