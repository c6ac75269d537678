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

const char* no_headline_word(NoHeadlineReason r) {
  switch (r) {
    case NoHeadlineReason::kTimeLimit:
      return "time_limit";
    case NoHeadlineReason::kNotSettled:
      return "not_settled";
    case NoHeadlineReason::kJammed:
      return "jam";
    case NoHeadlineReason::kNoPile:
      return "no_pile";
    case NoHeadlineReason::kPhysicsStop:
      return "physics_stop";
    case NoHeadlineReason::kPhotographs:
      return "photographs";
    case NoHeadlineReason::kCount:
      break;
  }
  throw std::logic_error("no_headline_word: unknown reason");
}

std::optional<NoHeadline> no_headline(const RunStop& stop, const PileMeasure& pile) {
  const auto with = [&stop](const std::string& what) {
    return stop.detail.empty() ? what : what + ": " + stop.detail;
  };
  switch (stop.reason) {
    case StopReason::kPhysics:
      return NoHeadline{NoHeadlineReason::kPhysicsStop,
                        with("the engine stopped the run (" + stop_reason_text(stop) + ")")};
    case StopReason::kTimeLimit:
      return NoHeadline{NoHeadlineReason::kTimeLimit,
                        with("stopped by the time limit before the pile settled")};
    case StopReason::kSettleTimeLimit:
      return NoHeadline{NoHeadlineReason::kNotSettled, with("the pile did not settle")};
    case StopReason::kClogged:
      return NoHeadline{NoHeadlineReason::kJammed, with("jammed: the outlet clogged")};
    case StopReason::kSettled:
      break;
  }
  if (pile.clogged)
    return NoHeadline{NoHeadlineReason::kJammed, "jammed: the outlet clogged: " + pile.detail};
  if (pile.not_measured || pile.status == sim::PileStatus::kNoPile)
    return NoHeadline{NoHeadlineReason::kNoPile,
                      "formed no pile: no grain rests on the plate" +
                          (pile.detail.empty() ? std::string() : " (" + pile.detail + ")")};
  if (pile.status == sim::PileStatus::kNoFlanks)
    return NoHeadline{NoHeadlineReason::kNoPile,
                      "formed no measurable pile: no flank had enough surface grains for a fit "
                      "(" +
                          std::to_string(pile.pile_count) + " grains in the pile)"};
  return std::nullopt;
}

std::string no_headline_advice(NoHeadlineReason r) {
  switch (r) {
    case NoHeadlineReason::kTimeLimit:
      return "raise procedure.max_time_s, or shorten the run (a smaller sample.mass_kg, a faster "
             "procedure.lift_speed_m_s)";
    case NoHeadlineReason::kNotSettled:
      return "raise procedure.final_settle_max_s, or settle to a looser procedure.settle_speed_m_s";
    case NoHeadlineReason::kJammed:
      return "widen the outlet (container.bottom_diameter_m; below 3.75 d_max the paper's "
             "Fig. 10 funnel jams), or lower the rolling friction or cohesion that arches it";
    case NoHeadlineReason::kNoPile:
      return "use a larger sample.mass_kg, or smaller grains (sample.psd), so the pile is "
             "several grains high";
    case NoHeadlineReason::kPhysicsStop:
      return "see the likely cause printed with the stop";
    case NoHeadlineReason::kPhotographs:
      return "free the disk or make the run folder's images/ writable, then run again with "
             "--force";
    case NoHeadlineReason::kCount:
      break;
  }
  throw std::logic_error("no_headline_advice: unknown reason");
}

json to_json(const NoHeadline& n) {
  return {{"headline_angle_deg", nullptr},
          {"no_headline", {{"reason", no_headline_word(n.reason)}, {"message", n.message}}}};
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
