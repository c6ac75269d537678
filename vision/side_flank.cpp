// The flank lines and the toes of a side view's silhouette (side_view.hpp's design note, step 5).
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "vision/side_view_detail.hpp"

namespace reposetwin::vision {
using namespace side_detail;
namespace {

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

}  // namespace

namespace side_detail {

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

}  // namespace side_detail

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

}  // namespace reposetwin::vision
