#include "vision/top_view.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "numeric/median.hpp"
#include "vision/image.hpp"
#include "vision/text_detail.hpp"

namespace reposetwin::vision {
namespace {

using detail::str;

// Bilinear sample of a CV_32F image (clamped at the border).
double sample(const cv::Mat& img, double x, double y) {
  x = std::clamp(x, 0.0, img.cols - 1.001);
  y = std::clamp(y, 0.0, img.rows - 1.001);
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const double fx = x - x0, fy = y - y0;
  const float* r0 = img.ptr<float>(y0);
  const float* r1 = img.ptr<float>(y0 + 1);
  return (1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x0 + 1]) +
         fy * ((1 - fx) * r1[x0] + fx * r1[x0 + 1]);
}

}  // namespace

bool fit_circle(const std::vector<cv::Point2d>& pts, cv::Point2d& center, double& radius,
                double& rms) {
  if (pts.size() < 3) return false;
  cv::Point2d m(0, 0);
  for (const auto& p : pts) m += p;
  m *= 1.0 / pts.size();
  cv::Mat a(static_cast<int>(pts.size()), 3, CV_64F), b(static_cast<int>(pts.size()), 1, CV_64F);
  for (int i = 0; i < a.rows; ++i) {
    const cv::Point2d q = pts[i] - m;
    a.at<double>(i, 0) = q.x;
    a.at<double>(i, 1) = q.y;
    a.at<double>(i, 2) = 1.0;
    b.at<double>(i) = -(q.x * q.x + q.y * q.y);
  }
  cv::Mat x;
  if (!cv::solve(a, b, x, cv::DECOMP_SVD)) return false;
  const double cx = -0.5 * x.at<double>(0), cy = -0.5 * x.at<double>(1);
  const double r2 = cx * cx + cy * cy - x.at<double>(2);
  if (!(r2 > 0.0)) return false;
  center = m + cv::Point2d(cx, cy);
  radius = std::sqrt(r2);
  double ss = 0.0;
  for (const auto& p : pts) {
    const double r = cv::norm(p - center) - radius;
    ss += r * r;
  }
  rms = std::sqrt(ss / pts.size());
  return std::isfinite(radius);
}

namespace {

// The pile's grey level at the seed and the thresholds half way to the dominant levels below
// and above it.
struct SeedLevels {
  double pile = 0.0;    // median level around the seed
  double low = -1.0;    // a footprint pixel is above this ...
  double high = 256.0;  // ... and below this
};

SeedLevels seed_levels(const cv::Mat& gray, const cv::Point2d& seed, const TopSettings& s,
                       const cv::Rect& roi, const std::string& where) {
  const int half = std::max(3, std::min(roi.width, roi.height) / 100);
  const cv::Rect win = cv::Rect(static_cast<int>(seed.x) - half, static_cast<int>(seed.y) - half,
                                2 * half + 1, 2 * half + 1) &
                       cv::Rect(0, 0, roi.width, roi.height);
  const cv::Mat patch = gray(win).clone();
  const double p = numeric::median(std::vector<double>(patch.begin<float>(), patch.end<float>()));
  const cv::Mat hist = histogram256(gray);
  const double total = static_cast<double>(gray.total());
  auto dominant = [&](int lo, int hi) {
    int best = -1;
    float count = 0.0f;
    for (int i = std::max(lo, 0); i <= std::min(hi, 255); ++i)
      if (hist.at<float>(i) > count) {
        count = hist.at<float>(i);
        best = i;
      }
    return count >= 0.01 * total ? best : -1;
  };
  const int lo_peak = dominant(0, static_cast<int>(p - s.min_contrast));
  const int hi_peak = dominant(static_cast<int>(p + s.min_contrast) + 1, 255);
  if (lo_peak < 0 && hi_peak < 0)
    throw std::runtime_error(where + ": no footprint found (the pile level " + str(p) +
                             " at the seed does not stand out from its surroundings)");
  SeedLevels l;
  l.pile = p;
  l.low = lo_peak >= 0 ? 0.5 * (p + lo_peak) : -1.0;
  l.high = hi_peak >= 0 ? 0.5 * (p + hi_peak) : 256.0;
  return l;
}

// The footprint: the region around the seed within the levels, holes filled (CV_8U), refused
// when it touches the border or is a fragment of it. `box` receives its bounding box.
cv::Mat footprint_blob(const cv::Mat& gray, const cv::Point2d& seed, const SeedLevels& l,
                       const TopSettings& s, const cv::Rect& roi, const std::string& where,
                       cv::Rect& box) {
  cv::Mat mask = (gray > l.low) & (gray < l.high);
  if (s.morph_radius_px > 0) {
    const int k = 2 * s.morph_radius_px + 1;
    const cv::Mat se = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k));
    cv::morphologyEx(mask, mask, cv::MORPH_CLOSE, se);
    cv::morphologyEx(mask, mask, cv::MORPH_OPEN, se);
  }
  cv::Mat labels;
  cv::connectedComponents(mask, labels, 8, CV_32S);
  const int label = labels.at<int>(static_cast<int>(seed.y), static_cast<int>(seed.x));
  if (label == 0)
    throw std::runtime_error(where + ": no footprint found at the seed point " + str(seed.x) + "," +
                             str(seed.y));
  cv::Mat blob = labels == label;
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(blob, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  blob.setTo(0);
  cv::drawContours(blob, contours, -1, cv::Scalar(255), cv::FILLED);
  box = cv::boundingRect(blob);
  if (box.x == 0 || box.y == 0 || box.x + box.width >= roi.width ||
      box.y + box.height >= roi.height)
    throw std::runtime_error(where + ": the footprint touches the border of the " +
                             std::string(s.roi.empty() ? "image" : "region of interest") +
                             " (no footprint, or it is cut)");
  // A speckled footprint (grains with dark gaps or shadows between them, seen large) can fall
  // apart on one cue into one region per grain; the seed's region is then one grain, not the
  // footprint, and stands among many like it. The footprint holds most of the pile-like pixels
  // around it (strays are few), so a region holding less than half of those in a box three
  // times its size is a fragment, and the next cue is tried.
  const cv::Rect around =
      cv::Rect(box.x - box.width, box.y - box.height, 3 * box.width, 3 * box.height) &
      cv::Rect(0, 0, roi.width, roi.height);
  const double inside = cv::countNonZero(mask(around) & blob(around));
  const double all = cv::countNonZero(mask(around));
  if (inside < 0.5 * all)
    throw std::runtime_error(where + ": the region at the seed is a fragment (" +
                             str(std::round(100.0 * inside / all)) +
                             "% of the pile-like pixels around it), not the footprint");
  return blob;
}

// Outside level: median of a ring just outside the blob (worked on the blob's padded box).
double outside_level(const cv::Mat& gray, const cv::Mat& blob, const cv::Rect& box,
                     const TopSettings& s, const cv::Rect& roi, const std::string& where) {
  const int pad = 2 * s.edge_window_px + 10;
  const cv::Rect padded =
      cv::Rect(box.x - pad, box.y - pad, box.width + 2 * pad, box.height + 2 * pad) &
      cv::Rect(0, 0, roi.width, roi.height);
  cv::Mat ring, inner;
  const int k_out = 2 * s.edge_window_px + 9, k_in = 2 * s.edge_window_px + 3;
  cv::dilate(blob(padded), ring,
             cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k_out, k_out)));
  cv::dilate(blob(padded), inner,
             cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k_in, k_in)));
  ring &= ~inner;
  std::vector<double> outside;
  for (int r = 0; r < ring.rows; ++r)
    for (int c = 0; c < ring.cols; ++c)
      if (ring.at<uchar>(r, c)) outside.push_back(gray.at<float>(r + padded.y, c + padded.x));
  if (outside.empty()) throw std::runtime_error(where + ": no footprint surroundings found");
  return numeric::median(outside);
}

// Sub-pixel outline along rays from the blob centroid c0, between the pile level p and the
// surroundings' level back (local levels where the ray's own contrast suffices).
std::vector<cv::Point2d> ray_outline(const cv::Mat& gray, const cv::Mat& blob,
                                     const cv::Point2d& c0, double p, double back,
                                     const TopSettings& s, const cv::Rect& roi) {
  const int w = s.edge_window_px;
  std::vector<cv::Point2d> outline;
  outline.reserve(s.rays);
  const double rmax = std::hypot(roi.width, roi.height);
  for (int i = 0; i < s.rays; ++i) {
    const double a = 2.0 * std::numbers::pi * i / s.rays;
    const cv::Point2d d(std::cos(a), std::sin(a));
    // First pixel outside the blob along the ray.
    double rho0 = -1.0;
    for (double rho = 0.0; rho < rmax; rho += 0.5) {
      const int x = static_cast<int>(std::lround(c0.x + rho * d.x)),
                y = static_cast<int>(std::lround(c0.y + rho * d.y));
      if (x < 0 || y < 0 || x >= blob.cols || y >= blob.rows || !blob.at<uchar>(y, x)) {
        rho0 = rho;
        break;
      }
    }
    if (rho0 < w + 1.0) continue;
    // Local levels just inside and just outside the window follow shading and texture.
    auto mean_at = [&](double r0, double r1) {
      double acc = 0.0;
      int n = 0;
      for (double rho = r0; rho <= r1 + 1e-9; rho += 1.0, ++n)
        acc += sample(gray, c0.x + rho * d.x, c0.y + rho * d.y);
      return acc / n;
    };
    double pin = rho0 - w - 4.0 > 0.0 ? mean_at(rho0 - w - 4.0, rho0 - w - 1.0) : p;
    double pout = mean_at(rho0 + w + 1.0, rho0 + w + 4.0);
    if (std::abs(pin - pout) < 0.5 * s.min_contrast) {
      pin = p;
      pout = back;
    }
    // Pile occupies [.., e] along the ray; window [rho0 - w, rho0 + w] in unit steps.
    double sum = 0.0;
    for (int k = -w; k <= w; ++k) {
      const double rho = rho0 + k;
      sum += (sample(gray, c0.x + rho * d.x, c0.y + rho * d.y) - pout) / (pin - pout);
    }
    const double e = rho0 - w - 0.5 + sum;
    if (e > rho0 - w - 0.5 && e < rho0 + w + 0.5) outline.push_back(c0 + e * d);
  }
  return outline;
}

// The footprint's sizes from its outline: fitted circle, area, fitted ellipse.
TopProfile outline_shape(std::vector<cv::Point2d> outline, double pile_level,
                         const std::string& where) {
  TopProfile out;
  double radius = 0.0, rms = 0.0;
  if (!fit_circle(outline, out.center, radius, rms))
    throw std::runtime_error(where + ": circle fit to the footprint failed");
  out.diameter_circle_px = 2.0 * radius;
  out.circle_residual_px = rms;
  out.sigma_diameter_circle_px =
      2.0 * std::sqrt((rms * rms + 1.0 / 12.0) / static_cast<double>(outline.size()) * 2.0);
  double area = 0.0;
  for (size_t i = 0; i < outline.size(); ++i) {
    const cv::Point2d& a = outline[i];
    const cv::Point2d& b = outline[(i + 1) % outline.size()];
    area += a.x * b.y - b.x * a.y;
  }
  out.area_px = 0.5 * std::abs(area);
  out.diameter_area_px = 2.0 * std::sqrt(out.area_px / std::numbers::pi);
  std::vector<cv::Point2f> f(outline.begin(), outline.end());
  const cv::RotatedRect el = cv::fitEllipse(f);
  out.ellipse_major_px = std::max(el.size.width, el.size.height);
  out.ellipse_minor_px = std::min(el.size.width, el.size.height);
  out.ellipse_angle_deg = el.angle;
  out.ellipticity = 1.0 - out.ellipse_minor_px / out.ellipse_major_px;
  out.pile_level = pile_level;
  out.outline = std::move(outline);
  return out;
}

// Segments and measures the footprint on one feature image `gray` (ROI coordinates, CV_32F, grey
// levels 0..255): the region around `seed` whose level is closer to the seed's than to the
// dominant levels on either side. Throws std::runtime_error when no footprint stands out.
TopProfile measure_on_levels(const cv::Mat& gray, const cv::Point2d& seed, const TopSettings& s,
                             const cv::Rect& roi, const std::string& where) {
  const SeedLevels levels = seed_levels(gray, seed, s, roi, where);
  const double p = levels.pile;
  cv::Rect box;
  const cv::Mat blob = footprint_blob(gray, seed, levels, s, roi, where, box);
  const cv::Moments mo = cv::moments(blob, true);
  if (mo.m00 < 50.0)
    throw std::runtime_error(where + ": no footprint found (blob of " + str(mo.m00) + " px)");
  const cv::Point2d c0(mo.m10 / mo.m00, mo.m01 / mo.m00);
  const double back = outside_level(gray, blob, box, s, roi, where);
  if (std::abs(p - back) < s.min_contrast)
    throw std::runtime_error(where + ": no footprint found (pile level " + str(p) +
                             " vs surroundings " + str(back) + ")");
  std::vector<cv::Point2d> outline = ray_outline(gray, blob, c0, p, back, s, roi);
  if (outline.size() < 16)
    throw std::runtime_error(where + ": footprint outline not found (" + str(outline.size()) +
                             " rays)");
  return outline_shape(std::move(outline), p, where);
}

}  // namespace

TopProfile measure_top_pixels(const cv::Mat& image, const TopSettings& s,
                              const std::string& where) {
  if (s.rays < 8 || s.rays > 100000)
    throw std::invalid_argument(where + ": top settings rays must be 8..100000, got " +
                                str(s.rays));
  if (s.edge_window_px < 1 || s.edge_window_px > 50)
    throw std::invalid_argument(where + ": top settings edge_window_px must be 1..50, got " +
                                str(s.edge_window_px));
  if (!(s.texture_sigma_px > 0.0 && s.texture_sigma_px <= 50.0))
    throw std::invalid_argument(where + ": top settings texture_sigma_px must be in (0, 50], got " +
                                str(s.texture_sigma_px));
  const cv::Mat gray_full = gray_levels(image, where);
  check_contrast(gray_full, where);
  const cv::Rect full(0, 0, gray_full.cols, gray_full.rows);
  const cv::Rect roi = s.roi.empty() ? full : s.roi;
  if ((roi & full) != roi || roi.width < 16 || roi.height < 16)
    throw std::invalid_argument(where + ": roi " + str(roi.x) + "," + str(roi.y) + " " +
                                str(roi.width) + "x" + str(roi.height) +
                                " is not inside the image or smaller than 16x16 px");
  const cv::Point2d seed = (s.seed.x < 0 || s.seed.y < 0)
                               ? cv::Point2d(0.5 * (roi.width - 1), 0.5 * (roi.height - 1))
                               : s.seed - cv::Point2d(roi.x, roi.y);
  if (!cv::Rect2d(0, 0, roi.width, roi.height).contains(seed))
    throw std::invalid_argument(where + ": seed point " + str(s.seed.x) + "," + str(s.seed.y) +
                                " is outside the region of interest");
  const cv::Mat gray_roi = gray_full(roi).clone();
  auto smoothed = [&](cv::Mat m) {
    if (s.smoothing_sigma_px > 0.0)
      cv::GaussianBlur(m, m, cv::Size(), s.smoothing_sigma_px, s.smoothing_sigma_px);
    return m;
  };

  // Cues, in order: grey level; colour (blue minus red, offset to mid-grey), for colour images;
  // local texture (standard deviation of the grey level in a Gaussian window, doubled).
  std::vector<std::pair<std::string, cv::Mat>> cues;
  cues.emplace_back("grey level", smoothed(gray_roi.clone()));
  if (image.channels() >= 3) {
    std::vector<cv::Mat> ch;
    cv::split(image(roi), ch);
    cv::Mat b, r;
    const double k = image.depth() == CV_16U ? 255.0 / 65535.0 : 1.0;
    ch[0].convertTo(b, CV_32F, k);
    ch[2].convertTo(r, CV_32F, k);
    cues.emplace_back("colour (blue - red)", smoothed(b - r + 128.0));
  }
  {
    cv::Mat mu, mu2;
    cv::GaussianBlur(gray_roi, mu, cv::Size(), s.texture_sigma_px, s.texture_sigma_px);
    cv::GaussianBlur(gray_roi.mul(gray_roi), mu2, cv::Size(), s.texture_sigma_px,
                     s.texture_sigma_px);
    cv::Mat var = cv::max(mu2 - mu.mul(mu), 0.0), sd;
    cv::sqrt(var, sd);
    cues.emplace_back("texture (local grey-level deviation)", sd * 2.0);
  }
  std::string failures;
  for (const auto& [name, level] : cues) {
    try {
      TopProfile out = measure_on_levels(level, seed, s, roi, where);
      // The pile level reported is always the grey level at the seed.
      const int half = std::max(3, std::min(roi.width, roi.height) / 100);
      const cv::Rect win = cv::Rect(static_cast<int>(seed.x) - half,
                                    static_cast<int>(seed.y) - half, 2 * half + 1, 2 * half + 1) &
                           cv::Rect(0, 0, roi.width, roi.height);
      const cv::Mat patch = cues.front().second(win).clone();
      out.pile_level =
          numeric::median(std::vector<double>(patch.begin<float>(), patch.end<float>()));
      out.cue = name;
      const cv::Point2d off(roi.x, roi.y);
      out.center += off;
      for (auto& q : out.outline) q += off;
      return out;
    } catch (const std::runtime_error& e) {
      std::string msg = e.what();
      if (msg.rfind(where + ": ", 0) == 0) msg = msg.substr(where.size() + 2);
      failures += (failures.empty() ? "" : "; ") + name + ": " + msg;
    }
  }
  throw std::runtime_error(where + ": no footprint found by any cue (" + failures + ")");
}

}  // namespace reposetwin::vision
