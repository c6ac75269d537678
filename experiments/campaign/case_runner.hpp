// One campaign run = one pile test (+ its photographs measured by vision).
//
// The campaign runner (campaign.hpp) knows nothing of piles: it hands a CaseSpec and a folder to
// a case function. pile_case_fn() is that function for the pile test: it builds the case's scene
// (overrides and seed applied), runs it into CASE_DIR/run, photographs and measures the pile,
// and returns the numbers a report or a calibration needs: the particle-position angles, the
// image angle, the stop reason and the provenance.
#pragma once

#include "experiments/campaign/campaign.hpp"
#include "experiments/photos/pile_images.hpp"

namespace reposetwin::experiments {

struct CaseRunSettings {
  bool images = true;           // render and measure the final pile (vision angle)
  ImageSettings image;          // cameras and resolution
  int threads = 1;              // OpenMP threads per run (the pool runs runs side by side)
};

CaseFn pile_case_fn(const CaseRunSettings& settings);

/// True when the case made no pile (a clogged outlet: every particle lodged in the container).
bool case_made_no_pile(const nlohmann::json& case_result);

/// The angle `measure` of a finished case [deg]; 0 for "no pile". kImage falls back to atan(2H/D)
/// from particle positions when the run was not photographed (--no-images); kImageFlank needs the
/// photographs and throws without them. Throws if the run stopped on a physics failure (overlap,
/// NaN, escape): such a run has no angle.
double case_angle_deg(const nlohmann::json& case_result,
                      AngleMeasure measure = AngleMeasure::kImage);

}  // namespace reposetwin::experiments
