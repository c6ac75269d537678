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
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "experiments/loop_data.hpp"
#include "experiments/loop_sim.hpp"

namespace reposetwin::experiments {

enum class EffectKind { kPhysics, kMeasurement };

/// How a candidate's value reaches the test.
enum class EffectApply {
  kSetScene,     // scene key = value
  kFactorScene,  // scene key = value x the test's resolved value of that key
  kImageHeight,  // true camera height = value [m] (the lab declares its own, default level)
  kImageK1,      // true lens distortion k1 = value (the lab declares 0)
};

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
  /// Extra keys set together with `key` whenever the effect is on (e.g. the reference size).
  std::vector<std::pair<std::string, std::string>> companions;
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

/// The request for `test` with the effects applied on top of mu_r (rolling key) and the image
/// settings `base_image`. Throws InputError when a factor effect's key cannot be read from the
/// test's scene.
SimRequest make_request(const LabTest& test, const std::string& mu_key, double mu_r,
                        std::uint64_t seed, const std::vector<EffectSetting>& effects,
                        const ImageVariant& base_image);

/// The value of `key` in the test's resolved scene (its overrides applied), for factor effects
/// and scene-valued off values. Throws InputError naming the test and key when absent.
double scene_value(const LabTest& test, const std::string& key);

/// Whether the engine can build `test` with the effect at its probe value; an empty string means
/// yes, otherwise the reason.
std::string effect_unavailable(const LabTest& test, const CandidateEffect& effect);

nlohmann::json to_json(const CandidateEffect& e);

}  // namespace reposetwin::experiments
