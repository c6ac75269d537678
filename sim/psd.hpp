// Particle size distribution (PSD) from a sieve table, and drawing particle sizes from it.
//
// Design note. A user copies a lab sheet: sieve openings and the cumulative percent (by mass)
// passing each sieve. The paper's samples are scalped at d_max, and the fines below a declared
// cut-off d_min cannot be simulated, so a PsdSpec is the table plus these two cuts and a policy
// for the missing fines. Everything is resolved once into sieve intervals inside [d_min, d_max],
// each with its mass fraction (resolve_psd), which both the sampler and the reports use.
//
// Conventions (declared, since the paper gives none):
// - Between sieve sizes, the cumulative curve P(d) is interpolated linearly in d. This is only
//   used where d_min or d_max fall between two sieves.
// - Inside a sieve interval [a, b], diameters are drawn by number from a normal distribution
//   clipped to the interval, as the paper says EDEM does: mean (a + b) / 2, standard deviation
//   interval_sd_fraction * (b - a) (default 1/6, so the clip is at +-3 sd), clipping by rejection.
// - Interval masses follow the table: particles are drawn one at a time from the interval whose
//   drawn mass is furthest below its target (fraction * target mass), until the total drawn mass
//   reaches the target. Each interval then ends within one particle of its target, and the total
//   exceeds the target by less than the last particle's mass. The draw order interleaves sizes, so
//   a filling routine that inserts particles in this order does not segregate them by size.
// - Shaped grains (sample_psd_shapes): a grain's diameter is its sieve size, and its mass is its
//   shape's volume per cube of sieve size times d^3 times the density (the caller states how a
//   shape's sieve size is defined and computes that volume from the shape's true union). The
//   same greedy rule then runs over (interval, shape) cells, each with the target interval
//   fraction * shape fraction * mass, so every sieve class keeps its mass, every shape its mass
//   fraction, and every shape within every class both. One spherical shape of fraction 1 draws
//   exactly what sample_psd draws (sample_psd is that call).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "sim/random.hpp"

namespace reposetwin::sim {

/// A sieve table as copied from a lab sheet: sieve openings and cumulative percent passing.
struct SieveTable {
  std::vector<double> size;     // sieve openings, strictly increasing, > 0 [m]
  std::vector<double> passing;  // cumulative mass percent passing each sieve, in [0, 100],
                                // non-decreasing, 100 at the largest sieve [%]
};

/// What is done with the mass below d_min, which is not simulated.
enum class FinesPolicy {
  kRenormalise,  // the simulated particles carry the whole target mass, over [d_min, d_max]
  kDrop,         // the simulated mass is the target mass times the fraction above d_min
};

/// Returns "renormalise" or "drop".
std::string to_string(FinesPolicy policy);

/// A PSD to simulate: the table, the scalping size, the lower cut-off and the fines policy.
struct PsdSpec {
  SieveTable table;
  double d_max = 0.0;  // scalping size: larger material is removed and the curve renormalised to
                       // 100% at d_max; <= 0 means the largest sieve size [m]
  double d_min = 0.0;  // lower cut-off: finer material is not simulated; <= 0 means the smallest
                       // sieve size [m]
  FinesPolicy fines = FinesPolicy::kRenormalise;
  double interval_sd_fraction = 1.0 / 6.0;  // sd of the clipped normal per interval, as a
                                            // fraction of the interval width, in (0, 1] [-]
};

/// One sieve interval inside [d_min, d_max] with its share of the simulated mass.
struct PsdInterval {
  double lower = 0.0;          // smaller diameter [m]
  double upper = 0.0;          // larger diameter [m]
  double mass_fraction = 0.0;  // share of the simulated mass in this interval [-]
};

/// A PsdSpec resolved into intervals and the fractions it removes.
struct ResolvedPsd {
  double d_min = 0.0;                  // effective lower cut-off [m]
  double d_max = 0.0;                  // effective scalping size [m]
  std::vector<PsdInterval> intervals;  // in increasing size; fractions sum to 1
  double scalped_fraction = 0.0;       // mass fraction of the table's material above d_max, removed
                                       // by scalping: 1 - P(d_max) / 100 [-]
  double fines_fraction = 0.0;         // mass fraction of the scalped sample below d_min, which the
                                       // cut-off drops: P(d_min) / P(d_max) [-]
  double simulated_mass_factor = 1.0;  // simulated mass / target mass: 1 for "renormalise",
                                       // 1 - fines_fraction for "drop" [-]
  FinesPolicy fines = FinesPolicy::kRenormalise;
  double interval_sd_fraction = 1.0 / 6.0;  // as in PsdSpec [-]
};

/// Checks a sieve table; throws std::invalid_argument naming the field, index and value.
void validate_sieve_table(const SieveTable& table);

/// Cumulative percent passing [%] at diameter d [m], by linear interpolation between sieve sizes.
/// The table says nothing outside its sizes, so d must lie in [size.front(), size.back()]
/// (throws std::invalid_argument otherwise). The table must be valid.
double percent_passing(const SieveTable& table, double d);

/// Validates a spec and resolves it into intervals; throws std::invalid_argument on bad input
/// (bad table, d_max above the largest sieve, d_min below the smallest sieve, d_min >= d_max,
/// no material between d_min and d_max, sd fraction outside (0, 1]).
ResolvedPsd resolve_psd(const PsdSpec& spec);

/// Drawn mass of one interval, next to its target.
struct PsdIntervalSummary {
  double lower = 0.0;                 // [m]
  double upper = 0.0;                 // [m]
  double target_mass_fraction = 0.0;  // [-]
  double drawn_mass_fraction = 0.0;   // drawn mass in this interval / total drawn mass [-]
  std::size_t count = 0;              // particles drawn in this interval
};

/// What a sampling produced, for reports.
struct PsdSummary {
  double target_mass = 0.0;            // mass of the scalped sample asked for [kg]
  double simulated_target_mass = 0.0;  // target_mass * simulated_mass_factor [kg]
  double drawn_mass = 0.0;             // total mass of the drawn particles [kg]
  std::size_t count = 0;               // number of particles
  double d_min_drawn = 0.0;            // smallest diameter drawn [m]
  double d_max_drawn = 0.0;            // largest diameter drawn [m]
  double d_min = 0.0;                  // declared cut-off [m]
  double d_max = 0.0;                  // scalping size [m]
  double fines_fraction = 0.0;         // mass fraction below d_min, not simulated [-]
  double scalped_fraction = 0.0;       // mass fraction above d_max in the table's material [-]
  FinesPolicy fines = FinesPolicy::kRenormalise;
  std::vector<PsdIntervalSummary> intervals;
};

/// Particle diameters in draw order, with their summary.
struct PsdSample {
  std::vector<double> diameter;    // (n) [m]; for shaped grains, the sieve size
  std::vector<std::int32_t> shape; // (n) index into sample_psd_shapes' shapes; empty from
                                   // sample_psd
  PsdSummary summary;
};

/// A grain shape for sample_psd_shapes.
struct PsdShape {
  double volume_per_cube = 0.0;  // volume of a grain of sieve size d, divided by d^3 [-]
  double mass_fraction = 1.0;    // its share of the sample's mass [-]
  bool sphere = false;           // a sphere: its mass is computed as sample_psd's (same bits)
};

/// Draws particle diameters whose total mass matches target_mass [kg] (times the fines factor
/// for "drop") within one particle, for solid spheres of the given density [kg/m^3]. The result
/// depends only on the spec, the masses and the generator's state. Throws std::invalid_argument
/// for a bad spec or a non-positive mass or density.
PsdSample sample_psd(const PsdSpec& spec, double target_mass, double density, Rng& rng);

/// Draws grains of several shapes (design note): sieve sizes and shape indices whose masses
/// match target_mass within one grain. Throws std::invalid_argument for a bad spec, mass,
/// density, an empty shape list, a non-positive volume, or fractions that are negative or do not
/// sum to 1 within 1e-9.
PsdSample sample_psd_shapes(const PsdSpec& spec, double target_mass, double density,
                            const std::vector<PsdShape>& shapes, Rng& rng);

/// Expected number of particles sample_psd draws for this spec, mass [kg] and density [kg/m^3]:
/// the simulated mass of each interval divided by the mean sphere mass of its clipped normal
/// (computed by quadrature). For reports and for sizing containers.
double expected_particle_count(const PsdSpec& spec, double target_mass, double density);

/// Mean of d^3 [m^3] for the clipped normal of an interval [lower, upper] [m] with the given sd
/// fraction, by Simpson quadrature.
double clipped_normal_mean_cube(double lower, double upper, double sd_fraction);

}  // namespace reposetwin::sim
