// The free-rotor step of the rigid-body integrator (free_rotor_drift) on a torque-free
// asymmetric body, I1 < I2 < I3: energy kept without drift, rotation about the axes of least
// and largest inertia stable, about the intermediate axis unstable (the tennis-racket theorem) at
// the growth rate of the linearised Euler equations, lambda = w sqrt((I2 - I1)(I3 - I2) /
// (I1 I3)).
#include <gtest/gtest.h>

#include <cmath>

#include "sim/clump.hpp"

namespace reposetwin::sim {
namespace {

const Vec3 kInertia(1.0e-9, 2.0e-9, 3.5e-9);  // [kg m^2]

double energy(const Quat& q, const Vec3& l) {
  const Vec3 pi = q.conjugate() * l;
  return 0.5 * pi.cwiseProduct(pi).cwiseQuotient(kInertia).sum();
}

TEST(FreeRotor, KeepsTheEnergyOfAnAsymmetricBodyWithoutDrift) {
  // A generic spin (about 1 rad/s) and orientation; 1e5 steps of 1 ms, about 16 turns.
  Quat q(Eigen::AngleAxisd(0.4, Vec3(1, 2, 3).normalized()));
  const Vec3 l = Vec3(0.6e-9, -1.3e-9, 2.1e-9);
  const double e0 = energy(q, l);
  double worst = 0.0;
  double first_half = 0.0, second_half = 0.0;
  const int steps = 100000;
  for (int s = 1; s <= steps; ++s) {
    free_rotor_drift(q, l, kInertia, 1e-3);
    const double rel = (energy(q, l) - e0) / e0;
    worst = std::max(worst, std::abs(rel));
    (s <= steps / 2 ? first_half : second_half) += rel;
  }
  std::printf("  largest relative energy error %.2e, mean over the halves %.2e, %.2e\n", worst,
              first_half / (steps / 2), second_half / (steps / 2));
  EXPECT_LT(worst, 1e-6);
  // No drift: the mean error of the second half is that of the first.
  EXPECT_LT(std::abs(second_half - first_half) / (steps / 2), 1e-7);
  EXPECT_NEAR(q.norm(), 1.0, 1e-14);
  // The step is second order: the error at dt is about four times that at dt/2.
  auto largest_error = [&](double dt) {
    Quat qq(Eigen::AngleAxisd(0.4, Vec3(1, 2, 3).normalized()));
    double w = 0.0;
    for (int s = 0; s < static_cast<int>(20.0 / dt); ++s) {
      free_rotor_drift(qq, l, kInertia, dt);
      w = std::max(w, std::abs(energy(qq, l) - e0) / e0);
    }
    return w;
  };
  const double ratio = largest_error(4e-3) / largest_error(2e-3);
  EXPECT_NEAR(ratio, 4.0, 0.4);
}

/// Spins the body about body axis `axis` at 1 rad/s with a perturbation `eps` (relative) on the
/// two other axes; returns the largest relative perpendicular part of the body-frame angular
/// momentum over `steps` steps of dt and, through `growth`, its logarithmic growth rate between
/// the relative amplitudes 1e-7 and 1e-4 (0 if not reached), and through `flipped` whether the
/// momentum's component on `axis` changed sign.
double spin(int axis, double eps, int steps, double dt, double* growth, bool* flipped) {
  Vec3 pi = Vec3::Zero();
  pi[axis] = kInertia[axis] * 1.0;
  for (int a = 0; a < 3; ++a)
    if (a != axis) pi[a] = eps * pi[axis];
  Quat q = Quat::Identity();
  const Vec3 l = pi;  // body and world frames agree at t = 0
  double worst = 0.0, t_lo = -1.0, t_hi = -1.0, prev = 0.0;
  *flipped = false;
  for (int s = 1; s <= steps; ++s) {
    free_rotor_drift(q, l, kInertia, dt);
    const Vec3 p = q.conjugate() * l;
    Vec3 perp = p;
    perp[axis] = 0.0;
    const double a = perp.norm() / l.norm();
    worst = std::max(worst, a);
    if (p[axis] * l[axis] < 0.0) *flipped = true;
    // crossing times, interpolated in log(amplitude)
    auto cross = [&](double level, double& t) {
      if (t < 0.0 && a >= level && prev > 0.0 && prev < level)
        t = dt * (s - 1 + std::log(level / prev) / std::log(a / prev));
    };
    cross(1e-7, t_lo);
    cross(1e-4, t_hi);
    prev = a;
  }
  *growth = t_lo > 0.0 && t_hi > 0.0 ? std::log(1e3) / (t_hi - t_lo) : 0.0;
  return worst;
}

TEST(FreeRotor, TennisRacket) {
  double growth = 0.0;
  bool flipped = false;
  // Least and largest inertia: a perturbation of 1e-3 stays of its order.
  for (int axis : {0, 2}) {
    const double worst = spin(axis, 1e-3, 100000, 1e-3, &growth, &flipped);
    EXPECT_LT(worst, 1e-2) << "axis " << axis + 1;
    EXPECT_FALSE(flipped) << "axis " << axis + 1;
  }
  // Intermediate axis: a perturbation of 1e-10 grows at lambda and the body flips.
  const double worst = spin(1, 1e-10, 100000, 1e-3, &growth, &flipped);
  const double i1 = kInertia[0], i2 = kInertia[1], i3 = kInertia[2];
  const double theory = 1.0 * std::sqrt((i2 - i1) * (i3 - i2) / (i1 * i3));
  std::printf("  growth rate %.6f 1/s, theory %.6f 1/s (relative difference %.1e)\n", growth,
              theory, growth / theory - 1.0);
  EXPECT_GT(worst, 0.5);
  EXPECT_TRUE(flipped);
  EXPECT_NEAR(growth / theory, 1.0, 1e-4);
}

}  // namespace
}  // namespace reposetwin::sim
