// vision/side_view: the pile's silhouette in a side view, measured in pixels.
//
// Design note. This follows the lab's photo method (theta = atan(2H/D)) and the published image
// recipe, step by step, each step a function that can be tested alone:
//  1. Flat field (vision/image.hpp): grey / backdrop, so thresholds hold under uneven light.
//     Given an image of the empty scene, the pile is segmented on grey / empty scene instead
//     (background difference), while the plate line still comes from the fitted flat field.
//  2. Plate line: the strongest long "darker below" horizontal edge, found from the signed row
//     sum of the vertical gradient (noise and sloping flanks cancel in that sum, a long edge does
//     not), then refined column by column to sub-pixel and fitted with a robust (Huber) line, so
//     a slightly tilted camera is handled. It is detected, never taken as the lowest blob pixel.
//  3. Pile: Otsu's dark class above the plate line, opened and closed, the largest component
//     resting on the plate line (scale markers and dust are other components). The pile must
//     be darker than the backdrop (true of the renders and of a light lab backdrop); a pile cut
//     by the image or ROI border is refused.
//  4. Sub-pixel silhouette: along each row, the edge is placed where the integral of the pixel
//     coverage says it is (coverage = (backdrop - value) / (backdrop - pile)). Blur preserves
//     that integral, so the estimate is unbiased for blurred and anti-aliased edges alike.
//  5. H is the apex's perpendicular distance to the plate line. Flank angles are Huber line fits
//     over a middle band of the height (20-80% by default, excluding the rounded apex and the
//     toe). The toe points are the flank edges just above the plate (a low band, 2-12% of H,
//     excluding the blurred rows at the plate) carried to the plate line along the fitted
//     flank's slope; D is their distance. The low band gives the toe's position only, never its
//     own slope: on a pile of particles that band is one or two particles tall and its local
//     slope is the particles' outline (the bottom layer's near-vertical sides), so a free line
//     through it, extrapolated, put the toes of a rendered 80 mm sphere cone 3 mm too far out
//     each side (D 86 mm); along the flank's slope they land on the bottom layer's reach.
//     The apex of a sharp cone reads about half a pixel low (the tip narrower than a pixel is
//     lost); real apexes are rounded and H is then the top of the rounding.
// Everything here is in pixels and orthographic; vision/measure.hpp adds the scale and the
// perspective correction.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "vision/image.hpp"

namespace reposetwin::vision {

/// The plate (toe) line in the image: v = a + b u [px].
struct PlateLine {
  double a = 0.0;            // v at u = 0 [px]
  double b = 0.0;            // slope dv/du [-]
  double residual_px = 0.0;  // RMS distance of the edge samples to the fitted line [px]
  double sigma_px = 0.0;     // standard error of the line's position (mid image) [px]
  int support = 0;           // number of column samples that carried the fit [-]

  /// Row of the line at column u [px].
  double v_at(double u) const { return a + b * u; }
  /// Perpendicular distance of a pixel above the line [px] (positive above, i.e. smaller v).
  double height_above(const cv::Point2d& p) const;
  /// Unit direction of the line pointing to increasing u.
  cv::Point2d direction() const;
  /// Tilt of the line from the image horizontal [deg] (positive = v grows with u).
  double tilt_deg() const;
};

/// A straight line fitted to one flank of the silhouette.
struct FlankFit {
  cv::Point2d point;             // a point on the line [px]
  cv::Point2d direction;         // unit direction, pointing up the flank (towards the apex)
  double angle_deg = 0.0;        // angle between the flank and the plate line [deg]
  double residual_px = 0.0;      // RMS perpendicular distance of the edge points to the line [px]
  double sigma_fit_deg = 0.0;    // standard error of the angle from the fit residual [deg]
  double sigma_pixel_deg = 0.0;  // pixel quantisation (1/sqrt(12) px at each end) [deg]
  double sigma_deg = 0.0;        // both combined in quadrature [deg]
  int points = 0;                // edge points used [-]
  double low_px = 0.0, high_px = 0.0;  // height band of the fit above the plate line [px]
};

/// How a side view is segmented and measured. Every field has a default.
struct SideSettings {
  cv::Rect roi;                     // region of interest [px]; empty = the whole image
  cv::Mat backdrop;                 // image of the empty scene for background difference; or empty
  FlatFieldSettings flat_field;     // backdrop estimate when `backdrop` is empty
  double smoothing_sigma_px = 0.8;  // Gaussian pre-smoothing of the flat-fielded image [px]
  double threshold = 0.0;           // foreground below this flat-field level [-]; 0 = Otsu
  int morph_radius_px = 2;          // opening / closing radius [px]
  double min_area_fraction = 5e-4;  // smallest pile blob, as a fraction of the ROI area [-]
  double plate_max_tilt_deg = 3.0;  // largest plate-line tilt searched [deg]
  bool plate_darker_than_backdrop = true;  // the plate line is a bright-above / dark-below edge
  int edge_window_px = 5;         // half width of the sub-pixel edge window along a row [px]
  double flank_band_low = 0.2;    // flank fit band, lower end, as a fraction of H [-]
  double flank_band_high = 0.8;   // flank fit band, upper end, as a fraction of H [-]
  double toe_band_low = 0.02;     // toe band (carried down the flank), lower end, of H [-]
  double toe_band_high = 0.12;    // toe band, upper end, fraction of H [-]
  double toe_min_gap_px = 3.0;    // rows this close to the plate line are never used [px]
  std::vector<cv::Rect> exclude;  // image regions ignored by the pile search (scale markers)
};

/// The silhouette measurement in pixels (full-image coordinates, even when an ROI was set).
struct SideProfile {
  PlateLine plate;
  cv::Point2d apex;                // highest silhouette point (sub-pixel in height) [px]
  cv::Point2d toe_left;            // left toe on the plate line [px]
  cv::Point2d toe_right;           // right toe on the plate line [px]
  double height_px = 0.0;          // H: apex distance perpendicular to the plate line [px]
  double diameter_px = 0.0;        // D: distance between the toe points [px]
  double sigma_height_px = 0.0;    // uncertainty of H (apex quantisation, plate line) [px]
  double sigma_diameter_px = 0.0;  // uncertainty of D (toe band scatter, flank slope) [px]
  double theta_deg = 0.0;          // atan(2H/D) [deg]
  double sigma_theta_deg = 0.0;    // propagated from sigma_height_px and sigma_diameter_px [deg]
  FlankFit left, right;            // flank line fits
  std::vector<cv::Point2d> left_edge, right_edge;  // sub-pixel silhouette, one point per row
  cv::Rect blob_box;                               // bounding box of the pile blob [px]
  double pile_level = 0.0;  // flat-field level of the pile (backdrop = 1) [-]
  double threshold = 0.0;   // flat-field threshold used [-]
};

/// Finds the plate line in a flat-fielded image (CV_32F, backdrop about 1). Throws
/// std::runtime_error naming `where` when no long horizontal edge exists.
PlateLine find_plate_line(const cv::Mat& flat, const SideSettings& settings = {},
                          const std::string& where = "image");

/// A side view after the common first step: its region of interest, flat-fielded and smoothed.
struct SideImage {
  cv::Mat flat;     // CV_32F, divided by the fitted backdrop (about 1): plate line and markers
  cv::Mat segment;  // CV_32F, divided by the empty-scene image if one was given, else `flat`:
                    // pile segmentation and edges
  cv::Rect roi;     // where both sit in the full image [px]
};

/// Validates the settings and the image and computes its SideImage. Throws as
/// measure_side_pixels does.
SideImage prepare_side(const cv::Mat& image, const SideSettings& settings = {},
                       const std::string& where = "image");

/// Measures the pile silhouette of a prepared side view (see the overload below).
SideProfile measure_side_pixels(const SideImage& prepared, const SideSettings& settings = {},
                                const std::string& where = "image");

/// Measures the pile silhouette of a side view. `image` is any image `gray_levels` accepts.
/// Throws std::invalid_argument for unusable input (empty, all black, bad settings) and
/// std::runtime_error when no pile is found; messages start with `where`.
SideProfile measure_side_pixels(const cv::Mat& image, const SideSettings& settings = {},
                                const std::string& where = "image");

/// Fits a line to edge points with cv::fitLine (Huber) and reports its angle to `plate` with its
/// uncertainty; the direction is made to point away from the plate. Throws std::runtime_error
/// naming `what` when fewer than 3 points are given.
FlankFit fit_flank(const std::vector<cv::Point2d>& points, const PlateLine& plate,
                   const std::string& what);

}  // namespace reposetwin::vision
