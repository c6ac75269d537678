#include "vision/side_view.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <stdexcept>

namespace reposetwin::vision {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRadToDeg = 180.0 / kPi;
// Standard deviation of a uniform error over one pixel [px].
const double kQuantisationPx = 1.0 / std::sqrt(12.0);

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

// Robust straight line v = a + b u through samples: Theil-Sen (median of pairwise slopes).
void theil_sen(const std::vector<cv::Point2d>& p, double& a, double& b) {
  std::vector<double> slopes;
  const size_t step = std::max<size_t>(1, p.size() / 400);
  for (size_t i = 0; i < p.size(); i += step)
    for (size_t j = i + step; j < p.size(); j += step)
      if (p[j].x != p[i].x) slopes.push_back((p[j].y - p[i].y) / (p[j].x - p[i].x));
  b = slopes.empty() ? 0.0 : median(slopes);
  std::vector<double> icpt;
  icpt.reserve(p.size());
  for (const auto& q : p) icpt.push_back(q.y - b * q.x);
  a = median(icpt);
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
  // Signed row sums: a long horizontal edge adds up, noise and sloping flanks do not.
  cv::Mat profile;
  cv::reduce(gy, profile, 1, cv::REDUCE_SUM, CV_64F);
  int v0 = 1;
  double best = -std::numeric_limits<double>::infinity();
  for (int r = 1; r < flat.rows - 1; ++r) {
    const double p = profile.at<double>(r);
    if (p > best) {
      best = p;
      v0 = r;
    }
  }
  // An average step of 0.02 of the backdrop level over the whole width, at the least.
  if (!(best > 0.02 * 0.5 * flat.cols))
    throw std::runtime_error(
        where + ": no plate line found (no long horizontal " +
        std::string(s.plate_darker_than_backdrop ? "bright-to-dark" : "dark-to-bright") +
        " edge; strongest row " + str(v0) + ")");

  // Columns whose backdrop is visible above the search window carry the plate edge cleanly
  // (inside the pile the plate edge is weak and the pile's texture is not).
  const double tilt = std::tan(s.plate_max_tilt_deg / kRadToDeg);
  const int m1 = static_cast<int>(std::ceil(tilt * flat.cols * 0.5)) + 4;
  std::vector<int> cols;
  const int probe = std::max(0, v0 - m1 - 3);
  for (int c = 0; c < flat.cols; ++c)
    if (flat.at<float>(probe, c) > 0.75f) cols.push_back(c);
  if (static_cast<int>(cols.size()) < flat.cols / 10) {
    cols.clear();
    for (int c = 0; c < flat.cols; ++c) cols.push_back(c);
  }

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
  column_peaks(v0, 0.0, m1, pts, strength);
  if (pts.size() < 8)
    throw std::runtime_error(where + ": no plate line found (too few edge columns near row " +
                             str(v0) + ")");
  double a = v0, b = 0.0;
  theil_sen(pts, a, b);
  if (std::abs(b) > tilt + 1e-9) b = std::clamp(b, -tilt, tilt);

  PlateLine line;
  for (int pass = 0; pass < 2; ++pass) {
    column_peaks(a, b, 3, pts, strength);
    const double strong = 0.3 * median(strength);
    std::vector<cv::Point2f> kept;
    const double u_mid = 0.5 * (flat.cols - 1);
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
  cv::Point2d mean(0, 0);
  for (const auto& p : points) mean += p;
  mean *= 1.0 / points.size();
  std::vector<cv::Point2f> centred;
  centred.reserve(points.size());
  for (const auto& p : points)
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
  cv::Mat blob = labels == best;
  {
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(blob, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
    blob.setTo(0);
    cv::drawContours(blob, contours, -1, cv::Scalar(255), cv::FILLED);
    blob &= above;
  }
  const cv::Rect box(stats.at<int>(best, cv::CC_STAT_LEFT), stats.at<int>(best, cv::CC_STAT_TOP),
                     stats.at<int>(best, cv::CC_STAT_WIDTH),
                     stats.at<int>(best, cv::CC_STAT_HEIGHT));

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
        if (!(back > pile_level + 0.05)) back = 1.0;
        const double x = c1 + 0.5 - coverage_sum(r, c0, c1, back);
        if (x > c0 - 0.5 && x < c1 + 0.5) left.emplace_back(x, r);
      }
    }
    {
      const int c1 = ur + w, c0 = std::max(ur - w, mid + 1);
      if (c1 <= flat.cols - 2 && ur - c0 >= 2) {
        double back = row_mean(flat, r, c1 + 1, c1 + 4);
        if (!(back > pile_level + 0.05)) back = 1.0;
        const double x = c0 - 0.5 + coverage_sum(r, c0, c1, back);
        if (x > c0 - 0.5 && x < c1 + 0.5) right.emplace_back(x, r);
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
