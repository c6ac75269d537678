#include "experiments/io/calibration_record.hpp"

#include <cmath>
#include <filesystem>

#include "experiments/io/json_read.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
namespace {

Override override_from_json(const nlohmann::json& j) {
  known_fields(j, {"key", "value"});
  Override o{field<std::string>(j, "key"), field<std::string>(j, "value")};
  if (!is_toml_value(o.value))
    throw JsonFieldError("/value", "\"" + o.value + "\" is not a TOML value");
  return o;
}

double finite(const nlohmann::json& j, const char* key) {
  const double v = number_field(j, key);
  if (!std::isfinite(v)) throw JsonFieldError(std::string("/") + key, "must be a finite number");
  return v;
}

}  // namespace

std::vector<Override> CalibratedMaterial::scene_overrides() const {
  std::vector<Override> all = overrides;
  for (const std::string& k : keys) all.push_back(number_override(k, mu_r));
  return all;
}

nlohmann::json to_json(const CalibratedMaterial& m) {
  nlohmann::json ov = nlohmann::json::array();
  for (const Override& o : m.overrides) ov.push_back({{"key", o.key}, {"value", o.value}});
  return {
      {"scene", m.scene},
      {"scene_fnv1a", m.scene_fnv1a},
      {"overrides", ov},
      {"keys", m.keys},
      {"mu_r", m.mu_r},
      {"mu_r_interval", {m.mu_r_lo, m.mu_r_hi}},
      {"target_deg", m.target_deg},
      {"angle", m.angle},
      {"sieve_sheet", m.sieve_sheet.empty() ? nlohmann::json() : nlohmann::json(m.sieve_sheet)}};
}

CalibratedMaterial calibrated_material_from_json(const nlohmann::json& r, const std::string& file) {
  known_fields(r, {"scene", "scene_fnv1a", "overrides", "keys", "mu_r", "mu_r_interval",
                   "target_deg", "angle", "sieve_sheet"});
  CalibratedMaterial m;
  m.scene = field<std::string>(r, "scene");
  m.scene_fnv1a = field<std::string>(r, "scene_fnv1a");
  m.overrides = each(r, "overrides", override_from_json);
  m.keys = field<std::vector<std::string>>(r, "keys");
  if (m.keys.empty()) throw JsonFieldError("/keys", "names no calibrated key");
  m.mu_r = finite(r, "mu_r");
  const std::vector<double> interval = numbers_field(r, "mu_r_interval");
  if (interval.size() != 2 || !std::isfinite(interval[0]) || !std::isfinite(interval[1]) ||
      !(interval[0] <= m.mu_r && m.mu_r <= interval[1]))
    throw JsonFieldError("/mu_r_interval", "must be two finite numbers lo <= mu_r <= hi (mu_r is " +
                                               nlohmann::json(m.mu_r).dump() + ")");
  m.mu_r_lo = interval[0];
  m.mu_r_hi = interval[1];
  m.target_deg = finite(r, "target_deg");
  m.angle = field<std::string>(r, "angle");
  const nlohmann::json& sieve = json_read_detail::member(r, "sieve_sheet");
  if (!sieve.is_null()) m.sieve_sheet = field<std::string>(r, "sieve_sheet");
  // A path written in a file is relative to that file's folder.
  const fs::path here = fs::path(file).parent_path();
  if (fs::path(m.scene).is_relative()) m.scene = (here / m.scene).lexically_normal().string();
  if (!m.sieve_sheet.empty() && fs::path(m.sieve_sheet).is_relative())
    m.sieve_sheet = (here / m.sieve_sheet).lexically_normal().string();
  return m;
}

}  // namespace reposetwin::experiments
