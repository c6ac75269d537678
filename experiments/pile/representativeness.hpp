// Whether a pile test is representative of the lab's, said before it runs and with its result.
//
// Design note. A pile a few grains high, a sample whose finer half is not simulated, or an
// outlet a few grains wide gives an angle, but not the material's angle of repose; a user should
// hear so before spending the run and beside its answer, not find out from the paper. Three
// rules, each a number from the scene alone, so the plan can print them:
//   * pile height: H below 10 d_max. H is predicted as the cone of the simulated mass at the
//     loose solid fraction 0.6 (V = m / (rho 0.6), H = (3 V tan^2(theta) / pi)^(1/3)) over the
//     angles 20-45 deg that piles of rock take; the warning holds when H at 20 deg is below
//     10 d_max (at 45 deg the cone is 1.7 times as high, and the message gives both). After the
//     run the measured particle H is held to the same rule.
//   * mass not simulated: more than 10% of the sieve sheet's mass outside the simulated sizes
//     (finer than d_min, or scalped above d_max): 1 - (1 - scalped) (1 - fines).
//   * outlet: W / d_max below 3.75, W the container's outlet (bottom) diameter: the threshold of
//     the paper's Fig. 10, below which its funnel flow arches (jams) or stutters.
// Warnings are typed (an enum with a count) and carry their sentence; they never stop a run.
#pragma once

#include <array>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "experiments/io/scene.hpp"

namespace reposetwin::experiments {

/// Thresholds of the rules (design note); every field has a default.
struct RepresentativenessRules {
  double min_height_over_d_max = 10.0;  // H below this many d_max is too low a pile [-]
  double max_not_simulated = 0.10;      // mass fraction outside the simulated sizes [-]
  double min_outlet_over_d_max = 3.75;  // W / d_max below this jams (paper's Fig. 10) [-]
  double angle_lo_deg = 20.0;           // the angle range the height is predicted over [deg]
  double angle_hi_deg = 45.0;           // [deg]
  double solid_fraction = 0.6;          // of the pile's bulk volume [-]
};

/// The rules' three checks.
enum class RepresentativenessCheck { kPileHeight, kMassNotSimulated, kOutletWidth, kCount };
inline constexpr std::size_t kRepresentativenessChecks =
    static_cast<std::size_t>(RepresentativenessCheck::kCount);

/// The numbers the rules read, from the scene (and, after the run, the pile).
struct Representativeness {
  double d_max_m = 0.0;                     // the largest simulated size [m]
  double height_lo_m = 0.0;                 // predicted H at angle_lo_deg [m]
  double height_hi_m = 0.0;                 // predicted H at angle_hi_deg [m]
  std::optional<double> measured_height_m;  // the run's particle H [m], after the run
  double not_simulated_fraction = 0.0;      // of the sieve sheet's mass [-]
  double fines_fraction = 0.0;              // finer than d_min, of the scalped sample [-]
  double scalped_fraction = 0.0;            // above d_max, of the sheet [-]
  double outlet_m = 0.0;                    // W [m]
  double outlet_over_d_max = 0.0;           // W / d_max [-]
  RepresentativenessRules rules;
  /// Per check: the warning's sentence, or empty when the rule holds.
  std::array<std::string, kRepresentativenessChecks> warnings{};
  /// The warnings that apply, in check order.
  std::vector<std::string> warning_list() const;
};

/// The checks of `scene` before it runs. Throws InputError as the scene's own checks do.
Representativeness representativeness(const SceneConfig& scene,
                                      const RepresentativenessRules& rules = {});

/// The same, with the height rule applied to the run's measured pile height H [m] too.
Representativeness representativeness(const SceneConfig& scene, double measured_height_m,
                                      const RepresentativenessRules& rules = {});

/// The word of a check in files ("pile_height", "mass_not_simulated", "outlet_width").
const char* check_word(RepresentativenessCheck c);

/// result.json's "representativeness": the numbers, the rules, and the warnings by check.
nlohmann::json to_json(const Representativeness& r);

/// The plan's lines ("plan: warning: ..."), one per warning; empty when every rule holds.
std::string representativeness_text(const Representativeness& r);

}  // namespace reposetwin::experiments
