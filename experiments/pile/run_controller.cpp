#include "experiments/pile/run_controller.hpp"

namespace reposetwin::experiments::pile_detail {
using nlohmann::json;

const char* phase_name(Phase p) {
  switch (p) {
    case Phase::kFill:
      return "fill";
    case Phase::kLift:
      return "lift";
    case Phase::kSettle:
      return "settle";
    case Phase::kDone:
      return "done";
  }
  return "?";
}

Phase phase_from(const std::string& s) {
  if (s == "fill") return Phase::kFill;
  if (s == "lift") return Phase::kLift;
  if (s == "settle") return Phase::kSettle;
  return Phase::kDone;
}

json Controller::to_json() const {
  using experiments::to_json;
  return {{"phase", phase_name(phase)},
          {"phase_start", phase_start},
          {"lift_start", lift_start},
          {"lift_end", lift_end},
          {"inside_last", inside_last},
          {"inside_changed", inside_changed},
          {"next_frame", next_frame},
          {"frames", frames},
          {"ke_threshold", ke_threshold},
          {"r_min", r_min},
          {"r_max", r_max},
          {"wall_seconds", wall_seconds},
          {"cpu_seconds", cpu_seconds},
          {"max_overlap_seen", max_overlap_seen},
          {"stop_reason", phase == Phase::kDone ? stop_reason_text(stop) : ""},
          {"stop_detail", stop.detail},
          {"scene_fnv1a", scene_hash},
          {"templates_fnv1a", templates_hash},
          {"code_version", code_version},
          {"engine_version", engine_version},
          {"step", step},
          {"retained", retained},
          {"retained_mass", retained_mass},
          {"psd", to_json(psd)},
          {"events", to_json(events)}};
}
Controller Controller::from_json(const json& j) {
  Controller c;
  c.phase = phase_from(j.at("phase").get<std::string>());
  c.phase_start = j.at("phase_start");
  c.lift_start = j.at("lift_start");
  c.lift_end = j.at("lift_end");
  c.inside_last = j.at("inside_last");
  c.inside_changed = j.at("inside_changed");
  c.next_frame = j.at("next_frame");
  c.frames = j.at("frames");
  c.ke_threshold = j.at("ke_threshold");
  c.r_min = j.at("r_min");
  c.r_max = j.at("r_max");
  c.wall_seconds = j.at("wall_seconds");
  c.cpu_seconds = j.value("cpu_seconds", 0.0);  // absent in checkpoints older than the field
  c.max_overlap_seen = j.at("max_overlap_seen");
  if (!j.at("stop_reason").get<std::string>().empty())
    c.stop = stop_from_json({{"reason", j.at("stop_reason")}, {"detail", j.at("stop_detail")}});
  // Controller files written before these stamps have none, and are not checked.
  c.scene_hash = j.value("scene_fnv1a", std::string());
  c.code_version = j.value("code_version", std::string());
  c.engine_version = j.value("engine_version", std::string());
  c.templates_hash = j.value("templates_fnv1a", std::string());
  c.step = j.value("step", std::int64_t{-1});
  // Controller files from before the retained-material rule have none retained.
  c.retained = j.value("retained", std::int64_t{0});
  c.retained_mass = j.value("retained_mass", 0.0);
  c.psd = psd_record_from_json(j.at("psd"));
  c.events = run_events_from_json(j.at("events"));
  return c;
}

}  // namespace reposetwin::experiments::pile_detail
