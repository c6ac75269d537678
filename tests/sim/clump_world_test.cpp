// Clumps in the world: a one-sphere clump is the sphere (bit for bit), a free asymmetric body
// keeps its energy and angular momentum through the whole step, head-on impact rebounds at the
// declared restitution, a flat clump dropped on the plate comes to rest where it lands, the
// neighbor pairs and forces with clumps equal brute-force loops, runs with clumps are
// deterministic across thread counts and resume bit-identically, and removal takes whole clumps.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <set>

#include "sim/checkpoint.hpp"
#include "sim/random.hpp"
#include "sim/world.hpp"
#include "sim_test_util.hpp"

namespace reposetwin::sim {
namespace {

/// A tetrahedral clump of four spheres of radius r, centres at distance a from its centre.
ClumpShape tetrahedron(double r, double a) {
  const double k = a / std::sqrt(3.0);
  return {"tetra", {k * Vec3(1, 1, 1), k * Vec3(1, -1, -1), k * Vec3(-1, 1, -1),
                    k * Vec3(-1, -1, 1)},
          {r, r, r, r}};
}

/// A random rotation (uniform over the sphere of unit quaternions).
Quat random_rotation(Rng& rng) {
  Quat q(rng.normal(0, 1), rng.normal(0, 1), rng.normal(0, 1), rng.normal(0, 1));
  return q.normalized();
}

/// The funnel pour of sim_test_util.hpp with every second grain a clump: tetrahedra of four
/// spheres of 0.45 mm (reach 0.85 mm) in random orientations, the others spheres of 0.5-1 mm.
World clump_pour(int n, int parallel_min, double gravity_z = -20.0 * 9.81) {
  Model m = testing::make_model(PairParams{}, 46.8e6, Vec3(0, 0, gravity_z));
  m.walls.push_back(testing::plate());
  m.walls.push_back(testing::pour_funnel());
  m.settings.parallel_min_particles = parallel_min;
  m.add_clump_template(tetrahedron(0.45e-3, 0.4e-3));
  m.finalize(0.45e-3, 1e-3);
  World w(m);
  Rng rng(7);
  testing::for_each_funnel_site(n, [&](const Vec3& x, int k) {
    if (k % 2 == 0)
      w.add_clump(0, x, random_rotation(rng), 0);
    else
      w.add_particle(x, rng.uniform(0.5e-3, 1e-3), 0);
  });
  return w;
}

TEST(ClumpWorld, OneSphereClumpsGiveTheSpheresBits) {
  // The pinned pour of world_test (400 spheres at 20 g), once with spheres and once with each
  // sphere a one-sphere clump of its radius: every particle's position, velocity and angular
  // velocity agree bit for bit after 3000 steps (sliding, rolling and wall contacts included).
  omp_set_num_threads(1);
  World spheres = testing::funnel_pour(400, 0, -20.0 * 9.81);
  Model m = spheres.model();
  const Particles& p0 = spheres.state().particles;
  for (std::size_t i = 0; i < p0.size(); ++i)
    m.add_clump_template({"one", {Vec3::Zero()}, {p0.radius[i]}});
  World clumps(m);
  for (std::size_t i = 0; i < p0.size(); ++i)
    clumps.add_clump(static_cast<int>(i), p0.x[i], Quat::Identity(), p0.material[i]);
  for (int s = 0; s < 3000; ++s) {
    spheres.step();
    clumps.step();
  }
  const Particles& a = spheres.state().particles;
  const Particles& b = clumps.state().particles;
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(spheres.diagnose().contacts, 300u);
  std::size_t differ = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.id[i], b.id[i]);
    differ += (a.x[i] != b.x[i]) || (a.v[i] != b.v[i]) || (a.w[i] != b.w[i]);
  }
  EXPECT_EQ(differ, 0u);
  // (the bodies' energy, 1/2 w.L, rounds differently from the spheres' 1/2 I w^2)
  EXPECT_NEAR(clumps.diagnose().kinetic_energy / spheres.diagnose().kinetic_energy, 1.0, 1e-12);
}

TEST(ClumpWorld, FreeAsymmetricBodyKeepsEnergyAndAngularMomentum) {
  // No gravity, no walls: a three-sphere clump (I1 < I2 < I3) spinning at about 40 rad/s
  // (w dt about 3e-4) for 1e5 steps of the whole engine step.
  Model m = testing::make_model(PairParams{}, 46.8e6, Vec3::Zero());
  const int t = m.add_clump_template(
      {"triangle", {Vec3(0, 0, 0), Vec3(1.75e-3, 0, 0), Vec3(0.85e-3, 1.4e-3, 0.3e-3)},
       {1e-3, 0.9e-3, 0.8e-3}});
  m.finalize(0.8e-3, 1e-3);
  World w(m);
  w.add_clump(t, Vec3(0, 0, 0), Quat(Eigen::AngleAxisd(0.3, Vec3(1, 0, 1).normalized())), 0);
  w.set_body_velocity(0, Vec3(0.01, 0, 0), Vec3(20.0, -30.0, 15.0));
  const Bodies& b = w.state().bodies;
  const Vec3 inertia = b.inertia[0];
  ASSERT_LT(inertia[0], inertia[1]);
  ASSERT_LT(inertia[1], inertia[2]);
  const double e0 = w.diagnose().kinetic_energy;
  const Vec3 l0 = b.l[0];
  std::printf("  w dt = %.2e\n", b.w[0].norm() * m.dt);
  double worst_e = 0.0, worst_l = 0.0;
  for (int s = 0; s < 100000; ++s) {
    w.step();
    if (s % 100 != 0) continue;
    worst_e = std::max(worst_e, std::abs(w.diagnose().kinetic_energy - e0) / e0);
    // angular momentum from the body's angular velocity and inertia at its orientation
    const Mat3 r = b.q[0].toRotationMatrix();
    const Vec3 l = r * inertia.cwiseProduct(r.transpose() * b.w[0]);
    worst_l = std::max(worst_l, (l - l0).norm() / l0.norm());
  }
  std::printf("  largest relative drift: energy %.2e, angular momentum %.2e\n", worst_e, worst_l);
  EXPECT_LT(worst_e, 1e-6);
  EXPECT_LT(worst_l, 1e-6);
  // The components move with the body: each at x + R b, at v + w x r.
  const Particles& p = w.state().particles;
  const Mat3 r = b.q[0].toRotationMatrix();
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Vec3 arm = r * w.model().clumps[0].offsets[p.component[i]];
    EXPECT_LT((p.x[i] - b.x[0] - arm).norm(), 1e-15);
    EXPECT_LT((p.v[i] - b.v[0] - b.w[0].cross(arm)).norm(), 1e-12);
    EXPECT_EQ(p.w[i], b.w[0]);
  }
  EXPECT_NEAR(b.x[0].x(), 0.01 * w.state().time, 1e-12);
}

/// Head-on impact of two dumbbells moving along their common axis at +-v; returns the ratio of
/// the relative speeds after and before.
double dumbbell_rebound(double restitution, double v) {
  Model m = testing::make_model(testing::frictionless(restitution), 46.8e6, Vec3::Zero());
  const int t = m.add_clump_template({"dumbbell", {Vec3(-0.6e-3, 0, 0), Vec3(0.6e-3, 0, 0)},
                                      {1e-3, 1e-3}});
  // A thousand steps per Hertz contact time of the end spheres (R* = r/2) between the bodies
  // (m* = M/2), as the sphere engine's restitution test (contact_test.cpp).
  const double mass = m.materials[0].density * m.clumps[t].volume;
  const double e_star = 1.0 / (2.0 * (1 - 0.19 * 0.19) / 46.8e6);
  m.settings.time_step = hertz_contact_time(0.5 * mass, 0.5e-3, e_star, 2 * v) / 1000.0;
  m.finalize(1e-3, 1e-3);
  World w(m);
  // The long axis (least inertia) is the body's x axis; identity puts it along the world's x.
  w.add_clump(t, Vec3(0, 0, 0), Quat::Identity(), 0);
  w.add_clump(t, Vec3(2 * 1.6e-3 + 0.02e-3, 0, 0), Quat::Identity(), 0);
  w.set_body_velocity(0, Vec3(v, 0, 0), Vec3::Zero());
  w.set_body_velocity(1, Vec3(-v, 0, 0), Vec3::Zero());
  const Bodies& b = w.state().bodies;
  bool touched = false;
  for (int s = 0; s < 100000; ++s) {
    w.step();
    const double gap = std::abs(b.x[1].x() - b.x[0].x()) - 2 * 1.6e-3;
    if (gap < 0) touched = true;
    if (touched && gap > 0) break;
  }
  EXPECT_TRUE(touched);
  EXPECT_LT(b.w[0].norm() + b.w[1].norm(), 1e-9);  // no torque along the axis
  return (b.v[1].x() - b.v[0].x()) / (2 * v);
}

TEST(ClumpWorld, HeadOnImpactReboundsAtTheDeclaredRestitution) {
  // The contact's damping uses the bodies' masses (Particles: a component's `mass`), which is
  // what makes the rebound ratio the declared e for bodies of two spheres each.
  for (double e : {0.3, 0.79}) {
    const double ratio = dumbbell_rebound(e, 0.2);
    std::printf("  e %.2f: rebound ratio %.5f\n", e, ratio);
    EXPECT_NEAR(ratio, e, 0.01 * e);
  }
}

// The step a clump takes by default: a fraction of the Rayleigh time of the sphere of its own
// volume, not of its smallest sphere (sim::Model::finalize's r_step). Tetrahedra of four 1 mm
// spheres (the sphere of their volume: 1.54 mm) collide at 2 m/s, off-centre, in random
// orientations, elastic and frictionless. Two oracles: the Hertz contact time of the colliding
// spheres (m* = M/2, R* = r/2) spans at least as many steps as a sphere's of the same radius
// spans at the default step (a clump's contact moves its whole mass: 13.6 steps against the
// sphere's 12.5); and the kinetic energy, translational and rotational, is the same after the
// collision as before (a step too long for the contact makes it grow).
TEST(ClumpWorld, TheGrainsStepResolvesAClumpCollision) {
  const double r = 1e-3, a = 1.0e-3, v = 1.0;
  for (int trial = 0; trial < 8; ++trial) {
    Model m = testing::make_model(testing::frictionless(1.0), 46.8e6, Vec3::Zero());
    const int t = m.add_clump_template(tetrahedron(r, a));
    const double r_eq = std::cbrt(3.0 * m.clumps[t].volume / (4.0 * std::numbers::pi));
    m.finalize(r, r, r_eq);
    const double rho = m.materials[0].density, e_star = m.table.c(0, 0).e_star;
    const double mass = rho * m.clumps[t].volume;
    const double sphere_mass = rho * 4.0 / 3.0 * std::numbers::pi * r * r * r;
    const double steps = hertz_contact_time(0.5 * mass, 0.5 * r, e_star, 2 * v) / m.dt;
    const double sphere_steps = hertz_contact_time(0.5 * sphere_mass, 0.5 * r, e_star, 2 * v) /
                                (0.2 * m.rayleigh_time);
    EXPECT_GT(r_eq, 1.4 * r);
    EXPECT_NEAR(m.dt, 0.2 * m.rayleigh_time * r_eq / r, 1e-12 * m.dt);
    EXPECT_GE(steps, sphere_steps);
    World w(m);
    Rng rng(100 + trial);
    w.add_clump(t, Vec3(0, 0, 0), random_rotation(rng), 0);
    w.add_clump(t, Vec3(4.2e-3, 0.6e-3 * rng.uniform(-1, 1), 0.6e-3 * rng.uniform(-1, 1)),
                random_rotation(rng), 0);
    w.set_body_velocity(0, Vec3(v, 0, 0), Vec3::Zero());
    w.set_body_velocity(1, Vec3(-v, 0, 0), Vec3::Zero());
    const double before = w.diagnose().kinetic_energy;
    for (int s = 0; s < 20000; ++s) w.step();
    const double after = w.diagnose().kinetic_energy;
    EXPECT_LT(w.state().bodies.v[0].x(), 0.9 * v) << "they met";
    EXPECT_NEAR(after, before, 5e-3 * before) << "trial " << trial;
    std::printf("  trial %d: dt %.3e s (%.2f of the spheres' Rayleigh time), %.1f steps per "
                "contact (a sphere's at 0.2: %.1f), energy %+.3f%%\n",
                trial, m.dt, m.dt / m.rayleigh_time, steps, sphere_steps,
                100.0 * (after - before) / before);
  }
}

TEST(ClumpWorld, FlatClumpDroppedOnThePlateComesToRestWithoutDrift) {
  // Four spheres in a square (the plane of the square is normal to the axis of largest inertia,
  // the body's z), dropped from 1.5 mm onto the plate, tilted by 3 degrees and turning slowly,
  // with friction and rolling resistance: it lands on one sphere, rocks onto all four, and stays
  // flat and still where it settled.
  Model m = testing::make_model(PairParams{});
  m.walls.push_back(testing::plate());
  const double r = 1e-3, a = 0.8e-3;
  const int t = m.add_clump_template(
      {"square", {Vec3(a, a, 0), Vec3(a, -a, 0), Vec3(-a, a, 0), Vec3(-a, -a, 0)},
       {r, r, r, r}});
  m.finalize(r, r);
  World w(m);
  const Quat flat = m.clumps[t].axes.conjugate();  // body axes back to the square's frame
  const Quat tilt(Eigen::AngleAxisd(3.0 * std::numbers::pi / 180.0, Vec3(1, 0.4, 0).normalized()));
  w.add_clump(t, Vec3(1e-3, 2e-3, r + 1.5e-3), tilt * flat, 0);
  w.set_body_velocity(0, Vec3(0.002, 0, 0), Vec3(0, 0, 1.0));
  const Vec3 x0 = w.state().bodies.x[0];
  const double settle = 0.15, watch = 0.1;
  for (double time = 0; time < settle; time += m.dt) w.step();
  const Bodies& b = w.state().bodies;
  const Vec3 x1 = b.x[0];
  for (double time = 0; time < watch; time += m.dt) w.step();
  const Vec3 x2 = b.x[0];
  const Vec3 normal = b.q[0] * Vec3::UnitZ();
  std::printf("  landed %.3e m from where it fell, then moved %.3e m in %.2f s; KE %.2e J\n",
              (x1 - x0).head<2>().norm(), (x2 - x1).norm(), watch, w.diagnose().kinetic_energy);
  EXPECT_GT((x1 - x0).head<2>().norm(), 1e-7);  // it did move on landing
  EXPECT_LT((x1 - x0).head<2>().norm(), 3e-3);  // (it rocks and bounces: e = 0.79)
  EXPECT_LT((x2 - x1).norm(), 1e-9);            // and then stays
  EXPECT_GT(std::abs(normal.z()), 1.0 - 1e-9);  // flat
  EXPECT_LT(b.v[0].norm(), 1e-6);
  EXPECT_LT(b.w[0].norm(), 1e-3);
  // Resting on its four spheres: the weight shared by four Hertz contacts of overlap delta,
  // M g / 4 = 4/3 E* sqrt(r) delta^1.5.
  const double e_star = m.table.c(0, 1).e_star;
  const double delta = std::pow(b.mass[0] * 9.81 / 4 / (4.0 / 3.0 * e_star * std::sqrt(r)),
                                2.0 / 3.0);
  EXPECT_NEAR(x2.z(), r - delta, 0.01 * delta);
}

TEST(ClumpWorld, NeighborPairsAndForcesEqualBruteForce) {
  // 40 tetrahedra and 20 spheres scattered in a small box above the plate, many touching, with
  // random velocities and spins; after one force phase (every contact new: springs from zero)
  // the listed pairs equal the all-pairs oracle (no pair of one body), and each body's force and
  // torque equal the sum over a brute-force loop of the scalar kernel.
  Model m = testing::make_model(PairParams{});
  m.walls.push_back(testing::plate());
  m.settings.parallel_min_particles = 0;
  const int t = m.add_clump_template(tetrahedron(0.45e-3, 0.4e-3));
  m.finalize(0.45e-3, 0.7e-3);
  World w(m);
  Rng rng(3);
  for (int k = 0; k < 60; ++k) {
    const Vec3 x(rng.uniform(0, 5e-3), rng.uniform(0, 5e-3), rng.uniform(0.3e-3, 4e-3));
    if (k % 3 == 2) {
      w.add_particle(x, rng.uniform(0.45e-3, 0.7e-3), 0);
      w.state().particles.v.back() = Vec3(rng.normal(0, 0.05), rng.normal(0, 0.05), 0);
    } else {
      const std::size_t b = w.add_clump(t, x, random_rotation(rng), 0);
      w.set_body_velocity(b, Vec3(rng.normal(0, 0.05), rng.normal(0, 0.05), rng.normal(0, 0.05)),
                          Vec3(rng.normal(0, 50), rng.normal(0, 50), rng.normal(0, 50)));
    }
  }
  w.refresh_forces();
  const Particles& p = w.state().particles;
  const NeighborList& nl = w.state().neighbors;
  std::set<std::pair<int, int>> listed;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (std::int32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) {
      const int j = nl.second[k];
      listed.insert({std::min<int>(i, j), std::max<int>(i, j)});
      EXPECT_FALSE(p.body[i] >= 0 && p.body[i] == p.body[j]) << "a pair of one clump";
    }
  const auto oracle = brute_force_pairs(p, nl.skin);
  const std::set<std::pair<int, int>> want(oracle.begin(), oracle.end());
  EXPECT_EQ(listed, want);
  // Brute force: every touching pair of the oracle, the scalar kernel with zero springs.
  std::vector<Vec3> f(p.size()), tq(p.size(), Vec3::Zero());
  for (std::size_t i = 0; i < p.size(); ++i) f[i] = p.mass[i] * m.settings.gravity;
  std::size_t touching = 0, same_body_touching = 0;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (std::size_t j = i + 1; j < p.size(); ++j) {
      const double cut = p.radius[i] + p.radius[j];
      if (!((p.x[i] - p.x[j]).squaredNorm() < cut * cut)) continue;
      if (p.body[i] >= 0 && p.body[i] == p.body[j]) {
        ++same_body_touching;
        continue;
      }
      ++touching;
      const ContactConstants& c = m.table.c(0, 0);
      ContactHistory h;
      const ContactOutput o = hertz_mindlin(c, pair_input(p, c, i, j), m.dt, h);
      f[i] += o.force;
      f[j] -= o.force;
      tq[i] += o.torque_i;
      tq[j] += o.torque_j;
    }
  WallContacts wc;
  for (std::size_t i = 0; i < p.size(); ++i) {
    Vec3 n;
    double delta;
    if (wall_contact(m.walls[0], Vec3::Zero(), p.x[i], p.radius[i], &n, &delta))
      wc.add(static_cast<std::int32_t>(i), 0, n, delta, Vec3::Zero(), &m.table.c(0, 1));
  }
  for (std::size_t e = 0; e < wc.size(); ++e) {
    ContactHistory h;
    const ContactOutput o = hertz_mindlin(m.table.c(0, 1), wall_input(p, wc, e), m.dt, h);
    f[wc.particle[e]] += o.force;
    tq[wc.particle[e]] += o.torque_i;
  }
  EXPECT_GT(touching, 20u);
  EXPECT_GT(same_body_touching, 100u);
  EXPECT_GT(wc.size(), 3u);
  const Bodies& b = w.state().bodies;
  double scale = 0.0;
  for (const Vec3& v : f) scale = std::max(scale, v.norm());
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.body[i] >= 0) continue;
    EXPECT_LT((p.force[i] - f[i]).norm(), 1e-12 * scale) << "sphere " << i;
  }
  for (std::size_t k = 0; k < b.size(); ++k) {
    Vec3 fb = b.mass[k] * m.settings.gravity, tb = Vec3::Zero();
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (p.body[i] != static_cast<std::int32_t>(k)) continue;
      const Vec3 contact = f[i] - p.mass[i] * m.settings.gravity;
      fb += contact;
      tb += tq[i] + (p.x[i] - b.x[k]).cross(contact);
    }
    EXPECT_LT((b.force[k] - fb).norm(), 1e-12 * scale) << "body " << k;
    EXPECT_LT((b.torque[k] - tb).norm(), 1e-12 * scale * 1e-3) << "body " << k;
  }
}

TEST(ClumpWorld, DeterministicOnAnyThreadCountAndResumesBitIdentically) {
  auto run = [](int threads, int steps) {
    omp_set_num_threads(threads);
    World w = clump_pour(300, 0);
    for (int s = 0; s < steps; ++s) w.step();
    return w;
  };
  World one = run(1, 3000);
  const std::uint64_t h1 = state_hash(one.state());
  EXPECT_EQ(h1, state_hash(run(2, 3000).state()));
  EXPECT_GT(one.diagnose().contacts, 200u);
  EXPECT_EQ(one.diagnose().status, Status::kOk) << one.diagnose().detail;
  // Resume: a checkpoint after 1500 steps, 1500 more in a fresh world.
  omp_set_num_threads(1);
  World a = clump_pour(300, 0);
  for (int s = 0; s < 1500; ++s) a.step();
  const std::string path =
      (std::filesystem::temp_directory_path() / "reposetwin_clump_ckpt_test.bin").string();
  write_checkpoint(a, path);
  World b = clump_pour(0, 0);
  read_checkpoint(b, path);
  EXPECT_EQ(state_hash(a.state()), state_hash(b.state()));
  for (int s = 0; s < 1500; ++s) {
    a.step();
    b.step();
  }
  EXPECT_EQ(state_hash(b.state()), h1);
  EXPECT_EQ(state_hash(a.state()), h1);
  std::filesystem::remove(path);
}

TEST(ClumpWorld, RemovingAComponentRemovesItsWholeClump) {
  omp_set_num_threads(1);
  World w = clump_pour(100, 2000);
  for (int s = 0; s < 500; ++s) w.step();
  Particles& p = w.state().particles;
  const std::size_t n0 = p.size(), nb0 = w.state().bodies.size();
  std::vector<char> drop(n0, 0);
  std::int64_t gone_body = -1;
  for (std::size_t i = 0; i < n0; ++i)
    if (p.body[i] >= 0) {
      drop[i] = 1;  // one component of the first clump found
      gone_body = w.state().bodies.id[p.body[i]];
      break;
    }
  for (std::size_t i = 0; i < n0; ++i)
    if (p.body[i] < 0) {
      drop[i] = 1;  // and one sphere
      break;
    }
  EXPECT_EQ(w.remove_particles(drop), 5u);
  EXPECT_EQ(p.size(), n0 - 5);
  EXPECT_EQ(w.state().bodies.size(), nb0 - 1);
  for (std::int64_t id : w.state().bodies.id) EXPECT_NE(id, gone_body);
  for (int s = 0; s < 500; ++s) w.step();
  EXPECT_EQ(w.diagnose().status, Status::kOk);
  const BodyComponents& bc = w.state().body_components;
  for (std::size_t k = 0; k < w.state().bodies.size(); ++k)
    EXPECT_EQ(bc.start[k + 1] - bc.start[k], 4);
}

}  // namespace
}  // namespace reposetwin::sim

namespace reposetwin::sim {
namespace {

/// A dumbbell of two spheres of radius r with centres 2a apart, lying with its axis along the
/// downhill direction of an incline of angle theta (gravity tilted, as contact_test.cpp's
/// incline), both spheres on the plate at their static overlap. Friction mu_s, no rolling law
/// (the dumbbell cannot roll along its axis without lifting a sphere).
struct Incline {
  World world;
  double mass;
};
Incline dumbbell_on_incline(double theta, double mu_s, double r, double a) {
  const double g = 9.81;
  PairParams pair;
  pair.restitution = 0.5;
  pair.friction = mu_s;
  pair.rolling_model = RollingModel::kNone;
  Model m = testing::make_model(pair, 46.8e6, Vec3(g * std::sin(theta), 0, -g * std::cos(theta)));
  m.walls.push_back(testing::plate());
  const int t = m.add_clump_template({"dumbbell", {Vec3(-a, 0, 0), Vec3(a, 0, 0)}, {r, r}});
  m.finalize(r, r);
  const double mass = m.materials[0].density * m.clumps[t].volume;
  const double e_star = 1.0 / (2.0 * (1 - 0.19 * 0.19) / 46.8e6);
  const double fn = 0.5 * mass * g * std::cos(theta);
  const double delta = std::pow(3.0 * fn / (4.0 * e_star * std::sqrt(r)), 2.0 / 3.0);
  World w(m);
  w.add_clump(t, Vec3(0, 0, r - delta), m.clumps[t].axes.conjugate(), 0);
  return {std::move(w), mass};
}

TEST(ClumpIncline, DumbbellStaysSlidesOrTipsAsFrictionAndGeometryPredict) {
  // Along its axis the dumbbell slides once tan(theta) > mu_s, at a = g (sin theta - mu_s cos
  // theta), and tips over its lower sphere once the vertical through its centre of mass leaves
  // the lower contact, tan(theta) > a / r (centre of mass r above the plate, a uphill of it).
  const double r = 1e-3, pi = std::numbers::pi;
  // Long (a/r = 0.9, tipping at 42 deg) and mu_s = 0.466 (sliding at 25 deg).
  for (double deg : {22.0, 28.0}) {
    const double theta = deg * pi / 180.0;
    Incline in = dumbbell_on_incline(theta, 0.466, r, 0.9 * r);
    World& w = in.world;
    const Bodies& b = w.state().bodies;
    while (w.state().time < 0.02) w.step();
    const double x1 = b.x[0].x(), v1 = b.v[0].x(), t1 = w.state().time;
    while (w.state().time < 0.07) w.step();
    const double accel = (b.v[0].x() - v1) / (w.state().time - t1);
    const double tilt = std::abs((b.q[0] * Vec3::UnitX()).z());  // the axis' rise
    const double expect = 9.81 * (std::sin(theta) - 0.466 * std::cos(theta));
    std::printf("  a/r 0.9, mu_s 0.466, %.0f deg: moved %.3e m, acceleration %.4f m/s^2 "
                "(expected %.4f if sliding), axis rise %.1e\n",
                deg, b.x[0].x() - x1, accel, expect, tilt);
    if (deg < 25.0) {
      EXPECT_LT(std::abs(b.x[0].x() - x1), 1e-7) << deg;
    } else {
      EXPECT_NEAR(accel / expect, 1.0, 0.02) << deg;
    }
    EXPECT_LT(tilt, 1e-3) << deg;  // both spheres stay down
  }
  // Short (a/r = 0.5, tipping at 26.6 deg) on a rough plate (mu_s 1, sliding at 45 deg).
  for (double deg : {24.0, 29.0}) {
    const double theta = deg * pi / 180.0;
    Incline in = dumbbell_on_incline(theta, 1.0, r, 0.5 * r);
    World& w = in.world;
    const Bodies& b = w.state().bodies;
    double tilt = 0.0;  // the largest angle of the axis to the plate (tipped: it turns over)
    while (w.state().time < 0.1) {
      w.step();
      tilt = std::max(tilt, std::asin(std::min(1.0, std::abs((b.q[0] * Vec3::UnitX()).z()))));
    }
    std::printf("  a/r 0.5, mu_s 1, %.0f deg: axis rose to %.2e rad\n", deg, tilt);
    if (deg < 26.6) {
      EXPECT_LT(tilt, 5e-3) << deg;  // (the loads of the two contacts differ: elastic tilt)
    } else {
      EXPECT_GT(tilt, 0.5) << deg;  // tipped over
    }
  }
}

}  // namespace
}  // namespace reposetwin::sim
