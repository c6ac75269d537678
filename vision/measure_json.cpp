// The JSON forms of a side, top and combined measurement (the measurement.json sidecar and the
// measure command's output): one to_json per record, every field in its unit.
#include <nlohmann/json.hpp>

#include "vision/measure.hpp"

namespace reposetwin::vision {

namespace {

nlohmann::json pt(const cv::Point2d& p) { return nlohmann::json::array({p.x, p.y}); }

nlohmann::json flank_json(const FlankFit& f) {
  return {{"angle_deg", f.angle_deg},         {"sigma_deg", f.sigma_deg},
          {"sigma_fit_deg", f.sigma_fit_deg}, {"sigma_pixel_deg", f.sigma_pixel_deg},
          {"residual_px", f.residual_px},     {"points", f.points},
          {"band_px", {f.low_px, f.high_px}}, {"point_px", pt(f.point)},
          {"direction", pt(f.direction)}};
}

nlohmann::json spread_json(const Spread& s) {
  return {{"mean", s.mean}, {"stddev", s.stddev}, {"sigma_mean", s.sigma_mean}};
}

}  // namespace

nlohmann::json to_json(const SideMeasurement& m) {
  const SideProfile& p = m.pixels;
  nlohmann::json bar = nullptr;
  if (m.scale_bar)
    bar = {{"band_px", m.scale_bar->band_px},
           {"band_mm", m.scale_bar->band_mm},
           {"black_bands", m.scale_bar->black_bands},
           {"edges", m.scale_bar->edges},
           {"residual_px", m.scale_bar->residual_px},
           {"box_px",
            {m.scale_bar->box.x, m.scale_bar->box.y, m.scale_bar->box.width,
             m.scale_bar->box.height}}};
  nlohmann::json j = {
      {"view", "side"},
      {"image", m.source},
      {"H_m", m.height_m},
      {"D_m", m.diameter_m},
      {"theta_deg", m.theta_deg},
      {"sigma_H_m", m.sigma_height_m},
      {"sigma_D_m", m.sigma_diameter_m},
      {"D_definitions",
       {{"D_m", "the silhouette's reach at the toe line (the toe band carried down the flank, "
                "never beyond the outermost grain): the headline"},
        {"D_flank_foot_m", m.diameter_flank_m},
        {"theta_flank_foot_deg", m.theta_flank_foot_deg},
        {"sigma_D_definition_m", m.sigma_diameter_definition_m},
        {"rule", "half the difference of the two definitions joins sigma_D_m (vision/measure.hpp)"}}},
      {"sigma_theta_deg", m.sigma_theta_deg},
      {"flank_left_deg", m.flank_left_deg},
      {"flank_right_deg", m.flank_right_deg},
      {"sigma_flank_left_deg", m.sigma_flank_left_deg},
      {"sigma_flank_right_deg", m.sigma_flank_right_deg},
      {"crest_width_m", m.crest_width_m},
      {"sigma_crest_width_m", m.sigma_crest_width_m},
      {"method",
       "theta = atan(2H/D); H perpendicular to the detected plate line; D between the toe points "
       "on it; flanks: cv::fitLine DIST_HUBER over a middle band of H"},
      {"projection", m.perspective_corrected ? "perspective corrected" : "assumed orthographic"},
      {"scale",
       {{"source", to_string(m.scale_source)},
        {"mm_per_px", m.mm_per_px},
        {"sigma_rel", m.sigma_scale_rel},
        {"note", m.note},
        {"scale_bar", bar}}},
      {"pixels",
       {{"H_px", p.height_px},
        {"D_px", p.diameter_px},
        {"sigma_H_px", p.sigma_height_px},
        {"sigma_D_px", p.sigma_diameter_px},
        {"theta_deg", p.theta_deg},
        {"apex", pt(p.apex)},
        {"toe_left", pt(p.toe_left)},
        {"toe_right", pt(p.toe_right)},
        {"plate_line",
         {{"v_at_u0", p.plate.a},
          {"slope", p.plate.b},
          {"tilt_deg", p.plate.tilt_deg()},
          {"residual_px", p.plate.residual_px},
          {"support_columns", p.plate.support},
          {"from", p.far_edge ? "toes on the plate's top face" : "plate edge"}}},
        {"level_view", m.photo_camera ? "the photo re-projected onto a level camera at the same "
                                        "centre (vision/level_view.hpp); pixels are in that view"
                                      : "the photo itself"},
        {"crest",
         {{"width_px", m.crest.width_px},
          {"raw_width_px", m.crest.raw_width_px},
          {"sigma_px", m.crest.sigma_px},
          {"depth_px", m.crest.depth_px},
          {"left", pt(m.crest.left)},
          {"right", pt(m.crest.right)},
          {"rule",
           "silhouette width within max(3 px, 5% of H) of the apex, less the flank lines' "
           "spread over that depth (vision/crest.hpp)"}}},
        {"flank_left", flank_json(p.left)},
        {"flank_right", flank_json(p.right)},
        {"pile_level", p.pile_level},
        {"threshold", p.threshold}}}};
  j["warnings"] = nlohmann::json::array();
  for (const SideWarning& w : m.warnings)
    j["warnings"].push_back({{"kind", to_string(w.kind)},
                             {"biases_measure", biases_measure(w.kind)},
                             {"text", w.text}});
  j["pose_used"] = m.pose_used;
  if (m.pose) j["camera_pose"] = to_json(*m.pose);
  if (m.perspective_corrected) {
    j["camera_correction"] = {
        {"base_center_m", {m.base_center_m.x(), m.base_center_m.y(), m.base_center_m.z()}},
        {"plate_line_z_m", m.plate_line_z_m}};
  }
  return j;
}

namespace {

// The top view's crest: its width, or why it went unread, and the shading it was read from.
nlohmann::json to_json_crest(const TopMeasurement& m) {
  const TopCrest& c = m.crest;
  nlohmann::json j = {{"found", c.found},
                      {"plane", m.crest_plane},
                      {"pixels",
                       {{"center", pt(c.center)},
                        {"radius_px", c.radius_px},
                        {"sigma_radius_px", c.sigma_radius_px},
                        {"light_azimuth_deg", c.light_azimuth_deg},
                        {"flank_harmonic", c.flank_amplitude},
                        {"sigma_flank_harmonic", c.flank_sigma},
                        {"inner_level", c.inner_level},
                        {"outer_level", c.outer_level},
                        {"sigma_step", c.step_sigma}}}};
  if (c.found) {
    j["width_m"] = m.crest_width_m;
    j["sigma_width_m"] = m.sigma_crest_width_m;
  } else {
    j["reason"] = c.reason;
  }
  return j;
}

}  // namespace

nlohmann::json to_json(const TopMeasurement& m) {
  const TopProfile& p = m.pixels;
  nlohmann::json card = nullptr;
  if (m.checker_card)
    card = {{"square_px", m.checker_card->square_px},
            {"square_mm", m.checker_card->square_mm},
            {"squares", m.checker_card->squares}};
  return {
      {"view", "top"},
      {"image", m.source},
      {"D_circle_m", m.diameter_circle_m},
      {"D_equal_area_m", m.diameter_area_m},
      {"sigma_D_circle_m", m.sigma_diameter_circle_m},
      {"circle_residual_m", m.circle_residual_m},
      {"ellipticity", m.ellipticity},
      {"projection", m.perspective_corrected ? "perspective corrected" : "assumed orthographic"},
      {"scale",
       {{"source", to_string(m.scale_source)},
        {"mm_per_px", m.mm_per_px},
        {"sigma_rel", m.sigma_scale_rel},
        {"note", m.note},
        {"checker_card", card}}},
      {"pixels",
       {{"center", pt(p.center)},
        {"D_circle_px", p.diameter_circle_px},
        {"D_equal_area_px", p.diameter_area_px},
        {"circle_residual_px", p.circle_residual_px},
        {"ellipse_axes_px", {p.ellipse_major_px, p.ellipse_minor_px}},
        {"ellipse_angle_deg", p.ellipse_angle_deg},
        {"outline_points", p.outline.size()},
        {"cue", p.cue}}},
      {"crest", to_json_crest(m)}};
}

nlohmann::json to_json(const SideSummary& s) {
  return {{"views", s.views},
          {"H_m", spread_json(s.height_m)},
          {"D_m", spread_json(s.diameter_m)},
          {"theta_deg", spread_json(s.theta_deg)},
          {"flank_left_deg", spread_json(s.flank_left_deg)},
          {"flank_right_deg", spread_json(s.flank_right_deg)},
          {"flank_deg", spread_json(s.flank_deg)},
          {"crest_width_m", spread_json(s.crest_width_m)}};
}

}  // namespace reposetwin::vision
