// The plan printed before a run: its counts against an independent draw and closed forms, and
// the refusal above the limits naming the key that shrinks the run.
#include "experiments/pile/run_plan.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "experiments/io/scene_overrides.hpp"
#include "experiments/pile/pile_sample.hpp"
#include "sim/psd.hpp"
#include "sim/random.hpp"

namespace reposetwin::experiments {
namespace {

TEST(RunPlan, ParticleCountMatchesTheSamplersDraw) {
  const SceneConfig s = load_scene("");
  const RunPlan p = plan_run(s, 1);
  sim::Rng rng(s.seed);
  const double density = s.materials[material_index(s, s.sample_material, "")].density;
  const sim::PsdSample drawn = sim::sample_psd(s.psd.spec, s.mass, density, rng);
  EXPECT_NEAR(static_cast<double>(p.particles), static_cast<double>(drawn.summary.count),
              0.05 * static_cast<double>(drawn.summary.count));
  EXPECT_NEAR(p.fines_fraction, drawn.summary.fines_fraction, 1e-12);
  EXPECT_NEAR(p.d_min_mm, 2.5, 1e-9);
}

const std::string kSource = REPOSETWIN_SOURCE_DIR;

// A clump pour is priced by its spheres at their step: the plan's grains and spheres against the
// pile's own draw, its step against the engine's model of the drawn components, and the wall time
// of a tetrahedron pour against a sphere pour of the same sieve curve (issue 53: 6,451 tetrahedra
// of 25,804 spheres at dt 2.74e-5 s cost 1,310 CPU-s; planned as spheres they read 6 min).
TEST(RunPlan, ClumpsArePricedByTheirComponentsAtTheirStep) {
  const std::string scene = kSource + "/data/scenes/paper/table1_s4_dmax8p0_900g_reduced.toml";
  const std::vector<std::string> fines = {"sample.d_min_mm=4.0"};
  std::vector<std::string> tetra = fines;
  tetra.push_back(
      "sample.shape={ name = \"tetra_n4\", kind = \"template\", offsets = [[1, 0, -0.5], "
      "[-1, 0, -0.5], [0, 0.8, 0.6], [0, -0.8, 0.6]], radii = [0.9, 0.9, 0.9, 0.9] }");
  const SceneConfig s = load_scene(scene, tetra);
  const RunPlan p = plan_run(s, 1);
  const PileSample drawn = draw_pile_sample(s, material_index(s, s.sample_material, ""));
  std::int64_t components = 0;
  for (const std::int32_t k : drawn.shape)
    components += static_cast<std::int64_t>(s.shapes[static_cast<std::size_t>(k)].unit.size());
  const auto n = static_cast<double>(drawn.diameter.size());
  EXPECT_NEAR(static_cast<double>(p.particles), n, 0.02 * n);
  EXPECT_NEAR(static_cast<double>(p.components), static_cast<double>(components), 0.02 * 4 * n);
  EXPECT_GT(p.components, 3 * p.particles);
  // The step of the drawn components (their smallest is a touch above d_min's).
  const double dt = build_model(s, drawn.r_min, drawn.r_max).dt;
  EXPECT_NEAR(p.time_step_s, dt, 0.03 * dt);
  EXPECT_NE(plan_text(p).find(std::to_string(p.particles) + " grains of " +
                              std::to_string(p.components) + " spheres"),
            std::string::npos)
      << plan_text(p);
  // Against spheres of the same curve: fewer spheres, and a longer step (a clump steps at the
  // sphere of its smallest grain's volume, a sphere at its own radius: sim::Model::finalize).
  const RunPlan spheres = plan_run(load_scene(scene, fines), 1);
  EXPECT_EQ(spheres.components, spheres.particles);
  EXPECT_LT(p.time_step_s, spheres.time_step_s);
  EXPECT_GT(p.wall_s, 2.0 * spheres.wall_s);
}

TEST(RunPlan, FillHeightInACylinderIsVolumeOverArea) {
  const SceneConfig s = load_scene(kSource + "/data/scenes/paper/fig18_column_dmax70.toml");
  ASSERT_EQ(s.container.kind, "cylinder");
  const RunPlan p = plan_run(s, 2);
  const double density = s.materials[material_index(s, s.sample_material, "")].density;
  const double bulk = s.mass / (density * 0.6);
  const double r = 0.5 * s.container.bottom_diameter;
  EXPECT_NEAR(p.fill_height_m, bulk / (std::numbers::pi * r * r), 1e-9);
  EXPECT_NEAR(p.simulated_time_s,
              std::min(s.procedure.max_time, 0.8 + 0.75 * p.fill_height_m / s.procedure.lift_speed),
              1e-9);
  EXPECT_EQ(p.steps, static_cast<std::int64_t>(std::ceil(p.simulated_time_s / p.time_step_s)));
  EXPECT_NEAR(p.wall_s, static_cast<double>(p.steps * p.particles) / (2 * 1.3e6), 1e-6);
}

TEST(RunPlan, SmallerCutOffMeansMoreParticlesAndASmallerStep) {
  const std::string scene = kSource + "/data/scenes/paper/table1_s1_dmax2p0_200g.toml";
  const RunPlan coarse = plan_run(load_scene(scene), 1);
  const RunPlan fine = plan_run(load_scene(scene, {"sample.d_min_mm=0.5"}), 1);
  EXPECT_GT(fine.particles, 3 * coarse.particles);
  EXPECT_LT(fine.time_step_s, coarse.time_step_s);
  EXPECT_LT(fine.fines_fraction, coarse.fines_fraction);
  EXPECT_GT(fine.wall_s, 4 * coarse.wall_s);
}

TEST(RunPlan, AboveTheLimitsItIsRefusedNamingTheCutOffKey) {
  const RunPlan p = plan_run(load_scene(""), 1);
  EXPECT_EQ(plan_refusal(p, {}), "");
  PlanSettings few;
  few.max_particles = 100;
  const std::string why = plan_refusal(p, {}, few);
  EXPECT_NE(why.find("above the limit of 100"), std::string::npos) << why;
  EXPECT_NE(why.find("sample.d_min_mm"), std::string::npos) << why;
  EXPECT_NE(why.find("--yes"), std::string::npos) << why;
  PlanSettings slow;
  slow.particle_steps_per_s_per_thread = 10.0;  // days
  const std::string late = plan_refusal(plan_run(load_scene(""), 1, slow), {}, slow);
  EXPECT_NE(late.find("above the limit of 1h0m"), std::string::npos) << late;
  EXPECT_NE(plan_text(p).find("particle-steps/s"), std::string::npos);
}

// The advice names only what the command that plans takes: --set for run, a scene file's key
// for timestep, a campaign file's overrides for campaign and calibrate FILE (which take no
// --set), a test sheet's column for calibrate --tests and loop.
TEST(RunPlan, TheAdviceNamesWhatTheCommandTakes) {
  const RunPlan p =
      plan_run(load_scene(kSource + "/data/scenes/paper/table1_s1_dmax2p0_200g.toml",
                          {"sample.d_min_mm=0.5"}),
               1);
  ASSERT_LT(2.0 * p.d_min_mm, 0.9 * p.d_max_mm);  // the example is given
  PlanSettings few;
  few.max_particles = 100;
  using K = KeySource::Kind;
  struct Row {
    KeySource source;
    std::string says, never;
  };
  for (const Row& r :
       {Row{{K::kSetOption, ""}, "e.g. --set sample.d_min_mm=", ""},
        Row{{K::kSceneFile, "s.toml"}, "e.g. d_min_mm = ", "--set"},
        Row{{K::kCampaignFile, "c.toml"}, "e.g. overrides = { \"sample.d_min_mm\" = ", "--set"},
        Row{{K::kTestSheet, "tests.csv"}, "e.g. a column set:sample.d_min_mm of ", "--set"}}) {
    const std::string why = plan_refusal(p, r.source, few);
    EXPECT_NE(why.find(r.says), std::string::npos) << why;
    if (!r.never.empty()) EXPECT_EQ(why.find(r.never), std::string::npos) << why;
    if (!r.source.file.empty()) EXPECT_NE(why.find(r.source.file), std::string::npos) << why;
  }
}

TEST(RunPlan, DurationsReadAsAPersonWritesThem) {
  EXPECT_EQ(duration_text(45.2), "45s");
  EXPECT_EQ(duration_text(725), "12m5s");
  EXPECT_EQ(duration_text(3 * 3600 + 20 * 60), "3h20m");
  EXPECT_EQ(duration_text(4 * 86400 + 6 * 3600), "4d6h");
}

}  // namespace
}  // namespace reposetwin::experiments
