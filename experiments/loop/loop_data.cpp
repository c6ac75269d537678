#include "experiments/loop/loop_data.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "experiments/campaign/campaign.hpp"
#include "experiments/io/format.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/scene_overrides.hpp"
#include "experiments/loop/loop_effects.hpp"
#include "experiments/photos/lab_photos.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r\n");
  if (a == std::string::npos) return "";
  const auto b = s.find_last_not_of(" \t\r\n");
  return s.substr(a, b - a + 1);
}

// Where a message points: "FILE line N (test ID), column C".
struct Where {
  std::string file;
  int line = 0;
  std::string id;
  std::string at(const std::string& column) const {
    std::string s = file + " line " + std::to_string(line);
    if (!id.empty()) s += " (test " + id + ")";
    if (!column.empty()) s += ", column " + column;
    return s;
  }
};

double parse_number(const std::string& text, const Where& w, const std::string& column) {
  const std::string t = trim(text);
  std::size_t used = 0;
  double v = 0.0;
  try {
    v = std::stod(t, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (t.empty() || used != t.size() || !std::isfinite(v))
    throw InputError(w.at(column) + ": \"" + text + "\" is not a number");
  return v;
}

std::string toml_number(double v) { return toml_float(v, 17); }

}  // namespace

const std::vector<ConditionColumn>& condition_columns() {
  static const std::vector<ConditionColumn> k = {
      {"mass_kg", "sample.mass_kg", 1.0, "kg"},
      {"mass_g", "sample.mass_kg", 1e-3, "g"},
      {"W_mm", "container.bottom_diameter_m", 1e-3, "mm"},
      {"d_max_mm", "sample.d_max_mm", 1.0, "mm"},
      {"d_min_mm", "sample.d_min_mm", 1.0, "mm"},
      {"lift_speed_m_s", "procedure.lift_speed_m_s", 1.0, "m/s"},
      {"plate", "plate.material", 0.0, "material name"},
  };
  return k;
}

std::vector<std::string> split_csv_line(const std::string& line, const std::string& where) {
  std::vector<std::string> out;
  std::string cur;
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        cur += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        cur += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      out.push_back(cur);
      cur.clear();
    } else if (c != '\r') {
      cur += c;
    }
  }
  if (quoted) throw InputError(where + ": unterminated quote");
  out.push_back(cur);
  return out;
}

LabData read_lab_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open the measured-data CSV");
  LabData data;
  data.file = fs::absolute(path).lexically_normal().string();
  const fs::path dir = fs::path(data.file).parent_path();
  std::vector<std::string> header;
  std::string line;
  int line_no = 0;
  std::set<std::string> ids;
  std::map<std::string, int> col;
  auto has = [&](const std::string& c) { return col.count(c) > 0; };
  while (std::getline(in, line)) {
    ++line_no;
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    if (header.empty()) {
      header = split_csv_line(t, data.file + " line " + std::to_string(line_no));
      std::set<std::string> known = {"id",     "role",         "scene",     "H_mm",
                                     "D_mm",   "angle_deg",    "photo",     "photo_camera",
                                     "mm_per_px", "camera_height_m", "repeats", "note"};
      for (const auto& c : condition_columns()) known.insert(c.column);
      for (std::size_t i = 0; i < header.size(); ++i) {
        header[i] = trim(header[i]);
        const std::string& h = header[i];
        if (col.count(h))
          throw InputError(data.file + " line " + std::to_string(line_no) + ": column " + h +
                           " appears twice");
        if (!known.count(h) && h.rfind("set:", 0) != 0)
          throw InputError(data.file + " line " + std::to_string(line_no) + ": unknown column \"" +
                           h + "\" (see docs/loop.md; any scene key goes in a set:KEY column)");
        col[h] = static_cast<int>(i);
      }
      for (const char* req : {"id", "role", "scene"})
        if (!has(req))
          throw InputError(data.file + ": the required column \"" + std::string(req) +
                           "\" is missing");
      if (!has("angle_deg") && !(has("H_mm") && has("D_mm")) && !has("photo"))
        throw InputError(data.file +
                         ": a measured value is required: column angle_deg, or H_mm and D_mm, "
                         "or photo");
      continue;
    }
    Where w{data.file, line_no, ""};
    const std::vector<std::string> f = split_csv_line(line, w.at(""));
    if (f.size() != header.size())
      throw InputError(w.at("") + ": " + std::to_string(f.size()) + " fields for " +
                       std::to_string(header.size()) + " columns");
    auto get = [&](const std::string& c) -> std::string {
      return has(c) ? trim(f[static_cast<std::size_t>(col[c])]) : std::string();
    };
    LabTest test;
    test.line = line_no;
    test.id = get("id");
    if (!is_safe_name(test.id))
      throw InputError(w.at("id") + ": \"" + test.id +
                       "\" is not a safe name ([A-Za-z0-9][A-Za-z0-9._-]*)");
    if (!ids.insert(test.id).second)
      throw InputError(w.at("id") + ": test id \"" + test.id + "\" appears twice");
    w.id = test.id;
    test.role = get("role");
    if (test.role != "calibrate" && test.role != "validate")
      throw InputError(w.at("role") + ": \"" + test.role +
                       "\" must be \"calibrate\" or \"validate\"");
    const std::string scene = get("scene");
    if (scene.empty()) throw InputError(w.at("scene") + ": empty (a base scene file is required)");
    test.scene_path = (dir / scene).lexically_normal().string();
    if (!fs::exists(test.scene_path))
      throw InputError(w.at("scene") + ": \"" + test.scene_path + "\" does not exist");
    // Conditions -> overrides.
    for (const ConditionColumn& c : condition_columns()) {
      const std::string v = get(c.column);
      if (v.empty()) continue;
      if (c.factor == 0.0) {
        test.overrides.emplace_back(c.key, "\"" + v + "\"");
      } else {
        const double x = parse_number(v, w, c.column);
        if (!(x > 0.0))
          throw InputError(w.at(c.column) + ": " + v + " must be positive");
        test.conditions[c.column] = x;
        test.overrides.emplace_back(c.key, toml_number(c.factor * x));
      }
      test.override_columns.push_back(c.column);
    }
    for (const std::string& h : header) {
      if (h.rfind("set:", 0) != 0) continue;
      const std::string v = get(h);
      if (v.empty()) continue;
      const std::string key = h.substr(4);
      const std::string value = is_toml_value(v) ? v : "\"" + v + "\"";
      test.overrides.emplace_back(key, value);
      test.override_columns.push_back(h);
      try {
        test.conditions[h] = std::stod(v);
      } catch (const std::exception&) {
      }
    }
    // Build the scene now, naming the column whose override breaks it.
    std::vector<std::string> sets;
    for (const auto& [k, v] : test.overrides) sets.push_back(k + "=" + v);
    try {
      (void)load_scene(test.scene_path, sets);
    } catch (const std::exception& e) {
      std::string culprit;
      for (std::size_t k = 1; k <= sets.size() && culprit.empty(); ++k) {
        try {
          (void)load_scene(test.scene_path, {sets.begin(), sets.begin() + k});
        } catch (const std::exception&) {
          culprit = test.override_columns[k - 1] + " (" + sets[k - 1] + ")";
        }
      }
      throw InputError(w.at(culprit.empty() ? "scene" : culprit) +
                       ": the engine cannot build this test: " + e.what());
    }
    // Measured values.
    if (!get("camera_height_m").empty()) {
      test.camera_height_m = parse_number(get("camera_height_m"), w, "camera_height_m");
      if (*test.camera_height_m < 0.0)
        throw InputError(w.at("camera_height_m") + ": must not be negative");
    }
    if (!get("repeats").empty()) {
      const double n = parse_number(get("repeats"), w, "repeats");
      if (!(n >= 1.0) || n != std::floor(n) || n > 1000)
        throw InputError(w.at("repeats") + ": " + get("repeats") + " must be a whole number >= 1");
      test.repeats = static_cast<int>(n);
    }
    if (!get("H_mm").empty()) test.height_mm = parse_number(get("H_mm"), w, "H_mm");
    if (!get("D_mm").empty()) test.diameter_mm = parse_number(get("D_mm"), w, "D_mm");
    for (const char* c : {"H_mm", "D_mm"}) {
      const auto& v = std::string(c) == "H_mm" ? test.height_mm : test.diameter_mm;
      if (v && !(*v > 0.0)) throw InputError(w.at(c) + ": " + get(c) + " must be positive");
    }
    bool have_angle = false;
    if (!get("angle_deg").empty()) {
      test.angle_deg = parse_number(get("angle_deg"), w, "angle_deg");
      have_angle = true;
    } else if (test.height_mm && test.diameter_mm) {
      test.angle_deg = std::atan(2.0 * *test.height_mm / *test.diameter_mm) * 180.0 / M_PI;
      have_angle = true;
    }
    if (!get("photo").empty()) {
      std::stringstream ss(get("photo"));
      std::string p;
      while (std::getline(ss, p, ';'))
        if (!trim(p).empty()) test.photos.push_back((dir / trim(p)).lexically_normal().string());
      std::string cam = get("photo_camera");
      if (!cam.empty()) cam = (dir / cam).lexically_normal().string();
      std::optional<double> mmpx;
      if (!get("mm_per_px").empty()) mmpx = parse_number(get("mm_per_px"), w, "mm_per_px");
      json declared = {{"angle_deg", have_angle ? json(test.angle_deg) : json()}};
      const LabPhotoMeasurement m =
          measure_lab_photos(test.photos, {cam, mmpx},
                             {w.at("photo"), w.at("photo_camera"), w.at("mm_per_px"),
                              "photo_camera", "mm_per_px"});
      test.angle_deg = m.summary.theta_deg.mean;
      test.height_mm = 1e3 * m.summary.height_m.mean;
      test.diameter_mm = 1e3 * m.summary.diameter_m.mean;
      test.photo_measurement = m.record;
      test.photo_measurement["declared_in_csv"] = declared;
      have_angle = true;
    }
    if (!have_angle)
      throw InputError(w.at("angle_deg") + ": no measured value (angle_deg, H_mm and D_mm, or photo)");
    if (!(test.angle_deg > 0.0 && test.angle_deg < 90.0))
      throw InputError(w.at(test.photos.empty() ? "angle_deg" : "photo") + ": angle " +
                       toml_number(test.angle_deg) + " deg is outside (0, 90)");
    data.tests.push_back(std::move(test));
  }
  if (header.empty()) throw InputError(data.file + ": no header line");
  if (data.tests.empty()) throw InputError(data.file + ": no test rows");
  const double d_ref = reference_grain_diameter(data.tests);
  for (LabTest& t : data.tests) t.reference_diameter_m = d_ref;
  return data;
}

json to_json(const LabTest& t) {
  json o = json::object();
  for (const auto& [k, v] : t.overrides) o[k] = v;
  json j = {{"id", t.id},          {"line", t.line},           {"role", t.role},
            {"scene", t.scene_path}, {"overrides", o},         {"conditions", t.conditions},
            {"angle_deg", t.angle_deg}};
  if (t.height_mm) j["H_mm"] = *t.height_mm;
  if (t.diameter_mm) j["D_mm"] = *t.diameter_mm;
  if (t.camera_height_m) j["camera_height_m"] = *t.camera_height_m;
  j["repeats"] = t.repeats;
  if (t.reference_diameter_m > 0.0) j["reference_diameter_m"] = t.reference_diameter_m;
  if (!t.photos.empty()) {
    j["photos"] = t.photos;
    j["photo_measurement"] = t.photo_measurement;
  }
  return j;
}

}  // namespace reposetwin::experiments
