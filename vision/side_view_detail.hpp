// Pieces shared by the side view's files (side_view.cpp: segmentation and the silhouette,
// side_plate.cpp: the plate line and the plate's top face, side_flank.cpp: the flank and toe
// fits); not for use outside them. side_view.hpp's design note describes the method.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "numeric/median.hpp"
#include "vision/side_view.hpp"
#include "vision/text_detail.hpp"

namespace reposetwin::vision::side_detail {

using detail::kQuantisationPx;
using detail::kRadToDeg;
using detail::str;

using numeric::median;

// The toe on one side: the column alpha where the silhouette's low band meets the plate
// (h = 0), with its standard error. beta = dx/dh is the fixed slope used to carry the band down.
struct InterceptFit {
  double alpha = 0.0, beta = 0.0, sigma_alpha = 0.0;
  int n = 0;
};

/// The toe from the low band's silhouette points (heights h above the plate line, columns x),
/// carried to the plate along the flank (side_flank.cpp says how and why).
InterceptFit toe_intercept(const std::vector<double>& h, const std::vector<double>& x,
                           const FlankFit& flank, const PlateLine& plate);

/// The pile seen standing on the plate's top face, below its far edge.
struct TopFace {
  PlateLine toe_line;
  cv::Mat pile;  // the blob grown into the band (CV_8U, image size)
};

/// The pile on the plate's top face (side_plate.cpp says how), or std::nullopt.
std::optional<TopFace> pile_on_top_face(const cv::Mat& flat, const cv::Mat& blob,
                                        const PlateLine& edge, int morph_radius_px,
                                        const cv::Mat& valid = cv::Mat());

/// The lowest long edge with backdrop above it and not below `toe_line` (+4 px): the plate's far
/// edge as a camera above the plate sees it, or the plate line itself for a level camera.
/// std::nullopt when the plate fills the view (no edge with backdrop above it).
std::optional<PlateLine> find_far_edge(const cv::Mat& flat, const SideSettings& s,
                                       const PlateLine& toe_line, const std::string& where);

/// The pile standing on the plate's visible top face, its toe line given by the camera: the dark
/// class above the far edge (`above`, CV_8U image size, may be all zero) joined with the pixels
/// of the face band (below the far edge, or everything when there is none) unlike the plate's
/// level in their row, read at the band's outer columns; the component standing on the toe line
/// nearest the axis column, holes filled, down to `depth_below` px below the toe line. Empty when
/// nothing stands there.
cv::Mat pile_on_face(const cv::Mat& flat, const cv::Mat& above, const std::optional<PlateLine>& far,
                     const PlateLine& toe, double axis_u, double depth_below, int morph_radius_px,
                     const cv::Mat& valid);

}  // namespace reposetwin::vision::side_detail
