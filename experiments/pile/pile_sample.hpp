// The pile test's sample: drawing its grains, giving the engine their shapes, filling the
// container with them, and telling which grains are inside it.
//
// Design note. A grain is a sphere (a scene without shape keys: the engine's spheres, with the
// bits they always had) or a rigid clump of spheres (io/grain_shape.hpp). The sample is
// deterministic from the scene's seed: the PSD sampler draws the sieve sizes and shapes, then
// one uniformly random orientation per clump (Shoemake's uniform unit quaternion, from the same
// generator). Every clump is its shape's unit template scaled by its sieve size, so the model
// holds one template per grain, indexed by the grain's place in the draw; a resumed run draws
// the same sample from the seed and rebuilds the same templates, whose fingerprint
// (template_fingerprint) the run's controller keeps and checks. Mass properties scale exactly
// (sim::scale_clump_template): a shape's overlaps are integrated once, at parse time.
// The fill lattice is spaced by the largest grain's reach (its bounding sphere's diameter,
// d_max for spheres), so no two grains and no grain and the wall overlap however they turn.
// Everything the controller counts (inside the container, retained, kinetic energy per grain)
// is per grain: a clump is inside when its centre of mass is.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "experiments/io/scene.hpp"
#include "experiments/pile/pile_record.hpp"
#include "sim/psd.hpp"
#include "sim/world.hpp"

namespace reposetwin::experiments {

/// The sample as drawn: one entry per grain, in draw (and fill) order.
struct PileSample {
  std::vector<double> diameter;       // sieve size [m]
  std::vector<std::int32_t> shape;    // index into SceneConfig::shapes; empty for spheres
  std::vector<sim::Quat> orientation; // body to world; empty for spheres
  sim::PsdSummary summary;
  double r_min = 0.0, r_max = 0.0;    // smallest and largest sphere (component) radius [m]
};

/// Draws the scene's sample from its seed. Throws InputError for a PSD or mass it cannot draw.
PileSample draw_pile_sample(const SceneConfig& scene, int material);

/// Appends one clump template per grain of the sample to the model (none for spheres).
void add_grain_templates(sim::Model& model, const SceneConfig& scene, const PileSample& sample);

/// A hex FNV-1a of the model's clump templates (offsets, radii, volume, inertia; "" without).
std::string template_fingerprint(const sim::Model& model);

/// The model's walls (io/scene.hpp, build_model): wall 0 is the plate, wall 1 the container.
inline constexpr int kPlateWall = 0, kContainerWall = 1;

/// Places the sample on a loose staggered lattice inside the container, bottom up; above the
/// container's top the lattice continues in a column of the top's radius (it falls in).
void fill_container(sim::World& world, const SceneConfig& scene, const PileSample& sample,
                    int material);

/// Radius of the container's inside at height z_rel above its lower rim [m].
double container_radius(const ContainerConfig& c, double z_rel);

/// For each particle, whether its grain is inside the container (none when it is removed).
std::vector<char> inside_mask(const sim::World& world, const ContainerConfig& c);

/// Grains inside the container.
std::int64_t count_inside(const sim::World& world, const ContainerConfig& c);

/// The shapes of a clump sample as drawn, with the bodies and components as filled (the sample)
/// and in the world `st` now.
ShapeRecord shape_record(const SceneConfig& scene, const PileSample& sample, const sim::State& st);

/// Grains in the world: bodies when the sample is of clumps, else particles.
std::int64_t grain_count(const sim::State& st);

}  // namespace reposetwin::experiments
