#include "experiments/pile/pile_sample.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "experiments/io/hash.hpp"
#include "experiments/io/input_error.hpp"
#include "sim/random.hpp"

namespace reposetwin::experiments {

namespace {

// A uniformly distributed rotation (Shoemake 1992, Graphics Gems III, "Uniform random
// rotations"): three uniforms give a unit quaternion uniform on the 3-sphere.
sim::Quat random_orientation(sim::Rng& rng) {
  const double u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform();
  const double a = std::sqrt(1.0 - u1), b = std::sqrt(u1);
  const double t2 = 2.0 * std::numbers::pi * u2, t3 = 2.0 * std::numbers::pi * u3;
  return sim::Quat(b * std::cos(t3), a * std::sin(t2), a * std::cos(t2), b * std::sin(t3));
}

// The reach of grain g: its bounding sphere's radius about its centre [m].
double grain_reach(const SceneConfig& scene, const PileSample& sample, std::size_t g) {
  if (sample.shape.empty()) return 0.5 * sample.diameter[g];
  return scene.shapes[static_cast<std::size_t>(sample.shape[g])].unit.reach * sample.diameter[g];
}

}  // namespace

PileSample draw_pile_sample(const SceneConfig& scene, int material) {
  sim::Rng rng(scene.seed);
  const double density = scene.materials[static_cast<std::size_t>(material)].density;
  sim::PsdSample drawn;
  try {
    if (scene.shapes.empty()) {
      drawn = sim::sample_psd(scene.psd.spec, scene.mass, density, rng);
    } else {
      std::vector<sim::PsdShape> shapes;
      for (const GrainShape& g : scene.shapes)
        shapes.push_back({g.volume_per_cube(), g.mass_fraction, g.sphere()});
      drawn = sim::sample_psd_shapes(scene.psd.spec, scene.mass, density, shapes, rng);
    }
  } catch (const std::invalid_argument& e) {
    throw InputError(scene.file + ": sample: " + e.what());
  }
  PileSample s;
  s.diameter = std::move(drawn.diameter);
  s.summary = drawn.summary;
  if (scene.shapes.empty()) {
    s.r_min = 0.5 * s.summary.d_min_drawn;
    s.r_max = 0.5 * s.summary.d_max_drawn;
    return s;
  }
  s.shape = std::move(drawn.shape);
  s.orientation.reserve(s.diameter.size());
  for (std::size_t g = 0; g < s.diameter.size(); ++g) s.orientation.push_back(random_orientation(rng));
  s.r_min = std::numeric_limits<double>::infinity();
  for (std::size_t g = 0; g < s.diameter.size(); ++g) {
    for (double r : scene.shapes[static_cast<std::size_t>(s.shape[g])].unit.radii) {
      s.r_min = std::min(s.r_min, r * s.diameter[g]);
      s.r_max = std::max(s.r_max, r * s.diameter[g]);
    }
  }
  return s;
}

void add_grain_templates(sim::Model& model, const SceneConfig& scene, const PileSample& sample) {
  model.clumps.reserve(model.clumps.size() + sample.shape.size());
  for (std::size_t g = 0; g < sample.shape.size(); ++g)
    model.clumps.push_back(sim::scale_clump_template(
        scene.shapes[static_cast<std::size_t>(sample.shape[g])].unit, sample.diameter[g]));
}

std::string template_fingerprint(const sim::Model& model) {
  if (model.clumps.empty()) return "";
  std::string bytes;
  auto put = [&bytes](const double* v, std::size_t n) {
    bytes.append(reinterpret_cast<const char*>(v), n * sizeof(double));
  };
  for (const sim::ClumpTemplate& t : model.clumps) {
    for (const sim::Vec3& o : t.offsets) put(o.data(), 3);
    put(t.radii.data(), t.radii.size());
    put(&t.volume, 1);
    put(t.inertia.data(), 3);
  }
  return fnv1a_hex(bytes);
}

double container_radius(const ContainerConfig& c, double z_rel) {
  const double t = std::clamp(z_rel / c.height, 0.0, 1.0);
  return 0.5 * (c.bottom_diameter + t * (c.top_diameter - c.bottom_diameter));
}

void fill_container(sim::World& world, const SceneConfig& scene, const PileSample& sample,
                    int material) {
  const std::size_t n = sample.diameter.size();
  double reach_max = 0.0;
  for (std::size_t g = 0; g < n; ++g) reach_max = std::max(reach_max, grain_reach(scene, sample, g));
  // (For spheres 2 * (d_max / 2) is d_max exactly: the lattice of the sphere engine.)
  const double s = 2.0 * reach_max * (1.0 + scene.procedure.lattice_gap);
  const ContainerConfig& c = scene.container;
  // Clearance from a slanted wall, measured horizontally: (s/2) / cos(wall slant).
  const double slope = 0.5 * (c.top_diameter - c.bottom_diameter) / c.height;
  const double secant = std::sqrt(1.0 + slope * slope);  // 1 / cos(wall slant)
  const double clearance = 0.5 * s * secant;
  // The jitter's own stream, so that the PSD draw and the orientations stay those of the seed.
  sim::Rng rng(scene.seed ^ 0x6a09e667f3bcc909ULL);
  const double jitter = scene.procedure.fill_jitter;
  // Grain g at lattice point p, moved by up to jitter x its room in the cell on each axis. The
  // grain stays inside its own cube of side s (cubes of a staggered layer and of the layers
  // s apart do not overlap, so grains do not), and above the plate. A horizontal move that
  // would take it nearer the slanted wall than its reach is dropped: the lattice point itself
  // keeps that clearance for every grain and any vertical move within the cube.
  auto place = [&](sim::Vec3 at, std::size_t g) {
    if (jitter <= 0.0) return at;
    const double reach = grain_reach(scene, sample, g);
    const double room = jitter * std::max(0.0, 0.5 * s - reach);
    const double dx = rng.uniform(-room, room), dy = rng.uniform(-room, room);
    const double dz = rng.uniform(-room, room);
    at.z() += dz;
    const double z_rel = at.z() - c.gap;
    const double r_wall =
        std::min(container_radius(c, z_rel - reach), container_radius(c, z_rel + reach)) -
        reach * secant;
    if (std::hypot(at.x() + dx, at.y() + dy) <= r_wall) {
      at.x() += dx;
      at.y() += dy;
    }
    return at;
  };
  std::size_t next = 0;
  for (int level = 0; next < n; ++level) {
    const double z_rel = 0.5 * s + level * s;
    const double r_avail = container_radius(c, z_rel) - clearance;
    if (level > 100000) throw std::logic_error("fill_container: runaway lattice");
    if (r_avail <= 0.0) continue;
    const int k = static_cast<int>(std::floor(r_avail / s));
    const double shift = (level % 2) ? 0.5 * s : 0.0;  // staggered layers
    for (int ix = -k - 1; ix <= k && next < n; ++ix) {
      for (int iy = -k - 1; iy <= k && next < n; ++iy) {
        const double x = ix * s + shift, y = iy * s + shift;
        if (std::hypot(x, y) > r_avail) continue;
        const sim::Vec3 at = place(sim::Vec3(x, y, c.gap + z_rel), next);
        if (sample.shape.empty())
          world.add_particle(at, 0.5 * sample.diameter[next], material);
        else  // grain g's template is model clump g
          world.add_clump(static_cast<int>(next), at, sample.orientation[next], material);
        ++next;
      }
    }
  }
}

std::vector<char> inside_mask(const sim::World& world, const ContainerConfig& c) {
  const sim::State& st = world.state();
  const sim::Particles& p = st.particles;
  std::vector<char> in(p.size(), 0);
  if (!st.walls[kContainerWall].enabled) return in;
  const double z0 = c.gap + st.walls[kContainerWall].offset.z();
  for (std::size_t i = 0; i < in.size(); ++i) {
    const sim::Vec3& x = p.body[i] >= 0 ? st.bodies.x[static_cast<std::size_t>(p.body[i])] : p.x[i];
    const double z_rel = x.z() - z0;
    if (z_rel < 0.0 || z_rel > c.height) continue;
    in[i] = std::hypot(x.x(), x.y()) < container_radius(c, z_rel);
  }
  return in;
}

std::int64_t count_inside(const sim::World& world, const ContainerConfig& c) {
  const std::vector<char> in = inside_mask(world, c);
  const sim::Particles& p = world.state().particles;
  std::int64_t n = 0;
  for (std::size_t i = 0; i < in.size(); ++i)  // a clump once, by its first component
    n += in[i] && p.component[i] <= 0;
  return n;
}

ShapeRecord shape_record(const SceneConfig& scene, const PileSample& sample, const sim::State& st) {
  ShapeRecord r;
  r.sieve_convention =
      "a clump of principal extents L >= I >= S has sieve size I (its intermediate extent "
      "passes the square opening); its mass is the volume of the union of its spheres times "
      "the density";
  std::vector<double> mass(scene.shapes.size(), 0.0);
  double total = 0.0;
  for (const GrainShape& g : scene.shapes) {
    GrainShapeRecord gr;
    gr.name = g.name;
    gr.kind = g.kind;
    gr.target_mass_fraction = g.mass_fraction;
    gr.components = static_cast<int>(g.unit.size());
    gr.elongation = g.elongation;
    gr.flatness = g.flatness;
    gr.roundness = g.roundness;
    gr.angularity = g.angularity;
    gr.measured_elongation = g.longest / g.intermediate;
    gr.measured_flatness = g.intermediate / g.shortest;
    gr.volume_per_cube = g.volume_per_cube();
    gr.outlet_diameter = g.outlet_diameter;
    r.shapes.push_back(gr);
  }
  for (std::size_t g = 0; g < sample.shape.size(); ++g) {
    const auto k = static_cast<std::size_t>(sample.shape[g]);
    const double d = sample.diameter[g];
    mass[k] += scene.shapes[k].volume_per_cube() * d * d * d;
    total += scene.shapes[k].volume_per_cube() * d * d * d;
    r.shapes[k].count += 1;
    r.components_initial += static_cast<std::int64_t>(scene.shapes[k].unit.size());
  }
  for (std::size_t k = 0; k < mass.size(); ++k)
    r.shapes[k].drawn_mass_fraction = total > 0 ? mass[k] / total : 0.0;
  r.bodies_initial = static_cast<std::int64_t>(sample.shape.size());
  r.bodies_final = static_cast<std::int64_t>(st.bodies.size());
  r.components_final = static_cast<std::int64_t>(st.particles.size());
  return r;
}

std::int64_t grain_count(const sim::State& st) {
  return static_cast<std::int64_t>(st.bodies.size() > 0 ? st.bodies.size() : st.particles.size());
}

}  // namespace reposetwin::experiments
