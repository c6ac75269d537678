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
//
// The field (`export --field dump`): the same writer, the same material block (types, E, nu, the
// pair tables, the contact and rolling law, the PSD templates, the settling rule), with the lab's
// container and lift replaced by a free dump: grains released at a mass rate from a cylinder at
// a height above a flat ground (the plate's material and contacts, the only ground the
// calibration knows), in a wide flat domain split over N ranks (`processors px py 1`). What
// changes is stated in a table (field_scaling): the grain size by a coarse-graining factor S,
// the time step recomputed by build_model at the scaled radii (the twin's Rayleigh fraction of
// the smallest grain's Rayleigh time, so dt grows as S), E kept (the mean overlap at the pile's
// base, estimated in closed form, grows with the pile's height and is compared with the lab's),
// mu_r kept with the epsd2 convention. Where S would break the calibration it says so in numbers:
// a pile fewer than kMinGrainsHigh grains high is refused (its angle is a few grains' stack, not
// the bulk the calibration measured), a factor above kWarnSizeScale is warned of.
#pragma once

#include <array>
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
  std::string input_name = "in.pile";  // the input script's file name ("in.dump" in the field)
  std::string input;       // the LIGGGHTS input script
  std::string funnel_stl;  // container.stl: the container's surface (ASCII STL) [m]; empty in
                           // the field (no container)
  std::string notes;       // README.md: what was carried, what was not, and mu_r conventions
  std::string initial_data;  // initial.data: the filled sample to start from; empty: the deck
                             // inserts and fills itself
  std::string scaling;                // the field's scaling table (text); empty for the lab
  std::vector<std::string> warnings;  // where the field's scaling strains the calibration
};

/// The calibration a deck carries, for its notes and its header: the record, the file it was
/// read from, and each calibrated key's value in the exported scene (the calibrated mu_r unless
/// a --set changed it).
struct DeckCalibration {
  const CalibratedMaterial* material = nullptr;
  std::string file;                                       // its calibration.json
  std::vector<std::pair<std::string, double>> deck_values;  // key -> value in the deck [-]
};

/// A pile fewer grains high than this is refused: its angle is that of a few grains' stack.
inline constexpr double kMinGrainsHigh = 10.0;
/// A coarse-graining factor above this is warned of (an assumption, see field_scaling).
inline constexpr double kWarnSizeScale = 3.0;
/// Coordination number assumed in the closed-form overlap estimate at the pile's base [-].
inline constexpr double kAssumedCoordination = 6.0;
/// Bulk solid fraction assumed for the pile's volume (a poured, settled heap) [-].
inline constexpr double kAssumedSolidFraction = 0.6;
/// A fall onto the pile faster than this is warned of: the lab's lifted funnel lets grains out
/// slower, and a dump's impacts flatten its pile (docs/calibration.md, "To the field"). The
/// lowest release the deck accepts, a grain above the pile's top with a release cylinder 4
/// grains high, already falls faster for grains above 2.5 mm: for them the warning stands [m/s].
inline constexpr double kWarnImpactSpeed = 0.5;

/// The free dump of the field deck (`export --field dump`): grains released from a vertical
/// cylinder above the domain's centre at a mass rate, forming a pile on a flat ground. Defaults
/// are a small verification size (for 3-4 mm rock: about 6,000 grains, a pile about 45 mm and
/// 12 grains high, a second of release); a field study gives its own. Errors name the
/// command-line option each field is set by.
struct FieldDumpSettings {
  double mass = 0.3;            // --dump-mass-kg: total mass released (simulated grains) [kg]
  double rate = 0.3;            // --dump-rate-kg-s: release rate [kg/s]
  double release_height = 0.1;  // --dump-height-m: the release cylinder's bottom above the
                                // ground [m]
  double release_radius = 0.0;  // --release-radius-m: its radius; 0: the smallest that holds
                                // one insertion's mass at the insertion volume fraction [m]
  double width = 0.3;           // --domain-width-m: the domain and ground along x [m]
  double length = 0.3;          // --domain-length-m: along y [m]
  double size_scale = 1.0;      // --size-scale: every grain's diameter times this [-]
  int ranks = 0;                // --ranks: MPI ranks of the run; 0: `processors * * 1` [-]
};

/// What the field deck scales and how, with the numbers that judge it (field_scaling).
struct FieldScaling {
  double size_scale = 1.0;          // S [-]
  double d_min_lab = 0, d_max_lab = 0, d_min = 0, d_max = 0;  // grain sizes [m]
  double d_mean = 0;                // mass-mean diameter in the deck [m]
  double dt_lab = 0, dt = 0;        // time steps (build_model at the lab's and the scaled radii) [s]
  double rayleigh_fraction = 0;     // dt / Rayleigh time of the smallest grain [-]
  double youngs_modulus = 0;        // E in both [Pa]
  double angle_deg = 0;             // the angle the pile's size is estimated at [deg]
  bool angle_calibrated = false;    // from the calibration's target (else an assumed 35 deg)
  double pile_height = 0, pile_diameter = 0;  // expected cone of the dump [m]
  double lab_pile_height = 0;       // expected cone of the lab test's sample [m]
  double grains_high = 0;           // pile_height / d_mean [-]
  double grains = 0;                // expected number of grains [-]
  double overlap_lab = 0, overlap = 0;  // mean overlap / radius at the pile's base (estimate) [-]
  double mu_r = 0;                  // the grains' rolling coefficient, epsd2 convention [-]
  double impact_speed = 0;          // a grain's speed falling from the release's top onto the
                                    // expected pile's top, sqrt(2 g (z_top - H)) [m/s]
  double release_radius = 0;        // the release cylinder's radius in use [m]
  double release_zone_height = 0;   // its height [m]
  long long insert_every = 0;       // steps between insertions [-]
  std::array<int, 3> grid{0, 0, 1};  // processors px py pz; 0 0: LIGGGHTS chooses [-]
  std::vector<std::string> warnings;
};

/// The scaling of a field dump of `scene`, or an InputError naming the option and the value for
/// a dump the deck cannot honestly write (a bad value, a pile too few grains high, a pile wider
/// than the ground, a release inside the pile). `calibration` may be null (a scene file).
FieldScaling field_scaling(const SceneConfig& scene, const FieldDumpSettings& dump,
                           const DeckCalibration* calibration);

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
  // The field: a free dump instead of the lab's pile test (no container, no initial state).
  // Null: the lab deck.
  const FieldDumpSettings* field_dump = nullptr;
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
