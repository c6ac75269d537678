// Small builders shared by the sim tests.
#pragma once

#include <cmath>

#include "sim/model.hpp"
#include "sim/random.hpp"
#include "sim/world.hpp"

namespace reposetwin::sim::testing {

/// One particle material ("rock", index 0) and one wall material ("steel", index 1); every pair
/// gets `pair`. No walls; gravity as given.
inline Model make_model(const PairParams& pair, double youngs = 46.8e6,
                        Vec3 gravity = Vec3(0, 0, -9.81)) {
  Model m;
  Material rock;
  rock.name = "rock";
  rock.density = 2760.0;
  rock.youngs_modulus = youngs;
  rock.poisson_ratio = 0.19;
  Material steel = rock;
  steel.name = "steel";
  m.materials = {rock, steel};
  m.set_pair(0, 0, pair);
  m.set_pair(0, 1, pair);
  m.set_pair(1, 1, pair);
  m.settings.gravity = gravity;
  return m;
}

inline WallSpec plate(double z = 0.0) {
  WallSpec w;
  w.name = "plate";
  w.kind = WallKind::kPlane;
  w.material = 1;
  w.point = Vec3(0, 0, z);
  w.normal = Vec3(0, 0, 1);
  return w;
}

inline PairParams frictionless(double e) {
  PairParams p;
  p.restitution = e;
  p.friction = 0.0;
  p.rolling_friction = 0.0;
  p.rolling_model = RollingModel::kNone;
  return p;
}

/// The funnel of the pours: a shell 30 mm tall, 10 mm across at its bottom, 30 mm at its top.
inline WallSpec pour_funnel() {
  WallSpec funnel;
  funnel.name = "funnel";
  funnel.kind = WallKind::kShell;
  funnel.material = 1;
  funnel.z_bottom = 0.0;
  funnel.z_top = 0.03;
  funnel.r_bottom = 0.005;
  funnel.r_top = 0.015;
  return funnel;
}

/// Calls place(x, k) for the first n sites (k = 0 .. n-1) of a 2.1 mm lattice inside
/// pour_funnel(), layer after layer: grains up to 2 mm across start without overlap.
template <class Place>
void for_each_funnel_site(int n, Place&& place) {
  int placed = 0;
  for (int layer = 0; placed < n; ++layer) {
    const double z = 0.0015 + 0.0021 * layer;
    const double r_in = 0.005 + (0.015 - 0.005) * z / 0.03 - 0.0011;
    for (int ix = -8; ix <= 8 && placed < n; ++ix)
      for (int iy = -8; iy <= 8 && placed < n; ++iy) {
        const Vec3 x(0.0021 * ix + 0.0002 * (layer % 2), 0.0021 * iy, z);
        if (std::hypot(x.x(), x.y()) > r_in) continue;
        place(x, placed++);
      }
  }
}

/// A small pour: polydisperse spheres (d 1-2 mm) on a lattice inside a conical funnel (wall 1,
/// 10-30 mm across, 30 mm high) standing on a plate (wall 0), released under gravity_z, every
/// contact with `pair` (default: the paper's e 0.79, mu_s 0.466, EPSD mu_r 0.15).
inline World funnel_pour(int n = 400, int parallel_min = 2000, double gravity_z = -9.81,
                         const PairParams& pair = PairParams{}) {
  Model m = make_model(pair, 46.8e6, Vec3(0, 0, gravity_z));
  m.walls.push_back(plate());
  m.walls.push_back(pour_funnel());
  m.settings.parallel_min_particles = parallel_min;
  m.finalize(0.5e-3, 1e-3);
  World w(m);
  Rng rng(42);
  for_each_funnel_site(
      n, [&](const Vec3& x, int) { w.add_particle(x, rng.uniform(0.5e-3, 1e-3), 0); });
  return w;
}

}  // namespace reposetwin::sim::testing
