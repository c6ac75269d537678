#include "experiments/pile/headline.hpp"

#include <stdexcept>

namespace reposetwin::experiments {
using nlohmann::json;

Headline headline_from_images(const json& m) {
  if (!m.contains("side_summary") || !m["side_summary"].is_object())
    throw std::invalid_argument("image measurement: no side_summary to take the headline from");
  try {
    const json& s = m.at("side_summary");
    Headline h;
    h.angle_deg = s.at("theta_deg").at("mean").get<double>();
    h.angle_sd_deg = s.at("theta_deg").at("stddev").get<double>();
    h.height_m = s.at("H_m").at("mean").get<double>();
    h.diameter_m = s.at("D_m").at("mean").get<double>();
    h.views = s.at("views").get<int>();
    h.from_images = true;
    h.measure = kHeadlineFromImages;
    return h;
  } catch (const json::exception& e) {
    throw std::invalid_argument(std::string("image measurement: side_summary: ") + e.what());
  }
}

Headline headline_from_particles(const PileMeasure& pile) {
  Headline h;
  h.angle_deg = pile.theta_hd_deg;
  h.height_m = pile.height_m;
  h.diameter_m = pile.base_diameter_m;
  h.measure = kHeadlineFromParticles;
  return h;
}

json to_json(const Headline& h) {
  return {{"headline_angle_deg", h.angle_deg}, {"headline_angle_sd_deg", h.angle_sd_deg},
          {"headline_height_m", h.height_m},   {"headline_diameter_m", h.diameter_m},
          {"headline_views", h.views},         {"headline_measure", h.measure}};
}

const std::vector<MeasureDefinition>& measure_definitions() {
  static const std::vector<MeasureDefinition> defs = {
      {"headline_angle_deg", "result.json",
       "THE angle to compare with a lab's: atan(2H/D) with H and D read by vision from each side "
       "photograph (perspective corrected), mean over the side views; +/- is their spread"},
      {"theta_deg", "images/measurement.json",
       "the same image atan(2H/D) as the headline (mean over the side views)"},
      {"flank_deg", "images/measurement.json",
       "image flank angle: slope of lines fitted (Huber) to the silhouette's flanks between 20% "
       "and 80% of H, mean of both flanks over the side views"},
      {"crest_width_m", "images/measurement.json",
       "width of the flat top: the side silhouette's width within max(3 px, 5% of H) of the apex, "
       "less the fitted flank lines' spread over that depth (0 for a sharp cone), mean over the "
       "side views"},
      {"height_m, diameter_m", "images/measurement.json",
       "H from the plate line to the apex, D between the toe points, from the side photographs"},
      {"top.D_circle_m", "images/measurement.json",
       "footprint diameter from a circle fitted to the pile's outline in the top photograph"},
      {"pile.theta_hd_deg", "result.json",
       "particle atan(2H/D): H the highest pile particle top, D twice the median reach of the "
       "footprint over 36 sectors (no images)"},
      {"pile.height_m, pile.base_diameter_m", "result.json",
       "H and D of pile.theta_hd_deg, from particle positions"},
      {"pile.slice_angle_mean_deg", "result.json",
       "protractor (EDEM's measure): line fitted to the surface of thin slices through the centre "
       "between 20% and 80% of H, mean over 16 azimuths"},
      {"pile.equal_area_angle_deg", "result.json",
       "atan(4A/D^2), A the area under a slice's surface profile: the cone of the same "
       "cross-section, mean over slices"},
      {"pile.centre_of_mass_angle_deg", "result.json",
       "atan(4 z_com / (D/2)): the cone whose centre of mass is as high (exact for a solid cone)"},
  };
  return defs;
}

}  // namespace reposetwin::experiments
