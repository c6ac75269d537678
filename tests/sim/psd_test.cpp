// Tests of the PSD from a sieve table. Oracles: hand calculations on a small table, and the
// diameters themselves re-binned and re-weighed here (never the sampler's own summary alone).
#include "sim/psd.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace reposetwin::sim {
namespace {

constexpr double kDensity = 2760.0;  // [kg/m^3]

double mass_of(double d) { return kDensity * std::numbers::pi / 6.0 * d * d * d; }

// Sizes 0.5, 1, 2, 4 mm passing 10, 30, 60, 100 %.
SieveTable hand_table() { return {{0.5e-3, 1e-3, 2e-3, 4e-3}, {10.0, 30.0, 60.0, 100.0}}; }

TEST(PsdResolve, ScalpingAndFinesMatchHandCalculation) {
  PsdSpec spec{hand_table()};
  spec.d_max = 2e-3;
  spec.d_min = 0.75e-3;  // P(0.75 mm) = 10 + 0.5 * (30 - 10) = 20 %
  const ResolvedPsd r = resolve_psd(spec);
  EXPECT_DOUBLE_EQ(r.d_max, 2e-3);
  EXPECT_DOUBLE_EQ(r.d_min, 0.75e-3);
  EXPECT_NEAR(r.scalped_fraction, 0.4, 1e-12);        // 1 - 60/100
  EXPECT_NEAR(r.fines_fraction, 20.0 / 60.0, 1e-12);  // P(d_min) / P(d_max)
  EXPECT_NEAR(r.simulated_mass_factor, 1.0, 1e-12);
  ASSERT_EQ(r.intervals.size(), 2u);
  EXPECT_DOUBLE_EQ(r.intervals[0].lower, 0.75e-3);
  EXPECT_DOUBLE_EQ(r.intervals[0].upper, 1e-3);
  EXPECT_NEAR(r.intervals[0].mass_fraction, 10.0 / 40.0, 1e-12);  // (30 - 20) / (60 - 20)
  EXPECT_NEAR(r.intervals[1].mass_fraction, 30.0 / 40.0, 1e-12);  // (60 - 30) / (60 - 20)

  spec.fines = FinesPolicy::kDrop;
  EXPECT_NEAR(resolve_psd(spec).simulated_mass_factor, 1.0 - 20.0 / 60.0, 1e-12);
}

TEST(PsdResolve, ScalpBetweenSievesAndDefaults) {
  PsdSpec spec{hand_table()};
  spec.d_max = 3e-3;  // P(3 mm) = 60 + 0.5 * 40 = 80 %
  const ResolvedPsd r = resolve_psd(spec);
  EXPECT_DOUBLE_EQ(r.d_min, 0.5e-3);  // default: the smallest sieve
  EXPECT_NEAR(r.scalped_fraction, 0.2, 1e-12);
  EXPECT_NEAR(r.fines_fraction, 10.0 / 80.0, 1e-12);
  ASSERT_EQ(r.intervals.size(), 3u);
  EXPECT_NEAR(r.intervals[0].mass_fraction, 20.0 / 70.0, 1e-12);
  EXPECT_NEAR(r.intervals[1].mass_fraction, 30.0 / 70.0, 1e-12);
  EXPECT_NEAR(r.intervals[2].mass_fraction, 20.0 / 70.0, 1e-12);
  EXPECT_DOUBLE_EQ(r.intervals[2].upper, 3e-3);

  const ResolvedPsd whole = resolve_psd(PsdSpec{hand_table()});
  EXPECT_DOUBLE_EQ(whole.d_max, 4e-3);
  EXPECT_NEAR(whole.scalped_fraction, 0.0, 1e-12);
}

void expect_invalid(const PsdSpec& spec, const std::string& fragment) {
  try {
    resolve_psd(spec);
    ADD_FAILURE() << "no exception; expected one mentioning '" << fragment << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(PsdResolve, BadTablesThrowNamingFieldAndValue) {
  PsdSpec not_monotone{{{1e-3, 2e-3, 4e-3}, {40.0, 30.0, 100.0}}};
  expect_invalid(not_monotone, "percent passing[1] = 30");
  PsdSpec short_of_100{{{1e-3, 2e-3, 4e-3}, {10.0, 30.0, 90.0}}};
  expect_invalid(short_of_100, "percent passing[2] = 90");
  PsdSpec negative_size{{{-1e-3, 2e-3, 4e-3}, {10.0, 30.0, 100.0}}};
  expect_invalid(negative_size, "sieve size[0] = -0.001 m");
  PsdSpec not_increasing{{{1e-3, 1e-3, 4e-3}, {10.0, 30.0, 100.0}}};
  expect_invalid(not_increasing, "sieve size[1]");
  PsdSpec above_100{{{1e-3, 2e-3}, {10.0, 100.5}}};
  expect_invalid(above_100, "percent passing[1] = 100.5");
  PsdSpec mismatched{{{1e-3, 2e-3}, {100.0}}};
  expect_invalid(mismatched, "percent-passing values");
  PsdSpec too_short{{{1e-3}, {100.0}}};
  expect_invalid(too_short, "at least 2");

  PsdSpec d_max_above{hand_table()};
  d_max_above.d_max = 5e-3;
  expect_invalid(d_max_above, "d_max = 0.005 m");
  PsdSpec d_min_below{hand_table()};
  d_min_below.d_min = 0.1e-3;
  expect_invalid(d_min_below, "d_min = 0.0001 m");
  PsdSpec d_min_over_d_max{hand_table()};
  d_min_over_d_max.d_max = 1e-3;
  d_min_over_d_max.d_min = 2e-3;
  expect_invalid(d_min_over_d_max, "must be below d_max");
  PsdSpec empty_range{{{1e-3, 2e-3, 4e-3}, {0.0, 0.0, 100.0}}};
  empty_range.d_max = 2e-3;
  expect_invalid(empty_range, "no material");
  PsdSpec bad_sd{hand_table()};
  bad_sd.interval_sd_fraction = 0.0;
  expect_invalid(bad_sd, "interval_sd_fraction");
}

TEST(PsdSample, BadMassOrDensityThrows) {
  Rng rng(1);
  PsdSpec spec{hand_table()};
  EXPECT_THROW(sample_psd(spec, 0.0, kDensity, rng), std::invalid_argument);
  EXPECT_THROW(sample_psd(spec, 0.1, -1.0, rng), std::invalid_argument);
  EXPECT_THROW(sample_psd(spec, std::nan(""), kDensity, rng), std::invalid_argument);
}

// A five-interval table with an empty interval, scalped between sieves, about 1e5 particles.
PsdSpec rich_spec() {
  PsdSpec spec{{{0.5e-3, 0.6e-3, 0.71e-3, 0.85e-3, 1.0e-3, 1.18e-3, 1.4e-3, 2.0e-3},
                {5.0, 12.0, 25.0, 25.0, 48.0, 70.0, 85.0, 100.0}}};
  spec.d_max = 1.3e-3;
  spec.d_min = 0.55e-3;
  return spec;
}

TEST(PsdSample, MassFractionsTotalMassAndCountOn1e5Particles) {
  const PsdSpec spec = rich_spec();
  const ResolvedPsd r = resolve_psd(spec);
  // Choose the mass for about 1e5 particles from the expected count of 1 kg.
  const double mass = 1e5 / expected_particle_count(spec, 1.0, kDensity);
  Rng rng(12345);
  const PsdSample s = sample_psd(spec, mass, kDensity, rng);
  ASSERT_GT(s.diameter.size(), 90000u);
  ASSERT_LT(s.diameter.size(), 110000u);

  // Re-bin and re-weigh the diameters independently of the sampler's bookkeeping.
  std::vector<double> interval_mass(r.intervals.size(), 0.0);
  double total = 0.0;
  for (double d : s.diameter) {
    ASSERT_GE(d, r.d_min);
    ASSERT_LE(d, r.d_max);
    std::size_t k = 0;
    while (k + 1 < r.intervals.size() && d > r.intervals[k].upper) ++k;
    interval_mass[k] += mass_of(d);
    total += mass_of(d);
  }
  // Total mass: at least the target, and over it by less than the last particle's mass.
  EXPECT_GE(total, mass);
  EXPECT_LT(total - mass, mass_of(s.diameter.back()));
  EXPECT_NEAR(s.summary.drawn_mass, total, 1e-9 * total);
  EXPECT_EQ(s.summary.count, s.diameter.size());

  for (std::size_t k = 0; k < r.intervals.size(); ++k) {
    const double want = r.intervals[k].mass_fraction;
    const double got = interval_mass[k] / total;
    if (want == 0.0) {
      EXPECT_EQ(got, 0.0) << "interval " << k;
    } else {
      EXPECT_NEAR(got, want, 0.01 * want) << "interval " << k;
    }
    EXPECT_NEAR(s.summary.intervals[k].drawn_mass_fraction, got, 1e-9);
  }
  // The quadrature's expected count agrees with the Monte Carlo count.
  EXPECT_NEAR(static_cast<double>(s.diameter.size()), expected_particle_count(spec, mass, kDensity),
              0.01 * s.diameter.size());
  EXPECT_GE(s.summary.d_min_drawn, r.d_min);
  EXPECT_LE(s.summary.d_max_drawn, r.d_max);
}

TEST(PsdSample, SizesInsideAnIntervalFollowTheClippedNormal) {
  // One interval [1, 2] mm: mean 1.5 mm; the normal with sd = width/6 clipped at +-3 sd has
  // sd = sigma * sqrt(1 - 2*3*phi(3)/(2*Phi(3)-1)) = sigma * 0.98658.
  PsdSpec spec{{{1e-3, 2e-3}, {0.0, 100.0}}};
  Rng rng(7);
  const PsdSample s = sample_psd(spec, 40000 * mass_of(1.5e-3), kDensity, rng);
  double sum = 0.0, sum2 = 0.0;
  for (double d : s.diameter) {
    sum += d;
    sum2 += d * d;
  }
  const double n = static_cast<double>(s.diameter.size());
  const double mean = sum / n;
  const double sd = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, 1.5e-3, 0.003 * 1.5e-3);
  EXPECT_NEAR(sd, 1e-3 / 6.0 * 0.98658, 0.02 * 1e-3 / 6.0);
}

TEST(PsdSample, DropPolicyScalesTheSimulatedMass) {
  PsdSpec spec{hand_table()};
  spec.d_max = 2e-3;
  spec.d_min = 1e-3;  // fines fraction 30/60 = 0.5
  spec.fines = FinesPolicy::kDrop;
  Rng rng(3);
  const PsdSample s = sample_psd(spec, 0.01, kDensity, rng);
  EXPECT_NEAR(s.summary.fines_fraction, 0.5, 1e-12);
  EXPECT_NEAR(s.summary.simulated_target_mass, 0.005, 1e-15);
  EXPECT_GE(s.summary.drawn_mass, 0.005);
  EXPECT_LT(s.summary.drawn_mass - 0.005, mass_of(2e-3));
}

TEST(PsdSample, SameSeedSameDiametersOtherSeedOthers) {
  const PsdSpec spec = rich_spec();
  Rng a(99), b(99), c(100);
  const auto sa = sample_psd(spec, 0.01, kDensity, a);
  const auto sb = sample_psd(spec, 0.01, kDensity, b);
  const auto sc = sample_psd(spec, 0.01, kDensity, c);
  EXPECT_EQ(sa.diameter, sb.diameter);
  EXPECT_NE(sa.diameter, sc.diameter);
}

TEST(PsdQuadrature, MeanCubeOfANarrowIntervalIsItsMidpointCubed) {
  // For a narrow interval, E[d^3] -> m^3 + 3 m sd_eff^2 with sd_eff^2 = (0.98658 w/6)^2.
  const double a = 1.0, b = 1.1, m = 1.05, sd = 0.98658 * 0.1 / 6.0;
  EXPECT_NEAR(clipped_normal_mean_cube(a, b, 1.0 / 6.0), m * m * m + 3.0 * m * sd * sd, 1e-6);
}

}  // namespace
}  // namespace reposetwin::sim
