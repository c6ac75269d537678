#include "vision/side_view.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace reposetwin::vision {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;
// Standard deviation of a uniform error over one pixel [px].
const double kQuantisationPx = 1.0 / std::sqrt(12.0);
// A plate edge pixel has the backdrop this many rows above it [px].
constexpr int kCleanGapPx = 4;
// Long edges at least this fraction of the strongest are plate-line candidates [-].
constexpr double kPlateCandidateFraction = 0.2;

std::string str(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

void check_settings(const SideSettings& s, const std::string& where) {
  auto bad = [&](const std::string& field, double v, const std::string& rule) {
    throw std::invalid_argument(where + ": side settings " + field + " " + rule + ", got " +
                                str(v));
  };
  if (!(s.flank_band_low >= 0.0 && s.flank_band_low < s.flank_band_high &&
        s.flank_band_high <= 1.0))
    bad("flank_band_low/high", s.flank_band_low, "must satisfy 0 <= low < high <= 1");
  if (!(s.toe_band_low >= 0.0 && s.toe_band_low < s.toe_band_high && s.toe_band_high <= 1.0))
    bad("toe_band_low/high", s.toe_band_low, "must satisfy 0 <= low < high <= 1");
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

double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(mid), v.end());
  return v[mid];
}

// Sub-pixel position of the maximum of e around index i (parabola through three samples).
double parabola_peak(double em, double e0, double ep) {
  const double den = em - 2.0 * e0 + ep;
  if (std::abs(den) < 1e-12) return 0.0;
  return std::clamp(0.5 * (em - ep) / den, -0.5, 0.5);
}

// The points of a flank's silhouette that lie near one straight line: a Theil-Sen line
// x = x0 + k y (median of pairwise slopes, then median intercept) and the points within
// max(3 px, 5 robust sigmas) of it. All points when fewer than half (or 3) would remain. Only
// gross outliers go (the ends of a grain layer on the plate, tens of pixels off): at 3 sigmas
// the rough flanks of simulated piles lost rows too and their angles moved by up to 0.7 deg.
std::vector<cv::Point2d> flank_inliers(const std::vector<cv::Point2d>& p) {
  std::vector<double> slopes;
  const size_t step = std::max<size_t>(1, p.size() / 200);
  for (size_t i = 0; i < p.size(); i += step)
    for (size_t j = i + step; j < p.size(); j += step)
      if (p[j].y != p[i].y) slopes.push_back((p[j].x - p[i].x) / (p[j].y - p[i].y));
  if (slopes.empty()) return p;
  const double k = median(slopes);
  std::vector<double> icpt;
  icpt.reserve(p.size());
  for (const auto& q : p) icpt.push_back(q.x - k * q.y);
  const double x0 = median(icpt);
  const double norm = std::sqrt(1.0 + k * k);
  std::vector<double> dev;
  dev.reserve(p.size());
  for (const auto& q : p) dev.push_back(std::abs(q.x - x0 - k * q.y) / norm);
  const double cut = std::max(3.0, 5.0 * 1.4826 * median(dev));
  std::vector<cv::Point2d> kept;
  for (size_t i = 0; i < p.size(); ++i)
    if (dev[i] <= cut) kept.push_back(p[i]);
  return kept.size() >= std::max<size_t>(3, p.size() / 2) ? kept : p;
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

// The toe on one side: the column alpha where the silhouette's low band meets the plate
// (h = 0), with its standard error. beta = dx/dh is the fixed slope used to carry the band down.
struct InterceptFit {
  double alpha = 0.0, beta = 0.0, sigma_alpha = 0.0;
  int n = 0;
};

// The toe from the low band's silhouette points (heights h above the plate line, columns x) and
// the flank fitted over the middle band. Only the band's position is taken from the band; its
// slope is the flank's. A band a few percent of H tall is only a few particles tall on a real
// or simulated pile, and its local slope is the particles' outline (the bottom layer's near-
// vertical sides), not the pile's: a free line through it, extrapolated to the plate, throws the
// toe outwards by (slope error) x (band height). Carrying each band point to the plate along the
// flank direction instead makes the toe the band's offset from the flank line, which the
// particle texture only scatters. The offsets' median and then the mean of those within
// max(1 px, 3 robust sigmas) of it set aside loose particles lying on the plate beyond the toe
// (a low skirt in a level view). On a smooth cone the result is the flank line's toe.
InterceptFit toe_intercept(const std::vector<double>& h, const std::vector<double>& x,
                           const FlankFit& flank, const PlateLine& plate) {
  const cv::Point2d pd = plate.direction();
  const cv::Point2d up(pd.y, -pd.x);
  const double rise = flank.direction.dot(up);  // > 0 by fit_flank's orientation
  InterceptFit f;
  f.beta = flank.direction.x / std::max(rise, 1e-6);
  std::vector<double> off;
  off.reserve(h.size());
  for (size_t i = 0; i < h.size(); ++i) off.push_back(x[i] - f.beta * h[i]);
  const double med = median(off);
  std::vector<double> dev;
  for (double o : off) dev.push_back(std::abs(o - med));
  const double cut = std::max(1.0, 3.0 * 1.4826 * median(dev));
  double sum = 0.0, hsum = 0.0;
  for (size_t i = 0; i < off.size(); ++i)
    if (std::abs(off[i] - med) <= cut) {
      sum += off[i];
      hsum += h[i];
      ++f.n;
    }
  f.alpha = sum / f.n;
  // Never beyond the silhouette's own reach: where the band is the side of one layer of grains
  // (a flat pile, or a monolayer of grains around it), carrying every row along the flank moved
  // the toe outwards by up to the band's height times the flank's cotangent, while the toe is
  // the grains' reach. The reach is the band's outermost point, or, where the silhouette's
  // lowest rows slope like a flank (a least-squares line over the lowest quarter of the band, at
  // least 4 px, leaning inwards by at least half the flank's cotangent), its lowest row carried
  // down to the plate along the flank: that is a smooth cone's toe, while a grain's lower half
  // overhangs and its widest point is the reach. (The lowest rows' own slope is too noisy to
  // carry along: near the plate it mixes the bottom grains' outline with the flank.)
  const double outward = f.beta > 0.0 ? -1.0 : 1.0;
  double reach = -std::numeric_limits<double>::infinity();
  double h_low = std::numeric_limits<double>::infinity(), h_max = 0.0;
  for (size_t i = 0; i < h.size(); ++i) {
    reach = std::max(reach, outward * x[i]);
    h_low = std::min(h_low, h[i]);
    h_max = std::max(h_max, h[i]);
  }
  const double h_fit = h_low + std::max(4.0, 0.25 * (h_max - h_low));
  double sh = 0.0, sx = 0.0, shh = 0.0, shx = 0.0;
  int m = 0;
  for (size_t i = 0; i < h.size(); ++i)
    if (h[i] <= h_fit) {
      sh += h[i];
      sx += outward * x[i];
      shh += h[i] * h[i];
      shx += h[i] * outward * x[i];
      ++m;
    }
  double limit = reach;
  if (m >= 2 && shh * m - sh * sh > 1e-9) {
    const double slope = (m * shx - sh * sx) / (m * shh - sh * sh);  // outward per unit height
    const double carry = -slope >= 0.5 * std::abs(f.beta) ? std::abs(f.beta) : 0.0;
    double x_low = -std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < h.size(); ++i)
      if (h[i] <= h_low + 1.0) x_low = std::max(x_low, outward * x[i]);
    limit = std::max(limit, x_low + carry * h_low);
  }
  if (outward * f.alpha > limit) f.alpha = outward * limit;
  const double hm = hsum / f.n;
  double ss = 0.0;
  for (double o : off)
    if (std::abs(o - med) <= cut) ss += (o - f.alpha) * (o - f.alpha);
  const double s2 = f.n > 1 ? ss / (f.n - 1) : 0.0;
  // The slope's own error, dbeta = dphi / sin^2(phi), moves the toe by hm * dbeta.
  const double sin_phi = std::sin(flank.angle_deg / kRadToDeg);
  const double sigma_beta = flank.sigma_deg / kRadToDeg / std::max(sin_phi * sin_phi, 1e-6);
  f.sigma_alpha =
      std::sqrt((s2 + kQuantisationPx * kQuantisationPx) / f.n + hm * hm * sigma_beta * sigma_beta);
  return f;
}

// A camera above the plate sees the plate's top face as a band below its far edge (the edge
// find_plate_line finds: the lowest with backdrop above it), and the pile stands inside that
// band: its lower part is seen against the plate, not the backdrop, and its toes are below the
// far edge. Given the pile's blob above `edge` (CV_8U, image size), this grows the blob into the
// band (pixels unlike the plate's levels there, connected to the blob) and, when the pile
// reaches more than a few pixels below the edge, returns the
// line it stands on. The pile's lowest pixels trace the front half of its base (an ellipse
// through the two toes); at each end of the pile, the lowest pixel within 5% of its width is
// the bottom of the outermost grain, where it touches the plate (or, for a smooth pile, the end
// of the ellipse). The toe line runs through the two, parallel to the edge (lines on the plate
// stay parallel for a camera that does not roll). Measured on a rendered cone of 3.5 mm spheres
// photographed from 5 and 10 mm above the plate at 12 pile radii, it lies within 1-2 px of the
// base circle's tangent points. Returns std::nullopt when the pile ends at the edge (a level
// camera: the edge is the plate line) or the band cannot be read.
struct TopFace {
  PlateLine toe_line;
  cv::Mat pile;  // the blob grown into the band (CV_8U, image size)
};

std::optional<TopFace> pile_on_top_face(const cv::Mat& flat, const cv::Mat& blob,
                                        const PlateLine& edge, int morph_radius_px) {
  const cv::Rect box = cv::boundingRect(blob);
  if (box.empty()) return std::nullopt;
  const double h_above = edge.v_at(box.x + 0.5 * box.width) - box.y;
  if (!(h_above > 4.0)) return std::nullopt;
  // The plate's level, row by row, on each side of the pile (beyond its height above the edge
  // from its sides there, as it widens below the edge): the flat field is fitted to the backdrop
  // above and may drift over the band. Only columns with plate (not backdrop) just below the
  // edge count: beyond the plate's far corners the backdrop continues.
  auto first_row = [&](int c) { return static_cast<int>(std::floor(edge.v_at(c) - 0.5)) + 1; };
  const int r_top = std::max(0, std::min(first_row(0), first_row(flat.cols - 1)) + kCleanGapPx);
  int r_bot = std::min(
      flat.rows - 1, static_cast<int>(std::max(edge.v_at(0), edge.v_at(flat.cols - 1)) + h_above));
  if (r_bot - r_top < 4) return std::nullopt;
  const int pad = std::max(8, box.height);
  std::vector<int> left_cols, right_cols;
  for (int c = 0; c < flat.cols; ++c) {
    if (c >= box.x - pad && c < box.x + box.width + pad) continue;
    const int r = first_row(c) + kCleanGapPx;
    if (r < 0 || r >= flat.rows || std::abs(flat.at<float>(r, c) - 1.0f) < 0.25f) continue;
    (c < box.x ? left_cols : right_cols).push_back(c);
  }
  for (std::vector<int>* cols : {&left_cols, &right_cols}) {  // at most ~128 columns a side
    const size_t step = cols->size() / 128 + 1;
    std::vector<int> kept;
    for (size_t i = 0; i < cols->size(); i += step) kept.push_back((*cols)[i]);
    *cols = kept;
  }
  std::vector<double> level_left(flat.rows, std::nan("")), level_right(flat.rows, std::nan(""));
  std::vector<double> spread;
  for (int r = r_top; r <= r_bot; ++r) {
    std::vector<double> lv, rv;
    for (int c : left_cols)
      if (r >= first_row(c) + kCleanGapPx) lv.push_back(flat.at<float>(r, c));
    for (int c : right_cols)
      if (r >= first_row(c) + kCleanGapPx) rv.push_back(flat.at<float>(r, c));
    if (lv.size() >= 3) level_left[r] = median(lv);
    if (rv.size() >= 3) level_right[r] = median(rv);
    if (r < r_top + 6) {
      for (double v : lv) spread.push_back(std::abs(v - level_left[r]));
      for (double v : rv) spread.push_back(std::abs(v - level_right[r]));
    }
  }
  if (spread.size() < 30) return std::nullopt;
  const double tol = std::max(0.03, 4.0 * 1.4826 * median(spread));
  // The plate ends where its level steps (its near edge, its front face, the backdrop below):
  // the band is searched down to there only.
  for (int r = r_top + 1; r <= r_bot; ++r) {
    auto step = [&](const std::vector<double>& lv) {
      return std::isnan(lv[r]) || std::isnan(lv[r - 1]) ? false : std::abs(lv[r] - lv[r - 1]) > tol;
    };
    if (step(level_left) || step(level_right)) {
      r_bot = r - 1;
      break;
    }
  }
  // A pixel is plate when its level lies within the range of the plate's levels on the two
  // sides (give or take tol). One visible top face is one plane, read alike on both sides; a
  // level camera facing one of the square plate's corners (azimuth 45 or 135 deg) instead sees
  // two front faces below the edge, lit differently and meeting under the pile (with a blurred
  // column of in-between levels at the corner). A level interpolated across the pile differed
  // from both faces there, and the pile "continued" down the corner: H 64-76 mm for 47-59 mm.
  auto not_plate = [&](int r, int c) {
    const double l = level_left[r], rr = level_right[r];
    if (std::isnan(l) && std::isnan(rr)) return false;
    const double lo = std::isnan(l) ? rr : std::isnan(rr) ? l : std::min(l, rr);
    const double hi = std::isnan(l) ? rr : std::isnan(rr) ? l : std::max(l, rr);
    const float v = flat.at<float>(r, c);
    return v < lo - tol || v > hi + tol;
  };

  // A level camera's pile ends at the edge: nothing of it one "deep enough" row below the edge
  // (see the test on the deepest pixel below) ends the search early.
  const double min_depth = std::max(5.0, 0.04 * h_above);
  int below = 0;
  for (int c = box.x; c < box.x + box.width; ++c) {
    const int r = static_cast<int>(std::floor(edge.v_at(c) + min_depth)) + 1;
    if (r < r_top || r > r_bot) continue;
    if (not_plate(r, c)) ++below;
  }
  if (below < 3) return std::nullopt;
  // The band below the edge, as deep as the pile is tall above it; the pile widens downwards,
  // so every column is searched and connectivity to the blob decides. The first rows below the
  // edge are its blurred transition: they join the pile only in columns where the pile is on
  // both sides of them.
  cv::Mat grown = blob.clone();
  for (int c = 0; c < flat.cols; ++c) {
    const int r0 = first_row(c) + kCleanGapPx;
    for (int r = std::max(r0, 0); r <= r_bot; ++r) {
      if (not_plate(r, c)) grown.at<uchar>(r, c) = 255;
    }
    const int last_above = first_row(c) - 1;
    if (last_above >= 0 && r0 <= r_bot && blob.at<uchar>(last_above, c) && grown.at<uchar>(r0, c))
      for (int r = last_above + 1; r < r0; ++r) grown.at<uchar>(r, c) = 255;
  }
  if (morph_radius_px > 0) {
    const int k = 2 * morph_radius_px + 1;
    cv::morphologyEx(grown, grown, cv::MORPH_CLOSE,
                     cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k)));
  }
  cv::Mat labels;
  cv::connectedComponents(grown, labels, 8, CV_32S);
  // The component holding most of the blob.
  std::vector<int> overlap;
  for (int r = box.y; r < box.y + box.height; ++r)
    for (int c = box.x; c < box.x + box.width; ++c)
      if (blob.at<uchar>(r, c)) {
        const int l = labels.at<int>(r, c);
        if (l >= static_cast<int>(overlap.size())) overlap.resize(l + 1, 0);
        ++overlap[l];
      }
  if (overlap.size() < 2) return std::nullopt;
  const int label =
      static_cast<int>(std::max_element(overlap.begin() + 1, overlap.end()) - overlap.begin());
  const cv::Mat pile = labels == label;
  // Lowest pixel of the pile in each column, as a depth below the edge.
  std::vector<int> low(flat.cols, -1);
  int e0 = flat.cols, e1 = -1;
  double deepest = 0.0;
  for (int r = 0; r < flat.rows; ++r) {
    const uchar* m = pile.ptr<uchar>(r);
    for (int c = 0; c < flat.cols; ++c)
      if (m[c]) low[c] = r;
  }
  for (int c = 0; c < flat.cols; ++c) {
    if (low[c] < 0 || low[c] + 0.5 <= edge.v_at(c)) continue;
    e0 = std::min(e0, c);
    e1 = std::max(e1, c);
    deepest = std::max(deepest, low[c] + 0.5 - edge.v_at(c));
  }
  if (e1 - e0 < 8 || deepest <= min_depth) return std::nullopt;
  // Each toe: the lowest pixel near that end of the pile (detilted), i.e. the bottom of the
  // outermost grain on the plate, or the end of a smooth base ellipse.
  const int w = std::max(4, static_cast<int>(std::lround(0.05 * (e1 - e0))));
  auto lowest = [&](int from, int to) {
    double y = -1e300;
    for (int c = from; c <= to; ++c)
      if (low[c] >= 0) y = std::max(y, low[c] + 0.5 - edge.b * c);
    return y;
  };
  const double y_left = lowest(e0, e0 + w), y_right = lowest(e1 - w, e1);
  TopFace out;
  out.toe_line.b = edge.b;
  // The toe line is never above the far edge it was found under.
  out.toe_line.a = std::max(0.5 * (y_left + y_right), edge.a);
  out.toe_line.residual_px = 0.5 * std::abs(y_left - y_right);
  out.toe_line.support = 2;
  out.toe_line.sigma_px = std::hypot(out.toe_line.residual_px, kQuantisationPx);
  out.pile = pile;
  return out;
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
  throw std::runtime_error(
      where + ": no heap: the largest dark blob on the plate (" + str(best_area) + " px, " +
      str(stats.at<int>(best, cv::CC_STAT_HEIGHT)) + " px tall, " +
      str(stats.at<int>(best, cv::CC_STAT_WIDTH)) + " px wide) is one of " + str(similar + 1) +
      " blobs of similar size spread over " + str(u1 - u0 + 1) +
      " px of the plate: grains lying flat, apart, not a pile with an angle");
}

}  // namespace

double PlateLine::height_above(const cv::Point2d& p) const {
  return (v_at(p.x) - p.y) / std::sqrt(1.0 + b * b);
}

cv::Point2d PlateLine::direction() const {
  const double n = std::sqrt(1.0 + b * b);
  return {1.0 / n, b / n};
}

double PlateLine::tilt_deg() const { return std::atan(b) * kRadToDeg; }

PlateLine find_plate_line(const cv::Mat& flat, const SideSettings& s, const std::string& where) {
  CV_Assert(flat.type() == CV_32F);
  if (flat.rows < 8 || flat.cols < 8)
    throw std::invalid_argument(where + ": image region too small for a plate line (" +
                                str(flat.cols) + "x" + str(flat.rows) + " px)");
  cv::Mat gy;
  cv::Sobel(flat, gy, CV_32F, 0, 1, 3, s.plate_darker_than_backdrop ? -0.125 : 0.125);
  // The plate's edge against the backdrop: a step with the backdrop directly above it. Inside the
  // pile (and under a monolayer of grains on the plate) the plate line has pile above it instead;
  // those columns cannot tell the plate's edge from the grains' own top edge, so they are left out.
  auto backdrop_like = [](float v) { return v > 0.75f && v < 1.33f; };
  const int rows = flat.rows, ncols = flat.cols;
  // Row sums along lines of every tilt up to plate_max_tilt_deg (strips of columns, one step of
  // slope per pixel of drift across the image, searched coarse to fine): a long straight edge
  // adds up, noise, texture and sloping flanks do not.
  const int n_strips = std::clamp(ncols / 8, 4, 64);
  std::vector<double> strip_u(n_strips);
  std::vector<int> strip_c0(n_strips + 1, ncols);
  for (int k = 0; k < n_strips; ++k) {
    strip_c0[k] = k * ncols / n_strips;
    strip_u[k] = 0.5 * (strip_c0[k] + (k + 1) * ncols / n_strips - 1);
  }
  std::vector<std::vector<double>> strip_sum(n_strips, std::vector<double>(rows, 0.0));
  for (int r = kCleanGapPx; r < rows; ++r) {
    const float* g = gy.ptr<float>(r);
    const float* up = flat.ptr<float>(r - kCleanGapPx);
    for (int k = 0; k < n_strips; ++k) {
      float sum = 0.0f;
      for (int c = strip_c0[k]; c < strip_c0[k + 1]; ++c)
        if (g[c] > 0.0f && backdrop_like(up[c])) sum += g[c];
      strip_sum[k][r] = sum;
    }
  }
  const double u_mid = 0.5 * (ncols - 1);
  const double tilt = std::tan(s.plate_max_tilt_deg / kRadToDeg);
  const int n_slopes = static_cast<int>(std::ceil(tilt * ncols * 0.5));
  // Each strip shifted by a constant, linearly interpolated.
  auto sheared_profile = [&](double slope) {
    std::vector<double> prof(rows, 0.0);
    for (int k = 0; k < n_strips; ++k) {
      const double dv = slope * (strip_u[k] - u_mid);
      const int i0 = static_cast<int>(std::floor(dv));
      const double t = dv - i0;
      const std::vector<double>& sk = strip_sum[k];
      const int r0 = std::max(0, -i0), r1 = std::min(rows, rows - 1 - i0);
      for (int r = r0; r < r1; ++r) prof[r] += (1.0 - t) * sk[r + i0] + t * sk[r + i0 + 1];
    }
    return prof;
  };
  double b = 0.0, best = -1.0;
  auto try_slope = [&](int j) {
    const double slope = n_slopes > 0 ? tilt * j / n_slopes : 0.0;
    const std::vector<double> prof = sheared_profile(slope);
    for (int r = 1; r < rows - 1; ++r)
      if (prof[r] > best) {
        best = prof[r];
        b = slope;
      }
  };
  // Every fourth slope, then the neighbours of the best.
  for (int j = -n_slopes; j <= n_slopes; j += 4) try_slope(j);
  const int j_best = n_slopes > 0 ? static_cast<int>(std::lround(b / tilt * n_slopes)) : 0;
  for (int j = std::max(-n_slopes, j_best - 3); j <= std::min(n_slopes, j_best + 3); ++j)
    if (j != j_best) try_slope(j);
  // An average step of 0.02 of the backdrop level over the whole width, at the least.
  if (!(best > 0.02 * 0.5 * ncols))
    throw std::runtime_error(
        where + ": no plate line found (no long horizontal " +
        std::string(s.plate_darker_than_backdrop ? "bright-to-dark" : "dark-to-bright") +
        " edge below the backdrop)");
  // Several long edges may qualify: the plate's, and the top edge of a layer of grains lying on
  // the plate (a sparse pile edge), which is longer than the plate's visible ends beside the
  // pile. The plate is the lowest of them (grains lie on the plate, not under it).
  const std::vector<double> prof = sheared_profile(b);
  int v0 = -1;
  for (int r = rows - 3; r >= 2 && v0 < 0; --r) {
    const double p = prof[r];
    if (p >= kPlateCandidateFraction * best && p >= prof[r - 1] && p >= prof[r - 2] &&
        p >= prof[r + 1] && p >= prof[r + 2])
      v0 = r;
  }
  if (v0 < 0) v0 = 1;
  double a = v0 - b * u_mid;

  // Columns whose backdrop is directly above the line carry the plate edge cleanly.
  std::vector<int> cols;
  for (int c = 0; c < ncols; ++c) {
    const int r = static_cast<int>(std::lround(a + b * c)) - kCleanGapPx;
    if (r >= 0 && r < rows && backdrop_like(flat.at<float>(r, c))) cols.push_back(c);
  }
  if (static_cast<int>(cols.size()) < std::max(8, ncols / 40))
    throw std::runtime_error(where + ": no plate line found (the edge near row " + str(v0) +
                             " shows backdrop above it in only " +
                             str(static_cast<double>(cols.size())) + " columns)");

  auto column_peaks = [&](double a, double b, int m, std::vector<cv::Point2d>& pts,
                          std::vector<double>& strength) {
    pts.clear();
    strength.clear();
    for (int c : cols) {
      const int center = static_cast<int>(std::lround(a + b * c));
      const int lo = std::max(1, center - m), hi = std::min(flat.rows - 2, center + m);
      if (hi < lo) continue;
      int best_r = lo;
      float best_e = -std::numeric_limits<float>::infinity();
      for (int r = lo; r <= hi; ++r) {
        const float e = gy.at<float>(r, c);
        if (e > best_e) {
          best_e = e;
          best_r = r;
        }
      }
      if (!(best_e > 0.0f)) continue;
      const double off =
          parabola_peak(gy.at<float>(best_r - 1, c), best_e, gy.at<float>(best_r + 1, c));
      pts.emplace_back(c, best_r + off);
      strength.push_back(best_e);
    }
  };

  std::vector<cv::Point2d> pts;
  std::vector<double> strength;
  PlateLine line;
  for (int pass = 0; pass < 2; ++pass) {
    column_peaks(a, b, 3, pts, strength);
    const double strong = 0.3 * median(strength);
    std::vector<cv::Point2f> kept;
    for (size_t i = 0; i < pts.size(); ++i)
      if (strength[i] >= strong)
        kept.emplace_back(static_cast<float>(pts[i].x - u_mid), static_cast<float>(pts[i].y - a));
    if (kept.size() < 8)
      throw std::runtime_error(where + ": no plate line found (edge too weak near row " + str(a) +
                               ")");
    cv::Vec4f fl;
    cv::fitLine(kept, fl, cv::DIST_HUBER, 0, 0.01, 0.01);
    const double bb = fl[1] / fl[0];
    const double vmid = a + fl[3] + bb * (0.0 - fl[2]);  // v at u = u_mid
    b = bb;
    a = vmid - b * u_mid;
    double ss = 0.0;
    int n = 0;
    for (size_t i = 0; i < pts.size(); ++i) {
      if (strength[i] < strong) continue;
      const double r = (pts[i].y - (a + b * pts[i].x)) / std::sqrt(1.0 + b * b);
      ss += r * r;
      ++n;
    }
    line.a = a;
    line.b = b;
    line.residual_px = std::sqrt(ss / std::max(n, 1));
    line.support = n;
    line.sigma_px = std::sqrt(line.residual_px * line.residual_px / std::max(n, 1) +
                              kQuantisationPx * kQuantisationPx / std::max(n, 1));
  }
  return line;
}

FlankFit fit_flank(const std::vector<cv::Point2d>& points, const PlateLine& plate,
                   const std::string& what) {
  if (points.size() < 3)
    throw std::runtime_error(what + ": too few silhouette points for a flank fit (" +
                             str(static_cast<double>(points.size())) + ")");
  // Rows that belong to something else than the flank (a layer of grains on the plate reaching
  // into the band, a grain stuck out of the surface) lie far off the flank and would pull even a
  // Huber fit: a Theil-Sen line (column against row, never horizontal for a flank) sets aside
  // points farther from it than max(1.5 px, 3 robust sigmas) before the fit.
  const std::vector<cv::Point2d> inliers = flank_inliers(points);
  cv::Point2d mean(0, 0);
  for (const auto& p : inliers) mean += p;
  mean *= 1.0 / inliers.size();
  std::vector<cv::Point2f> centred;
  centred.reserve(inliers.size());
  for (const auto& p : inliers)
    centred.emplace_back(static_cast<float>(p.x - mean.x), static_cast<float>(p.y - mean.y));
  cv::Vec4f fl;
  cv::fitLine(centred, fl, cv::DIST_HUBER, 0, 0.01, 0.01);
  FlankFit f;
  cv::Point2d dir(fl[0], fl[1]);
  dir *= 1.0 / std::hypot(dir.x, dir.y);
  const cv::Point2d pd = plate.direction();
  const cv::Point2d up(pd.y, -pd.x);  // plate normal pointing to smaller v
  if (dir.dot(up) < 0.0) dir = -dir;
  f.direction = dir;
  f.point = mean + cv::Point2d(fl[2], fl[3]);
  f.angle_deg = std::atan2(std::abs(dir.dot(up)), std::abs(dir.dot(pd))) * kRadToDeg;
  const cv::Point2d normal(-dir.y, dir.x);
  double ss = 0.0, tmean = 0.0, tmin = 1e300, tmax = -1e300;
  std::vector<double> t;
  t.reserve(points.size());
  for (const auto& p : points) {
    const cv::Point2d d = p - f.point;
    const double r = d.dot(normal);
    ss += r * r;
    t.push_back(d.dot(dir));
    tmean += t.back();
    tmin = std::min(tmin, t.back());
    tmax = std::max(tmax, t.back());
  }
  const int n = static_cast<int>(points.size());
  tmean /= n;
  double stt = 0.0;
  for (double x : t) stt += (x - tmean) * (x - tmean);
  f.points = n;
  f.residual_px = std::sqrt(ss / n);
  const double dof = n > 2 ? static_cast<double>(n) / (n - 2) : 1.0;
  f.sigma_fit_deg = stt > 0.0 ? f.residual_px * std::sqrt(dof / stt) * kRadToDeg : 90.0;
  const double length = tmax - tmin;
  f.sigma_pixel_deg = length > 0.0 ? std::sqrt(2.0) * kQuantisationPx / length * kRadToDeg : 90.0;
  f.sigma_deg = std::hypot(f.sigma_fit_deg, f.sigma_pixel_deg);
  double hmin = 1e300, hmax = -1e300;
  for (const auto& p : points) {
    hmin = std::min(hmin, plate.height_above(p));
    hmax = std::max(hmax, plate.height_above(p));
  }
  f.low_px = hmin;
  f.high_px = hmax;
  return f;
}

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
  const cv::Rect roi = prepared.roi;
  if (flat.empty() || flat.size() != prepared.flat.size())
    throw std::invalid_argument(where + ": prepared side image is incomplete");
  SideProfile out;
  PlateLine plate = find_plate_line(prepared.flat, s, where);

  // Region strictly above the plate line (whole pixels); segmentation works on those rows only.
  int rows_above = 0;
  for (double c : {0.0, flat.cols - 1.0})
    rows_above = std::max(rows_above, static_cast<int>(std::floor(plate.v_at(c) - 0.5)) + 1);
  rows_above = std::clamp(rows_above, 1, flat.rows);
  const cv::Mat upper = flat.rowRange(0, rows_above);
  cv::Mat above(upper.size(), CV_8U, cv::Scalar(0));
  for (int r = 0; r < rows_above; ++r) {
    uchar* m = above.ptr<uchar>(r);
    for (int c = 0; c < flat.cols; ++c)
      if (r <= std::floor(plate.v_at(c) - 0.5)) m[c] = 255;
  }
  for (const cv::Rect& ex : s.exclude) {
    const cv::Rect local = (ex - roi.tl()) & cv::Rect(0, 0, above.cols, above.rows);
    if (!local.empty()) above(local).setTo(0);
  }
  if (cv::countNonZero(above) < 64)
    throw std::runtime_error(where + ": no pile found (the plate line at row " +
                             str(plate.v_at(0.5 * flat.cols) + roi.y) +
                             " leaves no image above it)");
  const double threshold = s.threshold > 0.0 ? s.threshold : otsu_threshold(upper, 0.0, 1.5, above);
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
  cv::Mat blob = labels == best;
  {
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(blob, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
    blob.setTo(0);
    cv::drawContours(blob, contours, -1, cv::Scalar(255), cv::FILLED);
    blob &= above;
  }
  // A camera above the plate: the pile stands on the plate's top face, below its far edge. The
  // blob then becomes the pile grown into the face, holes filled, strictly above the toe line.
  std::optional<PlateLine> far_edge;
  {
    cv::Mat full(flat.size(), CV_8U, cv::Scalar(0));
    blob.copyTo(full.rowRange(0, rows_above));
    if (auto face = pile_on_top_face(flat, full, plate, s.morph_radius_px)) {
      far_edge = plate;
      plate = face->toe_line;
      std::vector<std::vector<cv::Point>> contours;
      cv::findContours(face->pile, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
      blob = cv::Mat(flat.size(), CV_8U, cv::Scalar(0));
      cv::drawContours(blob, contours, -1, cv::Scalar(255), cv::FILLED);
      for (int r = 0; r < blob.rows; ++r) {
        uchar* m = blob.ptr<uchar>(r);
        for (int c = 0; c < blob.cols; ++c)
          if (r > std::floor(plate.v_at(c) - 0.5)) m[c] = 0;
      }
    }
  }
  const cv::Rect box = cv::boundingRect(blob);

  if (box.y == 0 || box.x == 0 || box.x + box.width >= flat.cols)
    throw std::runtime_error(where + ": the pile is cut by the " +
                             std::string(box.y == 0 ? "top" : "left or right") + " border of the " +
                             (s.roi.empty() ? "image" : "region of interest") +
                             "; H and D would be wrong");

  // Pile level: median of the flat field inside the eroded blob.
  double pile_level;
  {
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
    pile_level = median(vals);
  }
  if (!(pile_level < threshold))
    throw std::runtime_error(where + ": no pile found (blob level " + str(pile_level) +
                             " is not below the threshold " + str(threshold) + ")");

  // Sub-pixel silhouette, one left and one right point per row.
  const int w = s.edge_window_px;
  auto coverage_sum = [&](int r, int c0, int c1, double back) {
    const float* f = flat.ptr<float>(r);
    double sum = 0.0;
    for (int c = c0; c <= c1; ++c) sum += (back - f[c]) / (back - pile_level);
    return sum;
  };
  // Rows seen against the plate's top face (below its far edge) have no backdrop to measure
  // coverage against: their edge is the blob's pixel boundary.
  auto against_face = [&](int r, int c) { return far_edge && r + 0.5 > far_edge->v_at(c); };
  std::vector<cv::Point2d> left, right;
  for (int r = box.y; r < box.y + box.height; ++r) {
    const uchar* m = blob.ptr<uchar>(r);
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

  // Apex: the top row's middle column and its neighbours, refined along the column.
  cv::Point2d apex(0, 0);
  {
    const int r = box.y;
    const uchar* m = blob.ptr<uchar>(r);
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
        if (!(back > pile_level + 0.05)) back = 1.0;
        double sum = 0.0;
        for (int rr = r0; rr <= r1; ++rr)
          sum += (back - flat.at<float>(rr, c)) / (back - pile_level);
        y = r1 + 0.5 - sum;
        if (!(y > r0 - 0.5 && y < r1 + 0.5)) y = r - 0.5;
      }
      const cv::Point2d p(c, y);
      if (plate.height_above(p) > best_h) {
        best_h = plate.height_above(p);
        apex = p;
      }
    }
  }
  const double height = plate.height_above(apex);
  if (!(height > 4.0))
    throw std::runtime_error(where + ": no pile found (blob only " + str(height) +
                             " px above the plate line)");

  // Flank lines over the middle band of the height.
  auto band = [&](const std::vector<cv::Point2d>& edge) {
    std::vector<cv::Point2d> pts;
    for (const auto& p : edge) {
      const double h = plate.height_above(p);
      if (h >= s.flank_band_low * height && h <= s.flank_band_high * height) pts.push_back(p);
    }
    return pts;
  };
  out.left = fit_flank(band(left), plate, where + ": left flank");
  out.right = fit_flank(band(right), plate, where + ": right flank");

  // Toe points: the low band of each flank carried to the plate line along the flank's slope.
  const double toe_lo = std::max(s.toe_band_low * height, s.toe_min_gap_px);
  const double toe_hi = std::max(s.toe_band_high * height, toe_lo + 3.0);
  auto toe = [&](const std::vector<cv::Point2d>& edge, const FlankFit& flank,
                 const std::string& side) {
    std::vector<double> hs, xs;
    for (const auto& p : edge) {
      const double h = plate.height_above(p);
      if (h >= toe_lo && h <= toe_hi) {
        hs.push_back(h);
        xs.push_back(p.x);
      }
    }
    if (hs.size() < 3)
      throw std::runtime_error(where + ": " + side + " toe: too few silhouette rows between " +
                               str(toe_lo) + " and " + str(toe_hi) +
                               " px above the plate line (pile too small or cut by the image "
                               "border)");
    return toe_intercept(hs, xs, flank, plate);
  };
  const InterceptFit tl = toe(left, out.left, "left"), tr = toe(right, out.right, "right");
  const cv::Point2d toe_left(tl.alpha, plate.v_at(tl.alpha));
  const cv::Point2d toe_right(tr.alpha, plate.v_at(tr.alpha));

  out.plate = plate;
  out.far_edge = far_edge;
  out.apex = apex;
  out.toe_left = toe_left;
  out.toe_right = toe_right;
  out.height_px = height;
  out.diameter_px = std::hypot(toe_right.x - toe_left.x, toe_right.y - toe_left.y);
  if (!(out.diameter_px > 2.0))
    throw std::runtime_error(where + ": toe points coincide (D = " + str(out.diameter_px) + " px)");
  out.sigma_height_px = std::hypot(0.5 / std::sqrt(3.0), plate.sigma_px);
  out.sigma_diameter_px = std::hypot(tl.sigma_alpha, tr.sigma_alpha);
  out.theta_deg = std::atan(2.0 * out.height_px / out.diameter_px) * kRadToDeg;
  {
    const double hh = out.height_px, dd = out.diameter_px;
    const double den = dd * dd + 4.0 * hh * hh;
    const double dth_dh = 2.0 * dd / den, dth_dd = -2.0 * hh / den;
    out.sigma_theta_deg =
        std::hypot(dth_dh * out.sigma_height_px, dth_dd * out.sigma_diameter_px) * kRadToDeg;
  }
  out.left_edge = std::move(left);
  out.right_edge = std::move(right);
  out.blob_box = box;
  out.pile_level = pile_level;
  out.threshold = threshold;

  // Back to full-image coordinates.
  const cv::Point2d off(roi.x, roi.y);
  if (off.x != 0.0 || off.y != 0.0) {
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
  return out;
}

}  // namespace reposetwin::vision
