#include "experiments/pile/container.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace reposetwin::experiments {

double container_radius(const ContainerConfig& c, double z_rel) {
  const double t = std::clamp(z_rel / c.height, 0.0, 1.0);
  return 0.5 * (c.bottom_diameter + t * (c.top_diameter - c.bottom_diameter));
}

void fill_container(sim::World& world, const SceneConfig& scene,
                    const std::vector<double>& diameters, int material) {
  double d_max = 0.0;
  for (double d : diameters) d_max = std::max(d_max, d);
  const double s = d_max * (1.0 + scene.procedure.lattice_gap);
  const ContainerConfig& c = scene.container;
  // Clearance from a slanted wall, measured horizontally: (s/2) / cos(wall slant).
  const double slope = 0.5 * (c.top_diameter - c.bottom_diameter) / c.height;
  const double clearance = 0.5 * s * std::sqrt(1.0 + slope * slope);
  std::size_t next = 0;
  for (int level = 0; next < diameters.size(); ++level) {
    const double z_rel = 0.5 * s + level * s;
    const double r_avail = container_radius(c, z_rel) - clearance;
    if (level > 100000) throw std::logic_error("fill_container: runaway lattice");
    if (r_avail <= 0.0) continue;
    const int k = static_cast<int>(std::floor(r_avail / s));
    const double shift = (level % 2) ? 0.5 * s : 0.0;  // staggered layers
    for (int ix = -k - 1; ix <= k && next < diameters.size(); ++ix) {
      for (int iy = -k - 1; iy <= k && next < diameters.size(); ++iy) {
        const double x = ix * s + shift, y = iy * s + shift;
        if (std::hypot(x, y) > r_avail) continue;
        world.add_particle(sim::Vec3(x, y, c.gap + z_rel), 0.5 * diameters[next++], material);
      }
    }
  }
}

std::vector<char> inside_mask(const sim::World& world, const ContainerConfig& c) {
  const sim::State& st = world.state();
  std::vector<char> in(st.particles.size(), 0);
  if (!st.walls[kContainerWall].enabled) return in;
  const double z0 = c.gap + st.walls[kContainerWall].offset.z();
  for (std::size_t i = 0; i < in.size(); ++i) {
    const sim::Vec3& x = st.particles.x[i];
    const double z_rel = x.z() - z0;
    if (z_rel < 0.0 || z_rel > c.height) continue;
    in[i] = std::hypot(x.x(), x.y()) < container_radius(c, z_rel);
  }
  return in;
}

std::int64_t count_inside(const sim::World& world, const ContainerConfig& c) {
  const std::vector<char> in = inside_mask(world, c);
  return std::count(in.begin(), in.end(), 1);
}

}  // namespace reposetwin::experiments
