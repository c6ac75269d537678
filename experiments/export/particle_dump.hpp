// Grains from another engine's output, measured by the twin's own pile measure.
//
// Design note. A LIGGGHTS (or LAMMPS) `dump custom` is a text file of snapshots, each headed by
// `ITEM: TIMESTEP`, `ITEM: NUMBER OF ATOMS` and `ITEM: ATOMS <column names>`. The last snapshot
// is read, by the column names x, y, z and radius (in any order, among others), so the same
// measure reads a pile whatever wrote it; a missing column, a short row or a number that is not
// finite is an InputError naming the file and the line.
#pragma once

#include <string>
#include <vector>

#include "sim/contact.hpp"

namespace reposetwin::experiments {

/// The last snapshot of a dump: centres [m] and radii [m], one per grain.
struct ParticleDump {
  long long timestep = 0;
  std::vector<sim::Vec3> x;
  std::vector<double> radius;
};

/// Reads the last snapshot of a LAMMPS/LIGGGHTS `dump custom` text file.
ParticleDump read_particle_dump(const std::string& path);

/// Reads another engine's dump, or a twin snapshot when the name ends in ".vtp" (timestep 0),
/// so that any frame of a run is measured as another engine's grains are. Throws InputError
/// naming the file.
ParticleDump read_particles(const std::string& path);

}  // namespace reposetwin::experiments
