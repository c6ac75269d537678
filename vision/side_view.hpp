// vision/side_view: the pile's silhouette in a side view, measured in pixels.
//
// Design note. This follows the lab's photo method (theta = atan(2H/D)) and the published image
// recipe, step by step, each step a function that can be tested alone:
//  1. Flat field (vision/image.hpp): grey / backdrop, so thresholds hold under uneven light.
//     Given an image of the empty scene, the pile is segmented on grey / empty scene instead
//     (background difference), while the plate line still comes from the fitted flat field.
//  2. Plate line: a long straight "darker below" edge with the backdrop directly above it (the
//     plate's edge beside the pile), found from row sums of the vertical gradient along lines of
//     every tilt up to plate_max_tilt_deg (noise and sloping flanks cancel in those sums, a long
//     edge does not), then refined column by column to sub-pixel, over the columns with backdrop
//     directly above, and fitted with a robust (Huber) line, so a slightly tilted camera is
//     handled. It is detected, never taken as the lowest blob pixel. When several such edges
//     qualify, the plate is the lowest: a flat pile whose outer part is a sparse monolayer of
//     grains on the plate shows the monolayer's top, one grain diameter up, as a longer edge than
//     the plate's ends beside the pile (measured on the loop's 35 g pile on a 0.12-friction plate:
//     the plate line 4 mm up and D 22 mm for 100; on a rendered cone of 3.5 mm spheres with a
//     monolayer out to 52 mm: 3.6 mm up, D 35 mm for 104; now 0.0 mm and D 104.3 mm).
//     A camera above the plate (the lab's was 5-10 mm up) sees the plate's top face as a band
//     between its far edge (the edge above, against the backdrop) and its near edge, and the pile
//     stands inside the band. Taking the far edge as the plate line cut the pile there (H 9 and 4
//     mm for 14 at 5 and 10 mm up). So when the pile continues below that edge (pixels outside
//     the range of the plate's levels read on both sides of the pile, connected to it, more than
//     max(5 px, 4% of its height) deep), the plate line becomes the toe line: through the lowest
//     pixel near each end of the pile (the outermost grains' feet), parallel to the edge. Rows
//     seen against the top face take the blob's pixel boundary as their edge (there is no
//     backdrop for the coverage of step 4). The guard is the range: a level camera facing the
//     square plate's corner (azimuth 45 or 135 deg) sees two side faces below the plate line, lit
//     differently and meeting under the pile; a level interpolated across the pile differed from
//     both near the corner and read the corner as the pile standing on a top face (sample-3
//     piles: H 64-76 mm for 47-59 mm). A top face is one plane and reads alike on both sides.
//     Both sides are read, at the outermost columns the image has when the pile leaves less
//     than its height beside it (one side read alone took the other face for pile).
//     Limits: a toe line less than max(5 px, 4% of the pile's height) below the far edge is not
//     told from a level view's edge, and the far edge stays the plate line (a camera 5 mm up at
//     12 pile radii over the lab's 0.5 m plate); a raised camera facing the plate's corner sees
//     its far edges as a flat "^", not one line, and is not handled either.
//     With a declared camera (measure.hpp reads the photo in its level view, level_view.hpp)
//     the toe line is where the camera puts the base circle's tangent points (SideSettings::
//     toe_line), not searched: the far edge is then the lowest long edge above it (the near edge
//     and the front face below are never taken), within 3 px of it the plate is seen edge-on and
//     is the plate line, and below it the pile stands on the plate's top face: segmented against
//     the backdrop above the far edge and against the face's level below it, read row by row at
//     the band's outer tenths (side_detail::pile_on_face), the component on the axis column
//     standing on the toe line, with the loose grains at its foot. From high up the whole pile
//     is seen against the face (from 10 deg above a 0.5 m plate at 12 pile radii).
//  3. Pile: Otsu's dark class above the plate line, opened and closed, the largest component
//     resting on the plate line (scale markers and dust are other components). Grains lying
//     apart from it in the picture are strays and not part of it, as sim/pile_geometry.hpp
//     leaves out particles not joined to the pile. The pile must be darker than the backdrop
//     (true of the renders and of a light lab backdrop); a pile cut by the image or ROI border
//     is refused.
//  4. Sub-pixel silhouette: along each row, the edge is placed where the integral of the pixel
//     coverage says it is (coverage = (backdrop - value) / (backdrop - pile)). Blur preserves
//     that integral, so the estimate is unbiased for blurred and anti-aliased edges alike.
//  5. H is the apex's perpendicular distance to the plate line. Flank angles are Huber line fits
//     over a middle band of the height (20-80% by default, excluding the rounded apex and the
//     toe), after setting aside the rows farther than max(3 px, 5 robust sigmas) from a
//     Theil-Sen line: on a flat pile with a grain monolayer around it the band's lowest rows are
//     the monolayer's ends, which pulled a plain Huber fit to 7 deg for a 30 deg cone (at 3
//     sigmas the rough flanks of simulated piles lost rows as well, moving them up to 0.7 deg).
//     The toe points are the flank edges just above the plate (a low band, 2-12% of H, excluding
//     the blurred rows at the plate) carried to the plate line along the fitted flank's slope; D
//     is their distance. The low band gives the toe's position only, never its own slope: on a
//     pile of particles that band is one or two particles tall and its local slope is the
//     particles' outline (the bottom layer's near-vertical sides), so a free line through it,
//     extrapolated, put the toes of a rendered 80 mm sphere cone 3 mm too far out each side
//     (D 86 mm); along the flank's slope they land near the bottom layer's reach. The toe is
//     never farther out than the silhouette's own reach: the band's outermost point, or its
//     lowest row carried down along the flank when the lowest rows slope like a flank (a smooth
//     cone: the two agree). A grain's lower half overhangs and its widest point is the reach.
//     Without this, carrying every row along the flank put the toe on the empty plate beyond the
//     outermost grain, by up to the band's height times the flank's cotangent: most where the
//     band lies within one layer of grains (rendered flat cone of 3.5 mm spheres: D 51.3 mm for
//     48, now 48.2; synthetic monolayer edge +10 mm), but also on ordinary piles (rendered 80 mm
//     cone of 2 mm spheres: D 83.7 mm, now 82.3; simulated sample piles: D 1-4% smaller, their
//     image angle 0.3-0.8 deg nearer the particles' atan(2H/D)).
//     The apex of a sharp cone reads about half a pixel low (the tip narrower than a pixel is
//     lost); real apexes are rounded and H is then the top of the rounding.
// Everything here is in pixels and orthographic; vision/measure.hpp adds the scale and the
// perspective correction.
#pragma once

#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "vision/admission.hpp"
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
  // Where a declared camera puts things (measure.hpp fills these from a level view): the toe
  // line through the base circle's tangent points, the axis foot's column, and the pixels that
  // come from inside the photo (CV_8U, image size; empty = all). With a toe line the plate line
  // is not searched below it: the far edge is the lowest long edge above it, and the pile
  // stands on the toe line (on the plate's visible top face when the far edge is above it).
  std::optional<PlateLine> toe_line;  // [px], full-image coordinates
  std::optional<double> axis_u_px;    // [px], full-image coordinates
  double front_search_px = 0.0;       // how far below the toe line the base's front is sought [px]
  double camera_elevation_deg = 0.0;  // the camera above the plate, seen from the axis foot [deg]
  bool level_toe_line = false;        // the camera sees the plate edge-on (toe line = horizon)
  bool plate_edge_on = false;         // no top face is sought below the plate line found
  // A camera declared level: the lowest row its plate line can lie on (the toe line plus the
  // elevation a level camera is allowed), so a lower long edge (the plate's front face on a
  // bench, seen through a rolled camera) is never taken for it. [px], full-image coordinates
  std::optional<double> plate_line_lowest_v;
  cv::Mat valid;
  AdmissionSettings admission;  // the pixel checks' limits (admission.hpp)
};

/// The silhouette measurement in pixels (full-image coordinates, even when an ROI was set).
struct SideProfile {
  PlateLine plate;
  cv::Point2d apex;                // highest silhouette point (sub-pixel in height) [px]
  cv::Point2d toe_left;            // left toe on the plate line [px]
  cv::Point2d toe_right;           // right toe on the plate line [px]
  double height_px = 0.0;          // H: apex distance perpendicular to the plate line [px]
  double diameter_px = 0.0;        // D: distance between the toe points [px]
  // The flank lines' foot: where the two fitted flank lines meet the plate line, and their
  // distance, the other definition of D (measure.hpp's design note says which is reported).
  cv::Point2d foot_left, foot_right;  // [px]
  double diameter_flank_px = 0.0;     // [px]
  double sigma_height_px = 0.0;    // uncertainty of H (apex quantisation, plate line) [px]
  double sigma_diameter_px = 0.0;  // uncertainty of D (toe band scatter, flank slope) [px]
  double theta_deg = 0.0;          // atan(2H/D) [deg]
  double sigma_theta_deg = 0.0;    // propagated from sigma_height_px and sigma_diameter_px [deg]
  FlankFit left, right;            // flank line fits
  std::vector<cv::Point2d> left_edge, right_edge;  // sub-pixel silhouette, one point per row
  cv::Rect blob_box;                               // bounding box of the pile blob [px]
  double pile_level = 0.0;  // flat-field level of the pile (backdrop = 1) [-]
  double threshold = 0.0;   // flat-field threshold used [-]
  /// When the pile stands on the plate's visible top face (a camera above the plate): the
  /// plate's far edge against the backdrop, above the toe line that `plate` then is.
  std::optional<PlateLine> far_edge;
  /// With a predicted toe line on the plate's top face: the row of the base's front point (the
  /// pile's lowest pixels at the axis column), which the camera also predicts [px].
  std::optional<double> front_v_px;
  /// The plate line is the camera's toe line, no edge having been found there (a pile as wide as
  /// the view hides it): the photo's own plate edge, wherever it is, is then checked instead.
  bool plate_from_camera = false;
  /// The toe line is where the camera put it (a camera above the plate, declared so); else it
  /// was found in the photo, and H is read from it (measure.hpp).
  bool toe_line_predicted = false;
};

/// Finds the plate line in a flat-fielded image (CV_32F, backdrop about 1). Throws
/// std::runtime_error naming `where` when no long horizontal edge exists.
PlateLine find_plate_line(const cv::Mat& flat, const SideSettings& settings = {},
                          const std::string& where = "image");

/// find_plate_line over the rows above `max_row` only (where a declared camera can put the
/// plate line): a lower long edge (a bench under the plate) is never taken for it.
PlateLine find_plate_line_above(const cv::Mat& flat, int max_row,
                                const SideSettings& settings = {},
                                const std::string& where = "image");

/// A side view after the common first step: its region of interest, flat-fielded and smoothed.
struct SideImage {
  cv::Mat flat;     // CV_32F, divided by the fitted backdrop (about 1): plate line and markers
  cv::Mat segment;  // CV_32F, divided by the empty-scene image if one was given, else `flat`:
                    // pile segmentation and edges
  cv::Rect roi;     // where both sit in the full image [px]
  cv::Mat clipped;  // CV_8U, 255 where the photo is at its brightest level (over-exposed)
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
