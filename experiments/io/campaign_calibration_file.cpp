// The [calibration] table of a campaign file (see campaign_file.hpp for the format).
#include <filesystem>
#include <set>

#include "experiments/io/campaign_file_detail.hpp"
#include "experiments/io/campaign_keys.hpp"
#include "experiments/io/overrides.hpp"
#include "experiments/io/toml_edit.hpp"

namespace reposetwin::experiments::campaign_file {
namespace fs = std::filesystem;
namespace {

// calibration.key: one dotted key, or a list of distinct keys that all take the calibrated value.
void read_keys(TableReader& t, CampaignCalibration& cc) {
  const std::string& file = t.file();
  const std::string p = "calibration.";
  if (const toml::node* k = t.raw().get("key"); k && k->is_array()) {
    t.mark_used("key");
    for (const auto& e : *k->as_array()) {
      if (!e.is_string())
        throw bad(file, p + "key", value_text(*k), "must be a string or a list of strings");
      cc.keys.push_back(e.as_string()->get());
    }
    if (cc.keys.empty()) throw bad(file, p + "key", "[]", "needs at least one key");
    if (std::set<std::string>(cc.keys.begin(), cc.keys.end()).size() != cc.keys.size())
      throw bad(file, p + "key", value_text(*k), "a key is repeated");
    cc.key = cc.keys.front();
  } else {
    cc.key = t.string("key", cc.key);
    cc.keys = {cc.key};
  }
  for (const auto& k : cc.keys) split_dotted_key(k, file + ": key 'calibration.key'");
}

// The lab's side photos named as the calibration target (calibration.target_photos, a path or a
// list, relative to the campaign file) and their scale, recorded as given: calibration/
// (campaign_target.hpp) measures them while the campaign is loaded, so the file edge needs no
// vision. Every text that names a key in a message is recorded with them.
TargetPhotoFiles read_target_photos(TableReader& t) {
  const std::string& file = t.file();
  const std::string prefix = "calibration.";
  t.mark_used("target_photos");
  const toml::node* n = t.raw().get("target_photos");
  TargetPhotoFiles f;
  auto add = [&](const toml::node& e) {
    if (!e.is_string() || e.as_string()->get().empty())
      throw bad(file, prefix + "target_photos", value_text(*n),
                "must be a path or a list of paths (the lab's side photos)");
    fs::path path(e.as_string()->get());
    if (path.is_relative()) path = fs::path(file).parent_path() / path;
    f.photos.push_back(fs::absolute(path).lexically_normal().string());
  };
  if (const toml::array* a = n->as_array()) {
    for (const auto& e : *a) add(e);
  } else {
    add(*n);
  }
  if (f.photos.empty()) throw bad(file, prefix + "target_photos", "[]", "needs at least one photo");
  const std::string camera = t.string("target_photo_camera", "");
  if (!camera.empty()) {
    fs::path path(camera);
    if (path.is_relative()) path = fs::path(file).parent_path() / path;
    f.camera_json = path.lexically_normal().string();
  }
  f.mm_per_px = optional_number(t, "target_mm_per_px");
  const std::string at = file + ": key '" + prefix;
  f.photos_at = at + "target_photos'";
  f.camera_at = at + "target_photo_camera'";
  f.mm_per_px_at = at + "target_mm_per_px'";
  return f;
}

// The measured angle: target_deg typed in, or target_photos measured; target_sd_deg optional.
void read_target(TableReader& t, CampaignCalibration& cc) {
  const std::string& file = t.file();
  const std::string p = "calibration.";
  const auto target = optional_number(t, "target_deg");
  const toml::node* photos = t.raw().get("target_photos");
  if (target && photos)
    throw bad(file, p + "target_photos", value_text(*photos),
              "give either target_deg or target_photos, not both");
  if (!target && !photos)
    throw bad(file, p + "target_deg", "",
              "missing (the measured angle in degrees, or target_photos: the lab's side "
              "photos of the pile)");
  for (const char* k : {"target_photo_camera", "target_mm_per_px"})
    if (!photos && t.has(k))
      throw bad(file, p + k, value_text(*t.raw().get(k)), "only with target_photos");
  const auto sd = optional_number(t, "target_sd_deg");
  if (photos) {  // measured, and then checked, by calibration/ (campaign_target.hpp)
    cc.target_photo_files = read_target_photos(t);
    cc.target_photo_files->sd_deg = sd;
    return;
  }
  cc.target.angle_deg = *target;
  if (sd) cc.target.sd_deg = *sd;
  try {
    validate_target(cc.target);
  } catch (const std::invalid_argument& e) {
    throw bad(file, p + "target_deg", value_text(*t.raw().get("target_deg")), e.what());
  }
}

// mu_r_range, seeds, tolerance, budget and bootstrap size, each within its bounds.
void read_settings(TableReader& t, CalibrationSettings& s) {
  const std::string& file = t.file();
  const std::string p = "calibration.";
  const std::string range_text = t.has("mu_r_range") ? value_text(*t.raw().get("mu_r_range")) : "";
  if (!t.has("mu_r_range"))
    throw bad(file, p + "mu_r_range", "", "must be a list of two numbers [lo, hi]");
  const std::vector<double> range = t.numbers("mu_r_range");
  if (range.size() != 2)
    throw bad(file, p + "mu_r_range", range_text, "must be a list of two numbers [lo, hi]");
  s.mu_r_lo = range[0];
  s.mu_r_hi = range[1];
  if (!(s.mu_r_lo >= 0.0 && s.mu_r_hi > s.mu_r_lo))
    throw bad(file, p + "mu_r_range", range_text, "need 0 <= lo < hi");
  if (auto v = optional_integer(t, "seeds_per_point")) {
    if (*v < 1 || *v > 1000)
      throw bad(file, p + "seeds_per_point", std::to_string(*v), "must be 1..1000");
    s.seeds_per_point = static_cast<int>(*v);
  }
  if (auto v = optional_integer(t, "first_seed")) {
    if (*v < 0) throw bad(file, p + "first_seed", std::to_string(*v), "must be >= 0");
    s.first_seed = static_cast<std::uint64_t>(*v);
  }
  if (auto v = optional_number(t, "tolerance_deg")) {
    if (!(*v > 0.0))
      throw bad(file, p + "tolerance_deg", value_text(*t.raw().get("tolerance_deg")),
                "must be > 0");
    s.tolerance_deg = *v;
  }
  s.confirm_bracket = t.boolean("confirm", s.confirm_bracket);
  const int min_sims = (s.confirm_bracket ? 4 : 2) * s.seeds_per_point;
  if (auto v = optional_integer(t, "max_simulations")) {
    if (*v < min_sims || *v > 1000000)
      throw bad(file, p + "max_simulations", std::to_string(*v),
                "must be at least " + std::to_string(min_sims) +
                    " (seeds_per_point at both range ends" +
                    (s.confirm_bracket ? " and at the two confirmed bracket points)" : ")"));
    s.max_simulations = static_cast<int>(*v);
  } else if (s.max_simulations < min_sims) {
    throw bad(file, p + "seeds_per_point", std::to_string(s.seeds_per_point),
              "needs max_simulations >= " + std::to_string(min_sims) + " (default " +
                  std::to_string(s.max_simulations) + ")");
  }
  if (auto v = optional_integer(t, "bootstrap_replicates")) {
    if (*v < 100 || *v > 1000000)
      throw bad(file, p + "bootstrap_replicates", std::to_string(*v), "must be 100..1000000");
    s.bootstrap.replicates = static_cast<int>(*v);
  }
}

// calibration.method: "sequential" (calibration.hpp, the default) or "bracket".
CalibrationMethod read_method(TableReader& t) {
  const std::string m = t.string("method", "sequential");
  if (m == "sequential") return CalibrationMethod::kSequential;
  if (m == "bracket") return CalibrationMethod::kBracket;
  throw bad(t.file(), "calibration.method", "\"" + m + "\"",
            "must be \"sequential\" or \"bracket\"");
}

// The bracketing driver's settings: the common keys (range, seeds, budget, bootstrap) read as for
// the sequential driver, then its own; the budget defaults to three points.
void read_bracket_settings(TableReader& t, CampaignCalibration& cc) {
  const std::string& file = t.file();
  const std::string p = "calibration.";
  if (t.has("confirm"))
    throw bad(file, p + "confirm", value_text(*t.raw().get("confirm")),
              "only with method = \"sequential\" (the bracketing driver does not confirm)");
  if (t.has("tolerance_deg"))
    throw bad(file, p + "tolerance_deg", value_text(*t.raw().get("tolerance_deg")),
              "with method = \"bracket\" the tolerance is mu_r_tolerance (on mu_r)");
  CalibrationSettings& s = cc.settings;
  s.confirm_bracket = false;
  if (!t.has("seeds_per_point")) s.seeds_per_point = 2;
  read_settings(t, s);
  if (!t.has("max_simulations")) s.max_simulations = 3 * s.seeds_per_point;  // three points
  BracketSettings& b = cc.bracket;
  b.mu_r_lo = s.mu_r_lo;
  b.mu_r_hi = s.mu_r_hi;
  b.seeds.clear();
  for (int i = 0; i < s.seeds_per_point; ++i) b.seeds.push_back(s.first_seed + i);
  b.max_runs = s.max_simulations;
  b.bootstrap = s.bootstrap;
  b.mu_r_start = optional_number(t, "mu_r_start");
  b.ends_first = t.boolean("ends_first", false);
  if (b.ends_first && b.mu_r_start)
    throw bad(file, p + "mu_r_start", value_text(*t.raw().get("mu_r_start")),
              "not with ends_first = true (the first points are then the range ends)");
  if (auto v = optional_number(t, "slope_guess_deg")) b.slope_guess_deg = *v;
  if (auto v = optional_number(t, "mu_r_tolerance")) b.mu_r_tolerance = *v;
  if (auto v = optional_number(t, "max_jam_rate")) b.max_jam_rate = *v;
  try {
    validate_bracket_settings(b);
  } catch (const std::invalid_argument& e) {
    std::string key = "seeds_per_point";
    for (const char* k : {"mu_r_start", "slope_guess_deg", "mu_r_tolerance", "max_jam_rate"})
      if (std::string(e.what()).find(k) != std::string::npos) key = k;
    if (std::string(e.what()).find("max_simulations") != std::string::npos) key = "max_simulations";
    const toml::node* n = t.raw().get(key);
    throw bad(file, p + key, n ? value_text(*n) : std::string("(default)"), e.what());
  }
}

}  // namespace

CampaignCalibration read_calibration_table(TableReader& t, const Campaign& c, SceneCache& scenes) {
  t.known_keys(campaign_table_keys("calibration"));
  CampaignCalibration cc;
  read_keys(t, cc);
  cc.method = read_method(t);
  cc.table1_sample = read_table1_sample(t);
  if (t.has("angle"))
    cc.angle = parse_angle_measure(t.string("angle"), c.file + ": key 'calibration.angle'");
  read_target(t, cc);
  if (cc.method == CalibrationMethod::kBracket) {
    read_bracket_settings(t, cc);
  } else {
    for (const char* k :
         {"mu_r_start", "ends_first", "slope_guess_deg", "mu_r_tolerance", "max_jam_rate"})
      if (t.has(k))
        throw bad(t.file(), std::string("calibration.") + k, value_text(*t.raw().get(k)),
                  "only with method = \"bracket\"");
    read_settings(t, cc.settings);
  }
  // The keys must apply to the base scene.
  toml::table copy = scenes.get(c.scene_path);
  for (const auto& k : cc.keys)
    apply_override(copy, k, toml::value<double>(cc.settings.mu_r_lo),
                   c.file + ", key 'calibration.key' (scene " + c.scene_path + ")");
  return cc;
}

}  // namespace reposetwin::experiments::campaign_file
