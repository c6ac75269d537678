// How the baseline's mu_r grid grows while mu_r alone sits on its bound (next_grid_point): by the
// last step's spacing as --at-bound extend allows, clipped at 0, mu_max and a declared range;
// and, with a declared range, to the range's end whatever --at-bound says, so that the loop
// sees mu_r alone needing more than the range (and traces the candidates) instead of stopping
// inside it or calling a grid point the answer.
#include <gtest/gtest.h>

#include "experiments/loop/loop.hpp"
#include "experiments/loop/loop_stages.hpp"

namespace reposetwin::experiments {
namespace {

using loop_detail::next_grid_point;

const std::vector<double> kGrid = {0.1, 0.2, 0.35};

LoopSettings settings(GridBound policy, int extensions = 2) {
  LoopSettings s;
  s.at_bound = policy;
  s.grid_extensions = extensions;
  return s;
}

TEST(LoopGrid, ExtendAddsTheLastSpacingAsOftenAsAllowed) {
  const LoopSettings s = settings(GridBound::kExtend, 2);
  const auto first = next_grid_point(kGrid, false, 0, s);
  ASSERT_TRUE(first.next);
  EXPECT_DOUBLE_EQ(*first.next, 0.5);  // 0.35 + (0.35 - 0.2)
  const auto low = next_grid_point(kGrid, true, 1, s);
  ASSERT_TRUE(low.next);
  EXPECT_DOUBLE_EQ(*low.next, 0.0);  // 0.1 - 0.1
  const auto spent = next_grid_point(kGrid, false, 2, s);
  EXPECT_FALSE(spent.next);
  EXPECT_EQ(spent.stop, "");  // the settings stop it, not a bound
}

TEST(LoopGrid, ZeroAndMuMaxBoundTheGrowth) {
  LoopSettings s = settings(GridBound::kExtend, 5);
  s.mu_max = 0.45;
  EXPECT_DOUBLE_EQ(*next_grid_point(kGrid, false, 0, s).next, 0.45);
  const auto at_max = next_grid_point({0.1, 0.2, 0.45}, false, 1, s);
  EXPECT_FALSE(at_max.next);
  EXPECT_EQ(at_max.stop, "mu_max 0.45 reached");
  const auto at_zero = next_grid_point({0.0, 0.1}, true, 0, s);
  EXPECT_FALSE(at_zero.next);
  EXPECT_EQ(at_zero.stop, "mu_r cannot go below 0");
}

TEST(LoopGrid, TraceAndRefuseAddNothingWithoutADeclaredRange) {
  for (GridBound policy : {GridBound::kTrace, GridBound::kRefuse}) {
    const auto g = next_grid_point(kGrid, false, 0, settings(policy));
    EXPECT_FALSE(g.next);
    EXPECT_EQ(g.stop, "");
  }
}

TEST(LoopGrid, ADeclaredRangeIsReachedWhateverAtBoundSays) {
  for (GridBound policy : {GridBound::kTrace, GridBound::kRefuse, GridBound::kExtend}) {
    LoopSettings s = settings(policy, 0);
    s.mu_prior = {0.02, 0.4, "rock in our convention"};
    const auto high = next_grid_point(kGrid, false, 0, s);
    ASSERT_TRUE(high.next);
    EXPECT_DOUBLE_EQ(*high.next, 0.4);
    const auto low = next_grid_point(kGrid, true, 0, s);
    ASSERT_TRUE(low.next);
    EXPECT_DOUBLE_EQ(*low.next, 0.02);
    const auto reached = next_grid_point({0.1, 0.2, 0.4}, false, 1, s);
    EXPECT_FALSE(reached.next);
    EXPECT_EQ(reached.stop, "the declared range's end");
  }
}

TEST(LoopGrid, ExtensionsInsideADeclaredRangeStopAtItsEnd) {
  LoopSettings s = settings(GridBound::kExtend, 2);
  s.mu_prior = {0.02, 0.45, "rock in our convention"};
  EXPECT_DOUBLE_EQ(*next_grid_point(kGrid, false, 0, s).next, 0.45);  // 0.5 clipped
  // Extensions spent short of the range: its end comes next.
  EXPECT_DOUBLE_EQ(*next_grid_point({0.1, 0.15, 0.2}, false, 2, s).next, 0.45);
}

}  // namespace
}  // namespace reposetwin::experiments
