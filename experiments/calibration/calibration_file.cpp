#include "experiments/calibration/calibration_file.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <tuple>
#include <utility>

#include "experiments/io/files.hpp"
#include "experiments/io/hash.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/json_read.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;
namespace {

constexpr std::array kStatuses = {CalibrationStatus::kCalibrated, CalibrationStatus::kBudgetSpent,
                                  CalibrationStatus::kSeedNoiseLimited,
                                  CalibrationStatus::kCannotReachLow,
                                  CalibrationStatus::kCannotReachHigh};

// Every top-level key the record reads; the others are the driver's working (see the note).
// clang-format off
constexpr std::array kRecordKeys = {
    "status", "message", "target", "mu_r", "mu_r_interval", "interval_level", "interval_open",
    "fitted_angle_deg", "fitted_angle_halfwidth_deg", "not_calibrated", "reachable_deg",
    "simulations", "fit", "observations", "excluded_search_observations", "jam_rate_per_mu_r",
    "method", "campaign", "campaign_name", "key", "keys", "mu_r_range", "tolerance_deg",
    "seeds_per_point", "table1_sample", "scene", "rolling_model", "angle_method", "angle",
    "target_photos", "material", "created_utc", "code_version", "copied_from"};
// clang-format on

// ---- values -------------------------------------------------------------------------------

std::string text_value(const json& v) {
  if (!v.is_string())
    throw JsonFieldError("", std::string("is ") + v.type_name() + ", not a string");
  return v.get<std::string>();
}

double finite_value(const json& v) {
  if (!v.is_number())
    throw JsonFieldError("", std::string("is ") + v.type_name() + ", not a number");
  const double x = v.get<double>();
  if (!std::isfinite(x)) throw JsonFieldError("", "is not a finite number");
  return x;
}

double finite(const json& j, const char* key) { return nested(j, key, finite_value); }

// Two finite numbers [a, b].
std::pair<double, double> number_pair(const json& v) {
  if (!v.is_array() || v.size() != 2)
    throw JsonFieldError("",
                         std::string("is ") +
                             (v.is_array() ? "an array of " + std::to_string(v.size()) + " values"
                                           : std::string(v.type_name())) +
                             ", not two numbers");
  const std::vector<double> x = elements(v, finite_value);
  return {x[0], x[1]};
}

bool bool_value(const json& v) {
  if (!v.is_boolean())
    throw JsonFieldError("", std::string("is ") + v.type_name() + ", not true or false");
  return v.get<bool>();
}

int int_value(const json& v) {
  if (!v.is_number_integer())
    throw JsonFieldError("", std::string("is ") + v.type_name() + ", not a whole number");
  return v.get<int>();
}

std::string optional_text(const json& j, const char* key) {
  return j.contains(key) ? nested(j, key, text_value) : std::string();
}

CalibrationStatus status_value(const json& v) {
  return calibration_status_from_string(text_value(v));
}

// ---- sub-records --------------------------------------------------------------------------

json to_json(const Observation& o) {
  return {{"mu_r", o.mu_r}, {"seed", o.seed}, {"angle_deg", o.angle_deg}};
}

Observation observation_from_json(const json& j) {
  known_fields(j, {"mu_r", "seed", "angle_deg"});
  Observation o;
  o.mu_r = finite(j, "mu_r");
  o.seed = nested(j, "seed", [](const json& v) {
    if (!v.is_number_unsigned())
      throw JsonFieldError("",
                           std::string("is ") + v.type_name() + ", not a seed (a whole number)");
    return v.get<std::uint64_t>();
  });
  o.angle_deg = finite(j, "angle_deg");
  return o;
}

Target target_from_json(const json& j) {
  known_fields(j, {"angle_deg", "sd_deg"});
  return {finite(j, "angle_deg"), finite(j, "sd_deg")};
}

FitPoint fit_point_from_json(const json& j) {
  known_fields(j, {"mu_r", "n", "mean_deg", "sd_deg", "fitted_deg"});
  FitPoint p;
  p.mu_r = finite(j, "mu_r");
  p.n = nested(j, "n", int_value);
  p.mean_deg = finite(j, "mean_deg");
  p.sd_deg = finite(j, "sd_deg");
  p.fitted_deg = finite(j, "fitted_deg");
  return p;
}

// The fit with its method in words; the pooled noise is null (NaN) when it was not estimated.
std::pair<MonotoneFit, std::string> fit_from_json(const json& j) {
  known_fields(j, {"method", "points", "noise_sd_deg", "noise_dof"});
  MonotoneFit f;
  const std::string method = nested(j, "method", text_value);
  f.points = each(j, "points", fit_point_from_json);
  f.noise_sd_deg = number_field(j, "noise_sd_deg");
  f.noise_dof = nested(j, "noise_dof", int_value);
  return {f, method};
}

json to_json(const PourCount& q) {
  return {{"mu_r", q.mu_r},
          {"pours", q.pours},
          {"piles", q.piles},
          {"jams", q.jams},
          {"physics_stops", q.physics_stops},
          {"time_limits", q.time_limits},
          {"not_settled", q.not_settled},
          {"jam_rate", q.jam_rate},
          {"in_fit", q.in_fit}};
}

PourCount pour_count_from_json(const json& j) {
  known_fields(j, {"mu_r", "pours", "piles", "jams", "physics_stops", "time_limits", "not_settled",
                   "jam_rate", "in_fit"});
  PourCount q;
  q.mu_r = finite(j, "mu_r");
  q.pours = nested(j, "pours", int_value);
  q.piles = nested(j, "piles", int_value);
  q.jams = nested(j, "jams", int_value);
  q.physics_stops = nested(j, "physics_stops", int_value);
  // Counted since the time limit and the settling check were told apart from a jam: absent
  // (none counted) in the records written before.
  if (j.contains("time_limits")) q.time_limits = nested(j, "time_limits", int_value);
  if (j.contains("not_settled")) q.not_settled = nested(j, "not_settled", int_value);
  q.jam_rate = finite(j, "jam_rate");
  q.in_fit = nested(j, "in_fit", bool_value);
  return q;
}

json to_json(const RollingModelRecord& m) {
  json j = {{"keyword", m.keyword}, {"stated_in_scene", m.stated_in_scene}};
  if (!m.torque.empty()) j["torque"] = m.torque;
  if (!m.radius.empty()) j["radius"] = m.radius;
  if (!m.angular_velocity.empty()) j["angular_velocity"] = m.angular_velocity;
  return j;
}

RollingModelRecord rolling_model_from_json(const json& j) {
  known_fields(j, {"keyword", "stated_in_scene", "torque", "radius", "angular_velocity"});
  RollingModelRecord m;
  m.keyword = nested(j, "keyword", text_value);
  m.stated_in_scene = nested(j, "stated_in_scene", bool_value);
  m.torque = optional_text(j, "torque");
  m.radius = optional_text(j, "radius");
  m.angular_velocity = optional_text(j, "angular_velocity");
  return m;
}

json to_json(const TargetPhotosRecord& t) {
  json j = t.measurement.is_object() ? t.measurement : json::object();
  j["photos"] = t.photos;
  j["camera_sidecar"] = t.camera_sidecar.empty() ? json() : json(t.camera_sidecar);
  j["declared_mm_per_px"] = t.declared_mm_per_px ? json(*t.declared_mm_per_px) : json();
  return j;
}

// vision's measurement is kept whole: only the keys the report uses are typed (see the note).
TargetPhotosRecord target_photos_fields(const json& j) {
  if (!j.is_object())
    throw JsonFieldError("", std::string("is ") + j.type_name() + ", not an object");
  TargetPhotosRecord t;
  t.photos = each(j, "photos", text_value);
  if (t.photos.empty()) throw JsonFieldError("/photos", "names no photo");
  if (j.contains("camera_sidecar") && !j.at("camera_sidecar").is_null())
    t.camera_sidecar = nested(j, "camera_sidecar", text_value);
  if (j.contains("declared_mm_per_px") && !j.at("declared_mm_per_px").is_null())
    t.declared_mm_per_px = finite(j, "declared_mm_per_px");
  t.measurement = j;
  for (const char* k : {"photos", "camera_sidecar", "declared_mm_per_px"}) t.measurement.erase(k);
  return t;
}

json to_json(const NotCalibrated& n) {
  return {{"status", to_string(n.status)}, {"message", n.message}, {"mu_r_basis", n.mu_r_basis}};
}

NotCalibrated not_calibrated_from_json(const json& j) {
  known_fields(j, {"status", "message", "mu_r_basis"});
  return {nested(j, "status", status_value), nested(j, "message", text_value),
          nested(j, "mu_r_basis", text_value)};
}

std::string method_word(CalibrationMethod m) {
  return m == CalibrationMethod::kBracket ? "bracket" : "sequential";
}

CalibrationMethod method_value(const json& v) {
  const std::string w = text_value(v);
  if (w == "bracket") return CalibrationMethod::kBracket;
  if (w == "sequential") return CalibrationMethod::kSequential;
  throw JsonFieldError("", "is not a method (sequential or bracket)");
}

// ---- the record ---------------------------------------------------------------------------

// The answer first (see the design note): the status, the target angle, mu_r and its interval.
void read_answer(const json& j, CalibrationRecord& r) {
  r.status = nested(j, "status", status_value);
  r.target.angle_deg = nested(j, "target", [](const json& t) { return finite(t, "angle_deg"); });
  if (json_read_detail::member(j, "mu_r").is_null()) return;
  r.mu_r = finite(j, "mu_r");
  if (!j.contains("mu_r_interval"))
    throw JsonFieldError("/mu_r_interval", "missing: mu_r = " + json(*r.mu_r).dump() +
                                               " carries its 95% interval, two numbers");
  std::tie(r.mu_r_lo, r.mu_r_hi) = nested(j, "mu_r_interval", number_pair);
}

// The interval's level and open ends and the fitted angle: written with every calibrated mu_r,
// and absent beside a paper run's closest point, which has none of its own.
void read_interval_detail(const json& j, CalibrationRecord& r) {
  const bool required = r.mu_r && !r.not_calibrated;
  if (required || j.contains("interval_level")) r.interval_level = finite(j, "interval_level");
  if (required || j.contains("interval_open"))
    std::tie(r.interval_open_low, r.interval_open_high) =
        nested(j, "interval_open", [](const json& v) {
          if (!v.is_array() || v.size() != 2)
            throw JsonFieldError("", "is not two values [low, high] of true or false");
          const std::vector<bool> b = elements(v, bool_value);
          return std::pair<bool, bool>(b[0], b[1]);
        });
  if (required || j.contains("fitted_angle_deg"))
    r.fitted_angle_deg = finite(j, "fitted_angle_deg");
  if (required || j.contains("fitted_angle_halfwidth_deg"))
    r.fitted_angle_halfwidth_deg = finite(j, "fitted_angle_halfwidth_deg");
}

std::vector<std::string> keys_value(const json& j) {
  std::vector<std::string> keys = j.contains("keys")
                                      ? each(j, "keys", text_value)
                                      : std::vector<std::string>{nested(j, "key", text_value)};
  if (keys.empty()) throw JsonFieldError("/keys", "names no calibrated key");
  return keys;
}

CalibrationRecord record_fields(const json& j, const std::string& file) {
  if (!j.is_object())
    throw JsonFieldError("", std::string("is ") + j.type_name() +
                                 ", not an object (not a calibration record as `reposetwin "
                                 "calibrate` writes)");
  CalibrationRecord r;
  read_answer(j, r);
  r.target = nested(j, "target", target_from_json);
  r.message = nested(j, "message", text_value);
  if (j.contains("not_calibrated"))
    r.not_calibrated = nested(j, "not_calibrated", not_calibrated_from_json);
  read_interval_detail(j, r);
  std::tie(r.reachable_low_deg, r.reachable_high_deg) = nested(j, "reachable_deg", number_pair);
  if (j.contains("method")) r.method = nested(j, "method", method_value);
  r.simulations = nested(j, "simulations", int_value);
  std::tie(r.fit, r.fit_method) = nested(j, "fit", fit_from_json);
  r.observations = each(j, "observations", observation_from_json);
  r.excluded = each(j, "excluded_search_observations", observation_from_json);
  if (j.contains("jam_rate_per_mu_r"))
    r.pour_counts = each(j, "jam_rate_per_mu_r", pour_count_from_json);
  r.campaign = nested(j, "campaign", text_value);
  r.campaign_name = nested(j, "campaign_name", text_value);
  r.keys = keys_value(j);
  std::tie(r.mu_r_range_lo, r.mu_r_range_hi) = nested(j, "mu_r_range", number_pair);
  r.tolerance_deg = finite(j, "tolerance_deg");
  r.seeds_per_point = nested(j, "seeds_per_point", int_value);
  if (!json_read_detail::member(j, "table1_sample").is_null())
    r.table1_sample = nested(j, "table1_sample", int_value);
  r.scene = nested(j, "scene", text_value);
  r.rolling_model = nested(j, "rolling_model", rolling_model_from_json);
  r.angle_method = nested(j, "angle_method", text_value);
  if (j.contains("angle"))
    r.angle = nested(j, "angle", [](const json& v) {
      const std::string word = text_value(v);
      try {
        return parse_angle_measure(word, "angle");
      } catch (const std::invalid_argument&) {
        throw JsonFieldError("", "is not an angle measure (image, image_flank, particles, slice)");
      }
    });
  if (j.contains("target_photos") && !j.at("target_photos").is_null())
    r.target_photos = nested(j, "target_photos", target_photos_fields);
  if (j.contains("material") && !j.at("material").is_null())
    r.material = nested(j, "material",
                        [&](const json& m) { return calibrated_material_from_json(m, file); });
  r.created_utc = nested(j, "created_utc", text_value);
  r.code_version = optional_text(j, "code_version");
  r.copied_from = optional_text(j, "copied_from");
  for (const auto& [key, value] : j.items())
    if (std::find_if(kRecordKeys.begin(), kRecordKeys.end(),
                     [&](const char* k) { return key == k; }) == kRecordKeys.end())
      r.working[key] = value;
  return r;
}

}  // namespace

CalibrationStatus calibration_status_from_string(const std::string& word) {
  std::string list;
  for (CalibrationStatus s : kStatuses) {
    if (word == to_string(s)) return s;
    list += (list.empty() ? "" : ", ") + to_string(s);
  }
  throw std::invalid_argument("is not a calibration status (one of " + list + ")");
}

CalibrationRecord calibration_record(const CalibrationResult& c) {
  CalibrationRecord r;
  r.status = c.status;
  r.message = c.message;
  r.target = c.target;
  r.mu_r = c.mu_r;
  if (c.mu_r) {
    r.mu_r_lo = c.mu_r_low;
    r.mu_r_hi = c.mu_r_high;
    r.interval_level = c.interval_level;
    r.interval_open_low = c.interval_open_low;
    r.interval_open_high = c.interval_open_high;
    r.fitted_angle_deg = c.fitted_angle_deg;
    r.fitted_angle_halfwidth_deg = c.fitted_angle_halfwidth_deg;
  }
  r.reachable_low_deg = c.reachable_low_deg;
  r.reachable_high_deg = c.reachable_high_deg;
  r.simulations = c.simulations;
  r.fit_method = kMonotoneFitMethod;
  r.fit = c.fit;
  r.observations = c.observations;
  r.excluded = c.excluded;
  return r;
}

json to_json(const CalibrationRecord& r) {
  json j = r.working.is_object() ? r.working : json::object();
  json obs = json::array(), excluded = json::array(), pours = json::array();
  for (const Observation& o : r.observations) obs.push_back(to_json(o));
  for (const Observation& o : r.excluded) excluded.push_back(to_json(o));
  for (const PourCount& q : r.pour_counts) pours.push_back(to_json(q));
  json fit = to_json(r.fit);
  fit["method"] = r.fit_method;
  j["status"] = to_string(r.status);
  j["message"] = r.message;
  j["target"] = {{"angle_deg", r.target.angle_deg}, {"sd_deg", r.target.sd_deg}};
  j["mu_r"] = r.mu_r ? json(*r.mu_r) : json();
  if (r.mu_r) {
    j["mu_r_interval"] = {r.mu_r_lo, r.mu_r_hi};
    j["interval_level"] = r.interval_level;
    j["interval_open"] = {r.interval_open_low, r.interval_open_high};
    if (r.fitted_angle_deg) {
      j["fitted_angle_deg"] = *r.fitted_angle_deg;
      j["fitted_angle_halfwidth_deg"] = r.fitted_angle_halfwidth_deg;
    }
  }
  if (r.not_calibrated) j["not_calibrated"] = to_json(*r.not_calibrated);
  j["reachable_deg"] = {r.reachable_low_deg, r.reachable_high_deg};
  j["method"] = method_word(r.method);
  j["simulations"] = r.simulations;
  j["fit"] = fit;
  j["observations"] = obs;
  j["excluded_search_observations"] = excluded;
  if (r.method == CalibrationMethod::kBracket || !r.pour_counts.empty())
    j["jam_rate_per_mu_r"] = pours;
  j["campaign"] = r.campaign;
  j["campaign_name"] = r.campaign_name;
  j["key"] = r.keys.empty() ? json() : json(r.keys.front());
  j["keys"] = r.keys;
  j["mu_r_range"] = {r.mu_r_range_lo, r.mu_r_range_hi};
  j["tolerance_deg"] = r.tolerance_deg;
  j["seeds_per_point"] = r.seeds_per_point;
  j["table1_sample"] = r.table1_sample ? json(*r.table1_sample) : json();
  j["scene"] = r.scene;
  j["rolling_model"] = to_json(r.rolling_model);
  j["angle_method"] = r.angle_method;
  if (r.angle) j["angle"] = angle_measure_name(*r.angle);
  if (r.target_photos) j["target_photos"] = to_json(*r.target_photos);
  j["material"] = r.material ? to_json(*r.material) : json();
  j["created_utc"] = r.created_utc;
  if (!r.code_version.empty()) j["code_version"] = r.code_version;
  if (!r.copied_from.empty()) j["copied_from"] = r.copied_from;
  return j;
}

CalibrationRecord calibration_record_from_json(const json& j, const std::string& file) {
  try {
    return record_fields(j, file);
  } catch (const JsonFieldError& e) {
    throw file_field_error(e, file, j);
  }
}

TargetPhotosRecord target_photos_from_json(const json& j, const std::string& file) {
  try {
    return target_photos_fields(j);
  } catch (const JsonFieldError& e) {
    throw file_field_error(e.under("target_photos"), file, json{{"target_photos", j}});
  }
}

CalibrationRecord read_calibration_record(const std::string& file) {
  return calibration_record_from_json(read_json_file(file), file);
}

CalibratedMaterial read_calibrated_material(const std::string& folder) {
  std::error_code ec;
  if (!fs::is_directory(folder, ec))
    throw InputError(folder +
                     ": not a calibration folder (give the --out folder of "
                     "`reposetwin calibrate`, or a scene file)");
  const std::string file = (fs::path(folder) / kCalibrationRecordFile).string();
  if (!fs::exists(file, ec))
    throw InputError(folder + ": holds no " + kCalibrationRecordFile +
                     ": not the folder of a finished `reposetwin calibrate` (its --out)");
  const CalibrationRecord r = read_calibration_record(file);
  if (!r.mu_r || r.not_calibrated)
    throw InputError(file + ": status \"" + to_string(r.status) +
                     "\": this calibration reached no mu_r, so there is no calibrated material "
                     "to take further (" +
                     (r.not_calibrated ? r.not_calibrated->message : r.message) + ")");
  if (!r.material)
    throw InputError(file +
                     ": key \"material\" is missing: a calibration record written "
                     "before calibrations recorded their material; calibrate again into the same "
                     "--out (its finished runs are reused)");
  const CalibratedMaterial& m = *r.material;
  std::string text;
  try {
    text = read_file(m.scene);
  } catch (const InputError& e) {
    throw InputError(file + ": key \"material.scene\" = \"" + m.scene +
                     "\": the calibrated base scene cannot be read (" + e.what() + ")");
  }
  if (fnv1a_hex(text) != m.scene_fnv1a)
    throw InputError(file + ": key \"material.scene\" = \"" + m.scene +
                     "\": the scene was edited since it was calibrated (its text's hash is " +
                     fnv1a_hex(text) + ", the calibration's " + m.scene_fnv1a +
                     "); calibrate again, or export the scene file itself with --set");
  return m;
}

}  // namespace reposetwin::experiments
