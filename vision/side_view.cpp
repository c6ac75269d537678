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
  throw Refusal(Check::kPilePresent, where + ": no heap: the largest dark blob on the plate (" +
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
  cv::Mat others;        // CV_8U, the other dark objects there (same size)
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

// Pale pixels (hysteresis, as Canny's edges): Otsu splits the levels between the pile's mean and
// the backdrop's, and a pale grain at the pile's top (a light rock, a grain lit from above) can
// lie on the backdrop's side of the split although it differs from the backdrop far beyond its
// noise. Its pixels joined the backdrop and H read low: 2.5 mm on a 31 mm pile of mixed pale
// grains rendered by POV-Ray (0.94 against a backdrop of 1.00 +- 0.01, the split at 0.81), 1.0 mm
// on a 15 mm one. The pixels of `region` at or above `threshold` but darker than the backdrop by
// more than max(0.06, 6 robust sigmas) (the rule pile_on_predicted_toe uses for a backdrop
// without a dark class) are pale. The backdrop is a quadratic surface in the picture (a flat
// field leaves a few percent of gradient across it, more than the backdrop's own noise:
// 0.91-1.06 on a render), fitted to the pixels at least kClearPx from `dark`, then again without
// those beyond 3 robust sigmas of the first fit (pale grains read as backdrop). A pixel-wide
// fringe (the outline's own blur, which the sub-pixel edge reads) is opened away.
cv::Mat pale_pixels(const cv::Mat& upper, const cv::Mat& region, const cv::Mat& dark,
                    double threshold) {
  constexpr double kClearPx = 8.0;
  cv::Mat weak = cv::Mat::zeros(upper.size(), CV_8U);
  cv::Mat dist;
  cv::distanceTransform(dark == 0, dist, cv::DIST_L2, 3);
  const double su = 2.0 / std::max(1, upper.cols - 1), sv = 2.0 / std::max(1, upper.rows - 1);
  auto basis = [&](int r, int c, double* b) {
    const double u = c * su - 1.0, v = r * sv - 1.0;
    b[0] = 1.0, b[1] = u, b[2] = v, b[3] = u * u, b[4] = u * v, b[5] = v * v;
  };
  struct Sample {
    int r, c;
    float f;
  };
  std::vector<Sample> samples;
  for (int r = 0; r < upper.rows; r += 3)
    for (int c = 0; c < upper.cols; c += 3)
      if (region.at<uchar>(r, c) && dist.at<float>(r, c) > kClearPx)
        samples.push_back({r, c, upper.at<float>(r, c)});
  if (samples.size() < 64) return weak;
  cv::Mat coef;
  double sigma = 0.0;
  std::vector<char> use(samples.size(), 1);
  for (int pass = 0; pass < 2; ++pass) {
    cv::Mat a(0, 6, CV_64F), y(0, 1, CV_64F);
    for (size_t i = 0; i < samples.size(); ++i) {
      if (!use[i]) continue;
      double b[6];
      basis(samples[i].r, samples[i].c, b);
      a.push_back(cv::Mat(1, 6, CV_64F, b));
      y.push_back(static_cast<double>(samples[i].f));
    }
    if (a.rows < 64 || !cv::solve(a, y, coef, cv::DECOMP_SVD)) return weak;
    std::vector<double> res(samples.size());
    std::vector<double> dev;
    for (size_t i = 0; i < samples.size(); ++i) {
      double b[6];
      basis(samples[i].r, samples[i].c, b);
      res[i] = samples[i].f - cv::Mat(1, 6, CV_64F, b).dot(coef.t());
      if (use[i]) dev.push_back(std::abs(res[i]));
    }
    sigma = 1.4826 * median(dev);
    for (size_t i = 0; i < samples.size(); ++i) use[i] = std::abs(res[i]) <= 3.0 * sigma;
  }
  const double margin = std::max(0.06, 6.0 * sigma);
  for (int r = 0; r < upper.rows; ++r) {
    const float* f = upper.ptr<float>(r);
    const uchar* a = region.ptr<uchar>(r);
    uchar* w = weak.ptr<uchar>(r);
    for (int c = 0; c < upper.cols; ++c) {
      double b[6];
      basis(r, c, b);
      double back = 0.0;
      for (int k = 0; k < 6; ++k) back += b[k] * coef.at<double>(k);
      if (a[c] && f[c] >= threshold && f[c] < back - margin) w[c] = 255;
    }
  }
  const cv::Mat se = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3));
  cv::morphologyEx(weak, weak, cv::MORPH_OPEN, se);
  return weak;
}

// Sets the pixels of `mask` whose label in `labels` is marked in `keep`.
void add_labels(cv::Mat& mask, const cv::Mat& labels, const std::vector<char>& keep) {
  for (int r = 0; r < mask.rows; ++r) {
    const int* l = labels.ptr<int>(r);
    uchar* m = mask.ptr<uchar>(r);
    for (int c = 0; c < mask.cols; ++c)
      if (l[c] > 0 && keep[l[c]]) m[c] = 255;
  }
}

// `seed` with the pale pixels that touch it, through one another (CV_8U).
cv::Mat grown_through(const cv::Mat& seed, const cv::Mat& pale) {
  cv::Mat labels;
  const int n = cv::connectedComponents(seed | pale, labels, 8, CV_32S);
  std::vector<char> keep(n, 0);
  for (int r = 0; r < seed.rows; ++r) {
    const int* l = labels.ptr<int>(r);
    const uchar* g = seed.ptr<uchar>(r);
    for (int c = 0; c < seed.cols; ++c)
      if (g[c]) keep[l[c]] = 1;
  }
  cv::Mat out = seed.clone();
  add_labels(out, labels, keep);
  return out;
}

// The pile (component `best` of `labels`) with its pale grains (pale_pixels) and the dark
// patches they reach (a grain cut off from the pile by pale ones), never another object standing
// on the plate or hanging into the picture (refuse_foreign_objects judges those).
cv::Mat light_grains_of(const cv::Mat& upper, const cv::Mat& above, const cv::Mat& labels,
                        const cv::Mat& stats, int best, double threshold, const PlateLine& plate,
                        int rest_px) {
  cv::Mat grown = grown_through(labels == best, pale_pixels(upper, above, labels > 0, threshold));
  auto is_object = [&](int i) {
    const int x = stats.at<int>(i, cv::CC_STAT_LEFT), w = stats.at<int>(i, cv::CC_STAT_WIDTH);
    const int top = stats.at<int>(i, cv::CC_STAT_TOP);
    const int bottom = top + stats.at<int>(i, cv::CC_STAT_HEIGHT) - 1;
    const double line_v = std::min(plate.v_at(x), plate.v_at(x + w - 1));
    return top == 0 || bottom >= std::floor(line_v - 0.5) - rest_px;
  };
  cv::Mat near;
  cv::dilate(grown, near, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3)));
  std::vector<char> join(stats.rows, 0);
  for (int r = 0; r < upper.rows; ++r) {
    const int* l = labels.ptr<int>(r);
    const uchar* m = near.ptr<uchar>(r);
    for (int c = 0; c < upper.cols; ++c)
      if (m[c] && l[c] > 0 && l[c] != best && !join[l[c]] && !is_object(l[c])) join[l[c]] = 1;
  }
  add_labels(grown, labels, join);
  return grown;
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
    throw Refusal(Check::kPilePresent, where + ": no pile found (the plate line at row " +
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
  // With a declared camera the pile stands on its axis: of the blobs resting on the plate line
  // the largest that spans the axis column (a box or a tool at the side is not the pile).
  const std::optional<double> axis_u =
      s.axis_u_px ? std::optional<double>(*s.axis_u_px - roi.x) : std::nullopt;
  // The largest resting on the plate; with a declared camera, the largest of those that span
  // the pile's axis (a box or a bar beside the pile is not the pile).
  auto pick = [&](bool on_axis_only) {
    int found = -1, found_area = 0;
    for (int i = 1; i < n_labels; ++i) {
      const int area = stats.at<int>(i, cv::CC_STAT_AREA);
      if (area < min_area || area <= found_area) continue;
      const int x = stats.at<int>(i, cv::CC_STAT_LEFT), w = stats.at<int>(i, cv::CC_STAT_WIDTH);
      const int bottom =
          stats.at<int>(i, cv::CC_STAT_TOP) + stats.at<int>(i, cv::CC_STAT_HEIGHT) - 1;
      const double line_v = std::min(plate.v_at(x), plate.v_at(x + w - 1));
      if (bottom < std::floor(line_v - 0.5) - (s.morph_radius_px + 3)) continue;
      if (on_axis_only && !(*axis_u >= x - 0.5 && *axis_u <= x + w - 0.5)) continue;
      found = i;
      found_area = area;
    }
    return found;
  };
  const int best = pick(axis_u.has_value());
  if (best < 0)
    throw Refusal(Check::kPilePresent,
                  where + ": no pile found (no dark blob of at least " + str(std::round(min_area)) +
                      " px resting on the plate line at row " +
                      str(std::round(plate.v_at(0.5 * flat.cols) + roi.y)) +
                      (axis_u ? " at the pile's axis, column " + str(std::round(*axis_u + roi.x))
                              : std::string()) +
                      ")",
                  0.0, min_area);
  refuse_scattered_grains(stats, n_labels, best, plate, s.morph_radius_px, where);
  out.blob = light_grains_of(upper, above, labels, stats, best, threshold, plate,
                              s.morph_radius_px + 3);
  out.others = (out.blob == 0) & (labels > 0);
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
                          const cv::Rect& roi, PlateLine& plate,
                          std::optional<PlateLine>& far_edge) {
  const double axis_u = s.axis_u_px ? *s.axis_u_px - roi.x : 0.5 * (flat.cols - 1);
  cv::Mat full(flat.size(), CV_8U, cv::Scalar(0));
  pile.blob.copyTo(full.rowRange(0, pile.rows_above));
  const std::optional<TopFace> face = pile_on_top_face(flat, full, plate, s.morph_radius_px,
                                                            s.valid.empty() ? cv::Mat() : s.valid(roi));
  if (!face) return pile.blob;
  // A camera declared level sees no top face deeper than its allowed elevation shows: a toe line
  // below that is another edge (the plate's front face on a bench), and the plate line stands.
  if (s.plate_line_lowest_v &&
      face->toe_line.v_at(axis_u) > *s.plate_line_lowest_v - roi.y)
    return pile.blob;
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
// With a level view (level_view.hpp) the photo's border runs through the image: a pile pixel
// next to a pixel from outside the photo is cut by it just the same.
cv::Rect uncut_box(const cv::Mat& blob, const cv::Mat& valid, const SideSettings& s,
                   const std::string& where, bool refuse = true) {
  const cv::Rect box = cv::boundingRect(blob);
  std::string side;
  if (box.y == 0) side = "top";
  else if (box.x == 0 || box.x + box.width >= blob.cols) side = "left or right";
  else if (!valid.empty()) {
    cv::Mat outside;
    cv::dilate(valid == 0, outside, cv::Mat(), cv::Point(-1, -1), 2);
    cv::Mat cut = outside & blob;
    if (cv::countNonZero(cut) > 0) {
      const cv::Rect c = cv::boundingRect(cut);
      side = c.y <= box.y + 1 ? "top" : "left or right";
    }
  }
  if (!side.empty() && refuse)
    throw Refusal(Check::kNotCut, where + ": the pile is cut by the " + side + " border of the " +
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

// Apex: the silhouette's highest point, the top of its highest grain (the particles' H is the
// highest grain's top). Every column with pile pixels in the blob's top rows is refined along
// the column by its coverage against the backdrop above, and the highest cap is taken. Coverage is
// read against the grain's own level just below its top, not the pile's mean: a pale grain at
// 0.85 of the backdrop, read against a pile mean of 0.70, counted half a pixel per covered row
// and put the apex 1-2 px low. (The middle column of the top row, used before, fell between two
// grains' caps when the top row held both, 0.7 mm below the higher one's top on a 15 mm pile.)
cv::Point2d find_apex(const PileRegion& p, const PlateLine& plate,
                      const std::optional<PlateLine>& far_edge) {
  const cv::Mat& flat = p.flat;
  const cv::Rect& box = p.box;
  const int w = p.window;
  const int r = box.y;
  const int last = std::min(r + 2, box.y + box.height - 1);
  std::vector<cv::Point2d> tops;
  for (int c = box.x; c < box.x + box.width; ++c) {
    int top = -1;
    for (int rr = r; rr <= last && top < 0; ++rr)
      if (p.blob.at<uchar>(rr, c)) top = rr;
    if (top < 0) continue;
    double y = top - 0.5;
    const int r0 = top - w, r1 = std::min(top + w, box.y + box.height - 1);
    // Seen against the plate's top face the apex has no backdrop above it: its pixel edge.
    const bool against_face = far_edge && top + 0.5 > far_edge->v_at(c);
    if (r0 >= 1 && !against_face) {
      double back = col_mean(flat, c, r0 - 4, r0 - 1);
      if (!(back > p.level + 0.05)) back = 1.0;
      std::vector<double> inside;
      for (int rr = top + 1; rr <= r1; ++rr) inside.push_back(flat.at<float>(rr, c));
      double level = inside.empty() ? p.level : median(inside);
      if (!(back - level > 0.05)) level = p.level;
      double sum = 0.0;
      for (int rr = r0; rr <= r1; ++rr)
        sum += std::clamp((back - flat.at<float>(rr, c)) / (back - level), 0.0, 1.0);
      y = r1 + 0.5 - sum;
      if (!(y > r0 - 0.5 && y < r1 + 0.5)) y = top - 0.5;
    }
    tops.emplace_back(c, y);
  }
  // The highest cap: the columns within half a pixel of the highest, their middle column and
  // median height (one column's noise does not lift H; a flat top's middle is its apex).
  double best_h = -1e300;
  for (const auto& q : tops) best_h = std::max(best_h, plate.height_above(q));
  std::vector<double> us, vs;
  for (const auto& q : tops)
    if (plate.height_above(q) >= best_h - 0.5) {
      us.push_back(q.x);
      vs.push_back(q.y);
    }
  return {us[us.size() / 2], median(vs)};
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
  // The flank lines' foot on the plate line: point + t direction with v = a + b u.
  auto foot = [&](const FlankFit& f) {
    const double den = f.direction.y - plate.b * f.direction.x;
    if (std::abs(den) < 1e-9) return cv::Point2d(std::nan(""), std::nan(""));
    const double t = (plate.a + plate.b * f.point.x - f.point.y) / den;
    return f.point + t * f.direction;
  };
  out.foot_left = foot(out.left);
  out.foot_right = foot(out.right);
  out.diameter_flank_px =
      std::hypot(out.foot_right.x - out.foot_left.x, out.foot_right.y - out.foot_left.y);
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
  out.foot_left += off;
  out.foot_right += off;
  out.left.point += off;
  out.right.point += off;
  for (auto& p : out.left_edge) p += off;
  for (auto& p : out.right_edge) p += off;
  out.blob_box += roi.tl();
}

// The pile and what it stands on, found one of two ways (measure_side_pixels).
struct PileOnPlate {
  cv::Mat blob;                 // CV_8U, the pile, above the plate line
  cv::Mat others;               // CV_8U, other dark objects (same size), for the foreign check
  double threshold = 0.0;       // the dark class's threshold, where the pile was split by it
  bool above_backdrop = false;  // the pile was segmented against the backdrop (by threshold)
};

// Without a camera: the plate line detected (step 2), the pile above it, grown into the plate's
// top face when it continues below it.
PileOnPlate pile_on_detected_plate(const SideImage& prepared, const SideSettings& s,
                                   const std::string& where, SideProfile& out) {
  const cv::Mat& flat = prepared.segment;
  out.plate = s.plate_line_lowest_v
                  ? find_plate_line_above(prepared.flat,
                                          static_cast<int>(std::floor(*s.plate_line_lowest_v -
                                                                      prepared.roi.y)),
                                          s, where)
                  : find_plate_line(prepared.flat, s, where);
  const PileBlob pile = find_pile_blob(flat, out.plate, s, prepared.roi, where);
  PileOnPlate found;
  found.blob = s.plate_edge_on ? pile.blob : stand_on_top_face(flat, pile, s, prepared.roi, out.plate, out.far_edge);
  found.others = cv::Mat::zeros(found.blob.size(), CV_8U);
  pile.others.rowRange(0, std::min(pile.others.rows, found.blob.rows))
      .copyTo(found.others.rowRange(0, std::min(pile.others.rows, found.blob.rows)));
  found.threshold = pile.threshold;
  found.above_backdrop = true;
  return found;
}

// Within this many pixels of the toe line the far edge is the plate line itself (a level
// camera sees the plate edge-on) [px].
constexpr double kFaceMinPx = 3.0;

// The line v = a + b u of a full-image line in the region of interest's coordinates.
PlateLine in_roi(PlateLine line, const cv::Rect& roi) {
  line.a = line.a - roi.y + line.b * roi.x;
  return line;
}

// With a declared camera: the toe line is where the camera puts the base circle's tangent
// points. A level camera sees the plate edge-on there, and the detected plate line (within
// kFaceMinPx of it) is the plate line; a camera above the plate sees its top face, and the pile
// stands on the predicted toe line, seen against the backdrop above the far edge and against
// the face below it (side_detail::pile_on_face).
PileOnPlate pile_on_predicted_toe(const SideImage& prepared, const SideSettings& s,
                                  const std::string& where, SideProfile& out) {
  const cv::Mat& flat = prepared.segment;
  const cv::Rect& roi = prepared.roi;
  const PlateLine toe = in_roi(*s.toe_line, roi);
  const double axis_u = s.axis_u_px ? *s.axis_u_px - roi.x : 0.5 * (flat.cols - 1);
  const std::optional<PlateLine> far = find_far_edge(prepared.flat, s, toe, where);
  // A camera declared level with the plate sees it edge-on on the toe line: the plate line is
  // found in the photo as without a camera, and with it the toe line on the plate's top face of a
  // camera standing a little higher than declared (the lab's 5-10 mm: side_view.hpp step 2),
  // from which H is then read; measure.hpp allows that much. With no edge found (a pile as wide
  // as the image hides it) the toe line is the plate line.
  if (s.level_toe_line && s.plate_edge_on && far &&
      std::abs(toe.v_at(axis_u) - far->v_at(axis_u)) <= kFaceMinPx) {
    // Read edge-on (measure.cpp's retry): the long edge on the horizon is the plate line.
    out.plate = *far;
    const PileBlob pile = find_pile_blob(flat, out.plate, s, roi, where);
    return {pile.blob, pile.others, pile.threshold, true};
  }
  if (s.level_toe_line) {
    try {
      return pile_on_detected_plate(prepared, s, where, out);
    } catch (const Refusal&) {
      throw;
    } catch (const std::runtime_error&) {
      // No plate line in the photo (a pile as wide as the view hides it): the camera's.
    }
    out = SideProfile{};
    out.plate = toe;
    out.plate_from_camera = true;
    const PileBlob pile = find_pile_blob(flat, out.plate, s, roi, where);
    return {pile.blob, pile.others, pile.threshold, true};
  }

  if (far && toe.v_at(axis_u) - far->v_at(axis_u) <= kFaceMinPx) {
    out.plate = *far;
    const PileBlob pile = find_pile_blob(flat, out.plate, s, roi, where);
    return {pile.blob, pile.others, pile.threshold, true};
  }
  // The base below the image's bottom: the pile is cut by it.
  if (toe.v_at(axis_u) > flat.rows - 1.0)
    throw Refusal(Check::kNotCut,
                  where + ": the pile is cut by the bottom border of the " +
                      (s.roi.empty() ? "image" : "region of interest") +
                      ": the camera puts its base at row " +
                      str(std::round(toe.v_at(axis_u) + roi.y)) + ", below it; H and D would be "
                      "wrong",
                  toe.v_at(axis_u) + roi.y, flat.rows - 1.0 + roi.y);
  // The dark class above the far edge, when there is a far edge and something dark above it.
  cv::Mat above(flat.size(), CV_8U, cv::Scalar(0));
  double threshold = 0.0;
  if (far) {
    const int rows_above = std::clamp(
        static_cast<int>(std::floor(std::max(far->v_at(0), far->v_at(flat.cols - 1)) - 0.5)) + 1,
        1, flat.rows);
    const cv::Mat region = above_plate(flat, *far, s, roi, rows_above);
    if (cv::countNonZero(region) >= 64) {
      const cv::Mat upper = flat.rowRange(0, rows_above);
      threshold = s.threshold > 0.0 ? s.threshold : otsu_threshold(upper, 0.0, 1.5, region);
      // Backdrop alone, or with a few light grains of the pile's top, splits at its own noise:
      // then what lies below the backdrop's level by more than its noise allows is dark.
      if (!(threshold < 0.9)) {
        std::vector<double> v;
        for (int r = 0; r < rows_above; r += 2)
          for (int c = 0; c < flat.cols; c += 2)
            if (region.at<uchar>(r, c)) v.push_back(flat.at<float>(r, c));
        const double mid = median(v);
        for (double& x : v) x = std::abs(x - mid);
        threshold = mid - std::max(0.06, 6.0 * 1.4826 * median(v));
      }
      above.rowRange(0, rows_above) = (upper < threshold) & region;
    }
  }
  const double gap = std::max(0.0, toe.v_at(axis_u) - (far ? far->v_at(axis_u) : 0.0));
  cv::Mat grown = pile_on_face(flat, above, far, toe, axis_u, s.front_search_px,
                               s.morph_radius_px, s.valid.empty() ? cv::Mat() : s.valid(roi));
  if (grown.empty()) {
    // Something dark stands at the axis but ends well above the toe line: the pile stands on a
    // plate the camera puts elsewhere.
    if (far) {
      const int rows_above = std::clamp(static_cast<int>(std::floor(far->v_at(axis_u) + 0.5)) + 1,
                                        1, flat.rows);
      const int c = std::clamp(static_cast<int>(std::lround(axis_u)), 0, flat.cols - 1);
      int lowest = -1;
      for (int r = 0; r < rows_above; ++r)
        if (above.at<uchar>(r, c)) lowest = r;
      if (lowest >= 0 && toe.v_at(axis_u) - lowest > s.admission.camera_tolerance_px + kFaceMinPx)
        throw Refusal(Check::kCameraConsistent,
                      where + ": not measured through the declared camera: the pile at the axis "
                              "(column " + str(std::round(axis_u + roi.x)) + ") stands on row " +
                          str(lowest + roi.y) + ", " + str(std::round(toe.v_at(axis_u) - lowest)) +
                          " px above the toe line where the declared camera puts its base (row " +
                          str(std::round(toe.v_at(axis_u) + roi.y)) + ")",
                      toe.v_at(axis_u) - lowest, s.admission.camera_tolerance_px + kFaceMinPx);
    }
    throw Refusal(Check::kPilePresent,
                  where + ": no pile found standing on the toe line the camera predicts (row " +
                      str(std::round(toe.v_at(axis_u) + roi.y)) + ", " + str(std::round(gap)) +
                      " px below the plate's far edge) at the pile's axis (column " +
                      str(std::round(axis_u + roi.x)) + ")",
                  0.0);
  }
  // The base's front: the pile's lowest pixels over the middle tenth of its width.
  {
    const cv::Rect box = cv::boundingRect(grown);
    const int half = std::max(2, box.width / 20);
    std::vector<double> lows;
    for (int c = std::max(box.x, static_cast<int>(axis_u) - half);
         c <= std::min(box.x + box.width - 1, static_cast<int>(axis_u) + half); ++c)
      for (int r = box.y + box.height - 1; r >= box.y; --r)
        if (grown.at<uchar>(r, c)) {
          lows.push_back(r + 0.5);
          break;
        }
    if (!lows.empty()) out.front_v_px = median(lows) + roi.y;
  }
  for (int r = 0; r < grown.rows; ++r) {
    uchar* m = grown.ptr<uchar>(r);
    for (int c = 0; c < grown.cols; ++c)
      if (r > std::floor(toe.v_at(c) - 0.5)) m[c] = 0;
  }
  out.plate = toe;
  out.toe_line_predicted = true;
  // No far edge in view: every row is seen against the plate's face.
  out.far_edge = far ? *far : PlateLine{-1.5, 0.0, 0.0, 0.0, 0};
  PileOnPlate found;
  found.blob = grown;
  cv::Mat others = above & ~grown;
  found.others = others;
  found.threshold = threshold;
  found.above_backdrop = false;
  return found;
}

// A pile narrows upwards; a box, a scale bar or a tool standing on the plate does not: its width
// at 80% of its height is most of its width at 20%.
constexpr double kTaperLimit = 0.85;

// The silhouette's width in the row nearest `h` px above the plate line, or NaN.
double width_at(const SideProfile& p, double h) {
  auto x_at = [&](const std::vector<cv::Point2d>& edge) {
    double best = 1e300, x = std::nan("");
    for (const auto& q : edge) {
      const double d = std::abs(p.plate.height_above(q) - h);
      if (d < best) {
        best = d;
        x = q.x;
      }
    }
    return best <= 1.5 ? x : std::nan("");
  };
  return x_at(p.right_edge) - x_at(p.left_edge);
}

// A camera looking down on a pile from well above sees no taper either: the pile's outline is
// then its base, and the refusal says so (admission.hpp's kViewAngle).
constexpr double kSteepCameraDeg = 12.0;

// Below this height a pile is a few grains tall and its outline is the grains' own: a heap two
// grains high need not narrow between a fifth and four fifths of its height, and its "flanks"
// are a grain's side (the twin's tiny test scene: 58 px wide at both, flanks 90 deg); neither
// shape check applies. (With a camera, an object off the pile's axis is no pile whatever its
// size: find_pile_blob.) [px]
constexpr double kTaperMinHeightPx = 60.0;

void refuse_no_taper(const SideProfile& p, double camera_elevation_deg, const std::string& where) {
  if (p.height_px < kTaperMinHeightPx) return;
  const double low = width_at(p, 0.2 * p.height_px), high = width_at(p, 0.8 * p.height_px);
  if (!(low > 0.0 && high >= 0.0)) return;
  if (high > kTaperLimit * low && camera_elevation_deg > kSteepCameraDeg)
    throw Refusal(Check::kViewAngle,
                  where + ": the camera looks down on the pile from " +
                      str(camera_elevation_deg) + " deg above the plate and its outline does "
                      "not narrow upwards (" + str(std::round(high)) + " px wide at 80% of its "
                      "height, " + str(std::round(low)) + " px at 20%): the flanks face the "
                      "camera and the apex is not on the silhouette; photograph it from lower",
                  camera_elevation_deg, kSteepCameraDeg);
  if (high > kTaperLimit * low)
    throw Refusal(Check::kPilePresent,
                  where + ": no pile found: the object standing on the plate does not narrow "
                          "upwards (" + str(std::round(high)) + " px wide at 80% of its height, " +
                      str(std::round(low)) + " px at 20%): a box, a bar or a tool, not a pile",
                  high / low, kTaperLimit);
}

// A pile's silhouette narrows from the plate to its top. Something that hangs into it from
// above (the funnel's outlet, a hand) widens it again above a neck; something hanging just above
// it is a separate dark object near its top that does not stand on the plate.
void refuse_foreign_objects(const SideProfile& p, const cv::Mat& blob, const cv::Mat& others,
                            const SideSettings& s, const std::string& where) {
  // The neck: rows from the plate up, the narrowest width so far, and a row much wider above it.
  std::vector<std::pair<double, double>> rows;  // (height above the plate, width)
  for (double h = 0.05 * p.height_px; h <= p.height_px; h += 1.0) {
    const double w = width_at(p, h);
    if (w >= 0.0) rows.emplace_back(h, w);
  }
  double narrowest = 1e300;
  const double diameter = rows.empty() ? 0.0 : rows.front().second;
  for (const auto& [h, w] : rows) {
    // A neck is sought above 40% of the height: below it a base seen from above (an ellipse)
    // and the loose grains at the foot make the width rise and fall by themselves.
    if (h < 0.4 * p.height_px) continue;
    narrowest = std::min(narrowest, w);
    const double widening = w - narrowest;
    if (widening > std::max(8.0, 0.2 * diameter))
      throw Refusal(Check::kNoForeignObject,
                    where + ": something rests on the pile from above: its silhouette narrows to " +
                        str(std::round(narrowest)) + " px and widens again to " +
                        str(std::round(w)) + " px at " + str(std::round(h)) +
                        " px above the plate (the funnel, a hand or a tool in view)",
                    widening, std::max(8.0, 0.2 * diameter));
  }
  if (others.empty() || cv::countNonZero(others) == 0) return;
  // Other objects near the pile's silhouette that do not stand on the plate.
  const int gap = std::max(3, static_cast<int>(std::lround(s.admission.foreign_gap_fraction *
                                                           p.height_px)));
  cv::Mat near;
  cv::dilate(blob, near, cv::getStructuringElement(cv::MORPH_ELLIPSE,
                                                    cv::Size(2 * gap + 1, 2 * gap + 1)));
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(others, labels, stats, centroids, 8, CV_32S);
  const double min_area = std::max(20.0, 1e-4 * others.total());
  // Inside the pile's outline (its convex hull) a dark patch is the pile's own grains set apart
  // by lighter ones, not an object.
  std::vector<cv::Point> pts;
  cv::findNonZero(blob, pts);
  std::vector<cv::Point> hull;
  if (!pts.empty()) cv::convexHull(pts, hull);
  cv::Mat inside(blob.size(), CV_8U, cv::Scalar(0));
  if (hull.size() >= 3) cv::fillConvexPoly(inside, hull, cv::Scalar(255));
  std::vector<int> near_top;
  for (int i = 1; i < n; ++i) {
    const int area = stats.at<int>(i, cv::CC_STAT_AREA);
    if (area < min_area) continue;
    const int x = stats.at<int>(i, cv::CC_STAT_LEFT), w = stats.at<int>(i, cv::CC_STAT_WIDTH);
    const int bottom = stats.at<int>(i, cv::CC_STAT_TOP) + stats.at<int>(i, cv::CC_STAT_HEIGHT) - 1;
    const double line_v = std::min(p.plate.v_at(x), p.plate.v_at(x + w - 1));
    if (bottom >= std::floor(line_v - 0.5) - (s.morph_radius_px + 3)) continue;  // on the plate
    // Only what hangs above the pile's lower half: grains bouncing at the foot are strays.
    if (bottom > p.apex.y + 0.5 * p.height_px) continue;
    // What hangs from above has its middle above the apex; a dark patch beside the flanks is
    // the pile's own grains set apart by lighter ones.
    if (centroids.at<double>(i, 1) > p.apex.y) continue;
    const cv::Mat comp = labels == i;
    if (cv::countNonZero(comp & near) == 0) continue;
    if (2 * cv::countNonZero(comp & inside) > area) continue;
    near_top.push_back(i);
  }
  // One object, or two (a funnel's two walls): a backdrop's texture makes many.
  if (near_top.empty() || near_top.size() > 2) return;
  {
    const int i = near_top.front();
    const int area = stats.at<int>(i, cv::CC_STAT_AREA);
    const int bottom = stats.at<int>(i, cv::CC_STAT_TOP) + stats.at<int>(i, cv::CC_STAT_HEIGHT) - 1;
    throw Refusal(Check::kNoForeignObject,
                  where + ": an object hangs near the pile's top without standing on the plate (" +
                      str(area) + " px, its lowest row " + str(bottom) + ", within " + str(gap) +
                      " px of the silhouette): the funnel, a hand or a tool in view",
                  static_cast<double>(area), min_area);
  }
}

void refuse_flanks(const SideProfile& p, const AdmissionSettings& a, const std::string& where) {
  if (p.height_px < kTaperMinHeightPx) return;
  for (const auto& [name, f] : {std::pair{"left", &p.left}, std::pair{"right", &p.right}})
    if (!(f->angle_deg >= a.min_flank_deg && f->angle_deg <= a.max_flank_deg))
      throw Refusal(Check::kFlankLimits,
                    where + ": the " + name + " flank stands at " + str(f->angle_deg) +
                        " deg, outside " + str(a.min_flank_deg) + "-" + str(a.max_flank_deg) +
                        " deg: no granular pile stands so (an object's edge, or not a pile)",
                    f->angle_deg, f->angle_deg > a.max_flank_deg ? a.max_flank_deg : a.min_flank_deg);
}

// The pile must stand out from the backdrop, and its top must not be lost to white.
constexpr double kFadedTop = 0.2;

void refuse_exposure(const SideImage& prepared, const PileRegion& region, const SideProfile& p,
                     const AdmissionSettings& a, bool against_backdrop, const std::string& where) {
  // Against the plate's top face the pile was told from the face's own level (pile_on_face).
  const double contrast = std::abs(1.0 - region.level);
  if (against_backdrop && contrast < a.min_contrast)
    throw Refusal(Check::kExposure,
                  where + ": the pile barely stands out from the backdrop (contrast " +
                      str(contrast) + ", at least " + str(a.min_contrast) +
                      " needed): expose for the pile, not the light",
                  contrast, a.min_contrast);
  if (prepared.clipped.empty()) return;
  // A top washed out to white: the pile's top fifth reads more than kFadedTop of the way from
  // the pile's level to the backdrop's (its grains fading into the light), and the band just
  // above it is clipped at the sensor's brightest level, so where the apex ends cannot be told
  // (a 60 mm cone under a gain rising to 2.6 over its top: read 35 mm tall, its top fifth 24% of
  // the way, 62% of the band clipped). A white backdrop clipped around a well-exposed pile passes
  // while its top reads as the rest of it.
  const cv::Rect& box = region.box;
  const int top_rows = std::max(2, static_cast<int>(0.2 * p.height_px));
  std::vector<double> top_levels;
  for (int r = box.y; r < std::min(box.y + top_rows, box.y + box.height); ++r) {
    const uchar* m = region.blob.ptr<uchar>(r);
    const float* f = region.flat.ptr<float>(r);
    for (int c = box.x; c < box.x + box.width; ++c)
      if (m[c]) top_levels.push_back(f[c]);
  }
  if (top_levels.size() < 8) return;
  const double top_level = median(top_levels);
  const double faded = (top_level - region.level) / std::max(1e-6, 1.0 - region.level);
  const int band = std::max(3, static_cast<int>(0.1 * p.height_px));
  const cv::Rect above_top = cv::Rect(box.x, box.y - band, box.width, band) &
                             cv::Rect(0, 0, prepared.clipped.cols, prepared.clipped.rows);
  if (above_top.empty()) return;
  const double clipped =
      static_cast<double>(cv::countNonZero(prepared.clipped(above_top))) / above_top.area();
  if (faded > kFadedTop && clipped > a.max_clipped_fraction)
    throw Refusal(Check::kExposure,
                  where + ": the pile's top is washed out: its top fifth reads " +
                      str(std::round(100.0 * faded)) + "% of the way from the pile's level to the "
                      "backdrop's, and " + str(std::round(100.0 * clipped)) +
                      "% of the band above it is at the sensor's brightest level: the apex cannot "
                      "be told from the backdrop (expose for the pile)",
                  faded, kFadedTop);
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
  double max_level = 0.0;
  cv::minMaxLoc(gray_full, nullptr, &max_level);
  // Clipped: at the sensor's top level, in a photo that reaches it (255 of 8 bits, as scaled).
  out.clipped = max_level >= 254.5 ? cv::Mat(gray_full(roi) >= 254.5) : cv::Mat();
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
  const PileOnPlate pile = s.toe_line ? pile_on_predicted_toe(prepared, s, where, out)
                                      : pile_on_detected_plate(prepared, s, where, out);
  const cv::Mat& blob = pile.blob;
  const PlateLine& plate = out.plate;
  const cv::Mat valid =
      s.valid.empty() ? cv::Mat() : s.valid(prepared.roi).rowRange(0, blob.rows);
  // The border check waits for the silhouette: a pile that reaches the border through a
  // foreign object hanging into it (the funnel from the top) is refused for the object.
  PileRegion region{flat, blob, uncut_box(blob, valid, s, where, false), 0.0, s.edge_window_px};
  region.level = pile_level_of(flat, blob, region.box);
  if (pile.above_backdrop && !(region.level < pile.threshold))
    throw Refusal(Check::kPilePresent, where + ": no pile found (blob level " + str(region.level) +
                                           " is not below the threshold " + str(pile.threshold) +
                                           ")");
  silhouette(region, out.far_edge, out.left_edge, out.right_edge);
  out.apex = find_apex(region, plate, out.far_edge);
  out.height_px = plate.height_above(out.apex);
  if (!(out.height_px >= s.admission.min_height_px))
    throw Refusal(Check::kPilePresent,
                  where + ": no pile found (the object on the plate stands only " +
                      str(out.height_px) + " px above the plate line, less than " +
                      str(s.admission.min_height_px) + " px)",
                  out.height_px, s.admission.min_height_px);
  refuse_foreign_objects(out, blob, pile.others, s, where);
  uncut_box(blob, valid, s, where);
  refuse_no_taper(out, s.camera_elevation_deg, where);
  // Flank lines over the middle band of the height, then the toes below them.
  const double height = out.height_px;
  out.left = fit_flank(
      in_band(out.left_edge, plate, s.flank_band_low * height, s.flank_band_high * height), plate,
      where + ": left flank");
  out.right = fit_flank(
      in_band(out.right_edge, plate, s.flank_band_low * height, s.flank_band_high * height), plate,
      where + ": right flank");
  refuse_flanks(out, s.admission, where);
  refuse_exposure(prepared, region, out, s.admission, pile.above_backdrop, where);
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
