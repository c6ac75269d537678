// Tests of the pile measurement on synthetic piles whose H, D, centre and angle are known by
// construction (the oracle is the geometry used to build them, not the measurement code).
#include "sim/pile_geometry.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "sim/random.hpp"

namespace reposetwin::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

struct Spheres {
  std::vector<Vec3> x;
  std::vector<double> r;
  void add(double px, double py, double pz, double radius) {
    x.emplace_back(px, py, pz);
    r.push_back(radius);
  }
};

// Adds a ring of spheres of radius a at height z and radius rho around (cx, cy), spaced about
// `spacing` apart, starting at a random phase. With inward > 0, each sphere is moved a random
// distance in [0, inward] along the unit direction (-sin_t, -cos_t) in the (rho, z) plane (into
// a cone of slope angle t) and a random fraction of the spacing around the ring.
void add_ring(Spheres& s, double cx, double cy, double rho, double z, double a, double spacing,
              Rng& rng, double inward = 0.0, double sin_t = 0.0, double cos_t = 0.0) {
  if (rho < 1e-12) {
    s.add(cx, cy, z, a);
    return;
  }
  const int n = std::max(1, static_cast<int>(std::ceil(2.0 * kPi * rho / spacing)));
  const double phase = rng.uniform(0.0, 2.0 * kPi);
  for (int k = 0; k < n; ++k) {
    const double phi = phase + 2.0 * kPi * (k + (inward > 0.0 ? rng.uniform(-0.2, 0.2) : 0.0)) / n;
    const double depth = inward > 0.0 ? rng.uniform(0.0, inward) : 0.0;
    const double q = rho - depth * sin_t;
    s.add(cx + q * std::cos(phi), cy + q * std::sin(phi), z - depth * cos_t, a);
  }
}

// A cone of spheres with apex height h and base radius big_r centred at (cx, cy):
// - a bottom layer of rings on the plate, the outermost reaching exactly big_r;
// - the outer surface: spheres of radius a touching the cone from inside (centres on the cone
//   offset inward by a), in rows about 1.6 a apart along the slope and around;
// - an apex sphere whose top is exactly at h;
// - the inside: a cubic lattice (spacing 1.8 a, jitter +-0.05 a, radii 0.9-1.1 a) of spheres
//   at least one radius below the surface layer.
// So H = h, D = 2 big_r, the flank angle is atan(h / big_r) exactly. With roughness > 0 the
// surface spheres sink a random depth in [0, roughness a] into the cone and shift around their
// rings: the surface is no longer a perfect cone, and the fit must average the scatter out.
Spheres make_cone(double h, double big_r, double cx, double cy, double a, std::uint64_t seed,
                  double roughness = 0.0) {
  Rng rng(seed);
  Spheres s;
  const double theta = std::atan(h / big_r);
  const double sn = std::sin(theta), cs = std::cos(theta);
  const double spacing = 1.6 * a;
  // Bottom layer.
  for (double rho = big_r - a; rho > -1e-12; rho -= spacing) {
    add_ring(s, cx, cy, std::max(rho, 0.0), a, a, spacing, rng);
  }
  // Surface layer on the offset cone rho sin + z cos = big_r sin - a.
  const double z_top = (big_r * sn - a) / cs;
  for (double z = a; z < z_top; z += spacing * sn) {
    const double rho = (big_r * sn - a - z * cs) / sn;
    add_ring(s, cx, cy, rho, z, a, spacing, rng, roughness * a, sn, cs);
  }
  s.add(cx, cy, z_top, a);
  s.add(cx, cy, h - a, a);  // apex
  // Inside lattice.
  const double step = 1.8 * a;
  for (double z = a + step; z < h; z += step) {
    for (double px = -big_r; px <= big_r; px += step) {
      for (double py = -big_r; py <= big_r; py += step) {
        const double ra = a * rng.uniform(0.9, 1.1);
        const double qx = px + a * rng.uniform(-0.05, 0.05);
        const double qy = py + a * rng.uniform(-0.05, 0.05);
        const double qz = z + a * rng.uniform(-0.05, 0.05);
        const double rho = std::hypot(qx, qy);
        // Signed distance of the centre inside the cone surface.
        const double depth = big_r * sn - (rho * sn + qz * cs);
        if (depth >= 2.0 * a + (ra - a) * 2.0) s.add(cx + qx, cy + qy, qz, ra);
      }
    }
  }
  return s;
}

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
  EXPECT_EQ(measure_pile({}, {}).status, PileStatus::kNoPile);
  const PileGeometry g = measure_pile({Vec3(0, 0, 0.05), Vec3(0.001, 0, 0.05)}, {5e-4, 5e-4});
  EXPECT_EQ(g.status, PileStatus::kNoPile);
  EXPECT_EQ(g.stray_count, 2u);
  EXPECT_EQ(g.height, 0.0);
}

TEST(PileGeometry, BadInputThrows) {
  EXPECT_THROW(measure_pile({Vec3(0, 0, 0)}, {}), std::invalid_argument);
  EXPECT_THROW(measure_pile({Vec3(0, 0, 0)}, {-1.0}), std::invalid_argument);
  EXPECT_THROW(measure_pile({Vec3(0, std::nan(""), 0)}, {1e-3}), std::invalid_argument);
  PileGeometrySettings bad;
  bad.flank_low = 0.9;
  try {
    measure_pile({Vec3(0, 0, 1e-3)}, {1e-3}, bad);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("flank_low = 0.9"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace reposetwin::sim
