// A side view measured in pixels: the image prepared, the pile segmented above the plate line,
// its sub-pixel silhouette and apex, then the flank and toe fits (side_view.hpp's design note,
// steps 1, 3 and 4; side_plate.cpp and side_flank.cpp hold steps 2 and 5).
#include "vision/side_view.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <stdexcept>

#include "vision/side_view_detail.hpp"

namespace reposetwin::vision {
using namespace side_detail;
namespace {

void check_settings(const SideSettings& s, const std::string& where) {
  auto bad = [&](const std::string& field, double v, const std::string& rule) {
    throw std::invalid_argument(where + ": side settings " + field + " " + rule + ", got " +
                                str(v));
  };
  auto band = [&](const std::string& name, double low, double high) {
    if (!(low >= 0.0 && low < high && high <= 1.0))
      throw std::invalid_argument(where + ": side settings " + name + "_low = " + str(low) +
                                  ", " + name + "_high = " + str(high) +
                                  " must satisfy 0 <= low < high <= 1");
  };
  band("flank_band", s.flank_band_low, s.flank_band_high);
  band("toe_band", s.toe_band_low, s.toe_band_high);
  if (s.edge_window_px < 1 || s.edge_window_px > 50)
    bad("edge_window_px", s.edge_window_px, "must be 1..50");
  if (s.morph_radius_px < 0 || s.morph_radius_px > 50)
    bad("morph_radius_px", s.morph_radius_px, "must be 0..50");
  if (!(s.plate_max_tilt_deg >= 0.0 && s.plate_max_tilt_deg < 30.0))
    bad("plate_max_tilt_deg", s.plate_max_tilt_deg, "must be in [0, 30)");
  if (!(s.threshold >= 0.0 && s.threshold < 2.0))
    bad("threshold", s.threshold, "must be 0 (Otsu) or a flat-field level in (0, 2)");
  if (!(s.smoothing_sigma_px >= 0.0 && s.smoothing_sigma_px <= 20.0))
    bad("smoothing_sigma_px", s.smoothing_sigma_px, "must be in [0, 20]");
  if (!(s.min_area_fraction >= 0.0 && s.min_area_fraction < 1.0))
    bad("min_area_fraction", s.min_area_fraction, "must be in [0, 1)");
}

// Mean of row `r` of a CV_32F image over columns [c0, c1] (clamped); NaN if empty.
double row_mean(const cv::Mat& img, int r, int c0, int c1) {
  c0 = std::max(c0, 0);
  c1 = std::min(c1, img.cols - 1);
  if (c1 < c0) return std::numeric_limits<double>::quiet_NaN();
  const float* p = img.ptr<float>(r);
  double s = 0.0;
  for (int c = c0; c <= c1; ++c) s += p[c];
  return s / (c1 - c0 + 1);
}

double col_mean(const cv::Mat& img, int c, int r0, int r1) {
  r0 = std::max(r0, 0);
  r1 = std::min(r1, img.rows - 1);
  if (r1 < r0) return std::numeric_limits<double>::quiet_NaN();
  double s = 0.0;
  for (int r = r0; r <= r1; ++r) s += img.at<float>(r, c);
  return s / (r1 - r0 + 1);
}

// Grains spread flat over the plate, apart from each other in the picture, are no heap: the
// largest dark blob resting on the plate is then one clump of a few grains, and measured as a
// pile it read atan(2H/D) of 40-60 deg (two grains side by side: 45 deg) for a layer one grain
// tall. A heap's blob stands out: strays and loose grains around it are a small fraction of its
// area. So when at least two other blobs resting on the plate are each at least 30% of the
// largest's area, the picture is refused with the numbers.
void refuse_scattered_grains(const cv::Mat& stats, int n_labels, int best, const PlateLine& plate,
                             int morph_radius_px, const std::string& where) {
  const int best_area = stats.at<int>(best, cv::CC_STAT_AREA);
  int similar = 0;
  int u0 = std::numeric_limits<int>::max(), u1 = std::numeric_limits<int>::min();
  for (int i = 1; i < n_labels; ++i) {
    const int area = stats.at<int>(i, cv::CC_STAT_AREA);
    const int x = stats.at<int>(i, cv::CC_STAT_LEFT), w = stats.at<int>(i, cv::CC_STAT_WIDTH);
    const int bottom = stats.at<int>(i, cv::CC_STAT_TOP) + stats.at<int>(i, cv::CC_STAT_HEIGHT) - 1;
    const double line_v = std::min(plate.v_at(x), plate.v_at(x + w - 1));
    if (bottom < std::floor(line_v - 0.5) - (morph_radius_px + 3)) continue;
    if (10 * area < 3 * best_area) continue;
    u0 = std::min(u0, x);
    u1 = std::max(u1, x + w - 1);
    if (i != best) ++similar;
  }
  if (similar < 2) return;
  throw std::runtime_error(where + ": no heap: the largest dark blob on the plate (" +
                           str(best_area) + " px, " + str(stats.at<int>(best, cv::CC_STAT_HEIGHT)) +
                           " px tall, " + str(stats.at<int>(best, cv::CC_STAT_WIDTH)) +
                           " px wide) is one of " + str(similar + 1) +
                           " blobs of similar size spread over " + str(u1 - u0 + 1) +
                           " px of the plate: grains lying flat, apart, not a pile with an angle");
}

// The pile's blob: the dark class above the plate line, the largest component resting on it,
// holes filled. `threshold` is the flat-field level that split the classes.
struct PileBlob {
  cv::Mat blob;          // CV_8U, the rows above the plate line only (rows_above x cols)
  int rows_above = 0;    // whole rows strictly above the plate line at either image end
  double threshold = 0;  // flat-field threshold used [-]
};

// The region strictly above the plate line (whole pixels), less the excluded rectangles.
cv::Mat above_plate(const cv::Mat& flat, const PlateLine& plate, const SideSettings& s,
                    const cv::Rect& roi, int rows_above) {
  cv::Mat above(rows_above, flat.cols, CV_8U, cv::Scalar(0));
  for (int r = 0; r < rows_above; ++r) {
    uchar* m = above.ptr<uchar>(r);
    for (int c = 0; c < flat.cols; ++c)
      if (r <= std::floor(plate.v_at(c) - 0.5)) m[c] = 255;
  }
  for (const cv::Rect& ex : s.exclude) {
    const cv::Rect local = (ex - roi.tl()) & cv::Rect(0, 0, above.cols, above.rows);
    if (!local.empty()) above(local).setTo(0);
  }
  return above;
}

// Step 3: Otsu's dark class above the plate line, opened and closed, and of its components the
// largest resting on the plate line; grains scattered flat are refused.
PileBlob find_pile_blob(const cv::Mat& flat, const PlateLine& plate, const SideSettings& s,
                        const cv::Rect& roi, const std::string& where) {
  PileBlob out;
  int rows_above = 0;
  for (double c : {0.0, flat.cols - 1.0})
    rows_above = std::max(rows_above, static_cast<int>(std::floor(plate.v_at(c) - 0.5)) + 1);
  rows_above = std::clamp(rows_above, 1, flat.rows);
  out.rows_above = rows_above;
  const cv::Mat upper = flat.rowRange(0, rows_above);
  const cv::Mat above = above_plate(flat, plate, s, roi, rows_above);
  if (cv::countNonZero(above) < 64)
    throw std::runtime_error(where + ": no pile found (the plate line at row " +
                             str(plate.v_at(0.5 * flat.cols) + roi.y) +
                             " leaves no image above it)");
  const double threshold = s.threshold > 0.0 ? s.threshold : otsu_threshold(upper, 0.0, 1.5, above);
  out.threshold = threshold;
  cv::Mat fg = (upper < threshold) & above;
  if (s.morph_radius_px > 0) {
    const int k = 2 * s.morph_radius_px + 1;
    const cv::Mat se = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k));
    cv::morphologyEx(fg, fg, cv::MORPH_OPEN, se);
    cv::morphologyEx(fg, fg, cv::MORPH_CLOSE, se);
    fg &= above;
  }
  cv::Mat labels, stats, centroids;
  const int n_labels = cv::connectedComponentsWithStats(fg, labels, stats, centroids, 8, CV_32S);
  const double min_area = std::max(50.0, s.min_area_fraction * flat.total());
  int best = -1;
  int best_area = 0;
  for (int i = 1; i < n_labels; ++i) {
    const int area = stats.at<int>(i, cv::CC_STAT_AREA);
    if (area < min_area || area <= best_area) continue;
    const int x = stats.at<int>(i, cv::CC_STAT_LEFT), w = stats.at<int>(i, cv::CC_STAT_WIDTH);
    const int bottom = stats.at<int>(i, cv::CC_STAT_TOP) + stats.at<int>(i, cv::CC_STAT_HEIGHT) - 1;
    const double line_v = std::min(plate.v_at(x), plate.v_at(x + w - 1));
    if (bottom < std::floor(line_v - 0.5) - (s.morph_radius_px + 3)) continue;
    best = i;
    best_area = area;
  }
  if (best < 0)
    throw std::runtime_error(where + ": no pile found (no dark blob of at least " +
                             str(std::round(min_area)) + " px resting on the plate line at row " +
                             str(std::round(plate.v_at(0.5 * flat.cols) + roi.y)) + ")");
  refuse_scattered_grains(stats, n_labels, best, plate, s.morph_radius_px, where);
  out.blob = labels == best;
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(out.blob, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  out.blob.setTo(0);
  cv::drawContours(out.blob, contours, -1, cv::Scalar(255), cv::FILLED);
  out.blob &= above;
  return out;
}

// A camera above the plate: the pile stands on the plate's top face, below its far edge. The
// blob then becomes the pile grown into the face (CV_8U, image size), holes filled, strictly
// above the toe line, which replaces `plate`, and `far_edge` is set. Otherwise the blob stays
// as found, the rows above the plate line only (the pile level's erosion treats the rows beyond
// a matrix's border as pile, so the two sizes are not the same measurement).
cv::Mat stand_on_top_face(const cv::Mat& flat, const PileBlob& pile, const SideSettings& s,
                          PlateLine& plate, std::optional<PlateLine>& far_edge) {
  cv::Mat full(flat.size(), CV_8U, cv::Scalar(0));
  pile.blob.copyTo(full.rowRange(0, pile.rows_above));
  const std::optional<TopFace> face = pile_on_top_face(flat, full, plate, s.morph_radius_px);
  if (!face) return pile.blob;
  far_edge = plate;
  plate = face->toe_line;
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(face->pile, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  cv::Mat blob(flat.size(), CV_8U, cv::Scalar(0));
  cv::drawContours(blob, contours, -1, cv::Scalar(255), cv::FILLED);
  for (int r = 0; r < blob.rows; ++r) {
    uchar* m = blob.ptr<uchar>(r);
    for (int c = 0; c < blob.cols; ++c)
      if (r > std::floor(plate.v_at(c) - 0.5)) m[c] = 0;
  }
  return blob;
}

// Pile level: median of the flat field inside the eroded blob.
double pile_level_of(const cv::Mat& flat, const cv::Mat& blob, const cv::Rect& box) {
  cv::Mat inner;
  cv::erode(blob, inner, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(7, 7)));
  if (cv::countNonZero(inner) < 10) inner = blob;
  std::vector<double> vals;
  vals.reserve(static_cast<size_t>(cv::countNonZero(inner)));
  for (int r = box.y; r < box.y + box.height; ++r) {
    const uchar* m = inner.ptr<uchar>(r);
    const float* f = flat.ptr<float>(r);
    for (int c = box.x; c < box.x + box.width; ++c)
      if (m[c]) vals.push_back(f[c]);
  }
  return median(vals);
}

// The blob's box, refused when the image (or ROI) border cuts the pile.
cv::Rect uncut_box(const cv::Mat& blob, const SideSettings& s, const std::string& where) {
  const cv::Rect box = cv::boundingRect(blob);
  if (box.y == 0 || box.x == 0 || box.x + box.width >= blob.cols)
    throw std::runtime_error(where + ": the pile is cut by the " +
                             std::string(box.y == 0 ? "top" : "left or right") + " border of the " +
                             (s.roi.empty() ? "image" : "region of interest") +
                             "; H and D would be wrong");
  return box;
}

// What the silhouette and apex steps read the segmented pile from.
struct PileRegion {
  const cv::Mat& flat;  // CV_32F, the segmentation image
  const cv::Mat& blob;  // CV_8U, the pile
  cv::Rect box;         // the blob's bounding box
  double level = 0.0;   // the pile's flat-field level
  int window = 0;       // half width of the sub-pixel edge window [px]
};

// Step 4: the sub-pixel silhouette, one left and one right point per row.
void silhouette(const PileRegion& p, const std::optional<PlateLine>& far_edge,
                std::vector<cv::Point2d>& left, std::vector<cv::Point2d>& right) {
  const cv::Mat& flat = p.flat;
  const cv::Rect& box = p.box;
  const double pile_level = p.level;
  const int w = p.window;
  auto coverage_sum = [&](int r, int c0, int c1, double back) {
    const float* f = flat.ptr<float>(r);
    double sum = 0.0;
    for (int c = c0; c <= c1; ++c) sum += (back - f[c]) / (back - pile_level);
    return sum;
  };
  // Rows seen against the plate's top face (below its far edge) have no backdrop to measure
  // coverage against: their edge is the blob's pixel boundary.
  auto against_face = [&](int r, int c) { return far_edge && r + 0.5 > far_edge->v_at(c); };
  for (int r = box.y; r < box.y + box.height; ++r) {
    const uchar* m = p.blob.ptr<uchar>(r);
    int ul = -1, ur = -1;
    for (int c = box.x; c < box.x + box.width; ++c)
      if (m[c]) {
        ul = c;
        break;
      }
    if (ul < 0) continue;
    for (int c = box.x + box.width - 1; c >= ul; --c)
      if (m[c]) {
        ur = c;
        break;
      }
    const int mid = (ul + ur) / 2;
    // Left edge: the pile occupies [x, +inf) inside the window [c0, c1].
    {
      const int c0 = ul - w, c1 = std::min(ul + w, mid);
      if (c0 >= 1 && c1 - ul >= 2) {
        double back = row_mean(flat, r, c0 - 4, c0 - 1);
        if (against_face(r, c0)) {
          left.emplace_back(ul - 0.5, r);
        } else {
          if (!(back > pile_level + 0.05)) back = 1.0;
          const double x = c1 + 0.5 - coverage_sum(r, c0, c1, back);
          if (x > c0 - 0.5 && x < c1 + 0.5) left.emplace_back(x, r);
        }
      }
    }
    {
      const int c1 = ur + w, c0 = std::max(ur - w, mid + 1);
      if (c1 <= flat.cols - 2 && ur - c0 >= 2) {
        double back = row_mean(flat, r, c1 + 1, c1 + 4);
        if (against_face(r, c1)) {
          right.emplace_back(ur + 0.5, r);
        } else {
          if (!(back > pile_level + 0.05)) back = 1.0;
          const double x = c0 - 0.5 + coverage_sum(r, c0, c1, back);
          if (x > c0 - 0.5 && x < c1 + 0.5) right.emplace_back(x, r);
        }
      }
    }
  }
}

// Apex: the top row's middle column and its neighbours, refined along the column.
cv::Point2d find_apex(const PileRegion& p, const PlateLine& plate) {
  const cv::Mat& flat = p.flat;
  const cv::Rect& box = p.box;
  const int w = p.window;
  cv::Point2d apex(0, 0);
  const int r = box.y;
  const uchar* m = p.blob.ptr<uchar>(r);
  std::vector<int> cs;
  for (int c = box.x; c < box.x + box.width; ++c)
    if (m[c]) cs.push_back(c);
  const int cmid = cs[cs.size() / 2];
  double best_h = -1e300;
  for (int c = std::max(cmid - 1, 0); c <= std::min(cmid + 1, flat.cols - 1); ++c) {
    const int r0 = r - w, r1 = std::min(r + w, box.y + box.height - 1);
    double y = r - 0.5;
    if (r0 >= 1) {
      double back = col_mean(flat, c, r0 - 4, r0 - 1);
      if (!(back > p.level + 0.05)) back = 1.0;
      double sum = 0.0;
      for (int rr = r0; rr <= r1; ++rr) sum += (back - flat.at<float>(rr, c)) / (back - p.level);
      y = r1 + 0.5 - sum;
      if (!(y > r0 - 0.5 && y < r1 + 0.5)) y = r - 0.5;
    }
    const cv::Point2d q(c, y);
    if (plate.height_above(q) > best_h) {
      best_h = plate.height_above(q);
      apex = q;
    }
  }
  return apex;
}

// The silhouette points whose height above the plate line lies in [lo, hi] [px].
std::vector<cv::Point2d> in_band(const std::vector<cv::Point2d>& edge, const PlateLine& plate,
                                 double lo, double hi) {
  std::vector<cv::Point2d> pts;
  for (const auto& p : edge) {
    const double h = plate.height_above(p);
    if (h >= lo && h <= hi) pts.push_back(p);
  }
  return pts;
}

// Step 5, the toe of one side: the low band of the flank carried to the plate line along the
// flank's slope.
InterceptFit toe_of(const std::vector<cv::Point2d>& edge, const FlankFit& flank,
                    const PlateLine& plate, double toe_lo, double toe_hi, const std::string& what) {
  std::vector<double> hs, xs;
  for (const auto& p : edge) {
    const double h = plate.height_above(p);
    if (h >= toe_lo && h <= toe_hi) {
      hs.push_back(h);
      xs.push_back(p.x);
    }
  }
  if (hs.size() < 3)
    throw std::runtime_error(what + " toe: too few silhouette rows between " + str(toe_lo) +
                             " and " + str(toe_hi) +
                             " px above the plate line (pile too small or cut by the image "
                             "border)");
  return toe_intercept(hs, xs, flank, plate);
}

// H, D and atan(2H/D) with their uncertainties, from the apex and the two toes.
void set_geometry(SideProfile& out, const InterceptFit& tl, const InterceptFit& tr,
                  const std::string& where) {
  const PlateLine& plate = out.plate;
  out.toe_left = cv::Point2d(tl.alpha, plate.v_at(tl.alpha));
  out.toe_right = cv::Point2d(tr.alpha, plate.v_at(tr.alpha));
  out.diameter_px = std::hypot(out.toe_right.x - out.toe_left.x, out.toe_right.y - out.toe_left.y);
  if (!(out.diameter_px > 2.0))
    throw std::runtime_error(where + ": toe points coincide (D = " + str(out.diameter_px) + " px)");
  out.sigma_height_px = std::hypot(0.5 / std::sqrt(3.0), plate.sigma_px);
  out.sigma_diameter_px = std::hypot(tl.sigma_alpha, tr.sigma_alpha);
  out.theta_deg = std::atan(2.0 * out.height_px / out.diameter_px) * kRadToDeg;
  const double hh = out.height_px, dd = out.diameter_px;
  const double den = dd * dd + 4.0 * hh * hh;
  const double dth_dh = 2.0 * dd / den, dth_dd = -2.0 * hh / den;
  out.sigma_theta_deg =
      std::hypot(dth_dh * out.sigma_height_px, dth_dd * out.sigma_diameter_px) * kRadToDeg;
}

// From the region of interest's coordinates to the full image's.
void to_full_image(SideProfile& out, const cv::Rect& roi) {
  const cv::Point2d off(roi.x, roi.y);
  if (off.x == 0.0 && off.y == 0.0) return;
  out.plate.a = out.plate.a + off.y - out.plate.b * off.x;
  if (out.far_edge) out.far_edge->a = out.far_edge->a + off.y - out.far_edge->b * off.x;
  out.apex += off;
  out.toe_left += off;
  out.toe_right += off;
  out.left.point += off;
  out.right.point += off;
  for (auto& p : out.left_edge) p += off;
  for (auto& p : out.right_edge) p += off;
  out.blob_box += roi.tl();
}

}  // namespace

SideImage prepare_side(const cv::Mat& image, const SideSettings& s, const std::string& where) {
  check_settings(s, where);
  const cv::Mat gray_full = gray_levels(image, where);
  check_contrast(gray_full, where);
  cv::Rect roi = s.roi.empty() ? cv::Rect(0, 0, gray_full.cols, gray_full.rows) : s.roi;
  if ((roi & cv::Rect(0, 0, gray_full.cols, gray_full.rows)) != roi || roi.width < 16 ||
      roi.height < 16)
    throw std::invalid_argument(where + ": roi " + str(roi.x) + "," + str(roi.y) + " " +
                                str(roi.width) + "x" + str(roi.height) +
                                " is not inside the image (" + str(gray_full.cols) + "x" +
                                str(gray_full.rows) + ") or smaller than 16x16 px");
  cv::Mat backdrop;
  if (!s.backdrop.empty()) {
    if (s.backdrop.size() != image.size())
      throw std::invalid_argument(where + ": backdrop image size differs from the image size");
    backdrop = s.backdrop(roi);
  }
  SideImage out;
  out.roi = roi;
  out.flat = flat_field(gray_full(roi), cv::Mat(), s.flat_field, where);
  if (s.smoothing_sigma_px > 0.0)
    cv::GaussianBlur(out.flat, out.flat, cv::Size(), s.smoothing_sigma_px, s.smoothing_sigma_px);
  if (backdrop.empty()) {
    out.segment = out.flat;
  } else {
    // Background difference: the empty scene cancels backdrop texture, plate and markers alike.
    out.segment = flat_field(gray_full(roi), backdrop, s.flat_field, where);
    if (s.smoothing_sigma_px > 0.0)
      cv::GaussianBlur(out.segment, out.segment, cv::Size(), s.smoothing_sigma_px,
                       s.smoothing_sigma_px);
  }
  return out;
}

SideProfile measure_side_pixels(const cv::Mat& image, const SideSettings& s,
                                const std::string& where) {
  return measure_side_pixels(prepare_side(image, s, where), s, where);
}

SideProfile measure_side_pixels(const SideImage& prepared, const SideSettings& s,
                                const std::string& where) {
  check_settings(s, where);
  const cv::Mat& flat = prepared.segment;
  if (flat.empty() || flat.size() != prepared.flat.size())
    throw std::invalid_argument(where + ": prepared side image is incomplete");
  SideProfile out;
  out.plate = find_plate_line(prepared.flat, s, where);
  const PileBlob pile = find_pile_blob(flat, out.plate, s, prepared.roi, where);
  const cv::Mat blob = stand_on_top_face(flat, pile, s, out.plate, out.far_edge);
  const PlateLine& plate = out.plate;
  PileRegion region{flat, blob, uncut_box(blob, s, where), 0.0, s.edge_window_px};
  region.level = pile_level_of(flat, blob, region.box);
  if (!(region.level < pile.threshold))
    throw std::runtime_error(where + ": no pile found (blob level " + str(region.level) +
                             " is not below the threshold " + str(pile.threshold) + ")");
  silhouette(region, out.far_edge, out.left_edge, out.right_edge);
  out.apex = find_apex(region, plate);
  out.height_px = plate.height_above(out.apex);
  if (!(out.height_px > 4.0))
    throw std::runtime_error(where + ": no pile found (blob only " + str(out.height_px) +
                             " px above the plate line)");
  // Flank lines over the middle band of the height, then the toes below them.
  const double height = out.height_px;
  out.left = fit_flank(
      in_band(out.left_edge, plate, s.flank_band_low * height, s.flank_band_high * height), plate,
      where + ": left flank");
  out.right = fit_flank(
      in_band(out.right_edge, plate, s.flank_band_low * height, s.flank_band_high * height), plate,
      where + ": right flank");
  const double toe_lo = std::max(s.toe_band_low * height, s.toe_min_gap_px);
  const double toe_hi = std::max(s.toe_band_high * height, toe_lo + 3.0);
  const InterceptFit tl = toe_of(out.left_edge, out.left, plate, toe_lo, toe_hi, where + ": left");
  const InterceptFit tr =
      toe_of(out.right_edge, out.right, plate, toe_lo, toe_hi, where + ": right");
  set_geometry(out, tl, tr, where);
  out.blob_box = region.box;
  out.pile_level = region.level;
  out.threshold = pile.threshold;
  to_full_image(out, prepared.roi);
  return out;
}

}  // namespace reposetwin::vision
