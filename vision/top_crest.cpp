#include "vision/top_crest.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <stdexcept>

#include "numeric/median.hpp"
#include "vision/image.hpp"

namespace reposetwin::vision {

namespace {

using numeric::median;

// One ring's least-squares fit g = m + a cos(phi) + b sin(phi) (the normal equations, so a ring
// cut by the image border, or with an uneven azimuth coverage, is still fitted without bias).
struct Ring {
  double n = 0.0;
  cv::Matx33d ata = cv::Matx33d::zeros();
  cv::Vec3d atg{0.0, 0.0, 0.0};
  double a = 0.0, b = 0.0;
  bool ok = false;

  void add(double g, double c, double s) {
    const cv::Vec3d row(1.0, c, s);
    ata += row * row.t();
    atg += g * row;
    n += 1.0;
  }
  bool solve() {
    cv::Vec3d x;
    if (n < 12.0 || !cv::solve(ata, atg, x, cv::DECOMP_CHOLESKY)) return false;
    a = x[1];
    b = x[2];
    return true;
  }
};

std::string num(double v, int digits = 1) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

// The rings out to the footprint's edge about `c`, fitted on the smoothed grey levels.
std::vector<Ring> fit_rings(const cv::Mat& gray, cv::Point2d c, double radius, double width) {
  const int count = static_cast<int>(std::floor(radius / width));
  std::vector<Ring> rings(static_cast<std::size_t>(std::max(count, 0)));
  const int x0 = std::max(0, static_cast<int>(std::floor(c.x - radius)));
  const int x1 = std::min(gray.cols - 1, static_cast<int>(std::ceil(c.x + radius)));
  const int y0 = std::max(0, static_cast<int>(std::floor(c.y - radius)));
  const int y1 = std::min(gray.rows - 1, static_cast<int>(std::ceil(c.y + radius)));
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const double dx = x - c.x, dy = y - c.y, r = std::hypot(dx, dy);
      const int k = static_cast<int>(r / width);
      if (k >= count || r <= 0.0) continue;
      rings[static_cast<std::size_t>(k)].add(gray.at<float>(y, x), dx / r, dy / r);
    }
  for (Ring& ring : rings) ring.ok = ring.solve();
  return rings;
}

// The rings about one centre, projected on the light's azimuth.
struct Profile {
  double width = 0.0;  // ring width [px]
  std::vector<Ring> rings;
  std::vector<double> a1;          // a1 per ring (NaN where the ring could not be fitted)
  std::vector<std::size_t> flank;  // the flank band's rings
  std::size_t used = 0;            // rings inside the flank band's outer end
  double phi_l = 0.0;              // the light's azimuth [rad]
  double r(std::size_t k) const { return (static_cast<double>(k) + 0.5) * width; }
};

Profile ring_profile(const cv::Mat& gray, cv::Point2d c, double radius, double width,
                     const TopCrestSettings& settings) {
  Profile p;
  p.width = width;
  p.rings = fit_rings(gray, c, radius, width);
  double sa = 0.0, sb = 0.0;
  for (std::size_t k = 0; k < p.rings.size(); ++k) {
    if (p.r(k) <= settings.flank_to * radius) p.used = k + 1;
    if (!p.rings[k].ok || p.r(k) < settings.flank_from * radius ||
        p.r(k) > settings.flank_to * radius)
      continue;
    p.flank.push_back(k);
    sa += p.rings[k].n * p.rings[k].a;
    sb += p.rings[k].n * p.rings[k].b;
  }
  p.phi_l = std::atan2(sb, sa);
  for (const Ring& ring : p.rings)
    p.a1.push_back(ring.ok ? ring.a * std::cos(p.phi_l) + ring.b * std::sin(p.phi_l)
                           : std::nan(""));
  return p;
}

// The two-level step fitted to a1 inside ring `used` for a crest radius rc: ring k (centre
// r_k, width w) is outside rc by the fraction f_k = clamp((r_k + w/2 - rc) / w, 0, 1), its model
// low (1 - f_k) + high f_k, its weight N_k / sigma_unit^2. With `drop` set, the step's height
// is fixed at it (low = high - drop) and only one level is fitted.
struct StepFit {
  double low = 0.0, high = 0.0, chi2 = 0.0, sigma_step = 0.0, rings = 0.0;
};

StepFit fit_step(const Profile& p, double rc, double sigma_unit,
                 std::optional<double> drop = std::nullopt) {
  double s00 = 0.0, s01 = 0.0, s11 = 0.0, t0 = 0.0, t1 = 0.0;
  std::vector<double> f(p.used), w(p.used);
  StepFit out;
  for (std::size_t k = 0; k < p.used; ++k) {
    if (!p.rings[k].ok) continue;
    f[k] = std::clamp((p.r(k) + 0.5 * p.width - rc) / p.width, 0.0, 1.0);
    w[k] = p.rings[k].n / (sigma_unit * sigma_unit);
    const double y = drop ? p.a1[k] + *drop * (1.0 - f[k]) : p.a1[k];
    s00 += w[k] * (1.0 - f[k]) * (1.0 - f[k]);
    s01 += w[k] * (1.0 - f[k]) * f[k];
    s11 += w[k] * f[k] * f[k];
    t0 += w[k] * (1.0 - f[k]) * y;
    t1 += w[k] * f[k] * y;
    out.rings += 1.0;
  }
  const double det = s00 * s11 - s01 * s01;
  if (drop || s00 <= 0.0 || det <= 1e-12 * s00 * s11) {
    // One level over all (no ring inside rc, or the drop given).
    const double sw = s00 + 2.0 * s01 + s11;
    out.high = sw > 0.0 ? (t0 + t1) / sw : 0.0;
    out.low = out.high - drop.value_or(0.0);
    out.sigma_step = std::numeric_limits<double>::infinity();
  } else {
    out.low = (s11 * t0 - s01 * t1) / det;
    out.high = (s00 * t1 - s01 * t0) / det;
    // var(high - low) from the inverse normal matrix.
    out.sigma_step = std::sqrt((s11 + s00 + 2.0 * s01) / det);
  }
  for (std::size_t k = 0; k < p.used; ++k) {
    if (!p.rings[k].ok) continue;
    const double e = p.a1[k] - (out.low * (1.0 - f[k]) + out.high * f[k]);
    out.chi2 += w[k] * e * e;
  }
  return out;
}

// The step scanned over rc = 0 .. r_max in `steps` steps.
struct Scan {
  std::vector<double> rc;
  std::vector<StepFit> fits;
  std::size_t best = 0;
};

Scan scan_steps(const Profile& p, double r_max, double sigma_unit) {
  Scan s;
  const int steps = std::max(1, static_cast<int>(std::ceil(8.0 * r_max / p.width)));
  for (int i = 0; i <= steps; ++i) {
    s.rc.push_back(r_max * i / steps);
    s.fits.push_back(fit_step(p, s.rc.back(), sigma_unit));
  }
  s.best = static_cast<std::size_t>(
      std::min_element(s.fits.begin(), s.fits.end(),
                       [](const StepFit& a, const StepFit& b) { return a.chi2 < b.chi2; }) -
      s.fits.begin());
  return s;
}

// The noise of a1 per unit sqrt(pixels), from neighbouring flank rings' differences (robust:
// the median absolute deviation).
double flank_noise(const Profile& p) {
  std::vector<double> z;
  for (std::size_t q = 0; q + 1 < p.flank.size(); ++q) {
    const std::size_t k = p.flank[q], k1 = p.flank[q + 1];
    if (k1 != k + 1) continue;
    z.push_back((p.a1[k1] - p.a1[k]) / std::sqrt(1.0 / p.rings[k].n + 1.0 / p.rings[k1].n));
  }
  if (z.empty()) return 0.0;  // no adjacent flank rings: no noise estimate
  const double z_med = median(z);
  for (double& v : z) v = std::abs(v - z_med);
  return 1.4826 * median(z);
}

}  // namespace

TopCrest measure_top_crest(const cv::Mat& image, const TopProfile& footprint,
                           const TopCrestSettings& settings, const std::string& where) {
  if (image.empty()) throw std::invalid_argument(where + ": empty image");
  const double radius = 0.5 * footprint.diameter_circle_px;
  if (!(radius > 0.0)) throw std::invalid_argument(where + ": the footprint has no radius");
  TopCrest out;
  out.center = footprint.center;
  cv::Mat gray;
  gray_levels(image, where).convertTo(gray, CV_32F);
  if (settings.smoothing_sigma_px > 0.0)
    cv::GaussianBlur(gray, gray, cv::Size(), settings.smoothing_sigma_px);
  const double width = std::max(settings.min_ring_px, settings.ring_fraction * radius);

  // 1. The rings about the footprint's centre: the light, the flank's harmonic and its noise.
  Profile p = ring_profile(gray, out.center, radius, width, settings);
  if (p.flank.size() < 4) {
    out.reason = "the footprint (" + num(2.0 * radius) + " px across) holds " +
                 std::to_string(p.flank.size()) + " flank rings of " + num(width) +
                 " px; at least 4 are needed";
    return out;
  }
  // Never below what 8-bit levels alone leave (1/sqrt(12) per pixel, doubled by the harmonic's
  // fit): a noise-free render would otherwise weigh its rings infinitely.
  const double sigma_unit = std::max(flank_noise(p), std::sqrt(2.0 / 12.0));
  std::vector<double> flank_a1;
  double var_sum = 0.0;
  for (std::size_t k : p.flank) {
    flank_a1.push_back(p.a1[k]);
    var_sum += sigma_unit * sigma_unit / p.rings[k].n;
  }
  out.light_azimuth_deg = p.phi_l * 180.0 / std::numbers::pi;
  out.flank_amplitude = flank_a1.empty() ? 0.0 : median(flank_a1);
  out.flank_sigma = 1.2533 * std::sqrt(var_sum) / static_cast<double>(p.flank.size());
  if (!(out.flank_amplitude > settings.min_flank_snr * out.flank_sigma)) {
    out.reason = "the flank's brightness does not vary around the pile (first harmonic " +
                 num(out.flank_amplitude, 2) + " +- " + num(out.flank_sigma, 2) +
                 " grey levels): the light is along the view, so a top view shows no crest";
    return out;
  }

  // 2. The step, scanned over the crest's radius. The rings stay centred on the footprint's
  // circle: a search for the centre that fits the step best fits the grains instead (each
  // centre regroups their texture into the rings anew, and on a full cone drawn with grains the
  // best of some hundred centres beat the true one by chi^2 97 and read a 21 px crest), so a
  // top standing off the footprint's centre smears the step by the offset.
  const double r_max = settings.flank_from * radius;
  const Scan scan = scan_steps(p, r_max, sigma_unit);
  for (std::size_t k = 0; k < p.rings.size(); ++k) {
    out.ring_radius_px.push_back(p.r(k));
    out.ring_a1.push_back(p.a1[k]);
  }

  // 3. The decision. The uncertainty comes from chi^2 rising by one, widened by the fit's
  // reduced chi^2 where the profile is no clean step.
  const StepFit& f = scan.fits[scan.best];
  const double inflate = std::max(1.0, f.chi2 / std::max(1.0, f.rings - 3.0));
  out.inner_level = f.low;
  out.outer_level = f.high;
  out.step_sigma = f.sigma_step * std::sqrt(inflate);
  const double chi2_one_level = scan.fits.front().chi2;
  if (chi2_one_level - f.chi2 < settings.min_flank_snr * settings.min_flank_snr * inflate) {
    // No step worth the name: the crest is 0, bounded by the widest crest (a1 dropping by the
    // flank's P inside it: a level top has no harmonic) within chi^2 + 4 of one level.
    std::size_t s = 0;
    while (s + 1 < scan.rc.size() &&
           fit_step(p, scan.rc[s + 1], sigma_unit, out.flank_amplitude).chi2 <=
               chi2_one_level + 4.0 * inflate)
      ++s;
    out.found = true;
    out.radius_px = 0.0;
    out.sigma_radius_px = std::max(width / std::sqrt(12.0), scan.rc[s]);
    return out;
  }
  if (scan.best + 1 == scan.rc.size()) {
    out.reason = "the flank's shading does not start inside " + num(settings.flank_from, 2) +
                 " footprint radii (" + num(r_max) +
                 " px): the flat top is as wide as the flank band or the pile has no flank";
    return out;
  }
  double lo = scan.rc[scan.best], hi = lo;
  for (std::size_t s = scan.best; s-- > 0 && scan.fits[s].chi2 - f.chi2 <= inflate;)
    lo = scan.rc[s];
  for (std::size_t s = scan.best; s < scan.rc.size() && scan.fits[s].chi2 - f.chi2 <= inflate; ++s)
    hi = scan.rc[s];
  out.found = true;
  out.radius_px = scan.rc[scan.best];
  out.sigma_radius_px = std::max(width / std::sqrt(12.0), 0.5 * (hi - lo));
  return out;
}

}  // namespace reposetwin::vision
