// The pile sample with clumps: each sieve class keeps its mass when the grains are clumps whose
// sieve size is their intermediate extent, checked on the bodies the engine builds (extents
// measured from the placed component spheres along the body's principal axes, masses the
// engine's), each shape keeps its mass fraction, and a one-sphere template draws exactly the
// sphere sample.
#include "experiments/pile/pile_sample.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "experiments/io/scene.hpp"
#include "sim/clump.hpp"

namespace reposetwin::experiments {
namespace {

// Five sieve classes from 2 to 4 mm, about 1,500 grains in a funnel of 41 cm^3.
std::string scene_text(const std::string& shapes) {
  return R"(
[scene]
name = "sieve"
seed = 11
[sample]
mass_kg = 0.06
material = "rock"
[sample.psd]
sieve_mm = [2.0, 2.5, 3.0, 3.5, 4.0]
passing_percent = [0.0, 20.0, 45.0, 70.0, 100.0]
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
[numerics]
softened_youngs_modulus_pa = 5e6
)" + shapes;
}

const char* kMix = R"(
[[sample.shapes]]
name = "rod"
kind = "generated"
elongation = 1.5
spheres = 4
mass_fraction = 0.6
[[sample.shapes]]
name = "flat"
kind = "generated"
elongation = 1.2
flatness = 1.5
spheres = 6
roundness = 0.7
mass_fraction = 0.4
)";

// Grain g's place on a 1 cm grid, 16 a side, near the origin (so positions round finely).
sim::Vec3 at(std::size_t g) {
  return 0.01 * sim::Vec3(static_cast<double>(g % 16), static_cast<double>(g / 16 % 16),
                          static_cast<double>(g / 256));
}

// The body's intermediate extent, from its components as placed in the world, along the
// principal axes of its orientation.
double intermediate_extent(const sim::State& st, std::size_t b) {
  const sim::Mat3 rot = st.bodies.q[b].toRotationMatrix();
  double e[3];
  for (int a = 0; a < 3; ++a) {
    double lo = 1e30, hi = -1e30;
    for (std::int32_t k = st.body_components.start[b]; k < st.body_components.start[b + 1]; ++k) {
      const auto i = static_cast<std::size_t>(st.body_components.particle[k]);
      const double s = rot.col(a).dot(st.particles.x[i]);
      lo = std::min(lo, s - st.particles.radius[i]);
      hi = std::max(hi, s + st.particles.radius[i]);
    }
    e[a] = hi - lo;
  }
  std::sort(e, e + 3);
  return e[1];
}

TEST(PileSample, EachSieveClassKeepsItsMassForClumps) {
  const SceneConfig scene = parse_scene_text(scene_text(kMix), "sieve.toml");
  const int rock = material_index(scene, "rock", "");
  const PileSample sample = draw_pile_sample(scene, rock);
  ASSERT_GT(sample.diameter.size(), 500u);
  sim::Model model = build_model(scene, sample.r_min, sample.r_max);
  add_grain_templates(model, scene, sample);
  sim::World world(std::move(model));
  const std::size_t n = sample.diameter.size();
  for (std::size_t g = 0; g < n; ++g)  // on a 1 cm grid: nothing touches, nothing is stepped
    world.add_clump(static_cast<int>(g), at(g), sample.orientation[g], rock);
  sim::State& st = world.state();
  sim::index_body_components(st.particles, st.bodies.size(), st.body_components);
  ASSERT_EQ(st.bodies.size(), n);

  const double bounds[] = {2e-3, 2.5e-3, 3e-3, 3.5e-3, 4e-3};
  const double target[] = {0.20, 0.25, 0.25, 0.30};
  double mass[4] = {0, 0, 0, 0}, shape_mass[2] = {0, 0}, total = 0, largest = 0;
  for (std::size_t b = 0; b < n; ++b) {
    const double i_ext = intermediate_extent(st, b);
    EXPECT_NEAR(i_ext, sample.diameter[b], 1e-12 * sample.diameter[b]) << "grain " << b;
    const int k = static_cast<int>(std::upper_bound(bounds, bounds + 5, i_ext) - bounds) - 1;
    ASSERT_TRUE(k >= 0 && k < 4) << i_ext;
    mass[k] += st.bodies.mass[b];
    shape_mass[sample.shape[b]] += st.bodies.mass[b];
    total += st.bodies.mass[b];
    largest = std::max(largest, st.bodies.mass[b]);
  }
  // The total is the sample's mass within one grain; each class and each shape within one grain.
  EXPECT_GE(total, scene.mass);
  EXPECT_LT(total - scene.mass, largest);
  for (int k = 0; k < 4; ++k)
    EXPECT_NEAR(mass[k] / total, target[k], largest / total) << "class " << k;
  EXPECT_NEAR(shape_mass[0] / total, 0.6, largest / total);
  EXPECT_NEAR(shape_mass[1] / total, 0.4, largest / total);
}

// The engine's body mass is the union's, not the sum of its spheres': the same components,
// integrated afresh at their placed size and orientation, give the same volume.
TEST(PileSample, ABodysMassIsItsUnionsAtTheMaterialDensity) {
  const SceneConfig scene = parse_scene_text(scene_text(kMix), "sieve.toml");
  const int rock = material_index(scene, "rock", "");
  const PileSample sample = draw_pile_sample(scene, rock);
  sim::Model model = build_model(scene, sample.r_min, sample.r_max);
  add_grain_templates(model, scene, sample);
  sim::World world(std::move(model));
  for (std::size_t g = 0; g < 4; ++g)
    world.add_clump(static_cast<int>(g), at(g), sample.orientation[g], rock);
  sim::State& st = world.state();
  sim::index_body_components(st.particles, st.bodies.size(), st.body_components);
  for (std::size_t b = 0; b < 4; ++b) {
    std::vector<sim::Vec3> x;
    std::vector<double> r;
    double spheres = 0;
    for (std::int32_t k = st.body_components.start[b]; k < st.body_components.start[b + 1]; ++k) {
      const auto i = static_cast<std::size_t>(st.body_components.particle[k]);
      x.push_back(st.particles.x[i]);
      r.push_back(st.particles.radius[i]);
      spheres += 4.0 / 3.0 * 3.141592653589793 * std::pow(r.back(), 3);
    }
    const double v = sim::clump_mass_properties(x, r).volume;
    // Two integrations of the overlaps on differently oriented grids, each within about 1e-6.
    EXPECT_NEAR(st.bodies.mass[b], 2760.0 * v, 5e-6 * 2760.0 * v);
    EXPECT_LT(v, 0.9 * spheres);  // the overlaps are not counted twice
  }
}

TEST(PileSample, AOneSphereTemplateDrawsTheSphereSample) {
  const SceneConfig spheres = parse_scene_text(scene_text(""), "sieve.toml");
  const SceneConfig one = parse_scene_text(
      scene_text("[sample.shape]\nkind = \"template\"\noffsets = [[0.0, 0.0, 0.0]]\n"
                 "radii = [0.5]\n"),
      "sieve.toml");
  const PileSample a = draw_pile_sample(spheres, 0), b = draw_pile_sample(one, 0);
  EXPECT_TRUE(a.shape.empty());
  EXPECT_EQ(a.diameter, b.diameter);
  EXPECT_EQ(a.summary.drawn_mass, b.summary.drawn_mass);
  EXPECT_EQ(a.r_min, b.r_min);
  EXPECT_EQ(a.r_max, b.r_max);
}


// The fill with procedure.fill_jitter: grains leave their lattice points (the sample and its
// draw unchanged), yet no two overlap and none crosses the funnel's slanted wall or the plate,
// for spheres and for clumps; jitter 0 is the lattice itself.
void expect_jittered_fill_is_sound(const std::string& shapes) {
  const std::string base = scene_text(shapes);
  const SceneConfig lattice = parse_scene_text(base, "sieve.toml");
  const SceneConfig jittered =
      parse_scene_text(base + "[procedure]\nfill_jitter = 1.0\n", "sieve.toml");
  const int rock = material_index(lattice, "rock", "");
  auto fill = [&](const SceneConfig& scene) {
    const PileSample sample = draw_pile_sample(scene, rock);
    sim::Model model = build_model(scene, sample.r_min, sample.r_max);
    add_grain_templates(model, scene, sample);
    sim::World world(std::move(model));
    fill_container(world, scene, sample, rock);
    return world.state().particles;
  };
  const sim::Particles a = fill(lattice), b = fill(jittered);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 500u);
  const ContainerConfig& c = jittered.container;
  const double slope = 0.5 * (c.top_diameter - c.bottom_diameter) / c.height;
  double moved = 0.0;
  for (std::size_t i = 0; i < b.size(); ++i) {
    EXPECT_EQ(a.radius[i], b.radius[i]);
    moved = std::max(moved, (a.x[i] - b.x[i]).norm() / a.radius[i]);
    const double z = b.x[i].z() - c.gap;
    EXPECT_GE(z - b.radius[i], -1e-12) << "component " << i << " below the plate";
    // Horizontal distance from the slanted wall at the sphere's height, against its radius.
    const double t = std::clamp(z / c.height, 0.0, 1.0);
    const double wall = 0.5 * (c.bottom_diameter + t * (c.top_diameter - c.bottom_diameter));
    const double r_xy = std::hypot(b.x[i].x(), b.x[i].y());
    EXPECT_LE(r_xy + b.radius[i] * std::sqrt(1.0 + slope * slope), wall + 1e-12)
        << "component " << i << " through the wall";
    for (std::size_t j = i + 1; j < b.size(); ++j) {
      if (b.body[i] >= 0 && b.body[i] == b.body[j]) continue;  // one clump's own components
      EXPECT_GE((b.x[i] - b.x[j]).norm(), b.radius[i] + b.radius[j] - 1e-12)
          << "components " << i << " and " << j << " overlap";
    }
  }
  EXPECT_GT(moved, 0.1);  // off the lattice by a tenth of a radius at least somewhere
  const sim::Particles a2 = fill(lattice);
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a.x[i], a2.x[i]);
}

TEST(PileSample, AJitteredFillOfSpheresKeepsThemApartAndInside) { expect_jittered_fill_is_sound(""); }

TEST(PileSample, AJitteredFillOfClumpsKeepsThemApartAndInside) {
  expect_jittered_fill_is_sound(kMix);
}

}  // namespace
}  // namespace reposetwin::experiments
