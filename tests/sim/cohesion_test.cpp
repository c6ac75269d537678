// Simplified-JKR cohesion (contact.hpp, sjkr_cohesion) against closed forms:
// F(delta) = A delta^1.5 - B delta with A = 4/3 E* sqrt(R*) (Hertz) and B = pi k_c R* (cohesion).
//   rest on a plate under gravity:      A delta^1.5 - B delta = m g (solved here by bisection),
//   rest without gravity:               delta_eq = (B / A)^2,
//   undamped motion conserves           1/2 m* v^2 + U(delta), U = 2/5 A delta^2.5 - B/2 delta^2,
//   the work to pull a resting contact apart is W = -U(delta_eq) = B delta_eq^2 / 10,
//   the Coulomb cap is mu_s times the Hertz force (not the net force): mu_s B delta_eq unloaded.
// k_c = 0 must leave a run bit-identical to the model without the effect.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>

#include "sim/world.hpp"
#include "sim_test_util.hpp"

namespace reposetwin::sim {
namespace {

using testing::make_model;
using testing::plate;

constexpr double kR = 1e-3;    // sphere radius [m]
constexpr double kE = 46.8e6;  // softened Young's modulus [Pa]
constexpr double kNu = 0.19;
constexpr double kRho = 2760.0;
constexpr double kG = 9.81;
constexpr double kKc = 2e5;  // cohesion energy density [Pa]: cohesion ~ weight at rest

double sphere_mass(double r) { return kRho * 4.0 / 3.0 * std::numbers::pi * r * r * r; }
// E* of two bodies of the same material (rock on rock, or rock on the test's "steel").
double e_star() { return kE / (2.0 * (1.0 - kNu * kNu)); }

/// The normal law of one contact of effective radius r_eff.
struct Law {
  double a;  // Hertz: 4/3 E* sqrt(R*) [N/m^1.5]
  double b;  // cohesion: pi k_c R* [N/m]
  explicit Law(double r_eff, double k_c = kKc)
      : a(4.0 / 3.0 * e_star() * std::sqrt(r_eff)), b(std::numbers::pi * k_c * r_eff) {}
  double force(double d) const { return a * std::pow(d, 1.5) - b * d; }
  double energy(double d) const { return 0.4 * a * std::pow(d, 2.5) - 0.5 * b * d * d; }
  double delta_eq() const { return (b / a) * (b / a); }
};

/// Root of the increasing function f on [lo, hi] by bisection (f(lo) < 0 < f(hi)).
double bisect(const std::function<double(double)>& f, double lo, double hi) {
  EXPECT_LT(f(lo), 0.0);
  EXPECT_GT(f(hi), 0.0);
  for (int k = 0; k < 200; ++k) {
    const double mid = 0.5 * (lo + hi);
    (f(mid) < 0.0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

PairParams cohesive_pair(double e, double k_c = kKc) {
  PairParams p;
  p.restitution = e;
  p.cohesion_energy_density = k_c;
  return p;
}

TEST(CohesionRest, SphereOnAPlateRestsWhereHertzMinusCohesionBalancesWeight) {
  Model m = make_model(cohesive_pair(0.5), kE, Vec3(0, 0, -kG));
  m.walls.push_back(plate());
  m.finalize(kR, kR);
  World w(m);
  const Law law(kR);
  const double mg = sphere_mass(kR) * kG;
  const double expected =
      bisect([&](double d) { return law.force(d) - mg; }, law.delta_eq(), 100 * law.delta_eq());
  const double hertz_only = std::pow(mg / law.a, 2.0 / 3.0);
  ASSERT_GT(expected / hertz_only, 1.3) << "cohesion must matter for this test to mean anything";
  w.add_particle(Vec3(0, 0, kR - hertz_only), kR, 0);
  while (w.state().time < 0.05) w.step();
  const Particles& p = w.state().particles;
  EXPECT_NEAR((kR - p.x[0].z()) / expected, 1.0, 0.01);
  EXPECT_LT(p.v[0].norm(), 1e-5);
}

TEST(CohesionRest, TwoStackedSpheresRestAtBothBalances) {
  // The top contact carries m g with R* = R/2, the plate contact 2 m g with R* = R.
  Model m = make_model(cohesive_pair(0.5), kE, Vec3(0, 0, -kG));
  m.walls.push_back(plate());
  m.finalize(kR, kR);
  World w(m);
  const double mg = sphere_mass(kR) * kG;
  const Law top(0.5 * kR), bottom(kR);
  const double d_top =
      bisect([&](double d) { return top.force(d) - mg; }, top.delta_eq(), 100 * top.delta_eq());
  const double d_bottom = bisect([&](double d) { return bottom.force(d) - 2 * mg; },
                                 bottom.delta_eq(), 100 * bottom.delta_eq());
  w.add_particle(Vec3(0, 0, kR), kR, 0);
  w.add_particle(Vec3(0, 0, 3 * kR), kR, 0);
  while (w.state().time < 0.08) w.step();
  const Particles& p = w.state().particles;
  const std::size_t lo = p.x[0].z() < p.x[1].z() ? 0 : 1, hi = 1 - lo;
  EXPECT_NEAR((kR - p.x[lo].z()) / d_bottom, 1.0, 0.01);
  EXPECT_NEAR((2 * kR - (p.x[hi].z() - p.x[lo].z())) / d_top, 1.0, 0.01);
}

/// Spheres of two sizes, a layer standing on a plate and a layer dropping into its hollows;
/// the state hash after `steps`.
std::uint64_t drop_hash(const PairParams& pair, int steps) {
  Model m = make_model(pair);
  m.walls.push_back(plate());
  m.finalize(0.5 * kR, kR);
  World w(m);
  for (int k = 0; k < 12; ++k) {
    const double r = (k % 3 == 0) ? 0.5 * kR : kR;
    const int layer = k / 6, ix = k % 3, iy = (k / 3) % 2;
    const double shift = layer ? 1.05 * kR : 0.0;
    w.add_particle(Vec3(2.05 * kR * ix + shift, 2.05 * kR * iy + shift, r + layer * 2.0 * kR), r,
                   0);
  }
  for (int s = 0; s < steps; ++s) w.step();
  return state_hash(w.state());
}

TEST(CohesionOff, ZeroEnergyDensityIsBitIdenticalAndAnyPositiveValueIsNot) {
  const PairParams base;  // the keys absent: defaults
  PairParams zero = base;
  zero.cohesion_energy_density = 0.0;
  zero.rolling_size_exponent = 0.0;
  zero.rolling_reference_diameter = 2e-3;  // unused while the exponent is 0
  const std::uint64_t h = drop_hash(base, 3000);
  EXPECT_EQ(drop_hash(zero, 3000), h);
  PairParams some = base;
  some.cohesion_energy_density = 10.0;
  EXPECT_NE(drop_hash(some, 3000), h) << "the test must be able to see cohesion";
}

TEST(CohesionPull, TouchingSphereWithoutGravityStaysAttachedAndOscillatesInTheWell) {
  // No damping and no friction: energy is conserved, so the overlap swings between the start
  // value and the other root of U(delta) = U(delta_0), never reaching zero.
  PairParams pair = cohesive_pair(1.0);
  pair.friction = 0.0;
  pair.rolling_model = RollingModel::kNone;
  Model m = make_model(pair, kE, Vec3::Zero());
  m.walls.push_back(plate());
  m.settings.rayleigh_fraction = 0.05;
  m.finalize(kR, kR);
  World w(m);
  const Law law(kR);
  const double d0 = 0.05 * law.delta_eq();
  const double d_max = bisect([&](double d) { return law.energy(d) - law.energy(d0); },
                              law.delta_eq(), 10 * law.delta_eq());
  w.add_particle(Vec3(0, 0, kR - d0), kR, 0);
  double lo = 1.0, hi = 0.0;
  while (w.state().time < 0.02) {
    w.step();
    const double d = kR - w.state().particles.x[0].z();
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  EXPECT_GT(lo, 0.5 * d0) << "the sphere left the wall";
  EXPECT_NEAR(hi / d_max, 1.0, 0.01);
}

TEST(CohesionPull, DampedSphereWithoutGravitySettlesAtTheZeroForceOverlap) {
  Model m = make_model(cohesive_pair(0.3), kE, Vec3::Zero());
  m.walls.push_back(plate());
  m.finalize(kR, kR);
  World w(m);
  const Law law(kR);
  w.add_particle(Vec3(0, 0, kR - 0.05 * law.delta_eq()), kR, 0);
  while (w.state().time < 0.05) w.step();
  EXPECT_NEAR((kR - w.state().particles.x[0].z()) / law.delta_eq(), 1.0, 0.01);
}

TEST(CohesionFriction, CoulombCapUsesTheHertzForceSoCohesionAloneHoldsAGrain) {
  // Gravity along a plate (no normal load): the net normal force is zero at delta_eq, where the
  // Hertz force equals the cohesion, F_H = B delta_eq. The documented choice caps friction at
  // mu_s F_H: the sphere (rolling blocked) holds if m g < mu_s F_H and otherwise slides with
  // a = g - mu_s F_H / m. With the net force as the cap it would slide at any mu_s.
  const Law law(kR);
  const double m = sphere_mass(kR);
  const double f_h = law.b * law.delta_eq();
  const double mu_c = m * kG / f_h;
  ASSERT_LT(mu_c, 1.0);
  auto displacement = [&](double mu_s, double t) {
    PairParams pair = cohesive_pair(0.5);
    pair.friction = mu_s;
    pair.rolling_model = RollingModel::kEpsd;  // a huge mu_r blocks rolling
    pair.rolling_friction = 100.0;
    pair.rolling_damping = 1.0;
    Model model = make_model(pair, kE, Vec3(kG, 0, 0));
    model.walls.push_back(plate());
    model.finalize(kR, kR);
    World w(model);
    w.add_particle(Vec3(0, 0, kR - law.delta_eq()), kR, 0);
    while (w.state().time < t) w.step();
    return w.state().particles.x[0].x();
  };
  const double t = 0.1;
  EXPECT_LT(std::abs(displacement(1.2 * mu_c, t)), 1e-6);
  const double mu = 0.8 * mu_c;
  const double acc = kG - mu * f_h / m;
  EXPECT_NEAR(displacement(mu, t) / (0.5 * acc * t * t), 1.0, 0.02);
}

struct PairImpact {
  bool separated;      // the spheres left each other
  double ratio;        // final over initial relative speed
  double max_overlap;  // [m]
};

/// Two equal spheres approaching head-on with relative speed v, no gravity and no friction.
PairImpact pair_impact(double e, double v, double t_end) {
  PairParams pair = cohesive_pair(e);
  pair.friction = 0.0;
  pair.rolling_model = RollingModel::kNone;
  Model m = make_model(pair, kE, Vec3::Zero());
  m.settings.rayleigh_fraction = 0.05;
  m.finalize(kR, kR);
  World w(m);
  const double gap = 1e-8;
  w.add_particle(Vec3(-kR - 0.5 * gap, 0, 0), kR, 0);
  w.add_particle(Vec3(kR + 0.5 * gap, 0, 0), kR, 0);
  w.state().particles.v[0] = Vec3(0.5 * v, 0, 0);
  w.state().particles.v[1] = Vec3(-0.5 * v, 0, 0);
  PairImpact r{false, 0.0, 0.0};
  bool touched = false;
  while (w.state().time < t_end) {
    w.step();
    const Particles& p = w.state().particles;
    const double overlap = 2 * kR - std::abs(p.x[1].x() - p.x[0].x());
    r.max_overlap = std::max(r.max_overlap, overlap);
    touched = touched || overlap > 0;
    if (touched && overlap < 0) r.separated = true;
  }
  const Particles& p = w.state().particles;
  r.ratio = std::abs(p.v[1].x() - p.v[0].x()) / v;
  return r;
}

TEST(CohesionImpact, UndampedPairKeepsItsEnergyAndReachesTheEnergyBalanceOverlap) {
  // The cohesive force depends on the overlap only: an undamped collision gives back the
  // approach speed, and the deepest overlap solves 1/2 m* v^2 = U(delta_max).
  const Law law(0.5 * kR);
  const double m_eff = 0.5 * sphere_mass(kR);
  const double work = law.b * law.delta_eq() * law.delta_eq() / 10.0;  // well depth [J]
  const double ke = 3.0 * work;
  const double v = std::sqrt(2.0 * ke / m_eff);
  const double d_max =
      bisect([&](double d) { return law.energy(d) - ke; }, law.delta_eq(), 100 * law.delta_eq());
  const PairImpact r = pair_impact(1.0, v, 0.01);
  EXPECT_TRUE(r.separated);
  EXPECT_NEAR(r.ratio, 1.0, 0.01);
  EXPECT_NEAR(r.max_overlap / d_max, 1.0, 0.01);
  // Without cohesion the same speed would press only to (5/4 m* v^2 / A)^(2/5): visibly less.
  EXPECT_GT(d_max / std::pow(1.25 * m_eff * v * v / law.a, 0.4), 1.2);
}

TEST(CohesionImpact, DampedPairSticksWhenTheWellIsDeepAndBouncesWhenItIsShallow) {
  const Law law(0.5 * kR);
  const double m_eff = 0.5 * sphere_mass(kR);
  const double work = law.b * law.delta_eq() * law.delta_eq() / 10.0;
  const double e = 0.5;
  // Kinetic energy a twentieth of the work of separation: captured, comes to rest at delta_eq.
  const PairImpact slow = pair_impact(e, std::sqrt(2.0 * 0.05 * work / m_eff), 0.03);
  EXPECT_FALSE(slow.separated);
  EXPECT_LT(slow.ratio, 1e-3);
  // Kinetic energy 10^6 times that work: cohesion is a small perturbation of the Hertz contact
  // (B delta / A delta^1.5 = sqrt(delta_eq / delta) ~ 0.06 at the deepest point), so the pair
  // bounces, never faster than it came (cohesion is conservative, damping only takes).
  const PairImpact fast = pair_impact(e, std::sqrt(2.0 * 1e6 * work / m_eff), 0.002);
  EXPECT_TRUE(fast.separated);
  EXPECT_LT(fast.ratio, 1.0);
  EXPECT_NEAR(fast.ratio, e, 0.1 * e);
}

}  // namespace
}  // namespace reposetwin::sim
