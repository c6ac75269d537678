// vision/top_view: the pile's footprint seen from above, measured in pixels.
//
// Design note. From above, the pile is a roughly round patch on the plate, lit unevenly (the
// flank facing the light is brighter) and speckled by its particles, while the plate around it
// may be darker (the render convention) or lighter (a white lab board). So the footprint is not
// "the dark class": it is the region around a seed point (the image centre, the projected pile
// axis, or a caller's choice) whose grey level is closer to the pile's than to the dominant
// levels on either side of it in the histogram. The binary outline is only a first guess: each
// of N rays from its centre is then measured to sub-pixel with the coverage integral along the
// ray (blur preserves it), and the circle (algebraic least squares), the equal-area diameter
// (shoelace area of the sub-pixel outline) and an ellipse fit (cv::fitEllipse) are computed on
// those sub-pixel points.
//
// Grey level alone is not always enough: rendered rock grey in shade can have nearly the plate's
// luminance (a bluish plate, RGB about 70,80,95, against rock about 120,115,108 whose shadowed
// gaps darken it), and the grey-level region then leaks into the plate and reaches the border.
// The pile differs from such a plate in two other ways a lab photo shares: its colour (rock is
// neutral or warm, the plate bluish: blue minus red) and its texture (a heap of grains is
// speckled, a board is uniform: local standard deviation). So the same segmentation and
// sub-pixel outline are run on these cues in turn (grey level, then colour, then texture) and
// the first that isolates a footprint not touching the border is used; its name is reported.
// A cue also fails when the seed's region is only a fragment: grains seen large, with shadowed
// gaps between them, split the grey-level region into one region per grain, and the seed's one
// grain does not touch the border either. The footprint holds most of the pile-like pixels in a
// box three times its size (strays are few); a fragment holds a small share of them.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace reposetwin::vision {

/// How a top view is segmented and measured. Every field has a default.
struct TopSettings {
  cv::Rect roi;                     // region of interest [px]; empty = the whole image
  cv::Point2d seed{-1.0, -1.0};     // a pixel inside the pile [px]; negative = the ROI centre
  double smoothing_sigma_px = 1.0;  // Gaussian pre-smoothing [px]
  double min_contrast = 15.0;       // pile vs surroundings, fewest grey levels [grey levels]
  int morph_radius_px = 3;          // closing / opening radius [px]
  int rays = 360;                   // sub-pixel rays around the outline [-]
  int edge_window_px = 6;           // half length of the window along each ray [px]
  double texture_sigma_px = 4.0;    // Gaussian window of the local texture cue [px]
};

/// The footprint measurement in pixels (full-image coordinates).
struct TopProfile {
  cv::Point2d center;                     // fitted circle centre [px]
  double diameter_circle_px = 0.0;        // fitted circle diameter [px]
  double circle_residual_px = 0.0;        // RMS radial residual of the outline [px]
  double sigma_diameter_circle_px = 0.0;  // standard error of the circle diameter [px]
  double diameter_area_px = 0.0;          // equal-area diameter 2 sqrt(A / pi) [px]
  double area_px = 0.0;                   // footprint area [px^2]
  double ellipse_major_px = 0.0;          // fitted ellipse, full major axis [px]
  double ellipse_minor_px = 0.0;          // fitted ellipse, full minor axis [px]
  double ellipse_angle_deg = 0.0;         // cv::fitEllipse rotation angle [deg]
  double ellipticity = 0.0;               // 1 - minor / major [-]
  std::vector<cv::Point2d> outline;       // sub-pixel outline, one point per ray [px]
  double pile_level = 0.0;                // grey level of the pile at the seed [grey levels]
  std::string cue;                        // the cue that found the footprint (e.g. "grey level")
};

/// Measures the footprint in a top view. Throws std::invalid_argument for unusable input and
/// std::runtime_error when no footprint is found; messages start with `where`.
TopProfile measure_top_pixels(const cv::Mat& image, const TopSettings& settings = {},
                              const std::string& where = "image");

/// Algebraic least-squares circle through points: returns false for fewer than 3 points or
/// collinear ones. `rms` is the RMS radial residual.
bool fit_circle(const std::vector<cv::Point2d>& pts, cv::Point2d& center, double& radius,
                double& rms);

}  // namespace reposetwin::vision
