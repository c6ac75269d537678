// The wall candidate list (World::build_wall_candidates) against the oracle: after every step,
// every particle that touches an enabled wall, found by testing all particles against all walls,
// must be listed as a candidate of that wall. Walls move fast here (a funnel lifted at 0.3 m/s,
// a plate sinking) so the half-skin wall criterion and the rebuilds are exercised, and a wall
// is disabled and enabled again mid-run.
#include <gtest/gtest.h>

#include <set>
#include <utility>

#include "sim/walls.hpp"
#include "sim/world.hpp"
#include "sim_test_util.hpp"

namespace reposetwin::sim {
namespace {

/// Touching (particle, wall) pairs found by brute force, and those the candidate list holds.
std::pair<std::set<std::pair<int, int>>, std::set<std::pair<int, int>>> touching_and_listed(
    const World& w) {
  const State& s = w.state();
  std::set<std::pair<int, int>> touching, listed;
  for (std::size_t i = 0; i < s.particles.size(); ++i) {
    for (std::size_t k = 0; k < w.model().walls.size(); ++k) {
      Vec3 n;
      double delta;
      if (s.walls[k].enabled && wall_contact(w.model().walls[k], s.walls[k].offset,
                                             s.particles.x[i], s.particles.radius[i], &n, &delta))
        touching.emplace(static_cast<int>(i), static_cast<int>(k));
    }
  }
  for (std::size_t c = 0; c < s.wall_cand_particle.size(); ++c)
    for (std::int32_t q = s.wall_cand_start[c]; q < s.wall_cand_start[c + 1]; ++q)
      listed.emplace(s.wall_cand_particle[c], s.wall_cand_wall[q]);
  return {touching, listed};
}

TEST(WallCandidates, EveryTouchingParticleIsListedWhileWallsMove) {
  // A fast collapse (100 m/s^2) into the funnel: many wall contacts soon.
  World w = testing::funnel_pour(300, 2000, -100.0);
  const int steps = 6000;
  std::size_t checked_contacts = 0;
  for (int s = 0; s < steps; ++s) {
    if (s == 1500) w.set_wall_velocity(1, Vec3(0.0, 0.0, 0.3));  // lift the funnel fast
    if (s == 3000) w.set_wall_enabled(1, false);
    if (s == 3500) w.set_wall_enabled(1, true);
    if (s == 4000) w.set_wall_velocity(0, Vec3(0.0, 0.0, -0.05));  // the plate sinks
    w.step();
    const auto [touching, listed] = touching_and_listed(w);
    for (const auto& c : touching) {
      ASSERT_TRUE(listed.count(c)) << "step " << s << ": particle " << c.first << " touches wall "
                                   << c.second << " but is not a candidate";
    }
    checked_contacts += touching.size();
  }
  EXPECT_GT(checked_contacts, 20000u);  // the check saw many wall contacts
  // The funnel moved by many half-skins, so the wall criterion forced rebuilds.
  EXPECT_GT(w.state().walls[1].offset.z(), 10.0 * w.state().neighbors.skin);
}


TEST(WallCandidates, AWallSweepingIntoRestingParticlesIsSeen) {
  // A single layer at rest on the plate: no particle moves, so only the walls' own half-skin
  // criterion can trigger the rebuild that lists the particles a sweeping wall reaches.
  PairParams pair;
  Model m = testing::make_model(pair);
  m.walls.push_back(testing::plate());
  WallSpec pusher;
  pusher.name = "pusher";
  pusher.kind = WallKind::kPlane;
  pusher.material = 1;
  pusher.point = Vec3(-0.012, 0.0, 0.0);
  pusher.normal = Vec3(1.0, 0.0, 0.0);
  m.walls.push_back(pusher);
  m.finalize(0.75e-3, 0.75e-3);
  World w(m);
  for (int ix = -5; ix <= 5; ++ix)
    for (int iy = -5; iy <= 5; ++iy)
      w.add_particle(Vec3(0.002 * ix, 0.002 * iy, 0.75e-3), 0.75e-3, 0);
  w.set_wall_velocity(1, Vec3(0.5, 0.0, 0.0));
  std::size_t checked_contacts = 0;
  for (int s = 0; s < 3000; ++s) {
    w.step();
    const auto [touching, listed] = touching_and_listed(w);
    for (const auto& c : touching) {
      ASSERT_TRUE(listed.count(c)) << "step " << s << ": particle " << c.first << " touches wall "
                                   << c.second << " but is not a candidate";
      checked_contacts += c.second == 1 ? 1 : 0;
    }
  }
  EXPECT_GT(checked_contacts, 1000u);  // the pusher reached the layer and pushed it
}

}  // namespace
}  // namespace reposetwin::sim
