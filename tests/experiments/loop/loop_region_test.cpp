// The joint region of (mu_r, effect) holds its level: coverage over synthetic draws through a
// SURROGATE of the simulated response surfaces (closed-form curves shaped like the small-scene
// design's, not simulations: docs/loop.md "The small-scene design"), so that a hundred draws per
// case cost milliseconds. What is tested is the region's statistics (loop_region.hpp), which
// the loop applies unchanged to its simulated surfaces.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

#include "experiments/loop/loop_region.hpp"
#include "sim/random.hpp"

namespace reposetwin::experiments {
namespace {

// The eight tests of the small-scene design: mass (15, 35 g) x plate (steel, wood) x lift
// (0.03, 0.1 m/s).
struct Test {
  bool heavy, steel, fast;
};
std::vector<Test> design() {
  std::vector<Test> t;
  for (bool heavy : {false, true})
    for (bool steel : {true, false})
      for (bool fast : {false, true}) t.push_back({heavy, steel, fast});
  return t;
}

// The surrogate baseline: the angle rises with mu_r and saturates, a little more for the heavy
// piles, lower at the fast lift [deg].
double base_angle(const Test& x, double mu) {
  return 18.0 + (x.heavy ? 2.0 : 0.0) - (x.fast ? 1.0 : 0.0) +
         9.0 * (1.0 + (x.heavy ? 0.2 : 0.0)) * (1.0 - std::exp(-mu / 0.15));
}

// Each case's effect surface minus the baseline at the simulated value (t = 1) [deg]: the
// pattern each effect leaves on this design (docs/loop.md), and how it changes with mu_r.
using Effect = std::function<double(const Test&, double)>;
const Effect kPlate = [](const Test& x, double mu) {
  return -(x.steel ? 3.5 : 1.2) * (1.0 + 0.3 * (mu / 0.25 - 1.0));
};
const Effect kCohesion = [](const Test& x, double mu) {
  return (1.0 + (x.heavy ? 1.5 : 0.0)) * std::exp(-mu / 0.5);
};
// Rods steepen every pile alike, as mu_r does: the hard case.
const Effect kShape = [](const Test& x, double mu) {
  return (2.0 + (x.heavy ? 0.3 : 0.0)) * (1.0 - 0.8 * mu);
};

constexpr double kSigma = 0.98;  // one residual: 1.2 deg x sqrt(1/3 + 1/3) [deg]
constexpr double kMuLo = 0.02, kMuHi = 0.4;  // the declared prior of mu_r for rock [-]
constexpr double kTMax = 3.0;

struct Draw {
  std::vector<double> y;
};

std::vector<ProfileRow> scan(const std::vector<Test>& tests, const Effect& d,
                             const std::vector<double>& y) {
  std::vector<ProfileRow> rows;
  const int steps = 400;
  for (int q = 0; q <= steps; ++q) {
    ProfileRow r;
    r.mu = kMuLo + (kMuHi - kMuLo) * q / steps;
    for (std::size_t i = 0; i < tests.size(); ++i) {
      const double w = 1.0 / (kSigma * kSigma);
      const double yi = y[i] - base_angle(tests[i], r.mu), di = d(tests[i], r.mu);
      r.syy += w * yi * yi;
      r.sdy += w * di * yi;
      r.sdd += w * di * di;
    }
    rows.push_back(r);
  }
  return rows;
}

double chi2_at_truth(const std::vector<Test>& tests, const Effect& d, const std::vector<double>& y,
                     double mu, double t) {
  double c = 0.0;
  for (std::size_t i = 0; i < tests.size(); ++i)
    c += std::pow((y[i] - base_angle(tests[i], mu) - t * d(tests[i], mu)) / kSigma, 2);
  return c;
}

struct Coverage {
  int draws = 0, covered = 0, box_covered = 0, separated = 0;
  double mean_corr = 0.0;
};

Coverage coverage(const Effect& d, std::uint64_t seed, int draws) {
  const std::vector<Test> tests = design();
  sim::Rng rng(seed);
  Coverage c;
  for (int k = 0; k < draws; ++k) {
    const double mu = rng.uniform(0.08, 0.35), t = rng.uniform(0.3, 1.5);
    std::vector<double> y;
    for (const Test& x : tests) y.push_back(base_angle(x, mu) + t * d(x, mu) + kSigma * rng.normal());
    const JointRegion g = joint_region(scan(tests, d, y), 0.0, kTMax, static_cast<int>(y.size()));
    ++c.draws;
    if (chi2_at_truth(tests, d, y, mu, t) <= g.chi2_limit) ++c.covered;
    // The box the report gives holds the joint region, so it covers at least as often.
    if (mu >= g.mu_lo - 1e-3 && mu <= g.mu_hi + 1e-3 && t >= g.t_lo && t <= g.t_hi) ++c.box_covered;
    if (g.separated) ++c.separated;
    c.mean_corr += g.correlation / draws;
  }
  return c;
}

// Over 100 draws per case (hidden mu_r in 0.08-0.35, hidden strength 0.3-1.5 probes, one pile's
// noise on each of eight tests), the hidden pair lies inside the reported 95% region at least
// 90% of the time. Measured: plate 95%, cohesion 96%, shape 96% (docs/loop.md).
TEST(LoopRegion, NinetyFivePercentRegionCoversHiddenValues) {
  struct Case {
    const char* name;
    Effect d;
  };
  for (const Case& cs : {Case{"plate_friction", kPlate}, Case{"cohesion", kCohesion},
                         Case{"grain_shape", kShape}}) {
    const Coverage c = coverage(cs.d, 2026, 100);
    std::printf("%s: joint region covers %d of %d, its box %d; separated in %d; mean corr %.2f\n",
                cs.name, c.covered, c.draws, c.box_covered, c.separated, c.mean_corr);
    EXPECT_GE(c.covered, 90) << cs.name;
    EXPECT_GE(c.box_covered, c.covered) << cs.name;
  }
}

// Where mu_r and the effect move the piles alike (rods: every pile steeper), the region says it
// cannot separate them and reports the interval to the bound (measured: 0 of 40 separated,
// mean correlation -1.00); a plate that changes steel more than wood is separated more often
// (3 of 40, mean correlation 0.78: on eight tests one pile's noise still lets the region reach
// the range's bounds).
TEST(LoopRegion, SaysWhenTheDataCannotSeparateMuFromTheEffect) {
  const Coverage shape = coverage(kShape, 7, 40);
  const Coverage plate = coverage(kPlate, 7, 40);
  EXPECT_EQ(shape.separated, 0);
  EXPECT_GT(std::abs(shape.mean_corr), 0.95);
  EXPECT_GT(plate.separated, shape.separated);
  EXPECT_LT(std::abs(plate.mean_corr), 0.9);
}

// The region's rules on a case solved by hand: y = t d with d constant and no mu_r dependence
// (syy, sdy, sdd the same in every row): chi^2 = sum (y - t d)^2 / s^2, so the t interval is
// t_hat +- sqrt(q / sdd) with q = 5.99, and mu_r spans the whole scan (it reaches both bounds:
// not separated).
TEST(LoopRegion, ClosedFormIntervalWhenMuDoesNotMatter) {
  std::vector<ProfileRow> rows;
  // Four observations y = 1, 1.2, 0.8, 1 of d = 1 each, sigma 0.5: sdd = 16, sdy = 16, syy =
  // 16.32; t_hat = 1, chi2_min = 0.32 (below 2 dof: no widening).
  for (int k = 0; k < 5; ++k) rows.push_back({0.1 * k, 16.32, 16.0, 16.0});
  const JointRegion g = joint_region(rows, -10.0, 10.0, 4);
  EXPECT_NEAR(g.t, 1.0, 1e-12);
  EXPECT_NEAR(g.chi2_min, 0.32, 1e-12);
  EXPECT_DOUBLE_EQ(g.widening, 1.0);
  const double half = std::sqrt(-2.0 * std::log(0.05) / 16.0);
  EXPECT_NEAR(g.t_lo, 1.0 - half, 1e-12);
  EXPECT_NEAR(g.t_hi, 1.0 + half, 1e-12);
  EXPECT_TRUE(g.mu_at_bound);
  EXPECT_FALSE(g.separated);
  // A chi^2 above its degrees of freedom widens the region by chi2_min / (n - 2).
  for (auto& r : rows) r.syy = 16.0 + 8.0;  // chi2_min 8 on 2 dof: widening 4
  const JointRegion w = joint_region(rows, -10.0, 10.0, 4);
  EXPECT_NEAR(w.widening, 4.0, 1e-12);
  EXPECT_NEAR(w.t_hi - w.t, 2.0 * half, 1e-12);
}

// The region over several refit trials (value_region), on hand-made chords: the closed-form
// case above as one chord at p = 2 from off 1 (value = 1 + t), a second chord at p = 3 whose
// best fit is as good, and a third whose fit is far worse.
TEST(LoopRegion, RegionOverTrialsJoinsTheChordsAtOneLikelihood) {
  auto chord = [](double p, double syy, double sdy, double sdd) {
    ChordScan c;
    c.p = p;
    c.t_max = 3.0;
    for (int k = 0; k < 5; ++k) c.rows.push_back({0.1 * k, syy, sdy, sdd});
    c.region = joint_region(c.rows, 0.0, c.t_max, 4);
    return c;
  };
  const double half = std::sqrt(-2.0 * std::log(0.05) / 16.0);
  // One chord: its own region, t mapped to values 1 + t.
  const ChordScan a = chord(2.0, 16.32, 16.0, 16.0);
  const ValueRegion one = value_region({a}, 1.0);
  EXPECT_NEAR(one.value_lo, 1.0 + (1.0 - half), 1e-12);
  EXPECT_NEAR(one.value_hi, 1.0 + (1.0 + half), 1e-12);
  EXPECT_EQ(one.chords, 1);
  EXPECT_NEAR(one.chi2_limit, a.region.chi2_limit, 1e-12);
  // A second chord at p = 3 (value = 1 + 2t) with its optimum at t = 0.75 (value 2.5) and the
  // same chi2_min: its t interval is as wide, twice as wide in value, and holds the first's.
  const ChordScan b = chord(3.0, 0.32 + 16.0 * 0.75 * 0.75, 16.0 * 0.75, 16.0);
  EXPECT_NEAR(b.region.chi2_min, 0.32, 1e-12);
  const ValueRegion two = value_region({a, b}, 1.0);
  EXPECT_EQ(two.chords, 2);
  EXPECT_NEAR(two.value_lo, 1.0 + 2.0 * (0.75 - half), 1e-12);
  EXPECT_NEAR(two.value_hi, 1.0 + 2.0 * (0.75 + half), 1e-12);
  // A chord whose best chi^2 is 50 lies outside the limit and adds nothing.
  const ChordScan far = chord(5.0, 50.0 + 16.0, 16.0, 16.0);
  const ValueRegion three = value_region({a, b, far}, 1.0);
  EXPECT_EQ(three.chords, 2);
  EXPECT_DOUBLE_EQ(three.value_hi, two.value_hi);
  EXPECT_THROW(value_region({}, 1.0), std::invalid_argument);
}

// What would separate them (loop_region.hpp): with the shape case's information, a test whose
// response to the effect differs from its response to mu_r shrinks the effect's interval more
// than a repeat of a test like the others.
TEST(LoopRegion, NextTestThatBreaksTheTradeShrinksMost) {
  // Two tests that respond alike to mu_r and to t (information nearly singular).
  Eigen::Matrix2d info = Eigen::Matrix2d::Zero();
  for (const Eigen::Vector2d j : {Eigen::Vector2d(20.0, 2.0), Eigen::Vector2d(22.0, 2.3)})
    info += j * j.transpose();
  const std::vector<NextTestGain> g =
      rank_next_tests(info, {NextTest::one("repeat", 21.0, 2.1),
                             NextTest::one("rougher plate", 5.0, 2.5)});
  ASSERT_EQ(g.size(), 2u);
  EXPECT_EQ(g[0].name, "rougher plate");
  EXPECT_LT(g[0].t_interval_ratio, 0.5);
  EXPECT_GT(g[1].t_interval_ratio, 0.8);
  std::printf("next test: %s shrinks the effect's interval to %.2f (a repeat: %.2f)\n",
              g[0].name.c_str(), g[0].t_interval_ratio, g[1].t_interval_ratio);
}

}  // namespace
}  // namespace reposetwin::experiments
