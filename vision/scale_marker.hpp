// vision/scale_marker: finding the scale references of the shared render convention in an image.
//
// Design note. A photo without a calibrated camera needs a reference of known size in the
// picture. The renderer draws the same references the lab can print (see notes/marker.md):
//  - side view: a vertical bar of `count` horizontal bands, each `band_mm` tall, alternating black
//    and white, standing in the plane of the pile axis (so its scale is the scale at the axis);
//  - top view: a 4 x 4 black/white checker card of `square_mm` squares lying on the plate.
// Both are periodic, so the scale comes from a pitch fitted over many edges or squares rather
// than from one length: for the bar, the black bands are found as rectangle-like dark blobs
// stacked at a regular pitch, then every band edge is located to sub-pixel with the coverage
// integral along the bar's column profile, and the band height in pixels is the slope of a
// least-squares fit of edge position against edge index. For the card, the white squares are
// found as square bright blobs; their centroids form a lattice whose nearest-neighbour spacing is
// sqrt(2) squares whatever the card's rotation.
#pragma once

#include <opencv2/core.hpp>
#include <optional>
#include <string>

namespace reposetwin::vision {

/// A band scale bar found in a side view.
struct ScaleBar {
  cv::Rect box;              // bounding box of the black bands found [px]
  double band_px = 0.0;      // fitted band height [px]
  double band_mm = 10.0;     // band height of the reference [mm]
  double mm_per_px = 0.0;    // band_mm / band_px [mm/px]
  double residual_px = 0.0;  // RMS residual of the edge positions about the fit [px]
  double sigma_rel = 0.0;    // relative standard error of band_px [-]
  int black_bands = 0;       // black bands used [-]
  int edges = 0;             // band edges used [-]
};

/// A checker card found in a top view.
struct CheckerCard {
  cv::Rect box;             // bounding box of the white squares found [px]
  double square_px = 0.0;   // fitted square size [px]
  double square_mm = 10.0;  // square size of the reference [mm]
  double mm_per_px = 0.0;   // square_mm / square_px [mm/px]
  double sigma_rel = 0.0;   // relative spread of the neighbour spacings [-]
  int squares = 0;          // white squares used [-]
};

/// What the marker search looks for.
struct MarkerSettings {
  double band_mm = 10.0;    // band height of the side-view bar [mm]
  int min_black_bands = 3;  // fewest black bands that make a bar [-]
  double square_mm = 10.0;  // checker square size of the top-view card [mm]
  int min_squares = 3;      // fewest white squares that make a card [-]
  int min_feature_px = 4;   // smallest band height or square side searched [px]
};

/// Finds the band scale bar in a flat-fielded side view (CV_32F, backdrop about 1), or nullopt.
std::optional<ScaleBar> find_scale_bar_flat(const cv::Mat& flat, const MarkerSettings& s = {});

/// Finds the band scale bar in a side-view image (any image vision::gray_levels accepts).
std::optional<ScaleBar> find_scale_bar(const cv::Mat& image, const MarkerSettings& s = {},
                                       const std::string& where = "image");

/// Finds the checker card in a top-view image, or nullopt.
std::optional<CheckerCard> find_checker_card(const cv::Mat& image, const MarkerSettings& s = {},
                                             const std::string& where = "image");

}  // namespace reposetwin::vision
