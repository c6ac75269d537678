// A tiny pile-test scene for tests: tens of 3-4 mm spheres through a small funnel, a few
// seconds of simulation on one core.
#pragma once

namespace reposetwin::test_support {

inline constexpr const char* kTinyScene = R"(
[scene]
name = "tiny"
seed = 1
[sample]
mass_kg = 0.006
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
[numerics]
softened_youngs_modulus_pa = 5e6
rayleigh_fraction = 0.3
)";

/// Appended to kTinyScene: every grain a rod of four spheres, L/I = 1.5 (about 50 rods).
inline constexpr const char* kTinyRods = R"(
[sample.shape]
name = "rod"
kind = "generated"
elongation = 1.5
spheres = 4
)";

}  // namespace reposetwin::test_support
