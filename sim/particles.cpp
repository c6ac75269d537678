#include "sim/particles.hpp"

#include <cassert>

namespace reposetwin::sim {

void Particles::permute(const std::vector<std::size_t>& order) {
  assert(order.size() == size());
#define REPOSETWIN_PERMUTE_FIELD(type, name, doc)                             \
  {                                                                           \
    HugeVector<type> tmp(order.size());                                       \
    for (std::size_t i = 0; i < order.size(); ++i) tmp[i] = name[order[i]];   \
    name.swap(tmp);                                                           \
  }
  REPOSETWIN_PARTICLE_FIELDS(REPOSETWIN_PERMUTE_FIELD)
#undef REPOSETWIN_PERMUTE_FIELD
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
  const double m = density * 4.0 / 3.0 * 3.14159265358979323846 * r * r * r;
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
  return i;
}

}  // namespace reposetwin::sim
