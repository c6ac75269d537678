#include "vision/camera_pose.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "vision/text_detail.hpp"

namespace reposetwin::vision {
namespace {

using detail::kRadToDeg;

// The declared camera's optical axis below the horizontal [rad].
double declared_pitch(const camera::Camera& cam) {
  const Eigen::Vector3d f = cam.extrinsics.look_at - cam.extrinsics.position;
  return std::atan2(-f.z(), f.head<2>().norm());
}

// The angle of a pixel's ray below the optical axis, in the vertical plane [rad].
double below_axis(const camera::Camera& cam, double u, double v) {
  const Eigen::Vector3d d = camera::unproject(cam, Eigen::Vector2d(u, v)).direction;
  return std::asin(std::clamp(-d.z(), -1.0, 1.0)) - declared_pitch(cam);
}

struct ArcFit {
  double uc = 0.0, a = 0.0, vc = 0.0, b = 0.0, sigma_vc = 0.0, sigma_b = 0.0, rms = 0.0;
  int n = 0;
};

// Least squares of v = vc + b s over the points (s, v); `keep` selects them.
ArcFit fit_arc(const std::vector<double>& s, const std::vector<double>& v,
               const std::vector<bool>& keep) {
  ArcFit f;
  double ss = 0, sv = 0, sss = 0, ssv = 0;
  for (size_t i = 0; i < s.size(); ++i)
    if (keep[i]) {
      ss += s[i];
      sv += v[i];
      sss += s[i] * s[i];
      ssv += s[i] * v[i];
      ++f.n;
    }
  const double det = f.n * sss - ss * ss;
  if (f.n < 8 || !(det > 1e-9)) return f;
  f.b = (f.n * ssv - ss * sv) / det;
  f.vc = (sv - f.b * ss) / f.n;
  double r2 = 0.0;
  for (size_t i = 0; i < s.size(); ++i)
    if (keep[i]) r2 += std::pow(v[i] - f.vc - f.b * s[i], 2);
  const double s2 = r2 / std::max(1, f.n - 2);
  f.rms = std::sqrt(r2 / f.n);
  f.sigma_b = std::sqrt(s2 * f.n / det);
  f.sigma_vc = std::sqrt(s2 * sss / det);
  return f;
}

// Camera height and pitch from the ellipse's rows (vc, vc + b) and half width a [px].
struct HeightPitch {
  double h = 0.0, pitch = 0.0, radius = 0.0;
};

HeightPitch solve(const camera::Camera& cam, double distance, double uc, double a, double vc,
                  double b) {
  const Eigen::Vector3d dl = camera::unproject(cam, Eigen::Vector2d(uc - a, vc)).direction;
  const Eigen::Vector3d dr = camera::unproject(cam, Eigen::Vector2d(uc + a, vc)).direction;
  HeightPitch out;
  out.radius = distance * std::sin(0.5 * std::acos(std::clamp(dl.dot(dr), -1.0, 1.0)));
  const double lt = distance - out.radius * out.radius / distance, lf = distance - out.radius;
  const double dc = below_axis(cam, uc, vc), df = below_axis(cam, uc, vc + b);
  const double target = df - dc;
  auto g = [&](double h) { return std::atan(h / lf) - std::atan(h / lt); };
  double lo = 0.0, hi = std::sqrt(lf * lt);
  if (target <= 0.0) {
    hi = 0.0;
  } else if (target >= g(hi)) {
    lo = hi;
  }
  for (int k = 0; k < 80 && hi - lo > 1e-9 * distance; ++k) {
    const double mid = 0.5 * (lo + hi);
    (g(mid) < target ? lo : hi) = mid;
  }
  out.h = 0.5 * (lo + hi);
  out.pitch = std::atan(out.h / lt) - dc;
  return out;
}

// The pile's front outline on the plate's top face: the pixels from the toe line down that
// differ from the plate's level in their row (the median of the image's outer columns where the
// plate shows, 4% of the width each side), closed over 2 px gaps; the connected part of them that
// holds the toe line's row between the toes is the pile's lower part, and its lowest pixel in
// each column (the pixel's bottom) is the outline. Its column extent is the base ellipse's
// width: the silhouette's widest points are the ellipse's ends. `flat` is the segmentation
// image in ROI coordinates; the outline is in full-image coordinates.
struct Outline {
  std::vector<cv::Point2d> points;
  double u0 = 0.0, u1 = 0.0;  // column extent (pixel edges) [px]
};

Outline front_outline(const cv::Mat& flat, const cv::Point& off, const SideProfile& p) {
  Outline out;
  const int border = std::max(4, flat.cols / 25);
  std::vector<int> cols;
  for (int c = 0; c < border; ++c) cols.push_back(c);
  for (int c = flat.cols - border; c < flat.cols; ++c) cols.push_back(c);
  const auto first_face_row = [&](int c) {  // local row just below the far edge, + 4 px
    return static_cast<int>(std::floor(p.far_edge->v_at(c + off.x) - off.y + 0.5)) + 4;
  };
  std::vector<double> level(flat.rows, std::nan("")), spread;
  for (int r = 0; r < flat.rows; ++r) {
    std::vector<double> v;
    for (int c : cols)
      if (r >= first_face_row(c) && std::abs(flat.at<float>(r, c) - 1.0f) >= 0.25f)
        v.push_back(flat.at<float>(r, c));
    if (v.size() < 4) continue;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    level[r] = v[v.size() / 2];
    for (double x : v) spread.push_back(std::abs(x - level[r]));
  }
  if (spread.size() < 30) return out;
  std::nth_element(spread.begin(), spread.begin() + spread.size() / 2, spread.end());
  const double tol = std::max(0.03, 4.0 * 1.4826 * spread[spread.size() / 2]);
  const auto toe_row = [&](int c) {
    return static_cast<int>(std::floor(p.plate.v_at(c + off.x) - off.y + 0.5));
  };
  cv::Mat mask(flat.size(), CV_8U, cv::Scalar(0));
  for (int c = border; c < flat.cols - border; ++c)
    for (int r = std::max(toe_row(c) - 2, 0); r < flat.rows; ++r)
      if (!std::isnan(level[r]) && std::abs(flat.at<float>(r, c) - level[r]) > tol)
        mask.at<uchar>(r, c) = 255;
  cv::morphologyEx(mask, mask, cv::MORPH_CLOSE,
                   cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(5, 5)));
  cv::Mat labels;
  cv::connectedComponents(mask, labels, 8, CV_32S);
  std::vector<int> votes;
  const int c0 = std::max(border, static_cast<int>(std::ceil(p.toe_left.x)) - off.x);
  const int c1 = std::min(flat.cols - border - 1, static_cast<int>(std::floor(p.toe_right.x)) - off.x);
  for (int c = c0; c <= c1; ++c) {
    const int r = toe_row(c);
    if (r < 0 || r >= flat.rows) continue;
    const int l = labels.at<int>(r, c);
    if (l <= 0) continue;
    if (l >= static_cast<int>(votes.size())) votes.resize(l + 1, 0);
    ++votes[l];
  }
  if (votes.empty()) return out;
  const int label = static_cast<int>(std::max_element(votes.begin(), votes.end()) - votes.begin());
  if (label <= 0 || votes[label] == 0) return out;
  out.u0 = 1e300;
  out.u1 = -1e300;
  for (int c = 0; c < flat.cols; ++c) {
    int low = -1;
    for (int r = flat.rows - 1; r >= 0; --r)
      if (labels.at<int>(r, c) == label) {
        low = r;
        break;
      }
    if (low < 0) continue;
    out.points.emplace_back(c + off.x, low + 0.5 + off.y);
    out.u0 = std::min(out.u0, c - 0.5 + off.x);
    out.u1 = std::max(out.u1, c + 0.5 + off.x);
  }
  return out;
}

}  // namespace

std::optional<PoseEstimate> estimate_side_pose(const SideImage& prepared, const SideProfile& p,
                                               const camera::Camera& declared,
                                               const Eigen::Vector3d& axis_foot) {
  if (!p.far_edge) return std::nullopt;
  if (declared.projection != camera::Projection::kPerspective) return std::nullopt;
  const double distance = (declared.extrinsics.position.head<2>() - axis_foot.head<2>()).norm();
  if (!(distance > 0.0)) return std::nullopt;
  const Outline outline = front_outline(prepared.segment, prepared.roi.tl(), p);
  const std::vector<cv::Point2d>& front = outline.points;
  const double uc = 0.5 * (outline.u0 + outline.u1);
  const double a = 0.5 * (outline.u1 - outline.u0);
  if (front.size() < 16 || !(a > 8.0)) return std::nullopt;
  std::vector<double> s, v;
  for (const cv::Point2d& q : front) {
    const double x = (q.x - uc) / a;
    if (std::abs(x) >= 0.9) continue;
    s.push_back(std::sqrt(1.0 - x * x));
    v.push_back(q.y - p.plate.b * (q.x - uc));  // detilted about the centre column
  }
  std::vector<bool> keep(s.size(), true);
  ArcFit f = fit_arc(s, v, keep);
  if (f.n < 8) return std::nullopt;
  for (size_t i = 0; i < s.size(); ++i)
    keep[i] = std::abs(v[i] - f.vc - f.b * s[i]) <= std::max(1.0, 3.0 * f.rms);
  f = fit_arc(s, v, keep);
  if (f.n < 8) return std::nullopt;
  const HeightPitch hp = solve(declared, distance, uc, a, f.vc, f.b);
  PoseEstimate e;
  e.distance_m = distance;
  e.height_m = hp.h;
  e.elevation_deg = std::atan(hp.h / distance) * kRadToDeg;
  e.pitch_deg = hp.pitch * kRadToDeg;
  // Standard errors by finite differences over the fit's two parameters.
  const HeightPitch db = solve(declared, distance, uc, a, f.vc, f.b + f.sigma_b);
  const HeightPitch dv = solve(declared, distance, uc, a, f.vc + f.sigma_vc, f.b);
  e.sigma_elevation_deg = std::hypot(std::atan(db.h / distance) - std::atan(hp.h / distance),
                                     std::atan(dv.h / distance) - std::atan(hp.h / distance)) *
                          kRadToDeg;
  e.sigma_pitch_deg = std::hypot(db.pitch - hp.pitch, dv.pitch - hp.pitch) * kRadToDeg;
  e.declared_pitch_deg = declared_pitch(declared) * kRadToDeg;
  e.declared_elevation_deg =
      std::atan2(declared.extrinsics.position.z() - axis_foot.z(), distance) * kRadToDeg;
  e.centre_u_px = uc;
  e.centre_v_px = f.vc;
  e.semi_major_px = a;
  e.semi_minor_px = f.b;
  e.residual_px = f.rms;
  e.points = f.n;
  e.toe_line_gap_px = f.vc - p.plate.v_at(uc);
  e.sigma_toe_line_gap_px = std::hypot(f.sigma_vc, p.plate.sigma_px);
  return e;
}

bool pitch_contradicts(const PoseEstimate& e, double tolerance_deg) {
  return std::abs(e.pitch_deg - e.declared_pitch_deg) >
         std::max(tolerance_deg, 3.0 * e.sigma_pitch_deg);
}

std::string pose_contradiction(const PoseEstimate& e, double tolerance_deg) {
  auto num = [](double v) {
    if (std::abs(v) < 0.05) v = 0.0;  // no "-0.0"
    char b[32];
    std::snprintf(b, sizeof b, "%.1f", v);
    return std::string(b);
  };
  std::string why;
  if (pitch_contradicts(e, tolerance_deg))
    why = "the camera is declared pitched " + num(e.declared_pitch_deg) +
          " deg below the horizontal, but the pile's base ellipse in the photo says " +
          num(e.pitch_deg) + " +- " + num(e.sigma_pitch_deg) + " deg (elevation " +
          num(e.elevation_deg) + " deg for a declared " + num(e.declared_elevation_deg) +
          " deg, the camera " + num(1000.0 * e.height_m) + " mm above the plate)";
  if (e.toe_line_gap_px > std::max(3.0, 3.0 * e.sigma_toe_line_gap_px)) {
    if (!why.empty()) why += "; and ";
    why += "the toe line cuts through the pile's base: the base ellipse's ends lie " +
           num(e.toe_line_gap_px) + " px below it (its front " +
           num(e.toe_line_gap_px + e.semi_minor_px) + " px)";
    // The pose in numbers also when the pitch alone is within its tolerance, so that the reader
    // sees what the photo says against what was declared.
    if (!pitch_contradicts(e, tolerance_deg))
      why += "; the ellipse says the camera is pitched " + num(e.pitch_deg) + " +- " +
             num(e.sigma_pitch_deg) + " deg below the horizontal, declared " +
             num(e.declared_pitch_deg) + " deg";
  }
  return why;
}

bool pose_determined(const PoseEstimate& e) {
  return e.sigma_pitch_deg <= 0.5 && e.sigma_elevation_deg <= 0.5;
}

camera::Camera posed_camera(const camera::Camera& declared, const PoseEstimate& e,
                            const Eigen::Vector3d& axis_foot) {
  camera::Camera c = declared;
  const Eigen::Vector3d pos(declared.extrinsics.position.x(), declared.extrinsics.position.y(),
                            axis_foot.z() + e.height_m);
  Eigen::Vector2d fh = (declared.extrinsics.look_at - declared.extrinsics.position).head<2>();
  if (fh.norm() < 1e-12) fh = (axis_foot - declared.extrinsics.position).head<2>();
  fh.normalize();
  const double p = e.pitch_deg / kRadToDeg;
  const Eigen::Vector3d forward(fh.x() * std::cos(p), fh.y() * std::cos(p), -std::sin(p));
  c.extrinsics.position = pos;
  c.extrinsics.look_at = pos + e.distance_m * forward;
  c.extrinsics.up = Eigen::Vector3d::UnitZ();
  c.name = declared.name + " (pose from the photo)";
  return c;
}

nlohmann::json to_json(const PoseEstimate& e) {
  return {{"method", "the pile's base ellipse (front outline on the plate's top face) through "
                     "the declared lens and horizontal distance"},
          {"elevation_deg", e.elevation_deg},
          {"sigma_elevation_deg", e.sigma_elevation_deg},
          {"pitch_deg", e.pitch_deg},
          {"sigma_pitch_deg", e.sigma_pitch_deg},
          {"height_m", e.height_m},
          {"declared_elevation_deg", e.declared_elevation_deg},
          {"declared_pitch_deg", e.declared_pitch_deg},
          {"distance_m", e.distance_m},
          {"toe_line_gap_px", e.toe_line_gap_px},
          {"ellipse_px",
           {{"centre", {e.centre_u_px, e.centre_v_px}},
            {"semi_major", e.semi_major_px},
            {"semi_minor", e.semi_minor_px},
            {"residual", e.residual_px},
            {"points", e.points}}}};
}

}  // namespace reposetwin::vision
