// One campaign run = one pile test (+ its photographs measured by vision).
//
// The campaign runner (campaign.hpp) knows nothing of piles: it hands a CaseSpec and a folder to
// a case function. pile_case_fn() is that function for the pile test: it asks the pile service
// (pile_service.hpp) for the case's pour (scene, overrides, seed, photo settings), so a pile
// another campaign, a calibration or the loop already poured into the same store is not poured
// again, and returns a CaseResult: the particle-position angles, the image angle, the stop
// reason, the provenance and where the run and its photographs are. The case folder keeps the
// layout campaigns have always had (result.json, and run/ with the run's result.json,
// final.vtp, frames and images/), its run/ made of links to the pile and photographs in the
// store. The runner stores the result as JSON (to_json), and calibration and reports read it
// back with case_result_from_json.
#pragma once

#include <optional>
#include <string>

#include "experiments/campaign/campaign.hpp"
#include "experiments/campaign/pile_service.hpp"
#include "experiments/photos/pile_images.hpp"
#include "experiments/pile/pile_record.hpp"

namespace reposetwin::experiments {

struct CaseRunSettings {
  bool images = true;   // render and measure the final pile (vision angle)
  ImageSettings image;  // cameras and resolution (the campaign's: 1920 x 1080, 4 side views)
  int threads = 1;      // OpenMP threads per run (the pool runs runs side by side)
  // The pile service's store; empty: cache/ in the campaign's output folder (beside cases/).
  std::string store;
};

/// The pile request of a case: its scene, overrides and seed, photographed with
/// settings.image (centred on the footprint the run measured) when settings.images.
PileRequest case_request(const CaseSpec& spec, const CaseRunSettings& settings);

/// What the twin's photographs of a case's pile measured: the side views' mean.
struct CaseImages {
  double theta_deg = 0.0;             // atan(2H/D) [deg]
  double theta_sd_deg = 0.0;          // its spread over the side views [deg]
  double height_m = 0.0;              // H [m]
  double diameter_m = 0.0;            // D [m]
  double flank_deg = 0.0;             // flank-line angle [deg]
  std::string images = "run/images";  // the photographs' folder, relative to the case folder
                                      // (a link into the pile service's store)
};

/// One case's outcome (the "result" of its result.json).
struct CaseResult {
  RunStop stop;
  PileMeasure pile;
  ParticleCounts particles;
  RunPerformance performance;
  RunProvenance provenance;
  double psd_fines_fraction = 0.0;  // mass fraction of the PSD below d_min, not simulated [-]
  std::string run_dir = "run";      // the pile run's folder, relative to the case folder (its
                                    // entries are links into the pile service's store)
  std::optional<CaseImages> image;  // absent: not photographed (--no-images, or no pile)
  std::optional<ShapeRecord> shape;  // a clump sample's shapes as run; absent for spheres, so a
                                     // campaign over shape keys says in each case what it ran
};
nlohmann::json to_json(const CaseResult& r);
/// Reads a case result, or a run's whole result.json (its "result" member); std::invalid_argument
/// when the JSON is not a case result.
CaseResult case_result_from_json(const nlohmann::json& j);

CaseFn pile_case_fn(const CaseRunSettings& settings);

/// Reads every scene the campaign file can run as its pile run will (overrides applied, strict
/// parser): each case, the [calibration] at both ends of its mu_r range and each [[predict]]
/// test there, so that an override the scene parser refuses (an elongation below 1, a misspelt
/// shape key, a mass fraction that no longer sums to 1) is an InputError naming the campaign
/// file, the case (or "calibration", "prediction NAME") and the scene's key and value before
/// anything runs. The campaign and calibrate commands call it; read_campaign_file() checks only that
/// each override applies to its scene file, since a campaign is not always over pile scenes.
void check_pile_cases(const Campaign& campaign);

/// True when the case jammed: grains arched in the outlet and no pile formed.
bool case_made_no_pile(const nlohmann::json& case_result);

/// What a finished case gave: kPile when it has a headline angle, else the reason it has none.
/// Only kPile counts as an angle.
PileStatus case_outcome(const nlohmann::json& case_result);

/// case_outcome's word, for a campaign's counts (RunnerSettings::outcome_of).
std::string case_outcome_word(const nlohmann::json& case_result);

/// The one angle selector: the angle `measure` of a pile and its photographs [deg]. kImage falls
/// back to atan(2H/D) from particle positions when the pile was not photographed; kImageFlank
/// needs the photographs and throws std::runtime_error naming `where` without them.
double select_angle_deg(const PileMeasure& pile, const std::optional<PhotoMeasure>& photo,
                        AngleMeasure measure, const std::string& where);

/// The angle `measure` of a finished case [deg]. kImage falls back to atan(2H/D) from particle
/// positions when the run was not photographed (--no-images); kImageFlank needs the photographs
/// and throws without them. Throws std::runtime_error, naming the reason, for a case without a
/// headline (case_outcome not "pile": jammed, not settled, time limit, no pile, physics stop):
/// such a run has no angle.
double case_angle_deg(const nlohmann::json& case_result,
                      AngleMeasure measure = AngleMeasure::kImage);

}  // namespace reposetwin::experiments
