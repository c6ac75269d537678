// Rigid bodies (clumps) as a struct of arrays whose field list is written once.
//
// Design note. A clump's component spheres are ordinary particles (sim/particles.hpp) that carry
// the index of their body and their place in its template; the neighbor list, the contact kernels
// and the walls see only particles. What is the body's own, its centre of mass, orientation,
// momenta and the sums of its components' forces, lives here, one entry per body. The bodies are
// reordered with the particles at each neighbor-list build, by the place of their first component
// in the particle arrays (World::order_bodies), so that the bodies' phases walk the particle
// arrays in order rather than at random; ids stay.
// REPOSETWIN_BODY_FIELDS names every per-body array once; resizing, compaction and checkpoints
// iterate it (as REPOSETWIN_PARTICLE_FIELDS). The components of each body are found through
// BodyComponents, derived from the particles after every reordering.
#pragma once

#include <cstdint>
#include <vector>

#include "sim/clump.hpp"
#include "sim/huge_pages.hpp"
#include "sim/particles.hpp"

namespace reposetwin::sim {

// X(type, name, unit and meaning)
#define REPOSETWIN_BODY_FIELDS(X)                                                          \
  X(Vec3, x, "centre of mass [m]")                                                         \
  X(Quat, q, "orientation, a unit quaternion taking the body frame to the world frame")    \
  X(Vec3, v, "velocity of the centre of mass [m/s]")                                       \
  X(Vec3, w, "angular velocity, world frame [rad/s]")                                      \
  X(Vec3, l, "angular momentum about the centre of mass, world frame [kg m^2/s]")          \
  X(Vec3, force, "sum of the components' forces this step, gravity once [N]")              \
  X(Vec3, torque, "sum of the components' torques about the centre of mass [N m]")         \
  X(double, mass, "mass [kg]")                                                             \
  X(Vec3, inertia, "principal moments of inertia I1 <= I2 <= I3 [kg m^2]")                 \
  X(std::int32_t, shape, "template index into Model::clumps")                              \
  X(std::int32_t, material, "material index into Model::materials")                        \
  X(std::int64_t, id, "stable body id, unchanged by removals")

/// Per-body arrays, all of the same length.
struct Bodies {
#define REPOSETWIN_DECLARE_BODY_FIELD(type, name, doc) HugeVector<type> name;  // doc
  REPOSETWIN_BODY_FIELDS(REPOSETWIN_DECLARE_BODY_FIELD)
#undef REPOSETWIN_DECLARE_BODY_FIELD

  std::size_t size() const { return x.size(); }

  void resize(std::size_t n) {
#define REPOSETWIN_RESIZE_BODY_FIELD(type, name, doc) name.resize(n);
    REPOSETWIN_BODY_FIELDS(REPOSETWIN_RESIZE_BODY_FIELD)
#undef REPOSETWIN_RESIZE_BODY_FIELD
  }

  /// Keeps the bodies whose flag is true, in order.
  void keep(const std::vector<char>& flags);

  /// Reorders every field by `order` (new index k takes old index order[k]).
  void permute(const std::vector<std::int32_t>& order);

  /// A spherical top (I1 = I2 = I3 exactly, a one-sphere clump): its angular velocity is its
  /// state and it is kicked as a sphere, w += dt/2 T / I, which keeps a one-sphere clump's
  /// trajectory bit-identical to the sphere's. Any other body carries its angular momentum.
  bool spherical(std::size_t b) const {
    return inertia[b].x() == inertia[b].y() && inertia[b].y() == inertia[b].z();
  }
};

/// For each body, its components' particle indices in template order (CSR): body b's are
/// particle[start[b] .. start[b + 1]). Derived from Particles::body and Particles::component.
struct BodyComponents {
  std::vector<std::int32_t> start;     // (bodies + 1)
  std::vector<std::int32_t> particle;  // (components)

  bool indexed_for(std::size_t bodies) const { return start.size() == bodies + 1; }
};

/// Derives `bc` from the particles' body and component fields. Throws std::logic_error if a
/// body's components are not exactly 0 .. k-1.
void index_body_components(const Particles& p, std::size_t bodies, BodyComponents& bc);

}  // namespace reposetwin::sim
