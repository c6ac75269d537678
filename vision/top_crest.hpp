// vision/top_crest: the width of a pile's flat top in a top view, in pixels.
//
// Design note. Seen from above, a level crest and a sloped flank look alike grain by grain; what
// tells them apart in a photo, whatever the grains look like, is how the light falls on them.
// Under a light that is not along the view, the brightness of a surface of slope theta whose
// downhill direction points at azimuth phi goes, to first order (Lambert, light psi off the
// vertical towards azimuth phi_l),
//   I = cos(theta) cos(psi) + sin(theta) sin(psi) cos(phi - phi_l),
// so on a ring of radius r about the pile's axis a flank's grey level varies with the azimuth
// as cos(phi - phi_l), with an amplitude that grows with sin(theta), while a level top does not
// vary at all. Shadows cast across the flank turned away from the light add to the same
// harmonic. The rule, stated so that closed forms test it:
//   a1(r) = the cos(phi - phi_l) coefficient of a least-squares fit of m + a cos + b sin to the
//   grey levels of the ring at r, phi_l the phase of the flank rings' summed first harmonic
//   (flank_from..flank_to of the footprint radius), P the median a1 over those rings; the
//   crest radius r_c is the edge of a two-level step (low inside, high outside) fitted to
//   a1(r) by weighted least squares out to the flank band's outer end, r_c scanned over
//   0..flank_from footprint radii, its uncertainty where chi^2 rises by one (times the reduced
//   chi^2 when the profile is no clean step).
// A truncated cone of top radius r_t gives a step of a1 at r_t (r_c = r_t to the ring width);
// a full cone gives one level throughout. When the step does not beat one level by
// min_flank_snr^2 in chi^2, the crest is reported as 0 with, as its uncertainty, the widest
// crest whose chi^2 is within one of a single level's: a full cone gives a ring or two, a view
// too grainy to tell gives a bound as wide as the search, and says so by it. Grains add to a1 a
// noise that a step fit over every ring averages down, where a threshold crossing would follow one
// noisy ring. The noise of a1 is read off the flank rings themselves (the spread of neighbouring
// rings' differences), since the grains' texture is correlated over a grain's size in pixels and a
// pixel count would understate it; a ring of N pixels is given the flank's noise scaled by
// sqrt(N_flank / N). Two things a top view cannot give are said, not guessed: a light along the
// view (a ring light, an on-camera flash) leaves no harmonic on the flank (P within min_flank_snr
// of its noise), and the crest then goes unread with that reason; and the crest's width in metres
// needs the height it stands at (the plane of the flat top, not the plate), which the side
// views give (vision/measure.hpp).
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "vision/top_view.hpp"

namespace reposetwin::vision {

/// How a top view's crest is read. Every field has a default.
struct TopCrestSettings {
  double ring_fraction = 0.025;     // ring width as a fraction of the footprint radius [-]
  double min_ring_px = 2.0;         // narrowest ring [px]
  double flank_from = 0.45;         // inner end of the flank band, footprint radii [-]
  double flank_to = 0.85;           // outer end of the flank band, footprint radii [-]
  double smoothing_sigma_px = 1.5;  // Gaussian pre-smoothing [px]
  double min_flank_snr = 4.0;       // flank harmonic over its standard error, fewest [-]
};

/// The crest (flat top) read from a top view [px].
struct TopCrest {
  bool found = false;
  std::string reason;                  // why it went unread (found = false), in words and numbers
  cv::Point2d center;                  // the rings' centre: the footprint's circle [px]
  double radius_px = 0.0;              // crest radius r_c [px]
  double sigma_radius_px = 0.0;        // its uncertainty [px]
  double light_azimuth_deg = 0.0;      // image-frame azimuth where the flank is brightest [deg]
  double flank_amplitude = 0.0;        // P [grey levels]
  double flank_sigma = 0.0;            // standard error of P [grey levels]
  double inner_level = 0.0;            // the fitted step: a1 inside r_c [grey levels]
  double outer_level = 0.0;            // and outside it [grey levels]
  double step_sigma = 0.0;             // standard error of their difference [grey levels]
  std::vector<double> ring_radius_px;  // ring centres [px]
  std::vector<double> ring_a1;         // a1 on each ring [grey levels]
};

/// Reads the crest of a pile whose footprint `footprint` was measured in `image` (any image
/// vision::gray_levels accepts). Never throws for an unreadable crest (found = false with the
/// reason); throws std::invalid_argument for an empty image or footprint, messages starting
/// with `where`.
TopCrest measure_top_crest(const cv::Mat& image, const TopProfile& footprint,
                           const TopCrestSettings& settings = {},
                           const std::string& where = "image");

}  // namespace reposetwin::vision
