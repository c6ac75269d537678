// The neighbor list against the brute-force O(N^2) oracle, on random polydisperse packings
// (d_max / d_min = 8), and the forces it produces against a direct pair loop.
#include "sim/neighbor.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <map>
#include <set>

#include "sim/random.hpp"
#include "sim/world.hpp"
#include "sim_test_util.hpp"

namespace reposetwin::sim {
namespace {

Particles random_packing(int n, double r_min, double r_max, double box, std::uint64_t seed) {
  Particles p;
  Rng rng(seed);
  for (int i = 0; i < n; ++i) {
    // Radii spread in log-space over the whole range, many small, a few large.
    const double r = r_min * std::pow(r_max / r_min, rng.uniform() * rng.uniform());
    p.add(Vec3(rng.uniform(0, box), rng.uniform(0, box), rng.uniform(0, box)), r, 2760.0, 0, i);
  }
  return p;
}

std::set<std::pair<std::int64_t, std::int64_t>> id_pairs_of_list(const Particles& p,
                                                                 const NeighborList& nl) {
  std::set<std::pair<std::int64_t, std::int64_t>> s;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (std::int32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) {
      const std::int64_t a = p.id[i], b = p.id[nl.second[k]];
      EXPECT_TRUE(s.insert({std::min(a, b), std::max(a, b)}).second) << "pair listed twice";
    }
  return s;
}

class NeighborOracle : public ::testing::TestWithParam<bool> {};

TEST_P(NeighborOracle, PairsEqualBruteForce) {
  const bool sort = GetParam();
  for (std::uint64_t seed : {1, 2, 3}) {
    Particles p = random_packing(3000, 0.25e-3, 2e-3, 0.03, seed);
    NeighborList nl;
    nl.skin = 0.2e-3;
    build_neighbor_list(p, nl, sort);
    const auto got = id_pairs_of_list(p, nl);
    std::set<std::pair<std::int64_t, std::int64_t>> want;
    for (auto [i, j] : brute_force_pairs(p, nl.skin))
      want.insert({std::min(p.id[i], p.id[j]), std::max(p.id[i], p.id[j])});
    EXPECT_EQ(got, want) << "seed " << seed;
    EXPECT_GT(want.size(), 1000u);  // the packing is dense enough to test something
    // The incoming CSR lists every pair once, under its second particle.
    EXPECT_EQ(nl.in_pairs.size(), nl.second.size());
    for (std::size_t j = 0; j < p.size(); ++j)
      for (std::int32_t q = nl.in_start[j]; q < nl.in_start[j + 1]; ++q)
        EXPECT_EQ(nl.second[nl.in_pairs[q]], static_cast<std::int32_t>(j));
  }
}

INSTANTIATE_TEST_SUITE_P(Sorted, NeighborOracle, ::testing::Values(false, true));

// A broken state (a position NaN, infinite, or blown to 1e300 m by a runaway force) must not
// hang the build: it finishes, and the pairs among the finite particles are still all listed.
TEST(NeighborList, ANonFiniteOrFarPositionDoesNotHangTheBuild) {
  for (double bad :
       {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(), 1e300}) {
    Particles p = random_packing(500, 0.25e-3, 2e-3, 0.01, 4);
    NeighborList nl;
    nl.skin = 0.2e-3;
    build_neighbor_list(p, nl, /*sort_particles=*/false);
    const auto finite_pairs = id_pairs_of_list(p, nl);
    ASSERT_GT(finite_pairs.size(), 100u);
    const std::int64_t lost = p.id[17];
    p.x[17] = Vec3(bad, 0.005, 0.005);
    NeighborList broken;
    broken.skin = nl.skin;
    build_neighbor_list(p, broken, /*sort_particles=*/false);
    const auto got = id_pairs_of_list(p, broken);
    for (const auto& pair : finite_pairs) {
      if (pair.first != lost && pair.second != lost) {
        EXPECT_TRUE(got.count(pair)) << bad;
      }
    }
  }
}

// Springs survive a rebuild that reorders the particles: each pair keeps its springs, keyed by
// the stable ids of its particles (the oracle), negated when the pair is listed the other way
// round after the sort. Half the particles share one radius, so the index tie-break flips the
// order of many pairs; a pair with zero springs stays zero.
TEST(NeighborList, RebuildCarriesSpringsOverByParticle) {
  Particles p = random_packing(3000, 0.25e-3, 2e-3, 0.03, 7);
  for (std::size_t i = 0; i < p.size(); i += 2) p.radius[i] = 0.6e-3;
  NeighborList nl;
  nl.skin = 0.2e-3;
  build_neighbor_list(p, nl, /*sort_particles=*/false);  // random order
  Rng rng(11);
  std::map<std::pair<std::int64_t, std::int64_t>, ContactHistory> want;  // (first id, second id)
  for (std::size_t i = 0; i < p.size(); ++i)
    for (std::int32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) {
      ContactHistory h;
      if (rng.uniform() < 0.8) {
        h.tangential = Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)) * 1e-6;
        h.rolling = Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)) * 1e-7;
      }
      nl.history[k] = h;
      want[{p.id[i], p.id[nl.second[k]]}] = h;
    }
  build_neighbor_list(p, nl, /*sort_particles=*/true);
  std::size_t same = 0, flipped = 0;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (std::int32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) {
      const std::int64_t a = p.id[i], b = p.id[nl.second[k]];
      const ContactHistory& got = nl.history[k];
      if (auto it = want.find({a, b}); it != want.end()) {
        EXPECT_EQ(got.tangential, it->second.tangential);
        EXPECT_EQ(got.rolling, it->second.rolling);
        ++same;
      } else if (auto jt = want.find({b, a}); jt != want.end()) {
        EXPECT_EQ(got.tangential, (-jt->second.tangential).eval());
        EXPECT_EQ(got.rolling, (-jt->second.rolling).eval());
        ++flipped;
      } else {
        ADD_FAILURE() << "pair (" << a << ", " << b << ") was not listed before the rebuild";
      }
    }
  EXPECT_EQ(same + flipped, want.size());  // the particles did not move: the same pairs
  EXPECT_GT(flipped, 100u);                // the tie-break flipped some (216)
  EXPECT_GT(same, 500u);
}

TEST(NeighborForces, EqualADirectPairLoop) {
  // Random overlapping packing with random velocities: the world's forces (neighbor list,
  // per-pair results, gather) equal a direct O(N^2) loop over the contact kernel.
  PairParams pair;  // Hertz-Mindlin + EPSD defaults
  Model m = testing::make_model(pair, 46.8e6, Vec3::Zero());
  m.settings.time_step = 1e-7;
  m.finalize(0.25e-3, 2e-3);
  World w(m);
  Particles src = random_packing(1500, 0.25e-3, 2e-3, 0.02, 7);
  Rng rng(11);
  for (std::size_t i = 0; i < src.size(); ++i) {
    const std::size_t k = w.add_particle(src.x[i], src.radius[i], 0);
    w.state().particles.v[k] = Vec3(rng.normal(), rng.normal(), rng.normal()) * 0.1;
    w.state().particles.w[k] = Vec3(rng.normal(), rng.normal(), rng.normal()) * 10.0;
  }
  const Particles before = w.state().particles;
  w.refresh_forces();
  const Particles& p = w.state().particles;
  std::map<std::int64_t, std::size_t> index_of;
  for (std::size_t i = 0; i < p.size(); ++i) index_of[p.id[i]] = i;

  std::vector<Vec3> f(before.size(), Vec3::Zero()), t(before.size(), Vec3::Zero());
  const ContactConstants& c = w.model().table.c(0, 0);
  int touching = 0;
  for (std::size_t i = 0; i < before.size(); ++i) {
    for (std::size_t j = i + 1; j < before.size(); ++j) {
      const Vec3 d = before.x[i] - before.x[j];
      const double ri = before.radius[i], rj = before.radius[j];
      if (d.norm() >= ri + rj) continue;
      ++touching;
      ContactInput in;
      in.n = d.normalized();
      in.delta = ri + rj - d.norm();
      in.r_eff = ri * rj / (ri + rj);
      in.m_eff = before.mass[i] * before.mass[j] / (before.mass[i] + before.mass[j]);
      in.i_roll = 1.0 / (1.0 / (before.inertia[i] + before.mass[i] * ri * ri) +
                         1.0 / (before.inertia[j] + before.mass[j] * rj * rj));
      in.a_i = ri - 0.5 * in.delta;
      in.a_j = rj - 0.5 * in.delta;
      in.w_i = before.w[i];
      in.w_j = before.w[j];
      in.v_rel = before.v[i] - before.v[j] - in.a_i * before.w[i].cross(in.n) -
                 in.a_j * before.w[j].cross(in.n);
      ContactHistory h;
      const ContactOutput out = hertz_mindlin(c, in, m.dt, h);
      f[i] += out.force;
      f[j] -= out.force;
      t[i] += out.torque_i;
      t[j] += out.torque_j;
    }
  }
  ASSERT_GT(touching, 500);
  double fscale = 0, tscale = 0;
  for (std::size_t i = 0; i < f.size(); ++i) {
    fscale = std::max(fscale, f[i].norm());
    tscale = std::max(tscale, t[i].norm());
  }
  for (std::size_t i = 0; i < before.size(); ++i) {
    const std::size_t k = index_of.at(before.id[i]);
    EXPECT_LT((p.force[k] - f[i]).norm(), 1e-12 * fscale) << "particle id " << before.id[i];
    EXPECT_LT((p.torque[k] - t[i]).norm(), 1e-12 * tscale) << "particle id " << before.id[i];
  }
}

TEST(NeighborForces, PairsThatDoNotTouchCarryNoSpringOrReaction) {
  // A pour in which contacts open and close: after every step, each listed pair that does not
  // touch has zero springs and reactions and is not live (pair_live only skips clearing what is
  // already clear), and each touching pair is live with a reaction; the reactions sit in the
  // incoming slots.
  // 20 g: the spheres reach each other and the plate, collide and rebound within 2,000 steps.
  // Elastic contacts (e = 1): the normal force stays repulsive up to separation, so the caps do
  // not zero the springs in a contact's last step and only the clearing does.
  PairParams elastic;
  elastic.restitution = 1.0;
  World w = testing::funnel_pour(400, 2000, -20.0 * 9.81, elastic);
  int separated = 0, touching = 0;
  std::set<std::pair<std::int64_t, std::int64_t>> was_touching;  // by particle ids
  for (int s = 0; s < 2000; ++s) {
    w.step();
    const State& st = w.state();
    const Particles& p = st.particles;
    const NeighborList& nl = st.neighbors;
    ASSERT_EQ(nl.in_slot.size(), nl.pairs());
    std::set<std::pair<std::int64_t, std::int64_t>> now;
    for (std::size_t i = 0; i < p.size(); ++i) {
      for (std::int32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) {
        const std::int32_t j = nl.second[k];
        ASSERT_EQ(nl.in_pairs[nl.in_slot[k]], k);
        const bool touch = (p.x[i] - p.x[j]).norm() < p.radius[i] + p.radius[j];
        const std::pair<std::int64_t, std::int64_t> ids{p.id[i], p.id[j]};
        if (touch) {
          now.insert(ids);
          EXPECT_EQ(st.pair_live[k], 1);
          EXPECT_GT(st.reaction[nl.in_slot[k]].force.norm(), 0.0);
          ++touching;
        } else {
          EXPECT_EQ(nl.history[k].tangential, Vec3::Zero());
          EXPECT_EQ(nl.history[k].rolling, Vec3::Zero());
          EXPECT_EQ(st.reaction[nl.in_slot[k]].force, Vec3::Zero());
          EXPECT_EQ(st.reaction[nl.in_slot[k]].torque, Vec3::Zero());
          EXPECT_EQ(st.pair_live[k], 0);
          if (was_touching.count(ids) != 0) ++separated;
        }
      }
    }
    was_touching = now;
  }
  EXPECT_GT(touching, 10000);
  EXPECT_GT(separated, 0) << "no contact opened: the test did not exercise the clearing";
}

}  // namespace
}  // namespace reposetwin::sim
