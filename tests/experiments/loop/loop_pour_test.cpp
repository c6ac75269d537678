// The loop repeats a pour whose funnel jammed with a new seed, as a lab repeats it
// (run_repouring, experiments/loop_sim.hpp), against a stand-in for the simulation cache.
#include <gtest/gtest.h>

#include <set>
#include <vector>

#include "experiments/loop/loop_sim.hpp"

namespace reposetwin::experiments {
namespace {

// A stand-in cache: a pour forms a pile unless its seed is in `jams`; records every batch.
struct FakeCache {
  std::set<std::uint64_t> jams;
  std::vector<std::vector<std::uint64_t>> batches;
  std::vector<SimOutcome> operator()(const std::vector<SimRequest>& req) {
    batches.emplace_back();
    std::vector<SimOutcome> out;
    for (const SimRequest& r : req) {
      batches.back().push_back(r.seed);
      SimOutcome o;
      o.pile = jams.count(r.seed) == 0;
      o.seed = r.seed;
      o.angle_deg = o.pile ? 30.0 + static_cast<double>(r.seed % 7) : 0.0;
      out.push_back(o);
    }
    return out;
  }
};

std::vector<SimRequest> requests(const LabTest& t, std::vector<std::uint64_t> seeds) {
  std::vector<SimRequest> r;
  for (std::uint64_t s : seeds) r.push_back({&t, {}, s, ImageVariant{}});
  return r;
}

TEST(LoopPour, AJammedPourIsRepeatedWithTheNextSeedUntilAPileForms) {
  const LabTest t;
  FakeCache cache;
  const std::uint64_t k = kRepourSeedStride;
  cache.jams = {2, 2 + k, 3};
  auto run = [&cache](const std::vector<SimRequest>& r) { return cache(r); };
  const std::vector<SimOutcome> out = run_repouring(requests(t, {1, 2, 3}), 3, run);
  ASSERT_EQ(out.size(), 3u);
  // In request order; each outcome names the pour that made its pile.
  EXPECT_TRUE(out[0].pile);
  EXPECT_EQ(out[0].seed, 1u);
  EXPECT_EQ(out[0].clogged_pours, 0);
  EXPECT_TRUE(out[1].pile);
  EXPECT_EQ(out[1].seed, 2 + 2 * k);
  EXPECT_EQ(out[1].clogged_pours, 2);
  EXPECT_TRUE(out[2].pile);
  EXPECT_EQ(out[2].seed, 3 + k);
  EXPECT_EQ(out[2].clogged_pours, 1);
  // Only the jammed pours were repeated, and nothing after every pile had formed.
  ASSERT_EQ(cache.batches.size(), 3u);
  EXPECT_EQ(cache.batches[1], (std::vector<std::uint64_t>{2 + k, 3 + k}));
  EXPECT_EQ(cache.batches[2], (std::vector<std::uint64_t>{2 + 2 * k}));
}

TEST(LoopPour, APourStillJammedAfterTheLastRepeatIsReturnedWithoutAPile) {
  const LabTest t;
  FakeCache cache;
  cache.jams = {5, 5 + kRepourSeedStride};
  auto run = [&cache](const std::vector<SimRequest>& r) { return cache(r); };
  const std::vector<SimOutcome> out = run_repouring(requests(t, {4, 5}), 2, run);
  EXPECT_TRUE(out[0].pile);
  EXPECT_FALSE(out[1].pile);
  EXPECT_EQ(out[1].seed, 5 + kRepourSeedStride);
  EXPECT_EQ(out[1].clogged_pours, 1);
  // One pour in all: nothing is repeated.
  cache.batches.clear();
  const std::vector<SimOutcome> once = run_repouring(requests(t, {5}), 1, run);
  EXPECT_FALSE(once[0].pile);
  EXPECT_EQ(once[0].clogged_pours, 0);
  EXPECT_EQ(cache.batches.size(), 1u);
  EXPECT_THROW(run_repouring(requests(t, {5}), 0, run), std::invalid_argument);
}

// The tests that jammed before are poured first and alone, so that a refit trial their outlet
// ends fails before the other tests' (often costlier) piles are run; otherwise one group in order.
TEST(LoopPour, TestsThatJammedBeforeArePouredFirst) {
  using Groups = std::vector<std::vector<std::size_t>>;
  EXPECT_EQ(pour_groups({0, 0, 0, 2}), (Groups{{3}, {0, 1, 2}}));
  EXPECT_EQ(pour_groups({1, 0, 3, 0}), (Groups{{0, 2}, {1, 3}}));
  EXPECT_EQ(pour_groups({0, 0, 0}), (Groups{{0, 1, 2}}));
  EXPECT_EQ(pour_groups({1, 2}), (Groups{{0, 1}}));
}

}  // namespace
}  // namespace reposetwin::experiments
