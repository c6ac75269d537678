#include "experiments/io/calibration_record.hpp"

#include <cmath>
#include <filesystem>

#include "experiments/io/files.hpp"
#include "experiments/io/hash.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/json_read.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
namespace {

constexpr const char* kRecordKey = "material";

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

// "/material/overrides/0/key" as the user reads a key: material.overrides[0].key.
std::string dotted(const std::string& pointer) {
  std::string out;
  std::size_t from = 1;
  while (from <= pointer.size()) {
    const std::size_t slash = std::min(pointer.find('/', from), pointer.size());
    const std::string token = pointer.substr(from, slash - from);
    const bool index = !token.empty() && token.find_first_not_of("0123456789") == std::string::npos;
    out += index ? "[" + token + "]" : (out.empty() ? "" : ".") + token;
    from = slash + 1;
  }
  return out;
}

// The record's error as an InputError: the file, the key and, when there is one, its value.
InputError record_error(const JsonFieldError& e, const std::string& file,
                        const nlohmann::json& doc) {
  std::string value;
  const nlohmann::json::json_pointer p(e.pointer());
  if (!e.pointer().empty() && doc.contains(p)) {
    value = doc.at(p).dump();
    if (value.size() > 80) value = value.substr(0, 80) + "...";
    // known_fields puts the value in its own words already.
    if (e.problem().find("(value ") == std::string::npos)
      value = " = " + value;
    else
      value.clear();
  }
  return InputError(file + ": key " + dotted(e.pointer()) + value + ": " + e.problem());
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

CalibratedMaterial calibrated_material_from_json(const nlohmann::json& j, const std::string& file) {
  const nlohmann::json doc = {{kRecordKey, j}};
  try {
    return json_read_detail::at_token(j, kRecordKey, [&](const nlohmann::json& r) {
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
        throw JsonFieldError("/mu_r_interval",
                             "must be two finite numbers lo <= mu_r <= hi (mu_r is " +
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
    });
  } catch (const JsonFieldError& e) {
    throw record_error(e, file, doc);
  }
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
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(read_file(file));
  } catch (const nlohmann::json::exception& e) {
    throw InputError(file + ": not JSON (" + e.what() + ")");
  }
  if (!j.is_object() || !j.contains(kRecordKey))
    throw InputError(file + ": key " + kRecordKey + " is missing (the file is " +
                     (j.dump().size() > 40 ? j.dump().substr(0, 40) + "..." : j.dump()) +
                     "): not a calibration record written by `reposetwin calibrate`, or one "
                     "written before calibrations recorded their material; calibrate again into "
                     "the same --out (its finished runs are reused)");
  if (j.at(kRecordKey).is_null()) {
    const auto text = [&](const char* k) {
      return j.contains(k) && j.at(k).is_string() ? j.at(k).get<std::string>() : std::string("?");
    };
    throw InputError(file + ": status \"" + text("status") +
                     "\": this calibration reached no mu_r, so there is no calibrated material "
                     "to take further (" +
                     text("message") + ")");
  }
  CalibratedMaterial m = calibrated_material_from_json(j.at(kRecordKey), file);
  std::string text;
  try {
    text = read_file(m.scene);
  } catch (const InputError& e) {
    throw InputError(file + ": key material.scene = \"" + m.scene +
                     "\": the calibrated base scene cannot be read (" + e.what() + ")");
  }
  if (fnv1a_hex(text) != m.scene_fnv1a)
    throw InputError(file + ": key material.scene = \"" + m.scene +
                     "\": the scene was edited since it was calibrated (its text's hash is " +
                     fnv1a_hex(text) + ", the calibration's " + m.scene_fnv1a +
                     "); calibrate again, or export the scene file itself with --set");
  return m;
}

}  // namespace reposetwin::experiments
