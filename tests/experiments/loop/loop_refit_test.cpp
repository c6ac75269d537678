// Where the refit simulates after its first trials (follow_up_value): where the best trial's
// joint fit lands, off + t (p - off), until t is within the tolerance of 1, so that the value
// reported is a simulated one and not a chord's extrapolation. The responses here are closed
// forms, r_i(p) = g_i (p - off)^a_i per test, with the chord fit t = sum y r / sum r^2 that the
// loop's joint fit reduces to for one surface and a fixed mu_r.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "experiments/loop/loop_stages.hpp"

namespace reposetwin::experiments {
namespace {

using loop_detail::best_trial;
using loop_detail::follow_up_value;
using loop_detail::Refit;
using loop_detail::Trial;

struct Response {
  double gain;
  double exponent;
  double at(double p, double off) const { return gain * std::pow(p - off, exponent); }
};

// Two tests that bend differently, so a chord through a value other than the hidden one leaves a
// residual: the rougher the chord, the larger its RMSE.
const std::vector<Response> kTests = {{1.0, 0.5}, {2.0, 0.8}};

// The trial at p fitted to the data made at `hidden`: t by least squares along the chord from
// off, and its RMSE.
Trial trial_at(double p, double hidden, double off) {
  double yr = 0.0, rr = 0.0;
  for (const Response& r : kTests) {
    yr += r.at(hidden, off) * r.at(p, off);
    rr += r.at(p, off) * r.at(p, off);
  }
  Trial tr;
  tr.p = p;
  tr.joint.t = yr / rr;
  double ss = 0.0;
  for (const Response& r : kTests) {
    const double e = r.at(hidden, off) - tr.joint.t * r.at(p, off);
    ss += e * e;
  }
  tr.rmse = std::sqrt(ss / static_cast<double>(kTests.size()));
  return tr;
}

double value_of(const Trial& tr, double off) { return off + tr.joint.t * (tr.p - off); }

TEST(LoopRefit, FollowingTheFitConvergesOnABentResponse) {
  // Rods: off L/I 1, hidden 2.6, the first trial at 1.59 (the validation's shape_low_mu).
  const double off = 1.0, hidden = 2.6;
  Refit refit;
  refit.trials.push_back(trial_at(1.59, hidden, off));
  const double first = value_of(refit.trials.front(), off);
  EXPECT_LT(first, 2.3);  // the chord from one trial falls short on a concave response
  for (int k = 0; k < 3; ++k) {
    const auto next = follow_up_value(refit, off, 1.0, 3.0, 0.1);
    if (!next) break;
    refit.trials.push_back(trial_at(*next, hidden, off));
  }
  const Trial& best = best_trial(refit);
  EXPECT_GT(refit.trials.size(), 1u);
  EXPECT_NEAR(value_of(best, off), hidden, 0.05 * (hidden - off));
  EXPECT_LT(std::abs(value_of(best, off) - hidden), std::abs(first - hidden) / 4.0);
  EXPECT_LT(best.rmse, refit.trials.front().rmse);
}

TEST(LoopRefit, NoFollowUpWhenTheFitLandsOnTheTrial) {
  Refit refit;
  refit.trials.push_back(trial_at(2.6, 2.6, 1.0));
  EXPECT_NEAR(refit.trials.front().joint.t, 1.0, 1e-12);
  EXPECT_FALSE(follow_up_value(refit, 1.0, 1.0, 3.0, 0.1));
  refit.trials.front().joint.t = 1.08;  // inside the tolerance
  EXPECT_FALSE(follow_up_value(refit, 1.0, 1.0, 3.0, 0.1));
  refit.trials.front().joint.t = 1.12;  // outside it
  const auto next = follow_up_value(refit, 1.0, 1.0, 3.0, 0.1);
  ASSERT_TRUE(next);
  EXPECT_NEAR(*next, 1.0 + 1.12 * 1.6, 1e-12);
}

TEST(LoopRefit, TheFollowUpStaysInTheRangeAndNeverRepeatsAValue) {
  const double off = 0.0;
  Refit refit;
  Trial tr;
  tr.p = 0.2;
  tr.joint.t = 3.0;  // lands at 0.6, beyond the range's end 0.5
  tr.rmse = 1.0;
  refit.trials.push_back(tr);
  const auto clamped = follow_up_value(refit, off, 0.0, 0.5, 0.1);
  ASSERT_TRUE(clamped);
  EXPECT_DOUBLE_EQ(*clamped, 0.5);
  // Once the range's end is simulated and the fit still leans past it, nothing new is left.
  Trial end = tr;
  end.p = 0.5;
  end.joint.t = 1.5;
  end.rmse = 0.5;
  refit.trials.push_back(end);
  EXPECT_FALSE(follow_up_value(refit, off, 0.0, 0.5, 0.1));
  // A fit at the effect's off value (t = 0) asks for off itself, which the baseline holds.
  Refit at_off;
  tr.joint.t = 0.0;
  at_off.trials.push_back(tr);
  EXPECT_FALSE(follow_up_value(at_off, off, 0.0, 0.5, 0.1));
  EXPECT_FALSE(follow_up_value(Refit{}, off, 0.0, 0.5, 0.1));
}

TEST(LoopRefit, AValueThatFailedIsNotAskedAgain) {
  // A smooth plate: off 0.5 (declared), the best trial at 0.192 lands at 0.094, where the small
  // piles spread too thin to photograph; the trial there stepped back to a value between.
  const double off = 0.5;
  Refit refit;
  Trial tr;
  tr.p = 0.192;
  tr.joint.t = 1.317;
  tr.rmse = 0.535;
  refit.trials.push_back(tr);
  const auto next = follow_up_value(refit, off, 0.0, 1.5, 0.1);
  ASSERT_TRUE(next);
  EXPECT_NEAR(*next, off + 1.317 * (0.192 - off), 1e-12);
  refit.failed.push_back(*next);
  Trial between = tr;
  between.p = 0.5 * (*next + 0.192);
  between.joint.t = 0.8;
  between.rmse = 0.9;
  refit.trials.push_back(between);
  EXPECT_FALSE(follow_up_value(refit, off, 0.0, 1.5, 0.1));
}

TEST(LoopRefit, TheBestTrialIsTheLowestRmseAndTheFirstOfEquals) {
  Refit refit;
  for (double rmse : {1.2, 0.7, 0.9, 0.7}) {
    Trial tr;
    tr.p = rmse;
    tr.rmse = rmse;
    refit.trials.push_back(tr);
  }
  EXPECT_EQ(&best_trial(refit), &refit.trials[1]);
}

}  // namespace
}  // namespace reposetwin::experiments
