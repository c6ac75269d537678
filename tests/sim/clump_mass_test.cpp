// Mass properties of clump templates against closed forms: the union of collinear spheres is a
// solid of revolution whose radius squared is, between break points, one sphere's polynomial
// r^2 - (x - c)^2, so its volume and moments are exact polynomial integrals; the two-sphere
// case is also checked against the textbook lens volume; a triangle of three spheres that
// overlap pairwise (no point in all three) is the spheres minus three lenses, each lens placed
// from its own axisymmetric integrals. Then the principal frame, and bad input.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "sim/clump.hpp"

namespace reposetwin::sim {
namespace {

/// Integrals of an axisymmetric solid about the x axis (coordinates along the axis s, across
/// y): A0 = int dV, A1 = int s dV, A2 = int s^2 dV, B = int y^2 dV (= int z^2 dV).
struct AxialMoments {
  double a0 = 0, a1 = 0, a2 = 0, b = 0;
};

/// Exact integrals of the union of spheres centred at s = c[i] on the axis, radii r[i]: on each
/// interval between break points (sphere ends, intersections of two profiles) the profile is the
/// largest rho^2 = r_i^2 - (s - c_i)^2 = p0 + p1 s - s^2, integrated in closed form.
AxialMoments collinear_union(const std::vector<double>& c, const std::vector<double>& r) {
  std::vector<double> cuts;
  for (std::size_t i = 0; i < c.size(); ++i) {
    cuts.push_back(c[i] - r[i]);
    cuts.push_back(c[i] + r[i]);
    for (std::size_t j = i + 1; j < c.size(); ++j)
      cuts.push_back((r[j] * r[j] - r[i] * r[i] + c[i] * c[i] - c[j] * c[j]) /
                     (2.0 * (c[i] - c[j])));
  }
  std::sort(cuts.begin(), cuts.end());
  AxialMoments m;
  for (std::size_t k = 0; k + 1 < cuts.size(); ++k) {
    const double lo = cuts[k], hi = cuts[k + 1];
    if (!(hi > lo)) continue;
    const double mid = 0.5 * (lo + hi);
    int best = -1;
    double best_rho2 = 0.0;
    for (std::size_t i = 0; i < c.size(); ++i) {
      const double rho2 = r[i] * r[i] - (mid - c[i]) * (mid - c[i]);
      if (rho2 > best_rho2) {
        best_rho2 = rho2;
        best = static_cast<int>(i);
      }
    }
    if (best < 0) continue;  // a gap between spheres
    // rho^2 = p0 + p1 s + p2 s^2 and rho^4; coefficient lists, integrated term by term.
    const double p0 = r[best] * r[best] - c[best] * c[best], p1 = 2.0 * c[best], p2 = -1.0;
    const double q[5] = {p0 * p0, 2 * p0 * p1, p1 * p1 + 2 * p0 * p2, 2 * p1 * p2, p2 * p2};
    auto integral = [&](const double* coef, int terms, int shift) {
      double sum = 0.0;
      for (int e = 0; e < terms; ++e) {
        const int pw = e + shift + 1;
        sum += coef[e] * (std::pow(hi, pw) - std::pow(lo, pw)) / pw;
      }
      return sum;
    };
    const double p[3] = {p0, p1, p2};
    m.a0 += std::numbers::pi * integral(p, 3, 0);
    m.a1 += std::numbers::pi * integral(p, 3, 1);
    m.a2 += std::numbers::pi * integral(p, 3, 2);
    m.b += std::numbers::pi / 4.0 *
           integral(q, 5, 0);  // a disc of radius rho: int y^2 dA = pi rho^4 / 4
  }
  return m;
}

/// Volume, first and second moments (about the origin) of a solid with axial moments `m`
/// placed with its axis along unit e through point p.
struct Moments {
  double vol = 0;
  Vec3 first = Vec3::Zero();
  Mat3 second = Mat3::Zero();
};
Moments place(const AxialMoments& m, const Vec3& p, const Vec3& e) {
  Moments out;
  out.vol = m.a0;
  out.first = m.a0 * p + m.a1 * e;
  out.second = m.a0 * p * p.transpose() + m.a1 * (p * e.transpose() + e * p.transpose()) +
               m.a2 * e * e.transpose() + m.b * (Mat3::Identity() - e * e.transpose());
  return out;
}

/// Central inertia tensor (unit density) from volume, first and second moments.
Mat3 inertia_of(const Moments& m) {
  const Vec3 com = m.first / m.vol;
  const Mat3 central = m.second - m.vol * com * com.transpose();
  return central.trace() * Mat3::Identity() - central;
}

double rel_err_inertia(const Mat3& got, const Mat3& want) {
  return (got - want).norm() / want.norm();
}

/// A rotation taking the x axis to a generic direction, for shapes not aligned with the grid.
Quat generic_rotation() {
  return Quat(Eigen::AngleAxisd(0.7, Vec3(0.3, -0.5, 0.8).normalized())).normalized();
}

struct CollinearCase {
  const char* name;
  std::vector<double> c, r;
};

TEST(ClumpMass, CollinearSpheresMatchTheClosedFormAndConverge) {
  const std::vector<CollinearCase> cases = {
      {"two equal", {0.0, 1.2e-3}, {1e-3, 1e-3}},
      {"two unequal", {0.0, 1.1e-3}, {1e-3, 0.6e-3}},
      {"three, all overlapping", {-0.5e-3, 0.0, 0.6e-3}, {0.8e-3, 0.7e-3, 0.65e-3}},
      {"three in a row", {-1.2e-3, 0.0, 1.1e-3}, {0.7e-3, 0.8e-3, 0.6e-3}},
  };
  const Quat rot = generic_rotation();
  const Vec3 e = rot * Vec3::UnitX(), shift(3e-3, -2e-3, 1e-3);
  for (const CollinearCase& cs : cases) {
    const AxialMoments am = collinear_union(cs.c, cs.r);
    const Moments want = place(am, shift, e);
    const Mat3 want_inertia = inertia_of(want);
    std::vector<Vec3> centres;
    for (double s : cs.c) centres.push_back(shift + s * e);
    double prev_vol_err = 1.0, prev_inertia_err = 1.0;
    for (int cells : {256, 1024}) {
      const MassProperties mp = clump_mass_properties(centres, cs.r, {cells});
      const double vol_err = std::abs(mp.volume - want.vol) / want.vol;
      const double com_err = (mp.centre - want.first / want.vol).norm() / cs.r[0];
      const double inertia_err = rel_err_inertia(mp.inertia, want_inertia);
      std::printf("  %-24s cells %5d: volume %.2e, centre %.2e (of r), inertia %.2e\n", cs.name,
                  cells, vol_err, com_err, inertia_err);
      // The stated accuracy (sim/clump.hpp) at the default grid, and convergence towards it.
      if (cells == 1024) {
        EXPECT_LT(vol_err, 1e-6) << cs.name;
        EXPECT_LT(com_err, 1e-6) << cs.name;
        EXPECT_LT(inertia_err, 1e-6) << cs.name;
        EXPECT_LT(vol_err, prev_vol_err) << cs.name;
        EXPECT_LT(inertia_err, prev_inertia_err) << cs.name;
      }
      prev_vol_err = vol_err;
      prev_inertia_err = inertia_err;
    }
    // Not the sum of the spheres: the overlaps are counted once.
    double sum = 0.0;
    for (double r : cs.r) sum += 4.0 / 3.0 * std::numbers::pi * r * r * r;
    EXPECT_LT(want.vol, sum * (1.0 - 1e-3)) << cs.name;
  }
}

TEST(ClumpMass, TwoSpheresMatchTheLensVolume) {
  // Union = both spheres less the lens, V_lens = pi (R + r - d)^2 (d^2 + 2 d r - 3 r^2 + 2 d R +
  // 6 r R - 3 R^2) / (12 d) (the sphere-sphere intersection).
  const double big = 1e-3, small = 0.6e-3, d = 1.1e-3;
  const double lens =
      std::numbers::pi * std::pow(big + small - d, 2) *
      (d * d + 2 * d * small - 3 * small * small + 2 * d * big + 6 * small * big - 3 * big * big) /
      (12 * d);
  const double want =
      4.0 / 3.0 * std::numbers::pi * (big * big * big + small * small * small) - lens;
  const MassProperties mp =
      clump_mass_properties({Vec3(0, 0, 0), 1e-3 * Vec3(0.3, -0.9, std::sqrt(0.31))},
                            {big, small});  // |offset| = 1.1 mm
  EXPECT_NEAR(mp.volume / want, 1.0, 1e-6);
}

TEST(ClumpMass, TriangleOfThreeSpheresIsTheSpheresLessThreeLenses) {
  const std::vector<Vec3> c = {Vec3(0, 0, 0), Vec3(1.75e-3, 0, 0), Vec3(0.85e-3, 1.4e-3, 0.3e-3)};
  const std::vector<double> r = {1e-3, 0.9e-3, 0.8e-3};
  Moments want;
  for (std::size_t i = 0; i < 3; ++i) {
    const Moments s = place(collinear_union({0.0}, {r[i]}), c[i], Vec3::UnitX());
    want.vol += s.vol;
    want.first += s.first;
    want.second += s.second;
  }
  for (std::size_t i = 0; i < 3; ++i) {
    for (std::size_t j = i + 1; j < 3; ++j) {
      const Vec3 axis = c[j] - c[i];
      const double d = axis.norm();
      ASSERT_LT(d, r[i] + r[j]);
      // The lens lies within the ball through its rim circle; clear of the third sphere.
      const double s_plane = (d * d + r[i] * r[i] - r[j] * r[j]) / (2 * d);
      const double rim = std::sqrt(r[i] * r[i] - s_plane * s_plane);
      const std::size_t k = 3 - i - j;
      ASSERT_GT((c[i] + s_plane / d * axis - c[k]).norm(), r[k] + rim);
      // lens = sphere i + sphere j - their union, each from the axial closed form
      const AxialMoments u = collinear_union({0.0, d}, {r[i], r[j]});
      const AxialMoments si = collinear_union({0.0}, {r[i]});
      const AxialMoments sj = collinear_union({d}, {r[j]});
      AxialMoments lens{si.a0 + sj.a0 - u.a0, si.a1 + sj.a1 - u.a1, si.a2 + sj.a2 - u.a2,
                        si.b + sj.b - u.b};
      const Moments l = place(lens, c[i], axis / d);
      want.vol -= l.vol;
      want.first -= l.first;
      want.second -= l.second;
    }
  }
  const MassProperties mp = clump_mass_properties(c, r);
  EXPECT_NEAR(mp.volume / want.vol, 1.0, 1e-6);
  EXPECT_LT((mp.centre - want.first / want.vol).norm(), 1e-6 * r[0]);
  EXPECT_LT(rel_err_inertia(mp.inertia, inertia_of(want)), 1e-6);
}

TEST(ClumpMass, TemplateIsInItsPrincipalFrame) {
  // A dumbbell along a generic direction, and the triangle: in the template the centre of mass
  // is at the origin, the inertia tensor of the offsets' union is diagonal with I1 <= I2 <= I3,
  // and placing the template back with (centre, axes) gives the shape's own offsets.
  const Quat rot = generic_rotation();
  ClumpShape dumbbell{"dumbbell", {rot * Vec3(-0.5e-3, 0, 0), rot * Vec3(0.7e-3, 0, 0)},
                      {0.8e-3, 0.8e-3}};
  ClumpShape triangle{"triangle",
                      {Vec3(0, 0, 0), Vec3(1.75e-3, 0, 0), Vec3(0.85e-3, 1.4e-3, 0.3e-3)},
                      {1e-3, 0.9e-3, 0.8e-3}};
  for (const ClumpShape& shape : {dumbbell, triangle}) {
    const ClumpTemplate t = make_clump_template(shape);
    const MassProperties body = clump_mass_properties(t.offsets, t.radii);
    // (to the integration's accuracy: both tensors carry its error)
    EXPECT_LT(body.centre.norm(), 1e-6 * t.reach) << shape.name;
    const double scale = body.inertia.norm();
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(body.inertia(a, a), t.inertia[a], 1e-6 * scale) << shape.name;
      for (int b = 0; b < 3; ++b)
        if (a != b) EXPECT_NEAR(body.inertia(a, b), 0.0, 1e-6 * scale) << shape.name;
    }
    EXPECT_LE(t.inertia[0], t.inertia[1]);
    EXPECT_LE(t.inertia[1], t.inertia[2]);
    EXPECT_NEAR(t.axes.norm(), 1.0, 1e-12);
    EXPECT_GT(t.axes.toRotationMatrix().determinant(), 0.0);
    double reach = 0.0;
    for (std::size_t i = 0; i < t.size(); ++i) {
      EXPECT_LT((t.centre + t.axes * t.offsets[i] - shape.offsets[i]).norm(), 1e-12)
          << shape.name;
      reach = std::max(reach, t.offsets[i].norm() + t.radii[i]);
    }
    EXPECT_DOUBLE_EQ(t.reach, reach);
  }
  // The dumbbell's long axis is its axis of least inertia.
  const ClumpTemplate t = make_clump_template(dumbbell);
  EXPECT_NEAR(std::abs((t.axes * Vec3::UnitX()).dot(rot * Vec3::UnitX())), 1.0, 1e-9);
  // A single sphere: the closed form, exactly.
  const ClumpTemplate one = make_clump_template({"one", {Vec3(1e-3, 2e-3, 3e-3)}, {1e-3}});
  EXPECT_EQ(one.offsets[0], Vec3::Zero());
  EXPECT_EQ(one.inertia[0], one.inertia[2]);
  EXPECT_DOUBLE_EQ(one.volume, 4.0 / 3.0 * std::numbers::pi * 1e-9);
}

TEST(ClumpMass, BadShapesAreRefusedWithAClearMessage) {
  auto message = [](const ClumpShape& s) -> std::string {
    try {
      make_clump_template(s);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  const std::string zero = message({"flat", {Vec3(0, 0, 0), Vec3(1e-3, 0, 0)}, {1e-3, 0.0}});
  EXPECT_NE(zero.find("'flat'"), std::string::npos) << zero;
  EXPECT_NE(zero.find("component 1 radius = 0"), std::string::npos) << zero;
  const std::string negative = message({"neg", {Vec3(0, 0, 0)}, {-1e-3}});
  EXPECT_NE(negative.find("radius = -0.001"), std::string::npos) << negative;
  // Components 0-1 touch, 2 is apart: a body in pieces.
  const std::string pieces = message(
      {"pieces", {Vec3(0, 0, 0), Vec3(1.5e-3, 0, 0), Vec3(5e-3, 0, 0)}, {1e-3, 1e-3, 1e-3}});
  EXPECT_NE(pieces.find("component 2"), std::string::npos) << pieces;
  EXPECT_NE(pieces.find("in pieces"), std::string::npos) << pieces;
  EXPECT_NE(message({"empty", {}, {}}).find("no components"), std::string::npos);
  EXPECT_NE(message({"mismatch", {Vec3(0, 0, 0)}, {1e-3, 1e-3}}).find("1 offsets and 2 radii"),
            std::string::npos);
  // Touching at one point is one body.
  EXPECT_EQ(message({"touch", {Vec3(0, 0, 0), Vec3(2e-3, 0, 0)}, {1e-3, 1e-3}}), "");
}

}  // namespace
}  // namespace reposetwin::sim
