// The container of a pile test: its inside as a function of height, the loose lattice the sample
// is placed on inside it, and which particles are still inside.
//
// Design note. These are the geometry the pile controller (pile_run.cpp) asks about in its
// phases: the fill places the sample, the lift watches the count inside to tell flowing from
// lodged. They are plain functions of the scene's ContainerConfig and the world's state, kept
// apart from the controller so its file reads as the phases only. Wall 0 of the model is the
// plate and wall 1 the container (io/scene.hpp, build_model).
#pragma once

#include <cstdint>
#include <vector>

#include "experiments/io/scene.hpp"
#include "sim/world.hpp"

namespace reposetwin::experiments {

inline constexpr int kPlateWall = 0, kContainerWall = 1;

/// Radius of the container's inside at height z above its lower rim [m].
double container_radius(const ContainerConfig& c, double z_rel);

/// Places the sample on a loose square lattice inside the container, bottom up; above the
/// container's top the lattice continues in a column of the top's radius (it falls in).
void fill_container(sim::World& world, const SceneConfig& scene,
                    const std::vector<double>& diameters, int material);

/// Which particles are inside the container (none when it is removed).
std::vector<char> inside_mask(const sim::World& world, const ContainerConfig& c);

/// How many particles are inside the container.
std::int64_t count_inside(const sim::World& world, const ContainerConfig& c);

}  // namespace reposetwin::experiments
