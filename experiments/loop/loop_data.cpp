#include "experiments/loop/loop_data.hpp"

#include "experiments/io/suggest.hpp"
#include "experiments/io/numbers.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <stdexcept>
#include <sstream>

#include "experiments/campaign/campaign.hpp"
#include "experiments/io/csv.hpp"
#include "experiments/io/format.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/json_read.hpp"
#include "experiments/io/provenance.hpp"
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
  return plain_decimal(trim(text), w.at(column));
}

std::string toml_number(double v) { return toml_float(v, 17); }

}  // namespace

const char* role_name(Role role) {
  switch (role) {
    case Role::kCalibrate: return "calibrate";
    case Role::kValidate: return "validate";
  }
  throw std::logic_error("loop: no role " + std::to_string(static_cast<int>(role)));
}

std::optional<Role> parse_role(const std::string& text) {
  for (Role r : {Role::kCalibrate, Role::kValidate})
    if (text == role_name(r)) return r;
  return std::nullopt;
}

const std::vector<ConditionColumn>& condition_columns() {
  static const std::vector<ConditionColumn> k = {
      {"mass_kg", "sample.mass_kg", 1.0, "kg"},
      {"mass_g", "sample.mass_kg", 1e-3, "g"},
      {"W_mm", "container.bottom_diameter_m", 1e-3, "mm"},
      {"funnel_top_mm", "container.top_diameter_m", 1e-3, "mm"},
      {"funnel_height_mm", "container.height_m", 1e-3, "mm"},
      {"d_max_mm", "sample.d_max_mm", 1.0, "mm"},
      {"d_min_mm", "sample.d_min_mm", 1.0, "mm"},
      {"lift_speed_m_s", "procedure.lift_speed_m_s", 1.0, "m/s"},
      {"plate", "plate.material", 0.0, "material name"},
  };
  return k;
}

const std::vector<SheetColumn>& test_sheet_columns() {
  static const std::vector<SheetColumn> k = {
      {"id", "required: the test's name, [A-Za-z0-9][A-Za-z0-9._-]*, unique"},
      {"role",
       "calibrate (the test mu_r is fitted on) or validate (predicted at the calibrated mu_r); "
       "required by `loop`; for `calibrate --tests` optional: without it the first row "
       "calibrates and the others are predicted"},
      {"scene",
       "the test's base scene (TOML), relative to the sheet; required by `loop`; for "
       "`calibrate --tests` optional: empty or absent, the --scene"},
      {"angle_deg", "* the measured angle of repose atan(2H/D) [deg], in (0, 90)"},
      {"H_mm", "* the measured pile height [mm]; with D_mm the angle is atan(2H/D)"},
      {"D_mm", "* the measured pile base diameter [mm]"},
      {"photo",
       "* side photo(s) of the pile, ';'-separated, relative to the sheet; measured by vision as "
       "the twin's renders (they replace a typed angle, H and D)"},
      {"photo_camera",
       "a camera sidecar JSON for every photo of the row (else mm_per_px, a STEM.json beside "
       "each photo, or the scale marker in the image)"},
      {"mm_per_px", "the photos' scale at the pile axis [mm/px] (orthographic view assumed)"},
      {"camera_height_m", "the lab camera's height above the plate [m]"},
      {"crest_mm", "the measured crest (flat top) width [mm], >= 0"},
      {"repeats", "piles averaged into the measured values (default 1)"},
      {"note", "free text"},
  };
  return k;
}

std::string test_sheet_markdown() {
  std::string t = "| column | meaning |\n|---|---|\n";
  for (const SheetColumn& c : test_sheet_columns())
    t += "| `" + std::string(c.column) + "` | " + c.meaning + " |\n";
  for (const ConditionColumn& c : condition_columns())
    t += "| `" + std::string(c.column) + "` | a condition [" + c.unit + "]: sets the scene's `" +
         c.key + "` |\n";
  t += "| `set:KEY` | any other scene key, e.g. `set:contacts.rock-rock.restitution`; the value "
       "is TOML or a bare word |\n";
  return t +
         "\n\\* every row needs a measured value: `angle_deg`, or `H_mm` and `D_mm`, or "
         "`photo`.\n";
}

namespace {

// The measured-data CSV's columns: the header as written (trimmed) and each name's position.
struct Columns {
  std::vector<std::string> header;
  std::map<std::string, int> index;
  bool has(const std::string& c) const { return index.count(c) > 0; }
};

// One data row: its fields by column name (trimmed; empty when the column is absent).
struct Row {
  const Columns& cols;
  const std::vector<std::string>& fields;
  std::string get(const std::string& c) const {
    const auto it = cols.index.find(c);
    return it == cols.index.end() ? std::string()
                                  : trim(fields[static_cast<std::size_t>(it->second)]);
  }
};

// Phase 1: the header names only known columns, each once, and the required ones.
Columns read_header(const CsvTable& csv, const std::string& file, const LabSheetForm& form) {
  const std::string at = file + " line " + std::to_string(csv.header_line);
  std::set<std::string> known;
  for (const SheetColumn& c : test_sheet_columns()) known.insert(c.column);
  for (const auto& c : condition_columns()) known.insert(c.column);
  Columns cols;
  for (std::size_t i = 0; i < csv.header.size(); ++i) {
    const std::string h = trim(csv.header[i]);
    if (cols.has(h)) throw InputError(at + ": column " + h + " appears twice");
    if (!known.count(h) && h.rfind("set:", 0) != 0)
      throw InputError(at + ": unknown column \"" + h + "\"" + did_you_mean(h, known, "\"") +
                       " (see docs/calibration.md or docs/loop.md; any scene key goes in a "
                       "set:KEY column)");
    cols.header.push_back(h);
    cols.index[h] = static_cast<int>(i);
  }
  // Two columns that set one scene key (mass_kg and mass_g, or a set:KEY beside the named
  // column for KEY) would leave one silently winning on every row.
  std::map<std::string, std::string> setter;  // scene key -> the column that sets it
  for (const std::string& h : cols.header) {
    std::string key = h.rfind("set:", 0) == 0 ? h.substr(4) : std::string();
    for (const auto& c : condition_columns())
      if (h == c.column) key = c.key;
    if (key.empty()) continue;
    const auto [first, fresh] = setter.emplace(key, h);
    if (!fresh)
      throw InputError(at + ": columns " + first->second + " and " + h +
                       " both set the scene key " + key + "; keep one of them");
  }
  std::string header_text;
  for (const std::string& h : cols.header) header_text += (header_text.empty() ? "" : ",") + h;
  std::vector<std::string> required = {"id"};
  if (form.role_required) required.push_back("role");
  if (form.base_scene.empty()) required.push_back("scene");
  for (const std::string& req : required)
    if (!cols.has(req))
      throw InputError(at + ": the required column \"" + req + "\" is missing (header \"" +
                       header_text + "\")");
  if (!cols.has("angle_deg") && !(cols.has("H_mm") && cols.has("D_mm")) && !cols.has("photo"))
    throw InputError(at + ": a measured value is required: column angle_deg, or H_mm and D_mm, "
                          "or photo (header \"" + header_text + "\")");
  return cols;
}

// Phase 2: the test's id (safe, unique), role and base scene.
void read_identity(LabTest& test, const Row& row, Where& w, const fs::path& dir,
                   std::set<std::string>& ids, const LabSheetForm& form, bool first_row) {
  test.id = row.get("id");
  if (!is_safe_name(test.id))
    throw InputError(w.at("id") + ": \"" + test.id +
                     "\" is not a safe name ([A-Za-z0-9][A-Za-z0-9._-]*)");
  if (!ids.insert(test.id).second)
    throw InputError(w.at("id") + ": test id \"" + test.id + "\" appears twice");
  w.id = test.id;
  const std::string role = row.get("role");
  if (!form.role_required && !row.cols.has("role")) {
    test.role = first_row ? Role::kCalibrate : Role::kValidate;
  } else {
  const std::optional<Role> parsed = parse_role(role);
  if (!parsed)
    throw InputError(w.at("role") + ": \"" + role + "\" must be \"calibrate\" or \"validate\"");
  test.role = *parsed;
  }
  const std::string scene = row.get("scene");
  if (scene.empty() && form.base_scene.empty())
    throw InputError(w.at("scene") + ": empty (a base scene file is required)");
  test.scene_path =
      scene.empty() ? form.base_scene : (dir / scene).lexically_normal().string();
  std::error_code ec;
  if (!fs::exists(test.scene_path, ec))
    throw InputError(w.at("scene") + ": \"" + test.scene_path + "\" does not exist");
  if (!fs::is_regular_file(test.scene_path, ec))
    throw InputError(w.at("scene") + ": \"" + test.scene_path +
                     "\" is not a scene file (a folder, a pipe or a device)");
}

// Phase 3: conditions and set:KEY columns become overrides of the scene, which must build (the
// message names the column whose override breaks it).
void read_overrides(LabTest& test, const Row& row, const Where& w, const LabSheetForm& form) {
  for (const ConditionColumn& c : condition_columns()) {
    const std::string v = row.get(c.column);
    if (v.empty()) continue;
    if (c.factor == 0.0) {
      test.overrides.emplace_back(c.key, "\"" + v + "\"");
      test.text_conditions[c.column] = v;
    } else {
      const double x = parse_number(v, w, c.column);
      if (!(x > 0.0)) throw InputError(w.at(c.column) + ": " + v + " must be positive");
      test.conditions[c.column] = x;
      test.overrides.emplace_back(c.key, toml_number(c.factor * x));
    }
    test.override_columns.push_back(c.column);
  }
  for (const std::string& h : row.cols.header) {
    if (h.rfind("set:", 0) != 0) continue;
    const std::string v = row.get(h);
    if (v.empty()) continue;
    test.overrides.emplace_back(h.substr(4), typed_override(h.substr(4), v, w.at(h)).value);
    test.override_columns.push_back(h);
    // A number is plotted on an axis; anything else (a file name, a model keyword) as a
    // category.
    if (const std::optional<double> number = parse_plain_decimal(v)) {
      test.conditions[h] = *number;
    } else {
      test.text_conditions[h] =
          v.size() >= 2 && v.front() == '"' && v.back() == '"' ? v.substr(1, v.size() - 2) : v;
    }
  }
  std::vector<std::string> sets;
  for (const auto& [k, v] : form.common) sets.push_back(k + "=" + v);
  const std::size_t own = sets.size();
  for (const auto& [k, v] : test.overrides) sets.push_back(k + "=" + v);
  try {
    (void)load_scene(test.scene_path, sets);
  } catch (const std::exception& e) {
    // The first of the row's own overrides that breaks the scene; the scene itself (with the
    // sheet's common overrides) when it is broken without any of them.
    std::string culprit;
    try {
      (void)load_scene(test.scene_path, {sets.begin(), sets.begin() + own});
    } catch (const std::exception& common) {
      // The command's own overrides (its sieve sheet) that break a scene that builds without
      // them are named as the command gave them, never as the row's scene column.
      bool base_builds = own > 0;
      if (base_builds) {
        try {
          (void)load_scene(test.scene_path);
        } catch (const std::exception&) {
          base_builds = false;
        }
      }
      if (base_builds)
        throw InputError((form.common_origin.empty() ? std::string("the command line")
                                                     : form.common_origin) +
                         ": " + common.what());
      culprit = "scene";
    }
    for (std::size_t k = own + 1; k <= sets.size() && culprit.empty(); ++k) {
      try {
        (void)load_scene(test.scene_path, {sets.begin(), sets.begin() + k});
      } catch (const std::exception&) {
        culprit = test.override_columns[k - 1 - own] + " (" + sets[k - 1] + ")";
      }
    }
    throw InputError(w.at(culprit.empty() ? "scene" : culprit) +
                     ": the engine cannot build this test: " + e.what());
  }
}

// Phase 4a: the declared camera height, the repeats and the measured H, D and angle.
bool read_measured(LabTest& test, const Row& row, const Where& w) {
  if (!row.get("camera_height_m").empty()) {
    test.camera_height_m = parse_number(row.get("camera_height_m"), w, "camera_height_m");
    if (*test.camera_height_m < 0.0)
      throw InputError(w.at("camera_height_m") + ": must not be negative");
  }
  if (!row.get("repeats").empty()) {
    const double n = parse_number(row.get("repeats"), w, "repeats");
    if (!(n >= 1.0) || n != std::floor(n) || n > 1000)
      throw InputError(w.at("repeats") + ": " + row.get("repeats") +
                       " must be a whole number >= 1");
    test.repeats = static_cast<int>(n);
  }
  if (!row.get("H_mm").empty()) test.height_mm = parse_number(row.get("H_mm"), w, "H_mm");
  if (!row.get("D_mm").empty()) test.diameter_mm = parse_number(row.get("D_mm"), w, "D_mm");
  for (const char* c : {"H_mm", "D_mm"}) {
    const auto& v = std::string(c) == "H_mm" ? test.height_mm : test.diameter_mm;
    if (v && !(*v > 0.0)) throw InputError(w.at(c) + ": " + row.get(c) + " must be positive");
  }
  // The crest width is optional; a sharp cone's is 0.
  if (!row.get("crest_mm").empty()) {
    test.crest_mm = parse_number(row.get("crest_mm"), w, "crest_mm");
    if (*test.crest_mm < 0.0)
      throw InputError(w.at("crest_mm") + ": " + row.get("crest_mm") + " must not be negative");
    test.crest_source = "typed";
  }
  if (!row.get("angle_deg").empty()) {
    test.angle_deg = parse_number(row.get("angle_deg"), w, "angle_deg");
    return true;
  }
  if (test.height_mm && test.diameter_mm) {
    test.angle_deg = std::atan(2.0 * *test.height_mm / *test.diameter_mm) * 180.0 / M_PI;
    return true;
  }
  return false;
}

// Phase 4b: the photos, measured by vision; their measurement replaces the typed-in values.
void read_photos(LabTest& test, const Row& row, const Where& w, const fs::path& dir,
                 bool have_angle) {
  std::stringstream ss(row.get("photo"));
  std::string p;
  while (std::getline(ss, p, ';'))
    if (!trim(p).empty()) test.photos.push_back((dir / trim(p)).lexically_normal().string());
  std::error_code ec;
  for (const std::string& photo : test.photos)
    if (!fs::is_regular_file(photo, ec))
      throw InputError(w.at("photo") + ": \"" + photo + "\" does not exist (a photo path is "
                       "relative to the sheet's folder)");
  std::string cam = row.get("photo_camera");
  if (!cam.empty()) cam = (dir / cam).lexically_normal().string();
  std::optional<double> mmpx;
  if (!row.get("mm_per_px").empty()) mmpx = parse_number(row.get("mm_per_px"), w, "mm_per_px");
  json declared = {{"angle_deg", have_angle ? json(test.angle_deg) : json()}};
  test.photo_scale = {cam, mmpx};
  const LabPhotoMeasurement m = measure_lab_photos(
      test.photos, test.photo_scale,
      {w.at("photo"), w.at("photo_camera"), w.at("mm_per_px"), "photo_camera", "mm_per_px"});
  test.angle_deg = m.summary.theta_deg.mean;
  test.height_mm = 1e3 * m.summary.height_m.mean;
  test.diameter_mm = 1e3 * m.summary.diameter_m.mean;
  if (!test.crest_mm) {
    test.crest_mm = 1e3 * m.summary.crest_width_m.mean;
    test.crest_sigma_mm = 1e3 * m.summary.crest_width_m.sigma_mean;
    test.crest_source = "photo";
  }
  test.photo_measurement = m.record;
  test.photo_measurement["declared_in_csv"] = declared;
  // One camera photographing several piles is one view of each twin pile, not several.
  std::set<std::string> seen;
  for (const camera::Camera& c : m.cameras)
    if (seen.insert(camera::to_json(c).dump()).second) test.cameras.push_back(c);
}

// One data row as a test: the phases above, then the angle's range.
LabTest read_row(const CsvRecord& rec, const Columns& cols, const std::string& file,
                 const fs::path& dir, std::set<std::string>& ids, const LabSheetForm& form) {
  Where w{file, rec.line, ""};
  if (rec.fields.size() != cols.header.size())
    throw InputError(w.at("") + ": " + std::to_string(rec.fields.size()) + " fields for " +
                     std::to_string(cols.header.size()) + " columns");
  const Row row{cols, rec.fields};
  LabTest test;
  test.line = rec.line;
  read_identity(test, row, w, dir, ids, form, ids.empty());
  read_overrides(test, row, w, form);
  bool have_angle = read_measured(test, row, w);
  if (!row.get("photo").empty()) {
    read_photos(test, row, w, dir, have_angle);
    have_angle = true;
  }
  if (!have_angle && test.height_mm.has_value() != test.diameter_mm.has_value()) {
    const bool has_h = test.height_mm.has_value();
    throw InputError(w.at(has_h ? "D_mm" : "H_mm") + ": empty, while " +
                     (has_h ? "H_mm = " + row.get("H_mm") : "D_mm = " + row.get("D_mm")) +
                     " is given: the angle atan(2H/D) needs both (or type angle_deg)");
  }
  if (!have_angle)
    throw InputError(w.at("angle_deg") +
                     ": no measured value (angle_deg, H_mm and D_mm, or photo)");
  if (!(test.angle_deg > 0.0 && test.angle_deg < 90.0)) {
    // The angle's source: the photos, the typed angle, or the typed H and D it came from.
    if (test.photos.empty() && row.get("angle_deg").empty())
      throw InputError(w.at("H_mm") + " and D_mm: H " + row.get("H_mm") + " mm and D " +
                       row.get("D_mm") + " mm give an angle atan(2H/D) of " +
                       toml_number(test.angle_deg) + " deg, outside (0, 90)");
    throw InputError(w.at(test.photos.empty() ? "angle_deg" : "photo") + ": angle " +
                     toml_number(test.angle_deg) + " deg is outside (0, 90)");
  }
  return test;
}

}  // namespace

LabData read_lab_csv(const std::string& path, const LabSheetForm& form) {
  // Read only a regular file: opening a pipe would wait for a writer that never comes.
  std::string text;
  try {
    text = read_file(path);
  } catch (const std::exception& e) {
    throw InputError(std::string(e.what()) + " (the measured-data CSV)");
  }
  LabData data;
  data.file = fs::absolute(path).lexically_normal().string();
  const fs::path dir = fs::path(data.file).parent_path();
  const CsvTable csv = parse_csv(text, data.file);
  if (csv.header.empty()) throw InputError(data.file + ": no header line");
  const Columns cols = read_header(csv, data.file, form);
  std::set<std::string> ids;
  for (const CsvRecord& rec : csv.rows)
    data.tests.push_back(read_row(rec, cols, data.file, dir, ids, form));
  if (data.tests.empty()) throw InputError(data.file + ": no test rows");
  const double d_ref = reference_grain_diameter(data.tests);
  for (LabTest& t : data.tests) t.reference_diameter_m = d_ref;
  return data;
}

json to_json(const LabTest& t) {
  json o = json::object();
  for (const auto& [k, v] : t.overrides) o[k] = v;
  json j = {{"id", t.id},          {"line", t.line},           {"role", role_name(t.role)},
            {"scene", t.scene_path}, {"overrides", o},         {"conditions", t.conditions},
            {"angle_deg", t.angle_deg}};
  if (!t.text_conditions.empty()) j["text_conditions"] = t.text_conditions;
  if (t.height_mm) j["H_mm"] = *t.height_mm;
  if (t.diameter_mm) j["D_mm"] = *t.diameter_mm;
  if (t.crest_mm) {
    j["crest_mm"] = *t.crest_mm;
    j["crest_source"] = t.crest_source;
  }
  if (t.crest_sigma_mm) j["crest_sigma_mm"] = *t.crest_sigma_mm;
  if (t.camera_height_m) j["camera_height_m"] = *t.camera_height_m;
  j["repeats"] = t.repeats;
  if (t.reference_diameter_m > 0.0) j["reference_diameter_m"] = t.reference_diameter_m;
  if (!t.photos.empty()) {
    j["photos"] = t.photos;
    j["photo_measurement"] = t.photo_measurement;
  }
  if (!t.cameras.empty()) {
    j["cameras"] = json::array();
    for (const camera::Camera& c : t.cameras) j["cameras"].push_back(camera::to_json(c));
  }
  return j;
}

Role role_from_json(const json& j) {
  const std::string text = j.get<std::string>();
  if (const std::optional<Role> r = parse_role(text)) return *r;
  throw JsonFieldError("", "\"" + text + "\" is not calibrate or validate");
}

namespace {

// The optional measured values and the photos of a test, as to_json writes them.
void read_lab_measurements(const json& j, LabTest& t) {
  auto optional_number = [&j](const char* key) -> std::optional<double> {
    if (!j.contains(key)) return std::nullopt;
    return number_field(j, key);
  };
  t.height_mm = optional_number("H_mm");
  t.diameter_mm = optional_number("D_mm");
  if (j.contains("crest_mm")) {
    t.crest_mm = number_field(j, "crest_mm");
    t.crest_source = field<std::string>(j, "crest_source");
  }
  t.crest_sigma_mm = optional_number("crest_sigma_mm");
  t.camera_height_m = optional_number("camera_height_m");
  t.reference_diameter_m = optional_number("reference_diameter_m").value_or(0.0);
  if (j.contains("photos")) {
    t.photos = field<std::vector<std::string>>(j, "photos");
    t.photo_measurement = field<json>(j, "photo_measurement");
  }
  if (j.contains("cameras"))
    t.cameras = each(j, "cameras", [](const json& c) { return camera::from_json(c); });
}

}  // namespace

LabTest lab_test_from_json(const json& j) {
  LabTest t;
  t.id = field<std::string>(j, "id");
  t.line = field<int>(j, "line");
  t.role = nested(j, "role", role_from_json);
  t.scene_path = field<std::string>(j, "scene");
  for (const auto& [key, value] : field<std::map<std::string, std::string>>(j, "overrides"))
    t.overrides.emplace_back(key, value);
  t.conditions = field<std::map<std::string, double>>(j, "conditions");
  if (j.contains("text_conditions"))
    t.text_conditions = field<std::map<std::string, std::string>>(j, "text_conditions");
  t.angle_deg = number_field(j, "angle_deg");
  t.repeats = field<int>(j, "repeats");
  read_lab_measurements(j, t);
  return t;
}

}  // namespace reposetwin::experiments
