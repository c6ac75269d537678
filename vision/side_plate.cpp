// The plate line of a side view and, for a camera above the plate, the toe line on the plate's
// top face (side_view.hpp's design note, step 2).
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

// A plate edge pixel has the backdrop this many rows above it [px].
constexpr int kCleanGapPx = 4;
// Long edges at least this fraction of the strongest are plate-line candidates [-].
constexpr double kPlateCandidateFraction = 0.2;
// The plate's level beside the pile is read from at least this many columns a side [-].
constexpr int kSideColumns = 16;

// Sub-pixel position of the maximum of e around index i (parabola through three samples).
double parabola_peak(double em, double e0, double ep) {
  const double den = em - 2.0 * e0 + ep;
  if (std::abs(den) < 1e-12) return 0.0;
  return std::clamp(0.5 * (em - ep) / den, -0.5, 0.5);
}

// The plate's top face below its far edge, row by row: its level on each side of the pile, how
// far down it reaches, and the tolerance within which a pixel reads as plate.
struct FaceBand {
  FaceBand(const cv::Mat& flat_field, const PlateLine& far_edge)
      : flat(flat_field), edge(far_edge) {}

  const cv::Mat& flat;
  const PlateLine& edge;
  cv::Mat valid;                    // CV_8U, pixels from inside the photo (empty: all)
  int r_top = 0, r_bot = 0;         // rows searched [px]
  std::vector<double> left, right;  // the plate's level per row beside the pile (NaN: none)
  double tol = 0.0;                 // a pixel within tol of the levels' range is plate [-]

  // The first row below the edge in column c.
  int first_row(int c) const { return static_cast<int>(std::floor(edge.v_at(c) - 0.5)) + 1; }

  // A pixel is plate when its level lies within the range of the plate's levels on the two
  // sides (give or take tol). One visible top face is one plane, read alike on both sides; a
  // level camera facing one of the square plate's corners (azimuth 45 or 135 deg) instead sees
  // two front faces below the edge, lit differently and meeting under the pile (with a blurred
  // column of in-between levels at the corner). A level interpolated across the pile differed
  // from both faces there, and the pile "continued" down the corner: H 64-76 mm for 47-59 mm.
  bool not_plate(int r, int c) const {
    const double l = left[r], rr = right[r];
    if (std::isnan(l) && std::isnan(rr)) return false;
    const double lo = std::isnan(l) ? rr : std::isnan(rr) ? l : std::min(l, rr);
    const double hi = std::isnan(l) ? rr : std::isnan(rr) ? l : std::max(l, rr);
    const float v = flat.at<float>(r, c);
    return v < lo - tol || v > hi + tol;
  }
};

// The plate's columns on each side of the pile: beyond its height above the edge from its sides
// there (as it widens below the edge), or, on a side where the image holds fewer than
// kSideColumns of those, that side's kSideColumns outermost columns (at least 8 px from the
// pile), the farthest from it the image has. Each side must be read: a level camera facing the
// plate's corner sees two faces, and with one side unread the other face reads as pile. With
// the margin alone, a pile as wide as most of the image left one side unread and grew into the
// other face down to the image border (the twin's 1800 g piles at azimuth 135 deg, pile 1140 px
// of 1920 and 380 px tall: refused as cut by the border; now H 78.0 mm, D 232.5 mm). Only
// columns with plate (not backdrop) just below the edge count: beyond the plate's far corners
// the backdrop continues.
void face_columns(const FaceBand& f, const cv::Rect& box, std::vector<int>& left_cols,
                  std::vector<int>& right_cols) {
  constexpr int kNearPx = 8;
  const int pad = std::max(kNearPx, box.height);
  left_cols.clear();
  right_cols.clear();
  for (int c = 0; c < f.flat.cols; ++c) {
    if (c >= box.x - kNearPx && c < box.x + box.width + kNearPx) continue;
    const int r = f.first_row(c) + kCleanGapPx;
    if (r < 0 || r >= f.flat.rows || std::abs(f.flat.at<float>(r, c) - 1.0f) < 0.25f) continue;
    (c < box.x ? left_cols : right_cols).push_back(c);
  }
  // Both lists ascend: the left side's outermost columns come first, the right side's last.
  const auto far_left = std::lower_bound(left_cols.begin(), left_cols.end(), box.x - pad);
  const long n_left = std::max<long>(far_left - left_cols.begin(), kSideColumns);
  left_cols.resize(std::min<size_t>(left_cols.size(), n_left));
  const auto far_right =
      std::lower_bound(right_cols.begin(), right_cols.end(), box.x + box.width + pad);
  const long n_right = std::max<long>(right_cols.end() - far_right, kSideColumns);
  if (static_cast<long>(right_cols.size()) > n_right)
    right_cols.erase(right_cols.begin(), right_cols.end() - n_right);
}

// The plate's level, row by row, on each side of the pile (face_columns says where): the flat
// field is fitted to the backdrop above and may drift over the band. Returns false when the
// band cannot be read.
bool read_face_levels(FaceBand& f, const cv::Rect& box, double h_above) {
  const cv::Mat& flat = f.flat;
  f.r_top = std::max(0, std::min(f.first_row(0), f.first_row(flat.cols - 1)) + kCleanGapPx);
  f.r_bot =
      std::min(flat.rows - 1,
               static_cast<int>(std::max(f.edge.v_at(0), f.edge.v_at(flat.cols - 1)) + h_above));
  if (f.r_bot - f.r_top < 4) return false;
  std::vector<int> left_cols, right_cols;
  face_columns(f, box, left_cols, right_cols);
  for (std::vector<int>* cols : {&left_cols, &right_cols}) {  // at most ~128 columns a side
    const size_t step = cols->size() / 128 + 1;
    std::vector<int> kept;
    for (size_t i = 0; i < cols->size(); i += step) kept.push_back((*cols)[i]);
    *cols = kept;
  }
  f.left.assign(flat.rows, std::nan(""));
  f.right.assign(flat.rows, std::nan(""));
  std::vector<double> spread;
  for (int r = f.r_top; r <= f.r_bot; ++r) {
    std::vector<double> lv, rv;
    // A level view's pixels from outside the photo (a rolled camera's corners) repeat its
    // border, the bench below the plate among them: they are no level of the plate.
    auto seen = [&](int c) { return f.valid.empty() || f.valid.at<uchar>(r, c); };
    for (int c : left_cols)
      if (r >= f.first_row(c) + kCleanGapPx && seen(c)) lv.push_back(flat.at<float>(r, c));
    for (int c : right_cols)
      if (r >= f.first_row(c) + kCleanGapPx && seen(c)) rv.push_back(flat.at<float>(r, c));
    if (lv.size() >= 3) f.left[r] = median(lv);
    if (rv.size() >= 3) f.right[r] = median(rv);
    if (r < f.r_top + 6) {
      for (double v : lv) spread.push_back(std::abs(v - f.left[r]));
      for (double v : rv) spread.push_back(std::abs(v - f.right[r]));
    }
  }
  if (spread.size() < 30) return false;
  f.tol = std::max(0.03, 4.0 * 1.4826 * median(spread));
  // The plate ends where its level steps (its near edge, its front face, the backdrop below):
  // the band is searched down to there only.
  for (int r = f.r_top + 1; r <= f.r_bot; ++r) {
    auto step = [&](const std::vector<double>& lv) {
      return std::isnan(lv[r]) || std::isnan(lv[r - 1]) ? false
                                                        : std::abs(lv[r] - lv[r - 1]) > f.tol;
    };
    if (step(f.left) || step(f.right)) {
      f.r_bot = r - 1;
      break;
    }
  }
  return true;
}

// The blob grown into the band: every column is searched (the pile widens downwards) and
// connectivity to the blob decides. The first rows below the edge are its blurred transition:
// they join the pile only in columns where the pile is on both sides of them. Returns the
// component holding most of the blob (CV_8U), or an empty matrix.
cv::Mat grow_into_face(const FaceBand& f, const cv::Mat& blob, const cv::Rect& box,
                       int morph_radius_px) {
  const cv::Mat& flat = f.flat;
  cv::Mat grown = blob.clone();
  for (int c = 0; c < flat.cols; ++c) {
    const int r0 = f.first_row(c) + kCleanGapPx;
    for (int r = std::max(r0, 0); r <= f.r_bot; ++r) {
      if (f.not_plate(r, c)) grown.at<uchar>(r, c) = 255;
    }
    const int last_above = f.first_row(c) - 1;
    if (last_above >= 0 && r0 <= f.r_bot && blob.at<uchar>(last_above, c) && grown.at<uchar>(r0, c))
      for (int r = last_above + 1; r < r0; ++r) grown.at<uchar>(r, c) = 255;
  }
  if (morph_radius_px > 0) {
    const int k = 2 * morph_radius_px + 1;
    cv::morphologyEx(grown, grown, cv::MORPH_CLOSE,
                     cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k)));
  }
  cv::Mat labels;
  cv::connectedComponents(grown, labels, 8, CV_32S);
  std::vector<int> overlap;
  for (int r = box.y; r < box.y + box.height; ++r)
    for (int c = box.x; c < box.x + box.width; ++c)
      if (blob.at<uchar>(r, c)) {
        const int l = labels.at<int>(r, c);
        if (l >= static_cast<int>(overlap.size())) overlap.resize(l + 1, 0);
        ++overlap[l];
      }
  if (overlap.size() < 2) return cv::Mat();
  const int label =
      static_cast<int>(std::max_element(overlap.begin() + 1, overlap.end()) - overlap.begin());
  return labels == label;
}

// The toe line under the grown pile: through the lowest pixel near each end (detilted), the
// bottom of the outermost grain on the plate or the end of a smooth base ellipse, parallel to
// the edge. std::nullopt when the pile does not reach deeper than min_depth below the edge.
std::optional<PlateLine> toe_line_under(const cv::Mat& pile, const PlateLine& edge,
                                        double min_depth) {
  // Lowest pixel of the pile in each column, as a depth below the edge.
  std::vector<int> low(pile.cols, -1);
  int e0 = pile.cols, e1 = -1;
  double deepest = 0.0;
  for (int r = 0; r < pile.rows; ++r) {
    const uchar* m = pile.ptr<uchar>(r);
    for (int c = 0; c < pile.cols; ++c)
      if (m[c]) low[c] = r;
  }
  for (int c = 0; c < pile.cols; ++c) {
    if (low[c] < 0 || low[c] + 0.5 <= edge.v_at(c)) continue;
    e0 = std::min(e0, c);
    e1 = std::max(e1, c);
    deepest = std::max(deepest, low[c] + 0.5 - edge.v_at(c));
  }
  if (e1 - e0 < 8 || deepest <= min_depth) return std::nullopt;
  const int w = std::max(4, static_cast<int>(std::lround(0.05 * (e1 - e0))));
  auto lowest = [&](int from, int to) {
    double y = -1e300;
    for (int c = from; c <= to; ++c)
      if (low[c] >= 0) y = std::max(y, low[c] + 0.5 - edge.b * c);
    return y;
  };
  const double y_left = lowest(e0, e0 + w), y_right = lowest(e1 - w, e1);
  PlateLine line;
  line.b = edge.b;
  // The toe line is never above the far edge it was found under.
  line.a = std::max(0.5 * (y_left + y_right), edge.a);
  line.residual_px = 0.5 * std::abs(y_left - y_right);
  line.support = 2;
  line.sigma_px = std::hypot(line.residual_px, kQuantisationPx);
  return line;
}

}  // namespace

namespace side_detail {

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
std::optional<TopFace> pile_on_top_face(const cv::Mat& flat, const cv::Mat& blob,
                                        const PlateLine& edge, int morph_radius_px,
                                        const cv::Mat& valid) {
  const cv::Rect box = cv::boundingRect(blob);
  if (box.empty()) return std::nullopt;
  const double h_above = edge.v_at(box.x + 0.5 * box.width) - box.y;
  if (!(h_above > 4.0)) return std::nullopt;
  FaceBand band(flat, edge);
  band.valid = valid;
  if (!read_face_levels(band, box, h_above)) return std::nullopt;
  // A level camera's pile ends at the edge: nothing of it one "deep enough" row below the edge
  // (see the test on the deepest pixel below) ends the search early.
  const double min_depth = std::max(5.0, 0.04 * h_above);
  int below = 0;
  for (int c = box.x; c < box.x + box.width; ++c) {
    const int r = static_cast<int>(std::floor(edge.v_at(c) + min_depth)) + 1;
    if (r < band.r_top || r > band.r_bot) continue;
    if (band.not_plate(r, c)) ++below;
  }
  if (below < 3) return std::nullopt;
  const cv::Mat pile = grow_into_face(band, blob, box, morph_radius_px);
  if (pile.empty()) return std::nullopt;
  const std::optional<PlateLine> toe_line = toe_line_under(pile, edge, min_depth);
  if (!toe_line) return std::nullopt;
  return TopFace{*toe_line, pile};
}

cv::Mat pile_on_face(const cv::Mat& flat, const cv::Mat& above, const std::optional<PlateLine>& far,
                     const PlateLine& toe, double axis_u, double depth_below, int morph_radius_px,
                     const cv::Mat& valid) {
  const int rows = flat.rows, cols = flat.cols;
  auto is_valid = [&](int r, int c) { return valid.empty() || valid.at<uchar>(r, c) != 0; };
  // The band: below the far edge's blurred rows (or from the top) to depth_below under the toe.
  auto first_row = [&](int c) {
    return far ? static_cast<int>(std::floor(far->v_at(c) - 0.5)) + 1 + kCleanGapPx : 0;
  };
  auto last_row = [&](int c) {
    return std::min(rows - 1, static_cast<int>(std::floor(toe.v_at(c) + depth_below)));
  };
  // The plate's level per row at the band's outer columns (a tenth of its valid width, at least
  // kSideColumns, each side): the pile stands in the middle, near the axis.
  std::vector<double> left(rows, std::nan("")), right(rows, std::nan(""));
  std::vector<double> spread;
  int r_min = rows, r_max = -1;
  for (int c = 0; c < cols; ++c) {
    r_min = std::min(r_min, std::max(0, first_row(c)));
    r_max = std::max(r_max, last_row(c));
  }
  for (int r = r_min; r <= r_max; ++r) {
    int c0 = -1, c1 = -1;
    for (int c = 0; c < cols; ++c)
      if (is_valid(r, c) && r >= first_row(c) && r <= last_row(c)) {
        if (c0 < 0) c0 = c;
        c1 = c;
      }
    if (c0 < 0 || c1 - c0 < 4 * kSideColumns) continue;
    const int n = std::max(kSideColumns, (c1 - c0 + 1) / 10);
    std::vector<double> lv, rv;
    for (int c = c0; c < c0 + n; ++c) lv.push_back(flat.at<float>(r, c));
    for (int c = c1 - n + 1; c <= c1; ++c) rv.push_back(flat.at<float>(r, c));
    left[r] = median(lv);
    right[r] = median(rv);
    for (double v : lv) spread.push_back(std::abs(v - left[r]));
    for (double v : rv) spread.push_back(std::abs(v - right[r]));
  }
  if (spread.size() < 30) return cv::Mat();
  // And the plate's level per row on each side of the axis tracked up the band from its lowest
  // rows: below the pile's front the band is plate alone, and each row higher takes the
  // histogram peak of its valid band pixels on that side nearest the row below's level (refined
  // by the median of the pixels near the peak). A pixel at either level is plate. The outer
  // columns alone read a bench beside the plate's far corners where the plate is narrower than
  // the view (the LIGGGHTS pours from 100 mm above: everything on the plate read as pile, the
  // photo refused); the tracked level alone may start on the plate's front face where the band
  // is thin (the same pours from 16 mm above: a 7 mm "pile" read at 27 deg). A row's most
  // common level is no plate's either: an even-coloured pile covers most of the row (the twin's
  // cone of spheres from 20 deg).
  std::vector<double> track_left(rows, std::nan("")), track_right(rows, std::nan(""));
  // The histogram is of log levels over the band's own range: the flat field is fitted to the
  // backdrop above and may drift over the band by orders of magnitude (a narrow strip of
  // backdrop above a camera looking down: levels 0.3-64 down the twin's 20 deg photo), so
  // levels are compared as ratios.
  auto log_of = [](double v) { return std::log(std::max(v, 1e-4)); };
  double lo_v = std::numeric_limits<double>::infinity(), hi_v = -lo_v;
  for (int r = r_min; r <= r_max; ++r)
    for (int c = 0; c < cols; ++c)
      if (is_valid(r, c) && r >= first_row(c) && r <= last_row(c)) {
        lo_v = std::min(lo_v, log_of(flat.at<float>(r, c)));
        hi_v = std::max(hi_v, log_of(flat.at<float>(r, c)));
      }
  if (!(hi_v >= lo_v)) return cv::Mat();
  constexpr double kBin = 0.005;   // 0.5% of the level
  constexpr double kNear = 0.05;   // a pixel within 5% of a peak belongs to it
  constexpr double kJump = 0.1;    // the plate's level changes less than 10% from row to row
  const int kBins = std::max(3, static_cast<int>(std::ceil((hi_v - lo_v) / kBin)) + 1);
  const int axis_c = std::clamp(static_cast<int>(std::lround(axis_u)), 0, cols - 1);
  std::vector<double> near;
  for (const bool is_left : {true, false}) {
    std::vector<double>& level = is_left ? track_left : track_right;
    const int c_begin = is_left ? 0 : axis_c, c_end = is_left ? axis_c : cols;
    double prev = std::nan("");
    for (int r = r_max; r >= r_min; --r) {
      std::vector<int> hist(kBins, 0);
      std::vector<float> vals;
      for (int c = c_begin; c < c_end; ++c)
        if (is_valid(r, c) && r >= first_row(c) && r <= last_row(c)) {
          const double v = log_of(flat.at<float>(r, c));
          vals.push_back(static_cast<float>(v));
          ++hist[std::clamp(static_cast<int>((v - lo_v) / kBin), 0, kBins - 1)];
        }
      if (static_cast<int>(vals.size()) < kSideColumns) continue;
      // The peaks of the histogram smoothed over three bins that hold a fair share of the row.
      const int min_count = std::max(kSideColumns / 2, static_cast<int>(0.03 * vals.size()));
      std::vector<int> smooth(kBins, 0);
      for (int k = 1; k + 1 < kBins; ++k) smooth[k] = hist[k - 1] + hist[k] + hist[k + 1];
      double pick = std::nan("");
      int pick_n = -1;
      for (int k = 1; k + 1 < kBins; ++k) {
        if (smooth[k] < min_count || smooth[k] < smooth[k - 1] || smooth[k] < smooth[k + 1])
          continue;
        const double peak = lo_v + (k + 0.5) * kBin;
        // The first row read takes the highest peak; every other the one nearest the level
        // below, if it lies within kJump of it.
        const bool better = std::isnan(prev)
                                ? smooth[k] > pick_n
                                : std::abs(peak - prev) <= kJump &&
                                      (std::isnan(pick) || std::abs(peak - prev) < std::abs(pick - prev));
        if (better) {
          pick = peak;
          pick_n = smooth[k];
        }
      }
      if (std::isnan(pick)) {
        level[r] = std::isnan(prev) ? prev : std::exp(prev);  // the plate hidden: it continues
        continue;
      }
      near.clear();
      for (float v : vals)
        if (std::abs(v - pick) <= kNear) near.push_back(std::exp(v));
      level[r] = near.size() >= 3 ? median(near) : std::exp(pick);
      for (double v : near) spread.push_back(std::abs(v - level[r]));
      prev = pick;
    }
  }
  for (int r = r_min; r <= r_max; ++r) {
    if (std::isnan(track_left[r])) track_left[r] = track_right[r];
    if (std::isnan(track_right[r])) track_right[r] = track_left[r];
  }
  const double tol = std::max(0.03, 4.0 * 1.4826 * median(spread));
  cv::Mat fg = above.empty() ? cv::Mat(rows, cols, CV_8U, cv::Scalar(0)) : above.clone();
  for (int c = 0; c < cols; ++c) {
    const int r0 = std::max(0, first_row(c));
    for (int r = r0; r <= last_row(c); ++r) {
      if (!is_valid(r, c) || (std::isnan(left[r]) && std::isnan(track_left[r]))) continue;
      const float v = flat.at<float>(r, c);
      const bool outer = !std::isnan(left[r]) && v >= std::min(left[r], right[r]) - tol &&
                         v <= std::max(left[r], right[r]) + tol;
      const bool tracked = !std::isnan(track_left[r]) && (std::abs(v - track_left[r]) <= tol ||
                                                          std::abs(v - track_right[r]) <= tol);
      if (!outer && !tracked) fg.at<uchar>(r, c) = 255;
    }
    // The far edge's blurred rows join the pile where it is on both sides of them.
    if (far) {
      const int last_above = r0 - kCleanGapPx - 1;
      if (last_above >= 0 && r0 < rows && fg.at<uchar>(last_above, c) && fg.at<uchar>(r0, c))
        for (int r = last_above + 1; r < r0; ++r) fg.at<uchar>(r, c) = 255;
    }
  }
  if (morph_radius_px > 0) {
    const int k = 2 * morph_radius_px + 1;
    const cv::Mat se = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k));
    cv::morphologyEx(fg, fg, cv::MORPH_OPEN, se);
    cv::morphologyEx(fg, fg, cv::MORPH_CLOSE, se);
  }
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(fg, labels, stats, centroids, 8, CV_32S);
  // Standing on the toe line: the component's lowest pixel reaches it (a component that ends
  // higher hangs above the plate, as the funnel does).
  std::vector<double> reach(n, -1e300);
  for (int r = 0; r < rows; ++r) {
    const int* l = labels.ptr<int>(r);
    for (int c = 0; c < cols; ++c)
      if (l[c] > 0) reach[l[c]] = std::max(reach[l[c]], r + 0.5 - toe.v_at(c));
  }
  const double min_area = std::max(50.0, 5e-4 * flat.total());
  int best = -1, best_area = 0;
  bool best_on_axis = false;
  for (int i = 1; i < n; ++i) {
    const int area = stats.at<int>(i, cv::CC_STAT_AREA);
    if (area < min_area || reach[i] < -(morph_radius_px + 3.0)) continue;
    const int x = stats.at<int>(i, cv::CC_STAT_LEFT), w = stats.at<int>(i, cv::CC_STAT_WIDTH);
    const bool on_axis = axis_u >= x && axis_u <= x + w - 1;
    if ((on_axis && !best_on_axis) || (on_axis == best_on_axis && area > best_area)) {
      best = i;
      best_area = area;
      best_on_axis = on_axis;
    }
  }
  if (best < 0) return cv::Mat();
  cv::Mat pile = labels == best;
  // Grains lying loose against the pile's foot: seen level they overlap the pile in the
  // picture (all stand on one line), seen from above the plate opens between them vertically
  // while their columns stay. So that both views read one extent, the components that stand in
  // the pile's lowest fifth and whose columns overlap the pile's or lie within the closing's
  // reach of them (what joins them in a level view) join it, and so on outwards. (Within 3% of
  // the pile's width joined grains a level view leaves apart: +6 mm on a 75 mm pile.)
  {
    int x0 = stats.at<int>(best, cv::CC_STAT_LEFT);
    int x1 = x0 + stats.at<int>(best, cv::CC_STAT_WIDTH) - 1;
    const int top = stats.at<int>(best, cv::CC_STAT_TOP);
    const double toe_v = toe.v_at(axis_u);
    const double foot_top = toe_v - 0.2 * std::max(1.0, toe_v - top);
    std::vector<bool> joined(n, false);
    joined[best] = true;
    for (bool grew = true; grew;) {
      grew = false;
      const double gap = 2.0 * morph_radius_px + 1.0;
      for (int i = 1; i < n; ++i) {
        if (joined[i] || stats.at<int>(i, cv::CC_STAT_AREA) < 20) continue;
        const int x = stats.at<int>(i, cv::CC_STAT_LEFT), w = stats.at<int>(i, cv::CC_STAT_WIDTH);
        const int y = stats.at<int>(i, cv::CC_STAT_TOP), h = stats.at<int>(i, cv::CC_STAT_HEIGHT);
        if (y + h - 1 < foot_top || reach[i] < -(morph_radius_px + 3.0) - 0.2 * (toe_v - top))
          continue;
        if (x > x1 + gap || x + w - 1 < x0 - gap) continue;
        joined[i] = true;
        pile |= labels == i;
        x0 = std::min(x0, x);
        x1 = std::max(x1, x + w - 1);
        grew = true;
      }
    }
  }
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(pile, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  pile.setTo(0);
  cv::drawContours(pile, contours, -1, cv::Scalar(255), cv::FILLED);
  return pile;
}

}  // namespace side_detail

double PlateLine::height_above(const cv::Point2d& p) const {
  return (v_at(p.x) - p.y) / std::sqrt(1.0 + b * b);
}

cv::Point2d PlateLine::direction() const {
  const double n = std::sqrt(1.0 + b * b);
  return {1.0 / n, b / n};
}

double PlateLine::tilt_deg() const { return std::atan(b) * kRadToDeg; }

namespace {

// The plate's edge against the backdrop: a step with the backdrop directly above it. Inside the
// pile (and under a monolayer of grains on the plate) the plate line has pile above it instead;
// those columns cannot tell the plate's edge from the grains' own top edge, so they are left out.
bool backdrop_like(float v) { return v > 0.75f && v < 1.33f; }

// Row sums of the edge strength (positive vertical gradient with backdrop above) over strips of
// columns, from which lines of any tilt are summed.
struct EdgeStrips {
  std::vector<double> u;                 // centre column of each strip
  std::vector<int> c0;                   // first column of each strip, and the end (n + 1)
  std::vector<std::vector<double>> sum;  // per strip, per row
  int rows = 0;
  double u_mid = 0.0;  // the image's middle column, about which lines are tilted
};

EdgeStrips edge_strips(const cv::Mat& flat, const cv::Mat& gy) {
  const int rows = flat.rows, ncols = flat.cols;
  const int n_strips = std::clamp(ncols / 8, 4, 64);
  EdgeStrips st;
  st.rows = rows;
  st.u_mid = 0.5 * (ncols - 1);
  st.u.assign(n_strips, 0.0);
  st.c0.assign(n_strips + 1, ncols);
  for (int k = 0; k < n_strips; ++k) {
    st.c0[k] = k * ncols / n_strips;
    st.u[k] = 0.5 * (st.c0[k] + (k + 1) * ncols / n_strips - 1);
  }
  st.sum.assign(n_strips, std::vector<double>(rows, 0.0));
  for (int r = kCleanGapPx; r < rows; ++r) {
    const float* g = gy.ptr<float>(r);
    const float* up = flat.ptr<float>(r - kCleanGapPx);
    for (int k = 0; k < n_strips; ++k) {
      float sum = 0.0f;
      for (int c = st.c0[k]; c < st.c0[k + 1]; ++c)
        if (g[c] > 0.0f && backdrop_like(up[c])) sum += g[c];
      st.sum[k][r] = sum;
    }
  }
  return st;
}

// The edge strength summed along lines of one slope: each strip shifted by a constant, linearly
// interpolated.
std::vector<double> sheared_profile(const EdgeStrips& st, double slope) {
  const int rows = st.rows;
  std::vector<double> prof(rows, 0.0);
  for (size_t k = 0; k < st.sum.size(); ++k) {
    const double dv = slope * (st.u[k] - st.u_mid);
    const int i0 = static_cast<int>(std::floor(dv));
    const double t = dv - i0;
    const std::vector<double>& sk = st.sum[k];
    const int r0 = std::max(0, -i0), r1 = std::min(rows, rows - 1 - i0);
    for (int r = r0; r < r1; ++r) prof[r] += (1.0 - t) * sk[r + i0] + t * sk[r + i0 + 1];
  }
  return prof;
}

// The coarse plate line v = a + b u: row sums along lines of every tilt up to
// plate_max_tilt_deg (one step of slope per pixel of drift across the image, searched coarse to
// fine): a long straight edge adds up, noise, texture and sloping flanks do not. `v0` is the
// line's row at the middle column.
struct CoarseLine {
  double a = 0.0, b = 0.0;
  int v0 = 0;
};

CoarseLine coarse_plate_line(const EdgeStrips& st, int ncols, const SideSettings& s,
                             const std::string& where, int max_row) {
  const int rows = std::min(st.rows, max_row + 3);
  const double tilt = std::tan(s.plate_max_tilt_deg / kRadToDeg);
  const int n_slopes = static_cast<int>(std::ceil(tilt * ncols * 0.5));
  double b = 0.0, best = -1.0;
  auto try_slope = [&](int j) {
    const double slope = n_slopes > 0 ? tilt * j / n_slopes : 0.0;
    const std::vector<double> prof = sheared_profile(st, slope);
    for (int r = 1; r < std::min(rows - 1, max_row + 1); ++r)
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
  std::vector<double> prof = sheared_profile(st, b);
  prof.resize(rows, 0.0);
  int v0 = -1;
  for (int r = std::min(rows - 3, max_row); r >= 2 && v0 < 0; --r) {
    const double p = prof[r];
    if (p >= kPlateCandidateFraction * best && p >= prof[r - 1] && p >= prof[r - 2] &&
        p >= prof[r + 1] && p >= prof[r + 2])
      v0 = r;
  }
  if (v0 < 0) v0 = 1;
  return {v0 - b * st.u_mid, b, v0};
}

// Columns whose backdrop is directly above the line carry the plate edge cleanly.
std::vector<int> clean_columns(const cv::Mat& flat, const CoarseLine& line,
                               const std::string& where) {
  const int rows = flat.rows, ncols = flat.cols;
  std::vector<int> cols;
  for (int c = 0; c < ncols; ++c) {
    const int r = static_cast<int>(std::lround(line.a + line.b * c)) - kCleanGapPx;
    if (r >= 0 && r < rows && backdrop_like(flat.at<float>(r, c))) cols.push_back(c);
  }
  if (static_cast<int>(cols.size()) < std::max(8, ncols / 40))
    throw std::runtime_error(where + ": no plate line found (the edge near row " + str(line.v0) +
                             " shows backdrop above it in only " +
                             str(static_cast<double>(cols.size())) + " columns)");
  return cols;
}

// The edge's sub-pixel row in each clean column, within m rows of the line v = a + b u, with its
// strength.
void column_peaks(const cv::Mat& gy, const std::vector<int>& cols, double a, double b, int m,
                  std::vector<cv::Point2d>& pts, std::vector<double>& strength) {
  pts.clear();
  strength.clear();
  for (int c : cols) {
    const int center = static_cast<int>(std::lround(a + b * c));
    const int lo = std::max(1, center - m), hi = std::min(gy.rows - 2, center + m);
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
}

// The line refined twice: column peaks near it, the strong ones fitted by a Huber line.
PlateLine refine_plate_line(const cv::Mat& gy, const std::vector<int>& cols, double a, double b,
                            double u_mid, const std::string& where) {
  std::vector<cv::Point2d> pts;
  std::vector<double> strength;
  PlateLine line;
  for (int pass = 0; pass < 2; ++pass) {
    column_peaks(gy, cols, a, b, 3, pts, strength);
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

}  // namespace

namespace {

PlateLine find_plate_line_to(const cv::Mat& flat, const SideSettings& s, const std::string& where,
                             int max_row) {
  CV_Assert(flat.type() == CV_32F);
  if (flat.rows < 8 || flat.cols < 8)
    throw std::invalid_argument(where + ": image region too small for a plate line (" +
                                str(flat.cols) + "x" + str(flat.rows) + " px)");
  cv::Mat gy;
  cv::Sobel(flat, gy, CV_32F, 0, 1, 3, s.plate_darker_than_backdrop ? -0.125 : 0.125);
  const EdgeStrips strips = edge_strips(flat, gy);
  const CoarseLine coarse = coarse_plate_line(strips, flat.cols, s, where, max_row);
  const std::vector<int> cols = clean_columns(flat, coarse, where);
  return refine_plate_line(gy, cols, coarse.a, coarse.b, strips.u_mid, where);
}

}  // namespace

PlateLine find_plate_line(const cv::Mat& flat, const SideSettings& s, const std::string& where) {
  return find_plate_line_to(flat, s, where, flat.rows);
}

PlateLine find_plate_line_above(const cv::Mat& flat, int max_row, const SideSettings& s,
                                const std::string& where) {
  return find_plate_line_to(flat, s, where, std::max(8, std::min(max_row, flat.rows)));
}

namespace side_detail {

std::optional<PlateLine> find_far_edge(const cv::Mat& flat, const SideSettings& s,
                                       const PlateLine& toe_line, const std::string& where) {
  const int max_row = static_cast<int>(std::floor(toe_line.v_at(0.5 * (flat.cols - 1)) + 4.0));
  if (max_row < 8) return std::nullopt;
  try {
    PlateLine edge = find_plate_line_to(flat, s, where, std::min(max_row, flat.rows));
    // A refined line may slide onto a lower edge nearby; above the toe line or not at all.
    if (edge.v_at(0.5 * (flat.cols - 1)) > max_row + 2.0) return std::nullopt;
    return edge;
  } catch (const std::runtime_error&) {
    return std::nullopt;  // no long edge with backdrop above it: the plate fills the view
  }
}

}  // namespace side_detail

}  // namespace reposetwin::vision
