#include "vision/scale_marker.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "numeric/median.hpp"
#include "vision/image.hpp"

namespace reposetwin::vision {
namespace {

using numeric::median;

struct Blob {
  cv::Rect box;
  cv::Point2d centroid;
  int area = 0;
};

std::vector<Blob> blobs(const cv::Mat& mask, int connectivity) {
  cv::Mat labels, stats, centroids;
  const int n =
      cv::connectedComponentsWithStats(mask, labels, stats, centroids, connectivity, CV_32S);
  std::vector<Blob> out;
  for (int i = 1; i < n; ++i) {
    Blob b;
    b.box = cv::Rect(stats.at<int>(i, cv::CC_STAT_LEFT), stats.at<int>(i, cv::CC_STAT_TOP),
                     stats.at<int>(i, cv::CC_STAT_WIDTH), stats.at<int>(i, cv::CC_STAT_HEIGHT));
    b.area = stats.at<int>(i, cv::CC_STAT_AREA);
    b.centroid = cv::Point2d(centroids.at<double>(i, 0), centroids.at<double>(i, 1));
    out.push_back(b);
  }
  return out;
}

// Black bands: filled, rectangle-like dark blobs, wider than tall (about 2:1 by convention).
std::vector<Blob> band_candidates(const cv::Mat& flat, const MarkerSettings& s) {
  const double t = otsu_threshold(flat, 0.0, 1.5);
  const cv::Mat dark = flat < t;
  std::vector<Blob> cand;
  for (const Blob& b : blobs(dark, 4)) {
    if (b.box.height < s.min_feature_px || b.box.width < s.min_feature_px) continue;
    // A band cut by the image border has the wrong height.
    if (b.box.x == 0 || b.box.y == 0 || b.box.x + b.box.width == flat.cols ||
        b.box.y + b.box.height == flat.rows)
      continue;
    const double fill = static_cast<double>(b.area) / b.box.area();
    const double aspect = static_cast<double>(b.box.width) / b.box.height;
    if (fill >= 0.8 && aspect >= 0.8 && aspect <= 4.0) cand.push_back(b);
  }
  return cand;
}

// The largest stack of candidates: same column, same size, regular vertical pitch (one black
// band per pitch, a white band of the same height between). `best_pitch` receives its pitch.
std::vector<Blob> band_stack(const std::vector<Blob>& cand, const MarkerSettings& s,
                             double& best_pitch) {
  std::vector<Blob> best_group;
  for (size_t i = 0; i < cand.size(); ++i) {
    std::vector<Blob> group;
    for (const Blob& b : cand) {
      const Blob& a = cand[i];
      if (std::abs(b.centroid.x - a.centroid.x) < 0.25 * a.box.width &&
          std::abs(b.box.width - a.box.width) <= 0.2 * a.box.width + 1 &&
          std::abs(b.box.height - a.box.height) <= 0.15 * a.box.height + 1)
        group.push_back(b);
    }
    if (static_cast<int>(group.size()) < s.min_black_bands) continue;
    std::sort(group.begin(), group.end(),
              [](const Blob& a, const Blob& b) { return a.centroid.y < b.centroid.y; });
    std::vector<double> gaps;
    for (size_t k = 1; k < group.size(); ++k)
      gaps.push_back(group[k].centroid.y - group[k - 1].centroid.y);
    const double pitch = *std::min_element(gaps.begin(), gaps.end());
    const double h = median([&] {
      std::vector<double> hs;
      for (const Blob& b : group) hs.push_back(b.box.height);
      return hs;
    }());
    // One black band per pitch, a white band of the same height between.
    if (!(pitch > 1.5 * h && pitch < 2.6 * h)) continue;
    bool regular = true;
    for (double g : gaps) {
      const double m = g / pitch;
      if (std::abs(m - std::round(m)) > 0.15 || std::round(m) > 2) regular = false;
    }
    if (!regular) continue;
    if (group.size() > best_group.size()) {
      best_group = group;
      best_pitch = pitch;
    }
  }
  return best_group;
}

}  // namespace

std::optional<ScaleBar> find_scale_bar_flat(const cv::Mat& flat, const MarkerSettings& s) {
  CV_Assert(flat.type() == CV_32F);
  double best_pitch = 0.0;
  const std::vector<Blob> best_group = band_stack(band_candidates(flat, s), s, best_pitch);
  if (static_cast<int>(best_group.size()) < s.min_black_bands) return std::nullopt;

  // Column profile through the middle half of the bar.
  int x0 = flat.cols, x1 = 0, y0 = flat.rows, y1 = 0;
  for (const Blob& b : best_group) {
    x0 = std::min(x0, b.box.x);
    x1 = std::max(x1, b.box.x + b.box.width - 1);
    y0 = std::min(y0, b.box.y);
    y1 = std::max(y1, b.box.y + b.box.height - 1);
  }
  const int w = x1 - x0 + 1;
  const int cx0 = x0 + w / 4, cx1 = std::max(cx0, x1 - w / 4);
  cv::Mat profile;
  cv::reduce(flat(cv::Rect(cx0, 0, cx1 - cx0 + 1, flat.rows)), profile, 1, cv::REDUCE_AVG, CV_64F);
  auto prof = [&](int r) { return profile.at<double>(std::clamp(r, 0, flat.rows - 1)); };
  std::vector<double> blacks, whites;
  for (size_t k = 0; k < best_group.size(); ++k) {
    blacks.push_back(prof(static_cast<int>(std::lround(best_group[k].centroid.y))));
    if (k + 1 < best_group.size())
      whites.push_back(prof(static_cast<int>(
          std::lround(0.5 * (best_group[k].centroid.y + best_group[k + 1].centroid.y)))));
  }
  // A single black band has no white level: 0, which the contrast test below refuses.
  const double kb = median(blacks), kw = whites.empty() ? 0.0 : median(whites);
  if (!(kw - kb > 0.2)) return std::nullopt;

  // Edge positions against their index: top of black band n at t0 + 2 n b, bottom at
  // t0 + (2 n + 1) b.
  const double band_est = 0.5 * best_pitch;
  const int m = std::clamp(static_cast<int>(band_est / 3.0), 2, 8);
  std::vector<double> idx, pos;
  for (const Blob& b : best_group) {
    const double n = std::round((b.centroid.y - best_group.front().centroid.y) / best_pitch);
    const int top = b.box.y, bottom = b.box.y + b.box.height - 1;
    {
      const int r0 = top - m, r1 = top + m;
      double sum = 0.0;
      for (int r = r0; r <= r1; ++r) sum += (kw - prof(r)) / (kw - kb);
      idx.push_back(2.0 * n);
      pos.push_back(r1 + 0.5 - sum);
    }
    {
      const int r0 = bottom - m, r1 = bottom + m;
      double sum = 0.0;
      for (int r = r0; r <= r1; ++r) sum += (kw - prof(r)) / (kw - kb);
      idx.push_back(2.0 * n + 1.0);
      pos.push_back(r0 - 0.5 + sum);
    }
  }
  const double n = static_cast<double>(idx.size());
  const double im = std::accumulate(idx.begin(), idx.end(), 0.0) / n;
  const double pm = std::accumulate(pos.begin(), pos.end(), 0.0) / n;
  double sii = 0.0, sip = 0.0;
  for (size_t k = 0; k < idx.size(); ++k) {
    sii += (idx[k] - im) * (idx[k] - im);
    sip += (idx[k] - im) * (pos[k] - pm);
  }
  if (!(sii > 0.0)) return std::nullopt;
  const double band = sip / sii;
  double ss = 0.0;
  for (size_t k = 0; k < idx.size(); ++k) {
    const double r = pos[k] - (pm + band * (idx[k] - im));
    ss += r * r;
  }
  if (!(band > 0.0)) return std::nullopt;
  ScaleBar bar;
  bar.box = cv::Rect(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
  bar.band_px = band;
  bar.band_mm = s.band_mm;
  bar.mm_per_px = s.band_mm / band;
  bar.residual_px = std::sqrt(ss / n);
  const double sigma_slope = idx.size() > 2 ? std::sqrt(ss / (n - 2) / sii) : 0.0;
  bar.sigma_rel =
      std::hypot(sigma_slope, (1.0 / std::sqrt(12.0)) / (2.0 * (bar.box.height))) / band;
  bar.black_bands = static_cast<int>(best_group.size());
  bar.edges = static_cast<int>(idx.size());
  return bar;
}

std::optional<ScaleBar> find_scale_bar(const cv::Mat& image, const MarkerSettings& s,
                                       const std::string& where) {
  const cv::Mat gray = gray_levels(image, where);
  check_contrast(gray, where);
  cv::Mat flat = flat_field(gray, cv::Mat(), FlatFieldSettings{}, where);
  return find_scale_bar_flat(flat, s);
}

std::optional<CheckerCard> find_checker_card(const cv::Mat& image, const MarkerSettings& s,
                                             const std::string& where) {
  const cv::Mat gray = gray_levels(image, where);
  check_contrast(gray, where);
  cv::Mat g8;
  gray.convertTo(g8, CV_8U);
  // White squares: the brightest class, well above the median (plate or pile).
  cv::Mat sub;
  const int step = std::max(1, std::max(g8.cols, g8.rows) / 500);
  cv::resize(g8, sub, cv::Size(), 1.0 / step, 1.0 / step, cv::INTER_NEAREST);
  std::vector<uchar> v(sub.begin<uchar>(), sub.end<uchar>());
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  const double med = v[v.size() / 2];
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() * 999 / 1000), v.end());
  const double top = v[v.size() * 999 / 1000];
  if (!(top - med > 40.0)) return std::nullopt;
  cv::Mat bright = g8 > 0.5 * (top + med);
  // Diagonal neighbours touch at a corner: one erosion separates them without moving centroids.
  cv::erode(bright, bright, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3)));
  std::vector<Blob> cand;
  for (const Blob& b : blobs(bright, 4)) {
    if (b.box.height < s.min_feature_px || b.box.width < s.min_feature_px) continue;
    const double aspect = static_cast<double>(b.box.width) / b.box.height;
    const double fill = static_cast<double>(b.area) / b.box.area();
    if (aspect > 0.75 && aspect < 1.33 && fill > 0.45) cand.push_back(b);
  }
  // Group by size and mutual proximity: each square's nearest similar square is a diagonal
  // neighbour at sqrt(2) sides (eroded side + 2 px is the side).
  std::vector<Blob> best;
  std::vector<double> best_spacing;
  for (size_t i = 0; i < cand.size(); ++i) {
    const double side = std::sqrt(static_cast<double>(cand[i].area)) + 2.0;
    std::vector<Blob> group;
    for (const Blob& b : cand)
      if (std::abs(b.area - cand[i].area) < 0.3 * cand[i].area &&
          cv::norm(b.centroid - cand[i].centroid) < 4.5 * side)
        group.push_back(b);
    if (static_cast<int>(group.size()) < s.min_squares || group.size() <= best.size()) continue;
    std::vector<double> spacing;
    for (const Blob& a : group) {
      double nn = 1e300;
      for (const Blob& b : group)
        if (&a != &b) nn = std::min(nn, cv::norm(a.centroid - b.centroid));
      if (std::abs(nn / side - std::sqrt(2.0)) < 0.25) spacing.push_back(nn / std::sqrt(2.0));
    }
    if (static_cast<int>(spacing.size()) < s.min_squares) continue;
    best = group;
    best_spacing = spacing;
  }
  if (best.empty()) return std::nullopt;
  // Lattice fit: centre k = c0 + i_k a + j_k b with integer (i_k, j_k) found from the nearest
  // diagonal neighbour of the first square, so the whole card's span sets the square size
  // (single centroids of a render without anti-aliasing are quantised to half pixels).
  CheckerCard card;
  const double sq0 = median(best_spacing);
  const Blob& ref = best.front();
  cv::Point2d diag(0, 0);
  double nn = 1e300;
  for (const Blob& b : best) {
    const double d = cv::norm(b.centroid - ref.centroid);
    if (&b != &ref && d < nn) {
      nn = d;
      diag = b.centroid - ref.centroid;
    }
  }
  const cv::Point2d perp(-diag.y, diag.x);
  const cv::Point2d a0 = 0.5 * (diag + perp), b0 = 0.5 * (diag - perp);
  const double det = a0.x * b0.y - a0.y * b0.x;
  double sq = sq0;
  double sigma_rel = 0.0;
  if (std::abs(det) > 1e-9 && best.size() >= 3) {
    const int n = static_cast<int>(best.size());
    cv::Mat design(n, 3, CV_64F), xs(n, 1, CV_64F), ys(n, 1, CV_64F);
    for (int k = 0; k < n; ++k) {
      const cv::Point2d d = best[k].centroid - ref.centroid;
      design.at<double>(k, 0) = 1.0;
      design.at<double>(k, 1) = std::round((d.x * b0.y - d.y * b0.x) / det);
      design.at<double>(k, 2) = std::round((a0.x * d.y - a0.y * d.x) / det);
      xs.at<double>(k) = best[k].centroid.x;
      ys.at<double>(k) = best[k].centroid.y;
    }
    cv::Mat px, py;
    if (cv::solve(design, xs, px, cv::DECOMP_SVD) && cv::solve(design, ys, py, cv::DECOMP_SVD)) {
      const double la = std::hypot(px.at<double>(1), py.at<double>(1));
      const double lb = std::hypot(px.at<double>(2), py.at<double>(2));
      if (la > 0.5 * sq0 && la < 2.0 * sq0 && lb > 0.5 * sq0 && lb < 2.0 * sq0) {
        sq = 0.5 * (la + lb);
        cv::Mat rx = design * px - xs, ry = design * py - ys;
        const double rms = std::sqrt((rx.dot(rx) + ry.dot(ry)) / (2.0 * n));
        double sii = 0.0;
        const double im = cv::mean(design.col(1))[0];
        for (int k = 0; k < n; ++k) sii += std::pow(design.at<double>(k, 1) - im, 2);
        sigma_rel = sii > 0.0 ? rms / std::sqrt(sii) / sq : 0.0;
      }
    }
  }
  card.square_px = sq;
  card.square_mm = s.square_mm;
  card.mm_per_px = s.square_mm / sq;
  card.sigma_rel = sigma_rel;
  card.squares = static_cast<int>(best.size());
  cv::Rect box = best.front().box;
  for (const Blob& b : best) box |= b.box;
  card.box = box;
  return card;
}

}  // namespace reposetwin::vision
