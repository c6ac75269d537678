#include "vision/crest.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "vision/text_detail.hpp"

namespace reposetwin::vision {
namespace {

using detail::kQuantisationPx;

// The point where a flank line through `q` (direction `flank`, up the flank) reaches `rise`
// pixels higher above the plate line.
cv::Point2d carried_up(const cv::Point2d& q, const FlankFit& flank, const cv::Point2d& up,
                       double rise) {
  const double per_unit = flank.direction.dot(up);
  return q + flank.direction * (rise / std::max(per_unit, 1e-6));
}

}  // namespace

Crest measure_crest(const SideProfile& p, const CrestSettings& s, const std::string& where) {
  if (!(s.depth_fraction > 0.0 && s.depth_fraction < 0.5) || !(s.min_depth_px >= 0.0)) {
    std::ostringstream os;
    os << where << ": crest settings depth_fraction must be in (0, 0.5) and min_depth_px >= 0, "
       << "got " << s.depth_fraction << " and " << s.min_depth_px;
    throw std::invalid_argument(os.str());
  }
  const double height = p.height_px;
  Crest c;
  c.depth_px = std::max(s.min_depth_px, s.depth_fraction * height);
  // A top narrower than the edge window (one grain standing on it) has no silhouette rows of its
  // own near the apex: the crest is read from the highest rows each side has.
  auto highest = [&](const std::vector<cv::Point2d>& edge) {
    double h = -std::numeric_limits<double>::infinity();
    for (const cv::Point2d& q : edge) h = std::max(h, p.plate.height_above(q));
    return h;
  };
  const double reach = height - std::min(highest(p.left_edge), highest(p.right_edge));
  if (std::isfinite(reach) && reach > c.depth_px && reach < 0.5 * height) c.depth_px = reach;
  const cv::Point2d dir = p.plate.direction();
  const cv::Point2d up(dir.y, -dir.x);
  // The outermost silhouette point on each side within the depth of the apex height.
  auto outermost = [&](const std::vector<cv::Point2d>& edge, double sign) {
    std::optional<cv::Point2d> best;
    for (const cv::Point2d& q : edge) {
      if (p.plate.height_above(q) < height - c.depth_px) continue;
      if (!best || sign * q.dot(dir) > sign * best->dot(dir)) best = q;
    }
    return best;
  };
  const auto ql = outermost(p.left_edge, -1.0), qr = outermost(p.right_edge, 1.0);
  if (!ql || !qr) {
    std::ostringstream os;
    os << where << ": crest: no silhouette row within " << c.depth_px << " px of the apex";
    throw std::runtime_error(os.str());
  }
  // Each end is carried up its flank to where the flank meets the top outline: at the apex
  // height on a flat top, lower where the top outline curves down towards the ends (a frustum's
  // rim seen from below the top: the rim's near point is the apex, its sides some pixels lower;
  // carried to the apex height the ends fell inside the rim by that much times the cotangent,
  // 36 mm for a 40 mm top). A few fixed-point steps: the top outline's height at the end's
  // column, the end carried to that height, again.
  // The top outline's height at column u, read on one side's edge: where that edge, walked down
  // from its highest row, passes the column (linear between rows); the apex height inside the
  // highest row's edge (the flat top).
  auto top_at = [&](const std::vector<cv::Point2d>& edge, double sign, double u) {
    std::vector<std::pair<double, double>> hx;  // (height, outward position), highest first
    for (const cv::Point2d& q : edge) hx.emplace_back(p.plate.height_above(q), sign * q.x);
    std::sort(hx.begin(), hx.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
    const double w = sign * u;
    if (hx.empty() || w <= hx.front().second) return height;
    for (size_t i = 1; i < hx.size(); ++i)
      if (hx[i].second >= w) {
        const double dx = hx[i].second - hx[i - 1].second;
        const double t = dx > 1e-9 ? (w - hx[i - 1].second) / dx : 1.0;
        return hx[i - 1].first + t * (hx[i].first - hx[i - 1].first);
      }
    return hx.back().first;
  };
  auto end_of = [&](const cv::Point2d& q, const FlankFit& flank,
                    const std::vector<cv::Point2d>& edge, double sign) {
    const double hq = p.plate.height_above(q);
    double top = height;
    cv::Point2d e = carried_up(q, flank, up, top - hq);
    for (int k = 0; k < 6; ++k) {
      top = std::clamp(top_at(edge, sign, e.x), hq, height);
      e = carried_up(q, flank, up, top - hq);
    }
    return e;
  };
  c.left = end_of(*ql, p.left, p.left_edge, -1.0);
  c.right = end_of(*qr, p.right, p.right_edge, 1.0);
  c.raw_width_px = (c.right - c.left).dot(dir);
  c.width_px = std::max(0.0, c.raw_width_px);
  // Each end's column to a quantisation step; the apex height's (H) half-pixel error moves both
  // ends along their flanks.
  auto cot = [](const FlankFit& f) { return 1.0 / std::tan(f.angle_deg * std::acos(-1.0) / 180); };
  c.sigma_px =
      std::hypot(std::sqrt(2.0) * kQuantisationPx, p.sigma_height_px * (cot(p.left) + cot(p.right)));
  return c;
}

}  // namespace reposetwin::vision
