// The calibrated material, taken to the field: a scene written as a LIGGGHTS 3.8 input deck.
//
// Design note. A user calibrates on a lab pile to simulate a stope, a dump or a chute with
// millions of grains, on a cluster, in the engine they run there; LIGGGHTS' own domain
// decomposition (mpirun) is how they outgrow one machine, not ours. So the deck carries the
// physics exactly where the two engines share a law, and says where they do not:
//  * Hertz normal and Mindlin tangential springs with history (`model hertz tangential
//    history`), the same E, nu, e and mu_s per material pair. The stiffness is the scene's
//    softened E for every material, as ours (numerics.softened_youngs_modulus_pa), with
//    `soft_particles yes` (LIGGGHTS refuses E below 5 MPa without it).
//  * Rolling: our `epsd` is Ai et al.'s type C with k_r = k_t R*^2 and the cap mu_r |F_n| R*,
//    which is LIGGGHTS' `epsd2` (Iwashita and Oda's stiffness); `epsd2` has no rolling dashpot,
//    so a scene's rolling_damping eta_r > 0 is not carried (the notes say so, with its value).
//    Our `cdt` uses each body's own w and lever arm (EDEM Standard); LIGGGHTS' `cdt` uses
//    w_i - w_j and R* (sim/contact.hpp), a documented difference of law.
//  * The PSD: one particletemplate/sphere per sieve interval inside [d_min, d_max], of the
//    interval's middle diameter, mixed by the interval's mass fraction
//    (particledistribution/discrete/massbased); ours draws a clipped normal inside each interval,
//    so the two PSDs share every interval's mass and mean size.
//  * The container as an STL mesh (mesh/surface, the same frustum as our shell wall), lifted
//    with move/mesh at the scene's speed; the plate as a z-plane primitive.
//  * The procedure: insert the sample inside the container (and a column above it when the
//    container alone cannot hold it at a random-insertion volume fraction of 0.3), let it fall
//    and settle (until the kinetic energy is below the twin's threshold, or for at most
//    procedure.fill_settle_max), lift the container by its own height
//    (its rim then stands above any pile it could hold), settle likewise (procedure.final_settle_max), and dump
//    the grains (id type x y z radius) to final.dump, which `reposetwin measure-particles` reads
//    with our pile measure.
// With an initial state (the twin's filled sample), the insertion is replaced by read_data and
// the rest is unchanged: the fill and the sizes inside a sieve interval are then the twin's, so a
// difference that remains is in the pour's dynamics (the contact laws, the walls, the integrator).
// Clumps are not exported yet (LIGGGHTS' multisphere templates would carry them): a scene with
// grain shapes is refused with that reason.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "experiments/io/calibration_record.hpp"
#include "experiments/io/scene.hpp"
#include "experiments/io/vtk_output.hpp"

namespace reposetwin::experiments {

/// The files of a deck, as text.
struct LiggghtsDeck {
  std::string input;       // in.pile: the LIGGGHTS input script
  std::string funnel_stl;  // container.stl: the container's surface (ASCII STL) [m]
  std::string notes;       // README.md: what was carried, what was not, and mu_r conventions
  std::string initial_data;  // initial.data: the filled sample to start from; empty: the deck
                             // inserts and fills itself
};

/// The calibration a deck carries, for its notes and its header: the record, the file it was
/// read from, and each calibrated key's value in the exported scene (the calibrated mu_r unless
/// a --set changed it).
struct DeckCalibration {
  const CalibratedMaterial* material = nullptr;
  std::string file;                                       // its calibration.json
  std::vector<std::pair<std::string, double>> deck_values;  // key -> value in the deck [-]
};

/// Settings of the deck that the scene does not hold.
struct LiggghtsDeckSettings {
  std::uint64_t seed = 1;           // LIGGGHTS' random seeds derive from it (primes > 10000)
  int facets = 64;                  // facets around the container's circumference [-]
  double insert_volume_fraction = 0.3;  // random insertion packs at most this [-]
  // The twin's sample as filled (a run's frames/filled.vtp): the deck reads it (read_data) and
  // starts at the lift, so the two engines compare the pour from one state. Null: the deck
  // inserts at random and lets the sample fall and settle.
  const SnapshotParticles* initial_state = nullptr;
  // The calibration the scene was rebuilt from (`export CAL_FOLDER`): the deck states the
  // calibrated value and its interval. Null: a scene file exported as it is.
  const DeckCalibration* calibration = nullptr;
};

/// Writes the deck of a scene. Throws InputError naming the scene file and the key for what
/// LIGGGHTS cannot run: grain shapes, a cylinder or funnel of zero size.
LiggghtsDeck liggghts_deck(const SceneConfig& scene, const LiggghtsDeckSettings& settings = {});

/// The rolling coefficient of our epsd (lever arm R*) in other engines' conventions, for equal
/// spheres: LIGGGHTS epsd2 and LAMMPS granular `rolling sds` use R* too (the same number); EDEM's
/// models use each body's own radius R = 2 R* for equal spheres, so mu_r,EDEM = mu_r / 2.
struct RollingConventions {
  double ours = 0.0, liggghts = 0.0, lammps = 0.0, edem = 0.0;
};
RollingConventions rolling_conventions(double mu_r_epsd);

}  // namespace reposetwin::experiments
