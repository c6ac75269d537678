// vision/crest: the width of a pile's flat top in a side view, in pixels.
//
// Design note. The twin's sphere piles have a flat top about as wide as the funnel outlet, and a
// lab pile is closer to a full cone; the crest's width tells the two apart where atan(2H/D)
// alone cannot (a wide crest lowers atan(2H/D) below the flank angle). The rule, stated so that
// closed forms test it:
//   the silhouette is read at a depth d = max(crest_min_depth_px, crest_depth_fraction * H)
//   below the apex (the band of rows within d of the apex height); its width there, along the
//   plate line, less what the fitted flanks alone add over that depth, d (cot phi_left +
//   cot phi_right), is the crest width.
// A truncated cone of top width w gives w (its silhouette is w + d (cot + cot) wide at depth d
// whatever d is, as long as d is above the flanks' straight part, so the rule does not depend on
// the band); a sharp cone gives 0 give or take the half-pixel apex quantisation times the
// cotangents; a rounded apex of radius rho gives about 2 sqrt(2 rho d) - 2 d cot phi, the width
// of its rounding at that depth. The crest's ends are placed at the apex height, on the flank
// lines carried up from the band's outermost points. Negative widths (pixel noise on a sharp
// apex) are reported as 0, the raw value kept.
#pragma once

#include <opencv2/core.hpp>
#include <vector>

#include "vision/side_view.hpp"

namespace reposetwin::vision {

/// The crest (flat top) of a side silhouette [px].
struct Crest {
  double width_px = 0.0;      // crest width along the plate line, >= 0 [px]
  double raw_width_px = 0.0;  // silhouette width at the depth minus the flanks' part [px]
  double sigma_px = 0.0;      // uncertainty: edge quantisation and the depth's effect [px]
  double depth_px = 0.0;      // depth below the apex at which the silhouette was read [px]
  cv::Point2d left, right;    // the crest's ends at the apex height [px]
};

/// How the crest is read (the rule in the design note).
struct CrestSettings {
  double depth_fraction = 0.05;  // depth below the apex, as a fraction of H [-]
  double min_depth_px = 3.0;     // but at least this deep [px]
};

/// The crest of a measured silhouette (SideProfile's edges, plate line, H and flank fits). A top
/// with no silhouette row of its own within the depth of the apex (one grain standing on it,
/// narrower than the edge window) is read from the highest rows each side has, down to half of
/// H. Throws std::runtime_error naming `where` when no silhouette row lies that high.
Crest measure_crest(const SideProfile& profile, const CrestSettings& settings = {},
                    const std::string& where = "image");

}  // namespace reposetwin::vision
