// The candidate effects of the loop: one registry table, one row per effect the base model
// (calibrated mu_r only) may lack.
//
// Design note. Each candidate is a real switch of the twin, never a fitted curve: a physics
// effect sets one scene key (engine) and is simulated; a measurement effect changes how the pile
// is photographed (render) and measured (vision), so its fingerprint re-photographs the baseline's
// piles without new simulations. Each row has an off value (the base model), a probe value (used
// for the fingerprint: large enough to stand out of the seed noise, inside the literature's range
// from REFERENCES.md "Closing the loop"), the parameter's allowed range, and how the value is
// applied: set as is, or as a factor on the test's declared value (lift speed, fines cut-off).
// A row whose scene key this engine build does not know (an effect not yet in sim/) is reported
// as unavailable by the loop, not silently dropped.
//
// Size-dependent rolling resistance, mu_r,eff = mu_r (d / d_ref)^alpha, takes d_ref from the data:
// the typical grain of the calibration tests (reference_grain_diameter), not a fixed size. With
// a fixed d_ref far from the sample's sizes (5 mm for 2.5-4.5 mm grains) alpha also rescales
// every contact's mu_r, so switching it on at its probe mostly moves mu_r (into the flat part of
// the angle's response when mu_r is already low) and its fingerprint loses the size pattern that
// tells it from mu_r; and mu_r's meaning changes with alpha, so the joint refit of (mu_r, alpha)
// may need a mu_r outside the calibrated grid. With d_ref at the typical grain, mu_r stays the
// typical grain's rolling friction and alpha only tilts it between fine and coarse grains.
//
// The camera's pose (`camera_pose`, opt-in) is how a person holds a camera: raised by h and
// pitched down to aim at the pile's axis foot, pitch atan(h / L) at horizontal distance L, while
// the lab declares it level. `camera_height` is the same height held level. Vision reads the
// pitch from the pile's base ellipse (vision/camera_pose.hpp) and refuses a photo whose pitch
// contradicts the declared one by more than 3 deg, so beyond a few degrees its probe reports
// the candidate unavailable with vision's numbers rather than a fingerprint. Opt-in until the
// synthetic loop tests have been run with it beside camera_height, whose fingerprint it nears
// at small pitches.
//
// Grain shape (`grain_shape`, opt-in) is the paper's own candidate for what spheres lack: every
// grain becomes a generated clump (io/grain_shape.hpp) of a fixed number of spheres in a row,
// and the one parameter is its elongation L/I (off: spheres, the base model; at L/I = 1 the
// rod's spheres coincide into one round grain, so the refit's line from off to the simulated
// value runs along the family). A scene that declares its own shapes cannot take it.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "experiments/loop/loop_data.hpp"
#include "experiments/loop/loop_sim.hpp"

namespace reposetwin::experiments {

enum class EffectKind { kPhysics, kMeasurement };

/// How a candidate's value reaches the test.
enum class EffectApply {
  kSetScene,     // scene key = value
  kFactorScene,  // scene key = value x the test's resolved value of that key
  kImageHeight,  // true camera height = value [m] (the lab declares its own, default level)
  kImageK1,      // true lens distortion k1 = value (the lab declares 0)
  kImagePose,    // true camera raised by value [m] and pitched down at the axis foot, declared
                 // level (a person's hold): pitch atan(value / distance)
  kShape,        // every grain a generated clump of kShapeSpheres spheres, elongation = value
};

/// The grain_shape candidate's sphere count: the family varies elongation L/I at a fixed
/// number of spheres per grain, so one parameter moves and the cost per grain stays the same.
inline constexpr int kShapeSpheres = 4;

/// One row of the registry.
struct CandidateEffect {
  std::string name;         // short id ("plate_friction")
  EffectKind kind = EffectKind::kPhysics;
  EffectApply apply = EffectApply::kSetScene;
  std::string key;          // scene key (physics) or image setting (measurement)
  double off = 0.0;         // value of the base model; for a kSetScene row with off_from_scene,
                            // the scene's own value is used
  bool off_from_scene = false;  // the off value is the test scene's value of `key`
  double probe = 0.0;       // value for the fingerprint
  double lo = 0.0;          // allowed range of the fitted value
  double hi = 0.0;
  std::string units;        // of the value
  std::string description;  // one sentence
  /// Extra keys set together with `key` whenever the effect is on (e.g. the reference size);
  /// the value "{d_ref}" stands for the test's reference_diameter_m [m].
  std::vector<std::pair<std::string, std::string>> companions = {};
  /// Tried only when named (--candidates): its simulations cost several times a sphere
  /// pile's, and a dataset must be designed for it.
  bool opt_in = false;
  /// Its fingerprint differs from mu_r's only between tests of different grain sizes: with one
  /// size distribution in every test it is a change of mu_r, which the calibration takes up.
  bool needs_size_contrast = false;
};

/// The registry (see the design note).
const std::vector<CandidateEffect>& candidate_effects();

/// A registry row by name; throws std::invalid_argument naming the known names.
const CandidateEffect& find_effect(const std::string& name);

/// An effect switched on at a value.
struct EffectSetting {
  const CandidateEffect* effect = nullptr;
  double value = 0.0;
};

/// The scene keys of a calibrated-parameter key list ("a,b": every key takes the same mu_r, as
/// calibrate's `key = [...]` does, e.g. rock-rock and rock-plate rolling friction together).
std::vector<std::string> split_keys(const std::string& keys);

/// Checks that every key of `mu_key` names a numeric value in the test's scene. Throws
/// InputError naming the key, the test and the reason.
void check_mu_key(const LabTest& test, const std::string& mu_key);

/// The request for `test` with the effects applied on top of mu_r (every key of `mu_key`, a
/// comma-separated list) and the image settings `base_image`. Throws InputError when a factor effect's key cannot be read from the
/// test's scene.
SimRequest make_request(const LabTest& test, const std::string& mu_key, double mu_r,
                        std::uint64_t seed, const std::vector<EffectSetting>& effects,
                        const ImageVariant& base_image);

/// The mass-median diameter d50 of the particles the test simulates [m]: the size at which the
/// scene's sieve table, scalped at d_max and cut at d_min (its overrides applied), passes half
/// of the simulated mass, interpolated linearly between sieve sizes. Throws InputError when the
/// scene cannot be loaded.
double median_grain_diameter(const LabTest& test);

/// The dataset's typical grain d_ref [m]: the geometric mean of median_grain_diameter over the
/// calibration tests (all tests when none has that role). Throws std::invalid_argument when
/// `tests` is empty.
double reference_grain_diameter(const std::vector<LabTest>& tests);

/// The value of `key` in the test's resolved scene (its overrides applied), for factor effects
/// and scene-valued off values. Throws InputError naming the test and key when absent.
double scene_value(const LabTest& test, const std::string& key);

/// Whether the engine can build `test` with the effect at its probe value; an empty string means
/// yes, otherwise the reason.
std::string effect_unavailable(const LabTest& test, const CandidateEffect& effect);

/// Why the effect cannot be told from mu_r on these tests as a whole (empty: it can). An effect
/// with needs_size_contrast is refused when every test simulates the same size distribution
/// (resolved sieve intervals and their mass fractions, overrides applied): its probes would cost
/// simulations and find a fingerprint the mu_r correction absorbs. Throws InputError when a
/// test's scene cannot be loaded.
std::string effect_unidentifiable(const std::vector<LabTest>& tests, const CandidateEffect& effect);

nlohmann::json to_json(const CandidateEffect& e);

}  // namespace reposetwin::experiments
