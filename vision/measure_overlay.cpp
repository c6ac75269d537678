// The overlay images: a measurement drawn on its photo (silhouette, plate line, flank lines,
// toes, apex and a block of the numbers), for a person to check what vision read.
#include <iomanip>
#include <opencv2/imgproc.hpp>

#include "vision/measure.hpp"

#include "vision/level_view.hpp"
#include "vision/text_detail.hpp"

namespace reposetwin::vision {
namespace {

using detail::fixed;

}  // namespace

namespace {

cv::Mat to_bgr8(const cv::Mat& image) {
  cv::Mat img = image;
  if (img.depth() == CV_16U) img.convertTo(img, CV_8U, 255.0 / 65535.0);
  cv::Mat out;
  if (img.channels() == 1)
    cv::cvtColor(img, out, cv::COLOR_GRAY2BGR);
  else if (img.channels() == 4)
    cv::cvtColor(img, out, cv::COLOR_BGRA2BGR);
  else
    out = img.clone();
  return out;
}

void text_block(cv::Mat& img, const std::vector<std::string>& lines) {
  const double scale = std::max(0.4, img.cols / 1800.0);
  const int thick = std::max(1, static_cast<int>(std::lround(scale * 1.5)));
  int base = 0;
  const cv::Size sz = cv::getTextSize("Hg", cv::FONT_HERSHEY_SIMPLEX, scale, thick, &base);
  const int line_h = static_cast<int>(sz.height * 1.8);
  int width = 0;
  for (const auto& l : lines)
    width =
        std::max(width, cv::getTextSize(l, cv::FONT_HERSHEY_SIMPLEX, scale, thick, &base).width);
  const int pad = line_h / 3;
  cv::rectangle(img, cv::Rect(0, 0, width + 2 * pad, line_h * static_cast<int>(lines.size()) + pad),
                cv::Scalar(255, 255, 255), cv::FILLED);
  for (size_t i = 0; i < lines.size(); ++i)
    cv::putText(img, lines[i], cv::Point(pad, static_cast<int>((i + 1) * line_h)),
                cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(0, 0, 0), thick, cv::LINE_AA);
}

cv::Point ip(const cv::Point2d& p) {
  return {static_cast<int>(std::lround(p.x)), static_cast<int>(std::lround(p.y))};
}

}  // namespace

cv::Mat draw_side_overlay(const cv::Mat& image, const SideMeasurement& m) {
  // A photo read in its level view is drawn in that view, where its lines were found.
  cv::Mat img = to_bgr8(m.photo_camera ? level_view(image, *m.photo_camera).image : image);
  const SideProfile& p = m.pixels;
  const int t = std::max(1, img.cols / 900);
  const int r = std::max(4, img.cols / 250);
  // Plate (toe) line.
  cv::line(img, ip({0.0, p.plate.v_at(0.0)}), ip({img.cols - 1.0, p.plate.v_at(img.cols - 1.0)}),
           cv::Scalar(255, 200, 0), t, cv::LINE_AA);
  if (p.far_edge)  // the plate's far edge, when the plate line is the toe line below it
    cv::line(img, ip({0.0, p.far_edge->v_at(0.0)}),
             ip({img.cols - 1.0, p.far_edge->v_at(img.cols - 1.0)}), cv::Scalar(160, 120, 0),
             std::max(1, t / 2), cv::LINE_AA);
  // Fitted flank lines, from the plate line to the apex height, fit band marked thicker.
  auto flank = [&](const FlankFit& f, const cv::Scalar& colour) {
    const double h0 = p.plate.height_above(f.point);
    const double dh = p.plate.height_above(f.point + f.direction) - h0;
    if (std::abs(dh) < 1e-9) return;
    auto at = [&](double h) { return f.point + f.direction * ((h - h0) / dh); };
    cv::line(img, ip(at(0.0)), ip(at(p.height_px)), colour, t, cv::LINE_AA);
    cv::line(img, ip(at(f.low_px)), ip(at(f.high_px)), colour, 3 * t, cv::LINE_AA);
  };
  flank(p.left, cv::Scalar(0, 0, 230));
  flank(p.right, cv::Scalar(0, 170, 0));
  // H: from the apex perpendicular down to the plate line; D: between the toes.
  const cv::Point2d dir = p.plate.direction();
  const cv::Point2d down(-dir.y, dir.x);
  cv::line(img, ip(p.apex), ip(p.apex + down * p.height_px), cv::Scalar(0, 140, 255), t,
           cv::LINE_AA);
  cv::line(img, ip(p.toe_left), ip(p.toe_right), cv::Scalar(255, 0, 255), 2 * t, cv::LINE_AA);
  cv::line(img, ip(m.crest.left), ip(m.crest.right), cv::Scalar(0, 220, 255), 2 * t, cv::LINE_AA);
  cv::circle(img, ip(p.apex), r, cv::Scalar(0, 220, 255), t, cv::LINE_AA);
  cv::circle(img, ip(p.toe_left), r, cv::Scalar(255, 0, 255), t, cv::LINE_AA);
  cv::circle(img, ip(p.toe_right), r, cv::Scalar(255, 0, 255), t, cv::LINE_AA);
  if (m.scale_bar) cv::rectangle(img, m.scale_bar->box, cv::Scalar(255, 0, 0), t);
  text_block(
      img, {"H = " + fixed(1000.0 * m.height_m, 1) + " +- " + fixed(1000.0 * m.sigma_height_m, 1) +
                " mm   D = " + fixed(1000.0 * m.diameter_m, 1) + " +- " +
                fixed(1000.0 * m.sigma_diameter_m, 1) + " mm",
            "theta = atan(2H/D) = " + fixed(m.theta_deg, 2) + " +- " + fixed(m.sigma_theta_deg, 2) +
                " deg",
            "crest (flat top) = " + fixed(1000.0 * m.crest_width_m, 1) + " +- " +
                fixed(1000.0 * m.sigma_crest_width_m, 1) + " mm" +
                (m.pose ? "   camera pitch from the photo: " + fixed(m.pose->pitch_deg, 1) + " deg"
                        : std::string()),
            "flanks: left " + fixed(m.flank_left_deg, 2) + " +- " +
                fixed(m.sigma_flank_left_deg, 2) + ", right " + fixed(m.flank_right_deg, 2) +
                " +- " + fixed(m.sigma_flank_right_deg, 2) + " deg",
            "scale: " + to_string(m.scale_source) + ", " + fixed(m.mm_per_px, 4) +
                " mm/px at the axis; " +
                (m.perspective_corrected ? "perspective corrected" : "assumed orthographic")});
  return img;
}

cv::Mat draw_top_overlay(const cv::Mat& image, const TopMeasurement& m) {
  cv::Mat img = to_bgr8(image);
  const TopProfile& p = m.pixels;
  const int t = std::max(1, img.cols / 900);
  for (size_t i = 0; i < p.outline.size(); ++i)
    cv::line(img, ip(p.outline[i]), ip(p.outline[(i + 1) % p.outline.size()]),
             cv::Scalar(0, 170, 0), t, cv::LINE_AA);
  cv::circle(img, ip(p.center), static_cast<int>(std::lround(0.5 * p.diameter_circle_px)),
             cv::Scalar(0, 0, 230), t, cv::LINE_AA);
  cv::drawMarker(img, ip(p.center), cv::Scalar(0, 0, 230), cv::MARKER_CROSS, 4 * t + 10, t);
  if (m.checker_card) cv::rectangle(img, m.checker_card->box, cv::Scalar(255, 0, 0), t);
  if (m.crest.found && m.crest.radius_px > 0.0)
    cv::circle(img, ip(m.crest.center), static_cast<int>(std::lround(m.crest.radius_px)),
               cv::Scalar(0, 215, 255), t, cv::LINE_AA);
  text_block(img,
             {"D (circle fit) = " + fixed(1000.0 * m.diameter_circle_m, 1) + " +- " +
                  fixed(1000.0 * m.sigma_diameter_circle_m, 1) + " mm",
              "D (equal area) = " + fixed(1000.0 * m.diameter_area_m, 1) +
                  " mm   ellipticity = " + fixed(m.ellipticity, 3),
              m.crest.found
                  ? "crest (flat top, from the shading) = " + fixed(1000.0 * m.crest_width_m, 1) +
                        " +- " + fixed(1000.0 * m.sigma_crest_width_m, 1) + " mm"
                  : "crest: not read from this view",
              "scale: " + to_string(m.scale_source) + ", " + fixed(m.mm_per_px, 4) + " mm/px; " +
                  (m.perspective_corrected ? "perspective corrected" : "assumed orthographic")});
  return img;
}

}  // namespace reposetwin::vision
