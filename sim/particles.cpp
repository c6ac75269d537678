#include "sim/particles.hpp"

#include <cassert>

namespace reposetwin::sim {

void Particles::permute(const std::vector<std::size_t>& order) {
  assert(order.size() == size());
  // In place, one cycle of the permutation at a time. A rebuild's order is nearly the identity
  // (the particles were sorted at the last rebuild and have moved little since), so most
  // particles stay where they are, and nothing is allocated: fresh arrays on huge pages would
  // each cost page faults (bench/README.md).
  std::vector<char> placed(order.size(), 0);
  for (std::size_t s = 0; s < order.size(); ++s) {
    if (placed[s] || order[s] == s) continue;
    // Along the cycle s <- order[s] <- order[order[s]] <- ... <- s, each place takes the value
    // of the next before that one is overwritten.
#define REPOSETWIN_PERMUTE_FIELD(type, name, doc)                     \
  {                                                                   \
    type held = name[s];                                              \
    std::size_t i = s;                                                \
    for (; order[i] != s; i = order[i]) name[i] = name[order[i]];     \
    name[i] = held;                                                   \
  }
    REPOSETWIN_PARTICLE_FIELDS(REPOSETWIN_PERMUTE_FIELD)
#undef REPOSETWIN_PERMUTE_FIELD
    for (std::size_t i = s; !placed[i]; i = order[i]) placed[i] = 1;
  }
}

void Particles::keep(const std::vector<char>& flags) {
  assert(flags.size() == size());
  std::vector<std::size_t> order;
  order.reserve(size());
  for (std::size_t i = 0; i < flags.size(); ++i)
    if (flags[i]) order.push_back(i);
#define REPOSETWIN_KEEP_FIELD(type, name, doc)                                \
  {                                                                           \
    HugeVector<type> tmp(order.size());                                       \
    for (std::size_t i = 0; i < order.size(); ++i) tmp[i] = name[order[i]];   \
    name.swap(tmp);                                                           \
  }
  REPOSETWIN_PARTICLE_FIELDS(REPOSETWIN_KEEP_FIELD)
#undef REPOSETWIN_KEEP_FIELD
}

std::size_t Particles::add(const Vec3& position, double r, double density, std::int32_t mat,
                           std::int64_t pid) {
  const double m = sphere_mass(density, r);
  const std::size_t i = size();
  resize(i + 1);  // every field of the list grows; those not set below are value-initialised
  x[i] = position;
  v[i].setZero();
  w[i].setZero();
  force[i].setZero();
  torque[i].setZero();
  radius[i] = r;
  mass[i] = m;
  inertia[i] = 0.4 * m * r * r;
  material[i] = mat;
  id[i] = pid;
  wall_history[i] = WallHistory{};
  body[i] = -1;
  component[i] = -1;
  return i;
}

}  // namespace reposetwin::sim
