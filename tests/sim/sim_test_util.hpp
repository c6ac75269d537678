// Small builders shared by the sim tests.
#pragma once

#include "sim/model.hpp"
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

}  // namespace reposetwin::sim::testing
