// A synthetic pile for tests: a cone of spheres whose H, D and flank angle are known exactly.
// Shared by the pile-geometry tests (sim/) and the render-and-measure tests (experiments/).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "sim/particles.hpp"
#include "sim/random.hpp"

namespace reposetwin::test_support {

using sim::Rng;
using sim::Vec3;

inline constexpr double kConePi = 3.14159265358979323846;

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
inline void add_ring(Spheres& s, double cx, double cy, double rho, double z, double a, double spacing,
              Rng& rng, double inward = 0.0, double sin_t = 0.0, double cos_t = 0.0) {
  if (rho < 1e-12) {
    s.add(cx, cy, z, a);
    return;
  }
  const int n = std::max(1, static_cast<int>(std::ceil(2.0 * kConePi * rho / spacing)));
  const double phase = rng.uniform(0.0, 2.0 * kConePi);
  for (int k = 0; k < n; ++k) {
    const double phi = phase + 2.0 * kConePi * (k + (inward > 0.0 ? rng.uniform(-0.2, 0.2) : 0.0)) / n;
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
inline Spheres make_cone(double h, double big_r, double cx, double cy, double a, std::uint64_t seed,
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

}  // namespace reposetwin::test_support
