// Tests of the pile measurement on synthetic piles whose H, D, centre and angle are known by
// construction (the oracle is the geometry used to build them, not the measurement code).
#include "sim/pile_geometry.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "../support/cone_pile.hpp"
#include "sim/random.hpp"

namespace reposetwin::sim {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

using test_support::Spheres;
using test_support::add_ring;
using test_support::make_cone;

void expect_cone(const PileGeometry& g, double h, double big_r, double cx, double cy,
                 std::size_t pile_count) {
  ASSERT_EQ(g.status, PileStatus::kOk);
  EXPECT_EQ(g.pile_count, pile_count);
  EXPECT_NEAR(g.height, h, 1e-9);
  EXPECT_NEAR(g.base_diameter, 2.0 * big_r, 1e-3 * big_r);
  EXPECT_NEAR(g.centre.x(), cx, 1e-3 * big_r);
  EXPECT_NEAR(g.centre.y(), cy, 1e-3 * big_r);
  const double theta = std::atan(h / big_r);
  EXPECT_NEAR(g.theta_hd, theta, 0.3 * kDeg);
  EXPECT_EQ(g.valid_slices, 16);
  EXPECT_NEAR(g.slice_angle_mean, theta, 0.3 * kDeg);
  EXPECT_LT(g.slice_angle_sd, 0.3 * kDeg);
  for (const PileSlice& s : g.slices) {
    EXPECT_TRUE(s.positive.valid && s.negative.valid);
    EXPECT_NEAR(s.angle, theta, 0.3 * kDeg) << "azimuth " << s.azimuth;
  }
  // The equal-area triangle and the centre of mass see the particle layers' offsets: looser.
  EXPECT_NEAR(g.equal_area_angle, theta, 2.0 * kDeg);
  EXPECT_NEAR(g.centre_of_mass_angle, theta, 3.0 * kDeg);
}

class ConeTest : public ::testing::TestWithParam<double> {};

TEST_P(ConeTest, CentredConeMeasuredExactly) {
  const double theta = GetParam() * kDeg;
  const double big_r = 0.03;
  const double h = big_r * std::tan(theta);
  const Spheres s = make_cone(h, big_r, 0.0, 0.0, 0.4e-3, 11);
  const PileGeometry g = measure_pile(s.x, s.r);
  expect_cone(g, h, big_r, 0.0, 0.0, s.x.size());
  EXPECT_EQ(g.stray_count, 0u);
}

INSTANTIATE_TEST_SUITE_P(Angles, ConeTest, ::testing::Values(25.0, 33.47, 40.0));

TEST(PileGeometry, RoughConeStillGivesTheFlankAngle) {
  const double big_r = 0.03, h = 0.02;
  const Spheres s = make_cone(h, big_r, 0.0, 0.0, 0.4e-3, 21, 0.5);
  const PileGeometry g = measure_pile(s.x, s.r);
  expect_cone(g, h, big_r, 0.0, 0.0, s.x.size());
  EXPECT_GT(g.flank_angle_sd, 0.0);  // the roughness is seen by single flanks
}

TEST(PileGeometry, OffCentreConeFindsItsCentre) {
  const double big_r = 0.025, h = 0.018;
  const Spheres s = make_cone(h, big_r, 0.013, -0.021, 0.35e-3, 5);
  expect_cone(measure_pile(s.x, s.r), h, big_r, 0.013, -0.021, s.x.size());
}

TEST(PileGeometry, PlateAboveZeroIsTheReference) {
  const double big_r = 0.02, h = 0.012;
  Spheres s = make_cone(h, big_r, 0.0, 0.0, 0.4e-3, 8);
  for (Vec3& p : s.x) p.z() += 0.05;
  PileGeometrySettings settings;
  settings.plate_z = 0.05;
  expect_cone(measure_pile(s.x, s.r, settings), h, big_r, 0.0, 0.0, s.x.size());
  EXPECT_EQ(measure_pile(s.x, s.r).status, PileStatus::kNoPile);  // nothing on a plate at z = 0
}

TEST(PileGeometry, StraysDoNotMoveTheMeasurement) {
  const double big_r = 0.03, h = 0.02, a = 0.4e-3;
  Spheres s = make_cone(h, big_r, 0.004, 0.002, a, 9);
  const std::size_t cone_count = s.x.size();
  // Lone particles that rolled away on the plate, one still falling above the apex.
  s.add(0.004 + 1.5 * big_r, 0.002, a, a);
  s.add(0.004 - 1.3 * big_r, 0.002 + 0.5 * big_r, a, a);
  s.add(0.004, 0.002 - 1.8 * big_r, a, 1.2 * a);
  s.add(0.004, 0.002, h + 6.0 * a, a);
  s.add(0.004 + 0.2 * big_r, 0.002, h + 20.0 * a, a);
  const PileGeometry g = measure_pile(s.x, s.r);
  expect_cone(g, h, big_r, 0.004, 0.002, cone_count);
  EXPECT_EQ(g.stray_count, 5u);

  // A short run-out of three touching particles at the toe joins the pile, but the median over
  // sectors keeps D.
  Spheres t = make_cone(h, big_r, 0.0, 0.0, a, 9);
  for (int k = 1; k <= 3; ++k) t.add(big_r - a + 1.9 * a * k, 0.0, a, a);
  const PileGeometry gt = measure_pile(t.x, t.r);
  EXPECT_EQ(gt.pile_count, t.x.size());
  EXPECT_NEAR(gt.base_diameter, 2.0 * big_r, 1e-3 * big_r);
  EXPECT_NEAR(gt.theta_hd, std::atan(h / big_r), 0.3 * kDeg);
  EXPECT_NEAR(gt.slice_angle_mean, std::atan(h / big_r), 0.3 * kDeg);
}

TEST(PileGeometry, PileClusterMatchesABruteForceSearch) {
  // Random polydisperse spheres in a box: the pile must be the plate-touching cluster of largest
  // volume found by an O(n^2) flood fill here, with the same count and the same H.
  Rng rng(17);
  for (int trial = 0; trial < 5; ++trial) {
    Spheres s;
    for (int i = 0; i < 150; ++i) {
      const double a = rng.uniform(0.5e-3, 1.5e-3);
      s.add(rng.uniform(0.0, 0.02), rng.uniform(0.0, 0.02), rng.uniform(a, 0.01), a);
    }
    const std::size_t n = s.x.size();
    std::vector<int> label(n, -1);
    int labels = 0;
    for (std::size_t seed = 0; seed < n; ++seed) {
      if (label[seed] >= 0) continue;
      std::vector<std::size_t> stack{seed};
      label[seed] = labels;
      while (!stack.empty()) {
        const std::size_t i = stack.back();
        stack.pop_back();
        for (std::size_t j = 0; j < n; ++j) {
          if (label[j] < 0 && (s.x[i] - s.x[j]).norm() <= 1.1 * (s.r[i] + s.r[j])) {
            label[j] = labels;
            stack.push_back(j);
          }
        }
      }
      ++labels;
    }
    std::vector<double> volume(labels, 0.0);
    std::vector<bool> on_plate(labels, false);
    for (std::size_t i = 0; i < n; ++i) {
      volume[label[i]] += std::pow(s.r[i], 3);
      if (s.x[i].z() <= 1.5 * s.r[i]) on_plate[label[i]] = true;
    }
    int best = -1;
    for (int l = 0; l < labels; ++l) {
      if (on_plate[l] && (best < 0 || volume[l] > volume[best])) best = l;
    }
    ASSERT_GE(best, 0);
    std::size_t count = 0;
    double top = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      if (label[i] != best) continue;
      ++count;
      top = std::max(top, s.x[i].z() + s.r[i]);
    }
    const PileGeometry g = measure_pile(s.x, s.r);
    EXPECT_EQ(g.pile_count, count) << "trial " << trial;
    EXPECT_EQ(g.stray_count, n - count);
    EXPECT_DOUBLE_EQ(g.height, top);
  }
}

TEST(PileGeometry, MonolayerHasNoFlanksAndKnownHeightDiameterAndCentreOfMass) {
  // One layer of spheres on the plate: H = 2a, D = 2R, z_com = a.
  const double a = 0.5e-3, big_r = 0.01;
  Spheres s;
  Rng rng(2);
  for (double rho = big_r - a; rho > -1e-12; rho -= 1.6 * a) {
    add_ring(s, 0.0, 0.0, std::max(rho, 0.0), a, a, 1.6 * a, rng);
  }
  const PileGeometry g = measure_pile(s.x, s.r);
  EXPECT_EQ(g.status, PileStatus::kNoFlanks);
  EXPECT_NEAR(g.height, 2.0 * a, 1e-12);
  EXPECT_NEAR(g.base_diameter, 2.0 * big_r, 1e-9);
  EXPECT_NEAR(g.centre_of_mass_height, a, 1e-12);
  EXPECT_NEAR(g.centre_of_mass_angle, std::atan(8.0 * a / (2.0 * big_r)), 1e-9);
  EXPECT_NEAR(g.theta_hd, std::atan(2.0 * a / big_r), 1e-9);
}

TEST(PileGeometry, NoPileWhenNothingTouchesThePlate) {
  EXPECT_EQ(measure_pile(std::vector<Vec3>{}, std::vector<double>{}).status,
            PileStatus::kNoPile);
  const PileGeometry g = measure_pile(std::vector<Vec3>{Vec3(0, 0, 0.05), Vec3(0.001, 0, 0.05)},
                                      std::vector<double>{5e-4, 5e-4});
  EXPECT_EQ(g.status, PileStatus::kNoPile);
  EXPECT_EQ(g.stray_count, 2u);
  EXPECT_EQ(g.height, 0.0);
}

TEST(PileGeometry, BadInputThrows) {
  EXPECT_THROW(measure_pile(std::vector<Vec3>{Vec3(0, 0, 0)}, std::vector<double>{}),
               std::invalid_argument);
  EXPECT_THROW(measure_pile(std::vector<Vec3>{Vec3(0, 0, 0)}, std::vector<double>{-1.0}),
               std::invalid_argument);
  EXPECT_THROW(measure_pile(std::vector<Vec3>{Vec3(0, std::nan(""), 0)}, std::vector<double>{1e-3}),
               std::invalid_argument);
  PileGeometrySettings bad;
  bad.flank_low = 0.9;
  try {
    measure_pile(std::vector<Vec3>{Vec3(0, 0, 1e-3)}, std::vector<double>{1e-3}, bad);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("flank_low = 0.9"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace reposetwin::sim
