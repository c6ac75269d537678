#include "experiments/pile/stop_hint.hpp"

#include "experiments/io/format.hpp"

namespace reposetwin::experiments {
namespace {

// The time step's key: an explicit step overrides the Rayleigh fraction (sim::Settings).
std::string step_key(const sim::Settings& n) {
  if (n.time_step > 0)
    return "numerics.time_step_s = " + significant(n.time_step, 4) +
           " (lower it, or remove it to take numerics.rayleigh_fraction of the Rayleigh time)";
  return "numerics.rayleigh_fraction = " + significant(n.rayleigh_fraction, 4) +
         " (the time step as a fraction of the Rayleigh time: lower it)";
}

// The stiffness key: the softened modulus when set, else the materials' own moduli.
std::string stiffness_key(const sim::Settings& n) {
  if (n.softened_youngs_modulus > 0)
    return "numerics.softened_youngs_modulus_pa = " + significant(n.softened_youngs_modulus, 4) +
           " (too soft for these impacts: raise it)";
  return "the materials' youngs_modulus_pa (too soft for these impacts: raise them)";
}

}  // namespace

std::string physics_stop_hint(sim::Status status, const SceneConfig& scene) {
  const sim::Settings& n = scene.settings;
  switch (status) {
    case sim::Status::kOk:
      return "";
    case sim::Status::kNan:
      return "The integration blew up; most likely the time step: " + step_key(n) + ".";
    case sim::Status::kOverlap:
      return "An overlap passed numerics.max_overlap_ratio = " +
             significant(n.max_overlap_ratio, 4) + "; most likely " + stiffness_key(n) +
             ", or the time step: " + step_key(n) + ".";
    case sim::Status::kEscaped:
      return "A grain was thrown beyond numerics.escape_distance_m = " +
             significant(n.escape_distance, 4) + " m; most likely the time step: " + step_key(n) +
             ", or " + stiffness_key(n) + ".";
  }
  return "";
}

}  // namespace reposetwin::experiments
