// Closed-form checks of the contact laws, one or two bodies at a time:
// Hertz contact time and restitution (pair and wall), slip to roll at 5/7, incline thresholds,
// constant-torque rolling deceleration, energy conservation and convergence in dt.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "sim/world.hpp"
#include "sim_test_util.hpp"

namespace reposetwin::sim {
namespace {

using testing::frictionless;
using testing::make_model;
using testing::plate;

constexpr double kR = 1e-3;      // sphere radius [m]
constexpr double kE = 46.8e6;    // softened Young's modulus [Pa]
constexpr double kNu = 0.19;
constexpr double kRho = 2760.0;

double sphere_mass(double r) { return kRho * 4.0 / 3.0 * std::numbers::pi * r * r * r; }

struct Impact {
  double duration;  // [s]
  double ratio;     // rebound / approach relative speed
};

/// Two equal spheres approaching head-on at relative speed v (or a sphere onto a plate).
Impact head_on(double e, double v, bool on_wall, double dt_per_contact = 1000.0) {
  Model m = make_model(frictionless(e), kE, Vec3::Zero());
  if (on_wall) m.walls.push_back(plate());
  const double m_eff = on_wall ? sphere_mass(kR) : 0.5 * sphere_mass(kR);
  const double r_eff = on_wall ? kR : 0.5 * kR;
  const double e_star = on_wall ? 1.0 / (2.0 * (1 - kNu * kNu) / kE) : kE / (2 * (1 - kNu * kNu));
  const double tc = hertz_contact_time(m_eff, r_eff, e_star, v);
  m.settings.time_step = tc / dt_per_contact;
  m.finalize(kR, kR);
  World w(m);
  if (on_wall) {
    w.add_particle(Vec3(0, 0, kR * 1.01), kR, 0);
    w.state().particles.v[0] = Vec3(0, 0, -v);
  } else {
    w.add_particle(Vec3(-kR * 1.01, 0, 0), kR, 0);
    w.add_particle(Vec3(kR * 1.01, 0, 0), kR, 0);
    w.state().particles.v[0] = Vec3(0.5 * v, 0, 0);
    w.state().particles.v[1] = Vec3(-0.5 * v, 0, 0);
  }
  auto gap = [&]() {
    const Particles& p = w.state().particles;
    if (on_wall) return p.x[0].z() - kR;
    return std::abs(p.x[1].x() - p.x[0].x()) - 2 * kR;
  };
  double t_start = -1, t_end = -1;
  for (int s = 0; s < 100000 && t_end < 0; ++s) {
    w.step();
    const double g = gap();
    if (g < 0 && t_start < 0) t_start = w.state().time;
    if (g >= 0 && t_start >= 0) t_end = w.state().time;
  }
  const Particles& p = w.state().particles;
  // Particle order may change on neighbor rebuilds: use the relative speed, which is symmetric.
  const double vrel = on_wall ? p.v[0].z() : std::abs(p.v[1].x() - p.v[0].x());
  return {t_end - t_start, vrel / v};
}

TEST(HertzImpact, ContactDurationMatchesHertz) {
  const double v = 0.5;
  const Impact pair = head_on(1.0, v, false);
  const double tc_pair =
      hertz_contact_time(0.5 * sphere_mass(kR), 0.5 * kR, kE / (2 * (1 - kNu * kNu)), v);
  EXPECT_NEAR(pair.duration / tc_pair, 1.0, 0.02);
  const Impact wall = head_on(1.0, v, true);
  const double tc_wall = hertz_contact_time(sphere_mass(kR), kR, kE / (2 * (1 - kNu * kNu)), v);
  EXPECT_NEAR(wall.duration / tc_wall, 1.0, 0.02);
  // Elastic: all speed comes back.
  EXPECT_NEAR(pair.ratio, 1.0, 1e-3);
}

class Restitution : public ::testing::TestWithParam<double> {};

TEST_P(Restitution, ReboundOverApproachEqualsE) {
  const double e = GetParam();
  EXPECT_NEAR(head_on(e, 0.8, false).ratio / e, 1.0, 0.01) << "sphere-sphere";
  EXPECT_NEAR(head_on(e, 0.8, true).ratio / e, 1.0, 0.01) << "sphere-plane";
  // Independent of the impact speed (Hertz with this damping is self-similar).
  EXPECT_NEAR(head_on(e, 0.1, true).ratio / e, 1.0, 0.01) << "slow sphere-plane";
}

INSTANTIATE_TEST_SUITE_P(E, Restitution, ::testing::Values(0.3, 0.79, 0.95));

/// A sphere resting on a plate, gravity tilted by `angle` (an incline of that angle).
World sphere_on_incline(const PairParams& pair, double angle_rad, double dt = 0.0) {
  const double g = 9.81;
  Model m = make_model(pair, kE, Vec3(g * std::sin(angle_rad), 0, -g * std::cos(angle_rad)));
  m.walls.push_back(plate());
  m.settings.time_step = dt;
  m.finalize(kR, kR);
  World w(m);
  // Start at the static Hertz overlap so there is no bounce.
  const double e_star = 1.0 / (2.0 * (1 - kNu * kNu) / kE);
  const double fn = sphere_mass(kR) * g * std::cos(angle_rad);
  const double delta = std::pow(3.0 * fn / (4.0 * e_star * std::sqrt(kR)), 2.0 / 3.0);
  w.add_particle(Vec3(0, 0, kR - delta), kR, 0);
  return w;
}

TEST(Friction, SlidingSphereEndsRollingAtFiveSevenths) {
  PairParams pair;
  pair.restitution = 0.5;
  pair.friction = 0.3;
  pair.rolling_model = RollingModel::kNone;
  World w = sphere_on_incline(pair, 0.0);
  const double v0 = 0.5;
  w.state().particles.v[0] = Vec3(v0, 0, 0);
  // Slip ends after t = 2 v0 / (7 mu g) ~ 0.05 s; run well past it.
  while (w.state().time < 0.15) w.step();
  const Particles& p = w.state().particles;
  EXPECT_NEAR(p.v[0].x() / v0, 5.0 / 7.0, 0.01 * 5.0 / 7.0);
  // Rolling without slip: v = w r (w about +y for motion along +x).
  EXPECT_NEAR(p.w[0].y() * kR / p.v[0].x(), 1.0, 0.01);
}

double displacement_after(World& w, double t) {
  const double x0 = w.state().particles.x[0].x();
  while (w.state().time < t) w.step();
  return w.state().particles.x[0].x() - x0;
}

TEST(Incline, RollingBlockedSlidesExactlyAboveFrictionAngle) {
  PairParams pair;
  pair.restitution = 0.5;
  pair.friction = 0.4;
  pair.rolling_model = RollingModel::kEpsd;  // a huge mu_r blocks rolling
  pair.rolling_friction = 100.0;
  pair.rolling_damping = 1.0;
  const double t = 0.1;
  World below = sphere_on_incline(pair, std::atan(0.95 * pair.friction));
  EXPECT_LT(std::abs(displacement_after(below, t)), 1e-6);  // stuck (elastic creep only)
  World above = sphere_on_incline(pair, std::atan(1.05 * pair.friction));
  // Sliding with a = g (sin a - mu cos a): compare the distance with the closed form.
  const double a = std::atan(1.05 * pair.friction);
  const double acc = 9.81 * (std::sin(a) - pair.friction * std::cos(a));
  const double d = displacement_after(above, t);
  EXPECT_NEAR(d / (0.5 * acc * t * t), 1.0, 0.05);
  EXPECT_LT(std::abs(above.state().particles.w[0].y()), 1e-2 * std::abs(above.state().particles.v[0].x()) / kR);
}

TEST(Incline, EpsdHoldsBelowItsAngleAndRollsAbove) {
  // On a plane R_r = R, so the model's critical incline is tan(alpha) = mu_r.
  PairParams pair;
  pair.restitution = 0.5;
  pair.friction = 0.8;
  pair.rolling_model = RollingModel::kEpsd;
  pair.rolling_friction = 0.2;
  pair.rolling_damping = 0.3;
  const double t = 0.1;
  World below = sphere_on_incline(pair, std::atan(0.9 * pair.rolling_friction));
  EXPECT_LT(std::abs(displacement_after(below, t)), 1e-6);
  const double a = std::atan(1.1 * pair.rolling_friction);
  World above = sphere_on_incline(pair, a);
  // Rolling without slip against the capped torque: a = 5/7 g (sin a - mu_r cos a).
  const double acc = 5.0 / 7.0 * 9.81 * (std::sin(a) - pair.rolling_friction * std::cos(a));
  const double d = displacement_after(above, t);
  EXPECT_NEAR(d / (0.5 * acc * t * t), 1.0, 0.05);
}

TEST(Rolling, ConstantTorqueDecelerationMatchesModel) {
  // Rolling without slip on a level plate with M = mu_r F_n a: m a R = -(F_f R), I dw = ...
  // gives a deceleration mu_r g a_lever / R / (1 + I / (m R^2)) = 5/7 mu_r g (a_lever ~ R).
  PairParams pair;
  pair.restitution = 0.5;
  pair.friction = 0.8;
  pair.rolling_model = RollingModel::kCdt;
  pair.rolling_friction = 0.1;
  World w = sphere_on_incline(pair, 0.0);
  const double v0 = 0.3;
  w.state().particles.v[0] = Vec3(v0, 0, 0);
  w.state().particles.w[0] = Vec3(0, v0 / kR, 0);
  for (int i = 0; i < 200; ++i) w.step();  // let the contact settle
  const double t0 = w.state().time, va = w.state().particles.v[0].x();
  while (w.state().time < t0 + 0.1) w.step();
  const double decel = (va - w.state().particles.v[0].x()) / (w.state().time - t0);
  EXPECT_NEAR(decel / (5.0 / 7.0 * pair.rolling_friction * 9.81), 1.0, 0.02);
}

/// Total energy of a system of spheres on a plate under gravity: kinetic + potential + Hertz
/// elastic energy 8/15 E* sqrt(R*) delta^2.5 of every contact.
double total_energy(const World& w) {
  const Particles& p = w.state().particles;
  const Model& m = w.model();
  const double g = -m.settings.gravity.z();
  double e = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    e += 0.5 * p.mass[i] * p.v[i].squaredNorm() + 0.5 * p.inertia[i] * p.w[i].squaredNorm();
    e += p.mass[i] * g * p.x[i].z();
    const double es_w = m.table.c(0, 1).e_star;
    const double dw = p.radius[i] - p.x[i].z();
    if (dw > 0) e += 8.0 / 15.0 * es_w * std::sqrt(p.radius[i]) * std::pow(dw, 2.5);
    for (std::size_t j = i + 1; j < p.size(); ++j) {
      const double d = p.radius[i] + p.radius[j] - (p.x[i] - p.x[j]).norm();
      if (d > 0) {
        const double r_eff = p.radius[i] * p.radius[j] / (p.radius[i] + p.radius[j]);
        e += 8.0 / 15.0 * m.table.c(0, 0).e_star * std::sqrt(r_eff) * std::pow(d, 2.5);
      }
    }
  }
  return e;
}

World bouncing_column(double dt) {
  Model m = make_model(frictionless(1.0), kE);
  m.walls.push_back(plate());
  m.settings.time_step = dt;
  m.finalize(0.5 * kR, kR);
  World w(m);
  // A loose column of spheres of two sizes dropped onto the plate: many collisions.
  for (int k = 0; k < 8; ++k) {
    const double r = (k % 2) ? kR : 0.5 * kR;
    w.add_particle(Vec3(0.3 * kR * (k % 3), 0.2 * kR * (k % 2), (2.5 + 2.5 * k) * kR), r, 0);
  }
  return w;
}

TEST(Energy, ConservedWithoutDampingOrFriction) {
  World w = bouncing_column(1e-6);
  const double e0 = total_energy(w);
  double max_up = 0;  // something must happen: spheres bouncing back up
  for (int s = 0; s < 100000; ++s) {
    w.step();
    if (s % 100 == 0)
      for (const Vec3& v : w.state().particles.v) max_up = std::max(max_up, v.z());
  }
  const double e1 = total_energy(w);
  EXPECT_LT(std::abs(e1 - e0) / e0, 1e-3);
  EXPECT_GT(max_up, 0.01);
}

TEST(Convergence, HalvingTheStepConverges) {
  // The rebound height of an inelastic sphere after its first bounce, at dt, dt/2, dt/4:
  // the differences shrink (second order for velocity Verlet away from contact onsets).
  auto rebound = [](double dt) {
    PairParams pair = frictionless(0.79);
    Model m = make_model(pair, kE);
    m.walls.push_back(plate());
    m.settings.time_step = dt;
    m.finalize(kR, kR);
    World w(m);
    w.add_particle(Vec3(0, 0, 5 * kR), kR, 0);
    bool hit = false;
    double top = 0;
    while (w.state().time < 0.05) {
      w.step();
      const Particles& p = w.state().particles;
      if (p.x[0].z() < kR) hit = true;
      if (hit && p.x[0].z() > kR) top = std::max(top, p.x[0].z());
    }
    return top;
  };
  const double h1 = rebound(4e-6), h2 = rebound(2e-6), h4 = rebound(1e-6);
  const double d12 = std::abs(h1 - h2), d24 = std::abs(h2 - h4);
  EXPECT_LT(d24, d12);
  // The converged rebound height is e^2 times the drop height (above the contact height).
  EXPECT_NEAR((h4 - kR) / (4 * kR), 0.79 * 0.79, 0.01);
}

// rotate_springs against the rotation itself: a spring in the tangent plane of a normal n0, the
// normal then turned by an angle a about an axis in that plane, is rotated by the same angle
// (Rodrigues' formula, the oracle) whenever it was perpendicular to the axis, for angles from
// 1e-9 rad (the series) to 0.3 rad (the exact rescale); it ends in the new tangent plane with its
// length kept, to a few roundings.
TEST(Springs, RotateWithTheNormalKeepingTheirLength) {
  const Vec3 n0 = Vec3(0.3, -0.5, 0.8).normalized();
  const Vec3 axis = n0.cross(Vec3(1, 0, 0)).normalized();  // in the tangent plane of n0
  const Vec3 t = axis.cross(n0);                           // perpendicular to the axis
  for (double a : {1e-9, 1e-6, 3e-4, 1e-3, 1.5e-3, 1e-2, 0.3}) {
    auto turn = [&](const Vec3& v) -> Vec3 {  // Rodrigues: v turned by a about the axis
      return v * std::cos(a) + axis.cross(v) * std::sin(a) + axis * axis.dot(v) * (1 - std::cos(a));
    };
    const Vec3 n = turn(n0);
    for (double len : {1e-9, 2e-5}) {
      ContactHistory h;
      h.tangential = len * t;
      h.rolling = 3e-7 * t;
      rotate_springs(n, h);
      for (const auto& [got, length] : {std::pair{h.tangential, len}, std::pair{h.rolling, 3e-7}}) {
        const Vec3 want = length * turn(t);
        EXPECT_LE((got - want).norm(), 8e-16 * length) << "angle " << a;
        EXPECT_LE(std::abs(got.norm() - length), 4e-16 * length) << "angle " << a;
        EXPECT_LE(std::abs(got.dot(n)), 4e-16 * length) << "angle " << a;
      }
    }
  }
  // A spring along the normal has no tangential part: it becomes zero; zero springs stay zero.
  ContactHistory h;
  h.tangential = 1e-6 * n0;
  rotate_springs(n0, h);
  EXPECT_EQ(h.tangential, Vec3::Zero());
  EXPECT_EQ(h.rolling, Vec3::Zero());
}

TEST(ModelValidation, RejectsBadParameters) {
  auto finalize_with = [](auto change) {
    Model m = make_model(PairParams{});
    change(m);
    m.finalize(1e-3, 1e-3);
  };
  EXPECT_THROW(finalize_with([](Model& m) { m.materials[0].density = 0; }), std::invalid_argument);
  EXPECT_THROW(finalize_with([](Model& m) { m.pairs[0].restitution = 1.5; }), std::invalid_argument);
  EXPECT_THROW(finalize_with([](Model& m) { m.pairs[0].restitution = 0.0; }), std::invalid_argument);
  EXPECT_THROW(finalize_with([](Model& m) { m.pairs[0].friction = -0.1; }), std::invalid_argument);
  EXPECT_THROW(finalize_with([](Model& m) { m.settings.time_step = 1.0; }), std::invalid_argument);
  EXPECT_THROW(finalize_with([](Model& m) { m.materials[0].youngs_modulus = -1; }),
               std::invalid_argument);
  try {
    finalize_with([](Model& m) { m.settings.time_step = 1.0; });
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("settings.time_step"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(finalize_with([](Model&) {}));
}

}  // namespace
}  // namespace reposetwin::sim
