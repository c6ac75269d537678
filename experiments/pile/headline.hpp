// The one headline angle of a pile run, and the names and definitions of every other measure.
//
// Design note. One pile gives several angles that differ by degrees (image atan(2H/D), particle
// atan(2H/D), the image flank, the protractor slice, the equal-area triangle), and only one of
// them is what a lab reports: atan(2H/D) with H and D read from side photographs. That one is
// the headline, under the same name in every output (result.json, a case's result, the run
// summary): `headline_angle_deg`, with `headline_measure` saying how it was obtained. Without
// photographs (`run --no-images`, and only then) the headline falls back to the particle
// atan(2H/D) and its measure says so. Every other measure keeps its own field name, and
// measure_definitions() gives each a one-line definition, shown by the run summary and listed in
// docs/measures.md.
//
// No headline without a pile. An angle is only an answer when the run ended on a settled pile
// that was measured: a run stopped by procedure.max_time_s (while filling, lifting or settling),
// one whose last settling reached procedure.final_settle_max_s, a jammed outlet, a run that left
// no measurable pile, an engine stop, or photographs asked for and not taken has no headline.
// no_headline() says which (a typed reason and a sentence); result.json then carries
// `"headline_angle_deg": null` with `no_headline` {reason, message}, the run exits non-zero, and
// campaigns and calibrations count the run by its reason, never as an angle.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "experiments/pile/pile_record.hpp"

namespace reposetwin::experiments {

/// headline_measure of a headline read from the side photographs (the lab's measure).
inline constexpr const char* kHeadlineFromImages = "image atan(2H/D), side views";
/// headline_measure of the fallback when no photographs were asked for (--no-images).
inline constexpr const char* kHeadlineFromParticles =
    "particle atan(2H/D) (no photographs: --no-images was given)";

/// The headline angle with the H and D it comes from.
struct Headline {
  double angle_deg = 0.0;     // atan(2H/D) [deg]
  double angle_sd_deg = 0.0;  // spread (sample sd) over the side views; 0 without images [deg]
  double height_m = 0.0;      // H [m]
  double diameter_m = 0.0;    // D [m]
  int views = 0;              // side views averaged; 0 without images
  bool from_images = false;
  std::string measure;  // kHeadlineFromImages or kHeadlineFromParticles
};

/// The headline of a pile measured from its side photographs: `measurement` is the JSON of
/// render_and_measure (photos/pile_images.hpp). Throws std::invalid_argument naming the field
/// when it lacks the side summary.
Headline headline_from_images(const nlohmann::json& measurement);
/// The fallback headline: the particle atan(2H/D) of sim/pile_geometry.
Headline headline_from_particles(const PileMeasure& pile);

/// Why a run has no headline angle.
enum class NoHeadlineReason {
  kTimeLimit,    // procedure.max_time_s stopped the run before its pile settled
  kNotSettled,   // the last settling reached procedure.final_settle_max_s still moving
  kJammed,       // grains arched in the outlet: no pile
  kNoPile,       // the run ended with no measurable pile (none on the plate, or no flanks)
  kPhysicsStop,  // the engine stopped the run (NaN, runaway overlap, an escaped particle)
  kPhotographs,  // photographs were asked for and could not be written or measured
  kCount
};

/// The reason's word in files and a campaign's counts ("time_limit", "not_settled", "jam",
/// "no_pile", "physics_stop", "photographs").
const char* no_headline_word(NoHeadlineReason r);

/// A run without a headline: why, as a type and as the sentence printed instead of an angle.
struct NoHeadline {
  NoHeadlineReason reason = NoHeadlineReason::kNoPile;
  std::string message;  // e.g. "not settled: the last settling reached ..."
};

/// Why a run that ended with `stop` and `pile` has no headline; nothing when it has one (it
/// settled and its pile was measured).
std::optional<NoHeadline> no_headline(const RunStop& stop, const PileMeasure& pile);

/// What to change in the scene to get a pile, for the reason (one sentence).
std::string no_headline_advice(NoHeadlineReason r);

/// The fields a result file gains without a headline: headline_angle_deg = null and
/// no_headline = {reason, message}.
nlohmann::json to_json(const NoHeadline& n);

/// The fields a result file gains: headline_angle_deg, headline_angle_sd_deg,
/// headline_height_m, headline_diameter_m, headline_views, headline_measure.
nlohmann::json to_json(const Headline& h);

/// One measure of a pile, as the outputs name it.
struct MeasureDefinition {
  const char* name;        // the field name in the output files
  const char* where;       // the file (and object) it is in
  const char* definition;  // one line: what it measures and how
};

/// Every measure a run reports, the headline first.
const std::vector<MeasureDefinition>& measure_definitions();

}  // namespace reposetwin::experiments
