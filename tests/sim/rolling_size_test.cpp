// Size-dependent rolling resistance (contact.hpp, rolling_size_factor) against closed forms:
// mu_r,eff = mu_r (d_c / d_ref)^alpha, d_c = 4 R* for a pair, 2 R on a wall.
//   EPSD and CDT torques at their caps, pair and wall, one force evaluation,
//   EPSD on an incline (sliding blocked): at rest below tan(theta) = mu_r,eff, rolling above,
//     for two sizes whose thresholds differ by (d1 / d2)^alpha,
//   CDT on a level plate: deceleration 5/7 mu_r,eff g for two sizes.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "sim/world.hpp"
#include "sim_test_util.hpp"

namespace reposetwin::sim {
namespace {

using testing::make_model;
using testing::plate;

constexpr double kE = 46.8e6;  // softened Young's modulus [Pa]
constexpr double kNu = 0.19;
constexpr double kRho = 2760.0;
constexpr double kG = 9.81;

double e_star() { return kE / (2.0 * (1.0 - kNu * kNu)); }
double hertz(double r_eff, double delta) {
  return 4.0 / 3.0 * e_star() * std::sqrt(r_eff) * std::pow(delta, 1.5);
}
double sphere_mass(double r) { return kRho * 4.0 / 3.0 * std::numbers::pi * r * r * r; }

/// Rolling resistance with size scaling; no sliding friction, no damping (the torque is then the
/// rolling torque alone and the normal force the plain Hertz force).
PairParams sized(RollingModel model, double mu_r, double alpha, double d_ref) {
  PairParams p;
  p.restitution = 1.0;
  p.friction = 0.0;
  p.rolling_model = model;
  p.rolling_friction = mu_r;
  p.rolling_damping = 0.0;
  p.rolling_size_exponent = alpha;
  p.rolling_reference_diameter = d_ref;
  return p;
}

class CapTest : public ::testing::TestWithParam<RollingModel> {};

TEST_P(CapTest, PairTorqueAtTheCapUsesFourTimesTheEffectiveRadius) {
  const double r0 = 1e-3, r1 = 0.5e-3, delta = 2e-6;
  const double mu_r = 0.1, alpha = 0.7, d_ref = 1e-3;
  Model m = make_model(sized(GetParam(), mu_r, alpha, d_ref), kE, Vec3::Zero());
  m.finalize(r1, r0);
  World w(m);
  w.add_particle(Vec3(0, 0, 0), r0, 0);
  w.add_particle(Vec3(r0 + r1 - delta, 0, 0), r1, 0);
  Particles& p = w.state().particles;
  const std::size_t big = p.radius[0] == r0 ? 0 : 1;
  p.w[big] = Vec3(0, 0, 1e4);  // spun hard about an axis normal to n: the spring saturates
  w.refresh_forces();
  const double r_eff = r0 * r1 / (r0 + r1);
  const double mu_eff = mu_r * std::pow(4.0 * r_eff / d_ref, alpha);
  const double f_n = hertz(r_eff, delta);
  // EPSD caps at mu_r F_n R*; CDT gives mu_r F_n a_i with a_i = R_i - delta/2.
  const double lever = GetParam() == RollingModel::kEpsd ? r_eff : r0 - 0.5 * delta;
  const double expected = mu_eff * f_n * lever;
  EXPECT_NEAR(p.torque[big].norm() / expected, 1.0, 1e-9);
  EXPECT_LT(p.torque[big].z(), 0.0) << "the torque must oppose the spin";
  // Without the size factor the torque would be mu_r F_n lever: the check can tell.
  EXPECT_GT(std::abs(mu_eff / mu_r - 1.0), 0.1);
}

TEST_P(CapTest, WallTorqueAtTheCapUsesTheParticleDiameter) {
  const double r = 0.7e-3, delta = 2e-6;
  const double mu_r = 0.2, alpha = -0.5, d_ref = 3e-3;
  Model m = make_model(sized(GetParam(), mu_r, alpha, d_ref), kE, Vec3::Zero());
  m.walls.push_back(plate());
  m.finalize(r, r);
  World w(m);
  w.add_particle(Vec3(0, 0, r - delta), r, 0);
  w.state().particles.w[0] = Vec3(1e4, 0, 0);
  w.refresh_forces();
  const double mu_eff = mu_r * std::pow(2.0 * r / d_ref, alpha);
  const double lever = GetParam() == RollingModel::kEpsd ? r : r - delta;
  const double expected = mu_eff * hertz(r, delta) * lever;
  EXPECT_NEAR(w.state().particles.torque[0].norm() / expected, 1.0, 1e-9);
  EXPECT_LT(w.state().particles.torque[0].x(), 0.0);
}

INSTANTIATE_TEST_SUITE_P(Models, CapTest,
                         ::testing::Values(RollingModel::kEpsd, RollingModel::kCdt));

/// A sphere of radius r resting on a plate, gravity tilted by `angle` (an incline).
World sphere_on_incline(const PairParams& pair, double r, double angle) {
  Model m = make_model(pair, kE, Vec3(kG * std::sin(angle), 0, -kG * std::cos(angle)));
  m.walls.push_back(plate());
  m.finalize(r, r);
  World w(m);
  const double fn = sphere_mass(r) * kG * std::cos(angle);
  const double delta = std::pow(3.0 * fn / (4.0 * e_star() * std::sqrt(r)), 2.0 / 3.0);
  w.add_particle(Vec3(0, 0, r - delta), r, 0);
  return w;
}

double displacement_after(World& w, double t) {
  const double x0 = w.state().particles.x[0].x();
  while (w.state().time < t) w.step();
  return w.state().particles.x[0].x() - x0;
}

TEST(RollingSize, EpsdInclineThresholdsOfTwoSizesDifferByTheSizeFactor) {
  // On a plate R_r = R, so the critical incline is tan(theta_c) = mu_r,eff = mu_r (2R/d_ref)^a.
  const double mu_r = 0.1, alpha = 1.0, d_ref = 2e-3;
  PairParams pair;
  pair.restitution = 0.5;
  pair.friction = 5.0;  // sliding blocked
  pair.rolling_model = RollingModel::kEpsd;
  pair.rolling_friction = mu_r;
  pair.rolling_damping = 0.3;
  pair.rolling_size_exponent = alpha;
  pair.rolling_reference_diameter = d_ref;
  const double r_small = 1e-3, r_large = 2e-3;
  const double tan_small = mu_r * std::pow(2 * r_small / d_ref, alpha);  // 0.1
  const double tan_large = mu_r * std::pow(2 * r_large / d_ref, alpha);  // 0.2
  EXPECT_NEAR(tan_small / tan_large, std::pow(r_small / r_large, alpha), 1e-12);
  const double t = 0.1;
  for (const auto& [r, tan_c] : {std::pair{r_small, tan_small}, std::pair{r_large, tan_large}}) {
    SCOPED_TRACE("radius " + std::to_string(r));
    World below = sphere_on_incline(pair, r, std::atan(0.9 * tan_c));
    EXPECT_LT(std::abs(displacement_after(below, t)), 1e-6);
    const double a = std::atan(1.1 * tan_c);
    World above = sphere_on_incline(pair, r, a);
    // Rolling without slip against the capped torque: acceleration 5/7 g (sin a - mu cos a).
    const double acc = 5.0 / 7.0 * kG * (std::sin(a) - tan_c * std::cos(a));
    EXPECT_NEAR(displacement_after(above, t) / (0.5 * acc * t * t), 1.0, 0.05);
  }
  // Between the two thresholds the small sphere rolls and the large one holds.
  const double mid = std::atan(0.15);
  World small = sphere_on_incline(pair, r_small, mid);
  World large = sphere_on_incline(pair, r_large, mid);
  EXPECT_GT(displacement_after(small, t), 1e-4);
  EXPECT_LT(std::abs(displacement_after(large, t)), 1e-6);
}

TEST(RollingSize, CdtDecelerationOnALevelPlateScalesWithSize) {
  // Rolling without slip with M = mu_r,eff F_n a: deceleration 5/7 mu_r,eff g (a ~ R).
  const double mu_r = 0.05, alpha = -0.5, d_ref = 2e-3;
  PairParams pair;
  pair.restitution = 0.5;
  pair.friction = 0.8;
  pair.rolling_model = RollingModel::kCdt;
  pair.rolling_friction = mu_r;
  pair.rolling_size_exponent = alpha;
  pair.rolling_reference_diameter = d_ref;
  for (const double r : {0.5e-3, 2e-3}) {
    SCOPED_TRACE("radius " + std::to_string(r));
    World w = sphere_on_incline(pair, r, 0.0);
    const double v0 = 0.3;
    w.state().particles.v[0] = Vec3(v0, 0, 0);
    w.state().particles.w[0] = Vec3(0, v0 / r, 0);
    for (int i = 0; i < 200; ++i) w.step();  // let the contact settle
    const double t0 = w.state().time, va = w.state().particles.v[0].x();
    while (w.state().time < t0 + 0.1) w.step();
    const double decel = (va - w.state().particles.v[0].x()) / (w.state().time - t0);
    const double mu_eff = mu_r * std::pow(2 * r / d_ref, alpha);  // 0.0707 and 0.0354
    EXPECT_NEAR(decel / (5.0 / 7.0 * mu_eff * kG), 1.0, 0.02);
  }
}

TEST(RollingSize, ModelRejectsAMissingReferenceDiameter) {
  auto finalize_with = [](double alpha, double d_ref, double k_c) {
    PairParams p;
    p.rolling_size_exponent = alpha;
    p.rolling_reference_diameter = d_ref;
    p.cohesion_energy_density = k_c;
    Model m = make_model(p);
    m.finalize(1e-3, 1e-3);
  };
  auto message = [&](double alpha, double d_ref, double k_c) -> std::string {
    try {
      finalize_with(alpha, d_ref, k_c);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(message(0.5, 0.0, 0.0).find("rolling_reference_diameter = 0"), std::string::npos)
      << message(0.5, 0.0, 0.0);
  EXPECT_NE(message(0.5, -1e-3, 0.0).find("rolling_reference_diameter = -0.001"),
            std::string::npos);
  EXPECT_NE(message(0.0, 0.0, -5.0).find("cohesion_energy_density = -5"), std::string::npos)
      << message(0.0, 0.0, -5.0);
  EXPECT_NE(message(NAN, 1e-3, 0.0).find("rolling_size_exponent"), std::string::npos);
  EXPECT_NO_THROW(finalize_with(0.0, 0.0, 0.0));
  EXPECT_NO_THROW(finalize_with(-0.3, 2e-3, 1e3));
}

}  // namespace
}  // namespace reposetwin::sim
