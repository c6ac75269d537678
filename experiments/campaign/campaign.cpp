#include "experiments/campaign/campaign.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cctype>
#include <charconv>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <iostream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "experiments/io/hash.hpp"
#include "experiments/io/overrides.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/photos/lab_photos.hpp"
#include "sim/contact.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
namespace {

// ---------------------------------------------------------------------------------------------
// Parsing helpers. Every error names the campaign file, the key and the value.

std::invalid_argument bad(const std::string& file, const std::string& key, const std::string& value,
                          const std::string& why) {
  return std::invalid_argument(file + ": key '" + key + "'" +
                               (value.empty() ? std::string() : " = " + value) + ": " + why);
}

std::string value_text(const toml::node& n) { return toml_value_text(n); }

void check_keys(const toml::table& t, const std::set<std::string>& allowed, const std::string& file,
                const std::string& prefix) {
  for (const auto& [k, v] : t) {
    if (!allowed.count(std::string(k.str()))) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      throw bad(file, prefix + std::string(k.str()), value_text(v),
                "unknown key (allowed: " + list + ")");
    }
  }
}

std::string get_string(const toml::table& t, const std::string& key, const std::string& file,
                       const std::string& prefix, bool required, const std::string& fallback = {}) {
  const toml::node* n = t.get(key);
  if (n == nullptr) {
    if (required) throw bad(file, prefix + key, "", "missing (a string is required)");
    return fallback;
  }
  if (!n->is_string()) throw bad(file, prefix + key, value_text(*n), "must be a string");
  return n->as_string()->get();
}

std::optional<double> get_number(const toml::table& t, const std::string& key,
                                 const std::string& file, const std::string& prefix) {
  const toml::node* n = t.get(key);
  if (n == nullptr) return std::nullopt;
  if (n->is_integer()) return static_cast<double>(n->as_integer()->get());
  if (n->is_floating_point()) return n->as_floating_point()->get();
  throw bad(file, prefix + key, value_text(*n), "must be a number");
}

std::optional<std::int64_t> get_int(const toml::table& t, const std::string& key,
                                    const std::string& file, const std::string& prefix) {
  const toml::node* n = t.get(key);
  if (n == nullptr) return std::nullopt;
  if (!n->is_integer()) throw bad(file, prefix + key, value_text(*n), "must be an integer");
  return n->as_integer()->get();
}

std::string resolve_scene(const std::string& file, const std::string& key,
                          const std::string& scene) {
  if (scene.empty()) throw bad(file, key, "\"\"", "empty scene path");
  fs::path p(scene);
  if (p.is_relative()) p = fs::path(file).parent_path() / p;
  p = p.lexically_normal();
  std::error_code ec;
  if (!fs::is_regular_file(p, ec))
    throw bad(file, key, "\"" + scene + "\"",
              "scene file not found (looked for " + p.string() + ")");
  return fs::absolute(p).lexically_normal().string();
}

// The calibration target measured on the lab's side photos (calibration.target_photos, a path or
// a list, relative to the campaign file) with vision/, as the renders are measured: the mean
// atan(2H/D) when the simulated angle is an atan(2H/D) (image, particles), the mean flank angle
// when it is a protractor-like angle (image_flank, slice), so both sides are read alike. The
// target's sd is the measurement's uncertainty of the mean (spread over the photos and their own
// errors); target_sd_deg, when given, replaces it. `record` receives the measurement.
Target target_from_photos(const toml::table& t, AngleMeasure angle, const std::string& file,
                          const std::string& prefix, nlohmann::json* record) {
  const toml::node* n = t.get("target_photos");
  std::vector<std::string> photos;
  auto add = [&](const toml::node& e) {
    if (!e.is_string() || e.as_string()->get().empty())
      throw bad(file, prefix + "target_photos", value_text(*n),
                "must be a path or a list of paths (the lab's side photos)");
    fs::path path(e.as_string()->get());
    if (path.is_relative()) path = fs::path(file).parent_path() / path;
    photos.push_back(fs::absolute(path).lexically_normal().string());
  };
  if (const toml::array* a = n->as_array()) {
    for (const auto& e : *a) add(e);
  } else {
    add(*n);
  }
  if (photos.empty())
    throw bad(file, prefix + "target_photos", "[]", "needs at least one photo");
  LabPhotoScale scale;
  std::string camera = get_string(t, "target_photo_camera", file, prefix, false);
  if (!camera.empty()) {
    fs::path path(camera);
    if (path.is_relative()) path = fs::path(file).parent_path() / path;
    scale.camera_json = path.lexically_normal().string();
  }
  scale.mm_per_px = get_number(t, "target_mm_per_px", file, prefix);
  const std::string at = file + ": key '" + prefix;
  const LabPhotoMeasurement m = measure_lab_photos(
      photos, scale,
      {at + "target_photos'", at + "target_photo_camera'", at + "target_mm_per_px'",
       prefix + "target_photo_camera", prefix + "target_mm_per_px"});
  const bool flank = angle == AngleMeasure::kImageFlank || angle == AngleMeasure::kSlice;
  const vision::Spread& s = flank ? m.summary.flank_deg : m.summary.theta_deg;
  *record = m.record;
  (*record)["photos"] = photos;
  (*record)["target_from"] = flank ? "flank_deg (mean flank angle over the photos)"
                                   : "theta_deg (atan(2H/D), mean over the photos)";
  return Target{s.mean, s.sigma_mean};
}

// Flattens an overrides table into dotted keys: { "a.b" = 1 } and { a.b = 1 } (a nested table in
// TOML) both give "a.b" = 1. Arrays are leaves.
void flatten(const toml::table& t, const std::string& prefix, toml::table& out) {
  for (const auto& [k, v] : t) {
    const std::string key =
        prefix.empty() ? std::string(k.str()) : prefix + "." + std::string(k.str());
    if (const auto* sub = v.as_table()) {
      flatten(*sub, key, out);
    } else {
      v.visit([&](const auto& x) { out.insert_or_assign(key, x); });
    }
  }
}

toml::table get_overrides(const toml::table& t, const std::string& file,
                          const std::string& prefix) {
  toml::table out;
  const toml::node* n = t.get("overrides");
  if (n == nullptr) return out;
  if (!n->is_table())
    throw bad(
        file, prefix + "overrides", value_text(*n),
        "must be a table of dotted keys, e.g. { \"contacts.rock-rock.rolling_friction\" = 0.1 }");
  flatten(*n->as_table(), "", out);
  for (const auto& [k, v] : out)
    split_dotted_key(k.str(), file + ": key '" + prefix + "overrides'");
  return out;
}

// Seeds: a list of distinct non-negative integers, or a count n meaning 1..n.
std::vector<std::uint64_t> parse_seeds(const toml::node& s, const std::string& file,
                                       const std::string& key) {
  std::vector<std::uint64_t> seeds;
  if (s.is_integer()) {
    const auto n = s.as_integer()->get();
    if (n < 1 || n > 100000) throw bad(file, key, value_text(s), "a count must be 1..100000");
    for (std::int64_t i = 1; i <= n; ++i) seeds.push_back(static_cast<std::uint64_t>(i));
  } else if (const auto* a = s.as_array()) {
    std::set<std::int64_t> seen;
    for (const auto& e : *a) {
      if (!e.is_integer() || e.as_integer()->get() < 0)
        throw bad(file, key, value_text(s), "every seed must be an integer >= 0");
      if (!seen.insert(e.as_integer()->get()).second)
        throw bad(file, key, value_text(s), "seed " + value_text(e) + " is repeated");
      seeds.push_back(static_cast<std::uint64_t>(e.as_integer()->get()));
    }
    if (seeds.empty()) throw bad(file, key, "[]", "needs at least one seed");
  } else {
    throw bad(file, key, value_text(s), "must be a list of integers or a count");
  }
  return seeds;
}

// An optional Table 1 sample number (1..4, the paper's samples).
std::optional<int> get_sample(const toml::table& t, const std::string& file,
                              const std::string& prefix) {
  const toml::node* n = t.get("table1_sample");
  if (n == nullptr) return std::nullopt;
  if (!n->is_integer() || n->as_integer()->get() < 1 || n->as_integer()->get() > 4)
    throw bad(file, prefix + "table1_sample", value_text(*n),
              "must be the paper's Table 1 sample number, an integer 1..4");
  return static_cast<int>(n->as_integer()->get());
}

// Text of a sweep value for a case name: shortest round-trip form for floats.
std::string name_text(const toml::node& v) {
  if (v.is_floating_point()) {
    char buf[64];
    auto r = std::to_chars(buf, buf + sizeof buf, v.as_floating_point()->get());
    return std::string(buf, r.ptr);
  }
  if (v.is_integer()) return std::to_string(v.as_integer()->get());
  if (v.is_string()) return v.as_string()->get();
  if (v.is_boolean()) return v.as_boolean()->get() ? "true" : "false";
  return value_text(v);
}

std::string sanitize(const std::string& s) {
  std::string out;
  for (char c : s)
    out.push_back(
        std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-' ? c : '_');
  return out;
}

nlohmann::json toml_to_json(const toml::node& n) {
  if (const auto* t = n.as_table()) {
    nlohmann::json j = nlohmann::json::object();
    for (const auto& [k, v] : *t) j[std::string(k.str())] = toml_to_json(v);
    return j;
  }
  if (const auto* a = n.as_array()) {
    nlohmann::json j = nlohmann::json::array();
    for (const auto& v : *a) j.push_back(toml_to_json(v));
    return j;
  }
  if (n.is_integer()) return n.as_integer()->get();
  if (n.is_floating_point()) return n.as_floating_point()->get();
  if (n.is_boolean()) return n.as_boolean()->get();
  if (n.is_string()) return n.as_string()->get();
  return value_text(n);  // dates and times
}

toml::table parse_toml_file(const std::string& path) {
  const std::string text = read_file(path);
  try {
    return toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    std::ostringstream os;
    os << path << ":" << e.source().begin.line << ":" << e.source().begin.column << ": "
       << e.description();
    throw std::invalid_argument(os.str());
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Campaign file.

namespace {
struct AngleMeasureInfo {
  AngleMeasure measure;
  const char* name;
  const char* method;
};
constexpr AngleMeasureInfo kAngleMeasures[] = {
    {AngleMeasure::kImage, "image",
     "vision on renders: atan(2H/D) per side view, perspective corrected (as the lab photo)"},
    {AngleMeasure::kImageFlank, "image_flank",
     "vision on renders: flank lines fitted to the silhouette per side view, mean of both flanks"},
    {AngleMeasure::kParticles, "particles", "particle positions: atan(2H/D)"},
    {AngleMeasure::kSlice, "slice",
     "particle positions: protractor on slices through the pile centre (EDEM's method)"},
};
}  // namespace

std::string angle_measure_name(AngleMeasure m) {
  for (const auto& a : kAngleMeasures)
    if (a.measure == m) return a.name;
  return "unknown";
}

std::string angle_measure_method(AngleMeasure m) {
  for (const auto& a : kAngleMeasures)
    if (a.measure == m) return a.method;
  return "unknown";
}

AngleMeasure parse_angle_measure(const std::string& name, const std::string& where) {
  std::string list;
  for (const auto& a : kAngleMeasures) {
    if (name == a.name) return a.measure;
    list += (list.empty() ? "" : ", ") + std::string(a.name);
  }
  throw std::invalid_argument(where + " = \"" + name + "\": unknown angle (one of " + list + ")");
}

std::string CaseSpec::relative_dir() const {
  return "cases/" + case_name + "/seed_" + std::to_string(seed);
}

std::string CaseSpec::id() const { return case_name + "/seed_" + std::to_string(seed); }

bool is_safe_name(std::string_view name) {
  if (name.empty() || name.size() > 100) return false;
  if (!std::isalnum(static_cast<unsigned char>(name[0]))) return false;
  for (char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-'))
      return false;
  return true;
}

Campaign load_campaign(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw std::runtime_error(path + ": campaign file not found");
  return parse_campaign(read_file(path), path);
}

Campaign parse_campaign(std::string_view text, const std::string& path) {
  const std::string file = fs::absolute(fs::path(path)).lexically_normal().string();
  toml::table root;
  try {
    root = toml::parse(text, file);
  } catch (const toml::parse_error& e) {
    std::ostringstream os;
    os << file << ":" << e.source().begin.line << ":" << e.source().begin.column << ": "
       << e.description();
    throw std::invalid_argument(os.str());
  }
  check_keys(root,
             {"name", "description", "paper", "scene", "seeds", "overrides", "case", "sweep",
              "calibration", "predict"},
             file, "");

  Campaign c;
  c.file = file;
  c.name = get_string(root, "name", file, "", true);
  if (!is_safe_name(c.name))
    throw bad(file, "name", "\"" + c.name + "\"",
              "not filesystem-safe (use letters, digits, '.', '_', '-'; start with a letter or "
              "digit; at most 100 characters)");
  c.description = get_string(root, "description", file, "", false);
  c.paper = get_string(root, "paper", file, "", false);
  c.scene_path = resolve_scene(file, "scene", get_string(root, "scene", file, "", true));

  if (const toml::node* s = root.get("seeds")) c.seeds = parse_seeds(*s, file, "seeds");

  const toml::table common = get_overrides(root, file, "");
  c.overrides = common;

  // The cases: [[case]] or [sweep].
  struct CaseDef {
    std::string name, scene, key_prefix;
    toml::table overrides;
  };
  std::vector<CaseDef> cases;
  const toml::node* case_node = root.get("case");
  const toml::node* sweep_node = root.get("sweep");
  if (case_node && sweep_node)
    throw bad(file, "sweep", "", "a campaign has either [[case]] tables or one [sweep], not both");
  if (case_node) {
    const auto* arr = case_node->as_array();
    if (arr == nullptr || !arr->is_array_of_tables() || arr->empty())
      throw bad(file, "case", value_text(*case_node), "must be one or more [[case]] tables");
    std::size_t i = 0;
    for (const auto& e : *arr) {
      const auto& t = *e.as_table();
      const std::string prefix = "case[" + std::to_string(i++) + "].";
      check_keys(t, {"name", "scene", "overrides", "description"}, file, prefix);
      CaseDef d;
      d.key_prefix = prefix;
      d.name = get_string(t, "name", file, prefix, true);
      if (!is_safe_name(d.name))
        throw bad(file, prefix + "name", "\"" + d.name + "\"",
                  "not filesystem-safe (use letters, digits, '.', '_', '-'; start with a letter or "
                  "digit; at most 100 characters)");
      get_string(t, "description", file, prefix, false);
      d.scene = t.get("scene") ? resolve_scene(file, prefix + "scene",
                                               get_string(t, "scene", file, prefix, true))
                               : c.scene_path;
      d.overrides = common;
      const toml::table own = get_overrides(t, file, prefix);
      for (const auto& [k, v] : own)
        v.visit([&](const auto& x) { d.overrides.insert_or_assign(k, x); });
      cases.push_back(std::move(d));
    }
  } else if (sweep_node) {
    const auto* t = sweep_node->as_table();
    if (t == nullptr) throw bad(file, "sweep", value_text(*sweep_node), "must be a table");
    check_keys(*t, {"key", "values", "name"}, file, "sweep.");
    const std::string key = get_string(*t, "key", file, "sweep.", true);
    const auto parts = split_dotted_key(key, file + ": key 'sweep.key'");
    const std::string prefix = get_string(*t, "name", file, "sweep.", false, parts.back());
    const toml::node* values = t->get("values");
    if (values == nullptr) throw bad(file, "sweep.values", "", "missing (a list is required)");
    const auto* va = values->as_array();
    if (va == nullptr || va->empty())
      throw bad(file, "sweep.values", value_text(*values), "must be a non-empty list");
    for (const auto& v : *va) {
      CaseDef d;
      d.key_prefix = "sweep.values";
      d.name = sanitize(prefix + "_" + name_text(v));
      if (!is_safe_name(d.name))
        throw bad(file, "sweep.values", value_text(v),
                  "gives case name \"" + d.name + "\", which is not filesystem-safe");
      d.scene = c.scene_path;
      d.overrides = common;
      v.visit([&](const auto& x) { d.overrides.insert_or_assign(key, x); });
      cases.push_back(std::move(d));
    }
  }

  // Unique names (case-insensitively, for case-insensitive file systems).
  std::map<std::string, std::string> seen_names;
  for (const auto& d : cases) {
    std::string lower;
    for (char ch : d.name)
      lower.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(ch))));
    if (!seen_names.emplace(lower, d.name).second)
      throw bad(file, d.key_prefix == "sweep.values" ? "sweep.values" : d.key_prefix + "name",
                "\"" + d.name + "\"", "case name is not unique");
  }
  if (!cases.empty() && c.seeds.empty())
    throw bad(file, "seeds", "", "missing (cases run once per seed: give a list or a count)");

  // Every override must apply to its scene now, not hours into the campaign.
  std::map<std::string, toml::table> scenes;
  auto scene_of = [&](const std::string& p) -> const toml::table& {
    auto it = scenes.find(p);
    if (it == scenes.end()) it = scenes.emplace(p, parse_toml_file(p)).first;
    return it->second;
  };
  std::map<std::string, std::string> hashes;
  for (const auto& d : cases) {
    toml::table copy = scene_of(d.scene);
    apply_overrides(copy, d.overrides, file + ", case " + d.name + " (scene " + d.scene + ")");
    if (!hashes.count(d.scene)) hashes[d.scene] = fnv1a_hex(read_file(d.scene));
  }

  std::size_t index = 0;
  for (const auto& d : cases) {
    for (auto seed : c.seeds) {
      CaseSpec s;
      s.index = index++;
      s.case_name = d.name;
      s.seed = seed;
      s.scene_path = d.scene;
      s.scene_hash = hashes[d.scene];
      s.overrides = d.overrides;
      c.runs.push_back(std::move(s));
    }
  }

  if (const toml::node* cal = root.get("calibration")) {
    const auto* t = cal->as_table();
    if (t == nullptr) throw bad(file, "calibration", value_text(*cal), "must be a table");
    const std::string p = "calibration.";
    check_keys(
        *t,
        {"key", "target_deg", "target_sd_deg", "target_photos", "target_photo_camera",
         "target_mm_per_px", "mu_r_range", "seeds_per_point", "first_seed", "tolerance_deg",
         "max_simulations", "bootstrap_replicates", "confirm", "table1_sample", "angle"},
        file, p);
    CampaignCalibration cc;
    if (const toml::node* k = t->get("key"); k && k->is_array()) {
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
      cc.key = get_string(*t, "key", file, p, false, cc.key);
      cc.keys = {cc.key};
    }
    for (const auto& k : cc.keys) split_dotted_key(k, file + ": key 'calibration.key'");
    cc.table1_sample = get_sample(*t, file, p);
    if (const toml::node* a = t->get("angle")) {
      if (!a->is_string()) throw bad(file, p + "angle", value_text(*a), "must be a string");
      cc.angle = parse_angle_measure(a->as_string()->get(), file + ": key '" + p + "angle'");
    }
    const auto target = get_number(*t, "target_deg", file, p);
    const toml::node* photos = t->get("target_photos");
    if (target && photos)
      throw bad(file, p + "target_photos", value_text(*photos),
                "give either target_deg or target_photos, not both");
    if (!target && !photos)
      throw bad(file, p + "target_deg", "",
                "missing (the measured angle in degrees, or target_photos: the lab's side "
                "photos of the pile)");
    for (const char* k : {"target_photo_camera", "target_mm_per_px"})
      if (!photos && t->get(k))
        throw bad(file, p + k, value_text(*t->get(k)), "only with target_photos");
    if (photos) {
      cc.target = target_from_photos(*t, cc.angle, file, p, &cc.target_photos);
    } else {
      cc.target.angle_deg = *target;
    }
    if (auto sd = get_number(*t, "target_sd_deg", file, p)) cc.target.sd_deg = *sd;
    const std::string target_key = photos ? "target_photos" : "target_deg";
    try {
      validate_target(cc.target);
    } catch (const std::invalid_argument& e) {
      const std::string shown = photos ? "measured " + std::to_string(cc.target.angle_deg) + " deg"
                                       : value_text(*t->get("target_deg"));
      throw bad(file, p + target_key, shown, e.what());
    }
    const toml::node* range = t->get("mu_r_range");
    const toml::array* ra = range ? range->as_array() : nullptr;
    if (ra == nullptr || ra->size() != 2 || !(*ra)[0].is_number() || !(*ra)[1].is_number())
      throw bad(file, p + "mu_r_range", range ? value_text(*range) : "",
                "must be a list of two numbers [lo, hi]");
    auto as_double = [](const toml::node& n) {
      return n.is_integer() ? static_cast<double>(n.as_integer()->get())
                            : n.as_floating_point()->get();
    };
    cc.settings.mu_r_lo = as_double((*ra)[0]);
    cc.settings.mu_r_hi = as_double((*ra)[1]);
    if (!(cc.settings.mu_r_lo >= 0.0 && cc.settings.mu_r_hi > cc.settings.mu_r_lo))
      throw bad(file, p + "mu_r_range", value_text(*range), "need 0 <= lo < hi");
    if (auto v = get_int(*t, "seeds_per_point", file, p)) {
      if (*v < 1 || *v > 1000)
        throw bad(file, p + "seeds_per_point", std::to_string(*v), "must be 1..1000");
      cc.settings.seeds_per_point = static_cast<int>(*v);
    }
    if (auto v = get_int(*t, "first_seed", file, p)) {
      if (*v < 0) throw bad(file, p + "first_seed", std::to_string(*v), "must be >= 0");
      cc.settings.first_seed = static_cast<std::uint64_t>(*v);
    }
    if (auto v = get_number(*t, "tolerance_deg", file, p)) {
      if (!(*v > 0.0))
        throw bad(file, p + "tolerance_deg", value_text(*t->get("tolerance_deg")), "must be > 0");
      cc.settings.tolerance_deg = *v;
    }
    if (const toml::node* v = t->get("confirm")) {
      if (!v->is_boolean()) throw bad(file, p + "confirm", value_text(*v), "must be true or false");
      cc.settings.confirm_bracket = v->as_boolean()->get();
    }
    const int min_sims = (cc.settings.confirm_bracket ? 4 : 2) * cc.settings.seeds_per_point;
    if (auto v = get_int(*t, "max_simulations", file, p)) {
      if (*v < min_sims || *v > 1000000)
        throw bad(
            file, p + "max_simulations", std::to_string(*v),
            "must be at least " + std::to_string(min_sims) +
                " (seeds_per_point at both range ends" +
                (cc.settings.confirm_bracket ? " and at the two confirmed bracket points)" : ")"));
      cc.settings.max_simulations = static_cast<int>(*v);
    } else if (cc.settings.max_simulations < min_sims) {
      throw bad(file, p + "seeds_per_point", std::to_string(cc.settings.seeds_per_point),
                "needs max_simulations >= " + std::to_string(min_sims) + " (default " +
                    std::to_string(cc.settings.max_simulations) + ")");
    }
    if (auto v = get_int(*t, "bootstrap_replicates", file, p)) {
      if (*v < 100 || *v > 1000000)
        throw bad(file, p + "bootstrap_replicates", std::to_string(*v), "must be 100..1000000");
      cc.settings.bootstrap.replicates = static_cast<int>(*v);
    }
    // The keys must apply to the base scene.
    toml::table copy = scene_of(c.scene_path);
    for (const auto& k : cc.keys)
      apply_override(copy, k, toml::value<double>(cc.settings.mu_r_lo),
                     file + ", key 'calibration.key' (scene " + c.scene_path + ")");
    c.calibration = cc;
  }

  if (const toml::node* pred = root.get("predict")) {
    const auto* arr = pred->as_array();
    if (arr == nullptr || !arr->is_array_of_tables() || arr->empty())
      throw bad(file, "predict", value_text(*pred), "must be one or more [[predict]] tables");
    if (!c.calibration)
      throw bad(file, "predict", "",
                "[[predict]] needs a [calibration] (it runs at the calibrated mu_r)");
    std::set<std::string> names;
    std::size_t i = 0;
    for (const auto& e : *arr) {
      const auto& t = *e.as_table();
      const std::string prefix = "predict[" + std::to_string(i++) + "].";
      check_keys(t,
                 {"name", "description", "scene", "measured_deg", "measured_sd_deg", "seeds",
                  "overrides", "interval_ends", "table1_sample"},
                 file, prefix);
      PredictionCase pc;
      pc.name = get_string(t, "name", file, prefix, true);
      if (!is_safe_name(pc.name))
        throw bad(file, prefix + "name", "\"" + pc.name + "\"",
                  "not filesystem-safe (use letters, digits, '.', '_', '-'; start with a letter or "
                  "digit; at most 100 characters)");
      std::string lower;
      for (char ch : pc.name)
        lower.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(ch))));
      if (!names.insert(lower).second)
        throw bad(file, prefix + "name", "\"" + pc.name + "\"", "prediction name is not unique");
      pc.description = get_string(t, "description", file, prefix, false);
      pc.scene_path =
          resolve_scene(file, prefix + "scene", get_string(t, "scene", file, prefix, true));
      const auto measured = get_number(t, "measured_deg", file, prefix);
      if (!measured)
        throw bad(file, prefix + "measured_deg", "", "missing (the test's measured angle in deg)");
      pc.measured.angle_deg = *measured;
      pc.measured.sd_deg = get_number(t, "measured_sd_deg", file, prefix).value_or(0.0);
      try {
        validate_target(pc.measured);
      } catch (const std::invalid_argument& err) {
        const std::string k = t.get("measured_sd_deg") && !(pc.measured.sd_deg >= 0.0)
                                  ? "measured_sd_deg"
                                  : "measured_deg";
        throw bad(file, prefix + k, value_text(*t.get(k)), err.what());
      }
      if (const toml::node* sd = t.get("seeds")) {
        pc.seeds = parse_seeds(*sd, file, prefix + "seeds");
      } else if (!c.seeds.empty()) {
        pc.seeds = c.seeds;
      } else {
        for (int k = 0; k < c.calibration->settings.seeds_per_point; ++k)
          pc.seeds.push_back(c.calibration->settings.first_seed + static_cast<std::uint64_t>(k));
      }
      if (const toml::node* v = t.get("interval_ends")) {
        if (!v->is_boolean())
          throw bad(file, prefix + "interval_ends", value_text(*v), "must be true or false");
        pc.interval_ends = v->as_boolean()->get();
      }
      pc.table1_sample = get_sample(t, file, prefix);
      pc.overrides = common;
      for (const auto& [k, v] : get_overrides(t, file, prefix))
        v.visit([&](const auto& x) { pc.overrides.insert_or_assign(k, x); });
      toml::table check = scene_of(pc.scene_path);
      toml::table with_mu = pc.overrides;
      for (const auto& k : c.calibration->keys)
        with_mu.insert_or_assign(k, c.calibration->settings.mu_r_lo);
      apply_overrides(check, with_mu,
                      file + ", prediction " + pc.name + " (scene " + pc.scene_path + ")");
      pc.scene_hash = fnv1a_hex(read_file(pc.scene_path));
      c.predictions.push_back(std::move(pc));
    }
  }

  if (c.runs.empty() && !c.calibration)
    throw bad(file, "case", "", "the campaign has no [[case]], no [sweep] and no [calibration]");
  return c;
}

toml::table build_case_scene(const CaseSpec& spec) {
  toml::table doc = parse_toml_file(spec.scene_path);
  apply_overrides(doc, spec.overrides,
                  "case " + spec.case_name + " (scene " + spec.scene_path + ")");
  return doc;
}

nlohmann::json to_json(const CaseSpec& spec) {
  return {{"case", spec.case_name},
          {"seed", spec.seed},
          {"scene", spec.scene_path},
          {"scene_fnv1a", spec.scene_hash},
          {"overrides", toml_to_json(spec.overrides)}};
}

// ---------------------------------------------------------------------------------------------
// Runner.

std::optional<RankInfo> detect_mpi_rank() {
  auto env_int = [](const char* name) -> std::optional<int> {
    const char* v = std::getenv(name);
    if (v == nullptr || *v == '\0') return std::nullopt;
    int out = 0;
    const auto r = std::from_chars(v, v + std::char_traits<char>::length(v), out);
    if (r.ec != std::errc()) return std::nullopt;
    return out;
  };
  auto rank = env_int("OMPI_COMM_WORLD_RANK");
  if (!rank) rank = env_int("PMIX_RANK");
  const auto size = env_int("OMPI_COMM_WORLD_SIZE");
  if (!rank || !size || *size < 1 || *rank < 0 || *rank >= *size) return std::nullopt;
  RankInfo info;
  info.rank = *rank;
  info.size = *size;
  for (const char* name :
       {"PMIX_NAMESPACE", "OMPI_MCA_orte_ess_jobid", "OMPI_MCA_ess_base_jobid"}) {
    if (const char* v = std::getenv(name); v && *v) {
      info.job = v;
      break;
    }
  }
  return info;
}

namespace {

constexpr const char* kResultFile = "result.json";
constexpr const char* kErrorFile = "error.json";
constexpr const char* kStartedFile = "started.json";
constexpr const char* kManifestFile = "campaign.json";
constexpr const char* kBatchFile = "batch.json";

std::string hostname() {
  char buf[256] = {};
  if (gethostname(buf, sizeof buf - 1) != 0) return "unknown";
  return buf;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::optional<nlohmann::json> read_json(const fs::path& p) {
  std::error_code ec;
  if (!fs::is_regular_file(p, ec)) return std::nullopt;
  try {
    return nlohmann::json::parse(read_file(p.string()));
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

// Whether a stored spec describes the same inputs as `spec` (the scene's path may have moved).
bool same_inputs(const nlohmann::json& stored, const CaseSpec& spec) {
  const auto now = to_json(spec);
  for (const char* k : {"case", "seed", "scene_fnv1a", "overrides"})
    if (!stored.contains(k) || stored[k] != now[k]) return false;
  return true;
}

// The started.json of an interrupted attempt at this run in `dir`, when the folder may be handed
// back to the case function to continue: same inputs, not failed (a failure is retried clean),
// and not forced.
std::optional<nlohmann::json> interrupted_attempt(const fs::path& dir, const CaseSpec& spec,
                                                  bool force) {
  std::error_code ec;
  if (force || fs::exists(dir / kErrorFile, ec) || fs::exists(dir / kResultFile, ec))
    return std::nullopt;
  auto started = read_json(dir / kStartedFile);
  if (!started || !started->contains("spec") || !same_inputs((*started)["spec"], spec))
    return std::nullopt;
  return started;
}

// Runs one run in its folder and records result.json or error.json. Never throws. An interrupted
// attempt with the same inputs keeps its folder, so the case function can continue its work
// (a pile run resumes from its checkpoint); result.json then records the earlier attempt(s).
bool execute_run(const CaseSpec& spec, const fs::path& out_dir, const CaseFn& case_fn,
                 const std::string& job, bool force) {
  const fs::path dir = out_dir / spec.relative_dir();
  const std::string started = utc_now();
  const auto t0 = std::chrono::steady_clock::now();
  nlohmann::json meta = {{"spec", to_json(spec)}, {"job", job},
                         {"host", hostname()},    {"pid", ::getpid()},
                         {"started", started},    {"code_version", code_version()}};
  try {
    std::error_code ec;
    if (auto earlier = interrupted_attempt(dir, spec, force)) {
      nlohmann::json attempts = earlier->value("earlier_attempts", nlohmann::json::array());
      earlier->erase("earlier_attempts");
      earlier->erase("spec");
      attempts.push_back(*earlier);
      meta["earlier_attempts"] = attempts;
    } else {
      fs::remove_all(dir, ec);  // a failed, forced or changed run restarts clean
      if (ec)
        throw std::runtime_error(dir.string() + ": cannot clean the run folder: " + ec.message());
    }
    fs::create_directories(dir);
    write_json_atomic((dir / kStartedFile).string(), meta);
    nlohmann::json result = case_fn(spec, dir.string());
    meta["finished"] = utc_now();
    meta["wall_time_s"] = seconds_since(t0);
    meta["result"] = std::move(result);
    write_json_atomic((dir / kResultFile).string(), meta);
    return true;
  } catch (const std::exception& e) {
    meta["error"] = e.what();
  } catch (...) {
    meta["error"] = "unknown exception";
  }
  meta["finished"] = utc_now();
  meta["wall_time_s"] = seconds_since(t0);
  try {
    write_json_atomic((dir / kErrorFile).string(), meta);
  } catch (...) {
  }
  return false;
}

// Status of one run as the manifest records it. Under MPI, rank 0 accepts only files of this job
// (or finished results of earlier jobs when not forcing).
struct RunStatus {
  std::string status;  // "finished", "failed", "pending"
  std::string error;
  double wall_time_s = 0.0;
};

RunStatus run_status(const fs::path& out_dir, const CaseSpec& spec, const std::string& job,
                     bool require_job_result, bool require_job_error) {
  const fs::path dir = out_dir / spec.relative_dir();
  std::error_code ec;
  if (fs::is_regular_file(dir / kResultFile, ec)) {
    auto j = read_json(dir / kResultFile);
    if (j && (!require_job_result || j->value("job", std::string()) == job))
      return {"finished", "", j->value("wall_time_s", 0.0)};
  }
  if (fs::is_regular_file(dir / kErrorFile, ec)) {
    auto j = read_json(dir / kErrorFile);
    if (j && (!require_job_error || j->value("job", std::string()) == job))
      return {"failed", j->value("error", std::string("unknown error")),
              j->value("wall_time_s", 0.0)};
  }
  return {"pending", "", 0.0};
}

nlohmann::json build_manifest(const Campaign& c, const fs::path& out_dir,
                              const std::vector<RunStatus>& st) {
  nlohmann::json runs = nlohmann::json::array();
  int finished = 0, failed = 0, pending = 0;
  for (std::size_t i = 0; i < c.runs.size(); ++i) {
    const auto& s = c.runs[i];
    nlohmann::json r = {{"case", s.case_name},
                        {"seed", s.seed},
                        {"dir", s.relative_dir()},
                        {"status", st[i].status}};
    if (st[i].status == "finished") {
      ++finished;
      r["wall_time_s"] = st[i].wall_time_s;
    } else if (st[i].status == "failed") {
      ++failed;
      r["error"] = st[i].error;
    } else {
      ++pending;
    }
    runs.push_back(r);
  }
  return {{"campaign", c.name},
          {"file", c.file},
          {"scene", c.scene_path},
          {"description", c.description},
          {"paper", c.paper},
          {"out_dir", fs::absolute(out_dir).string()},
          {"code_version", code_version()},
          {"updated", utc_now()},
          {"counts",
           {{"total", c.runs.size()},
            {"finished", finished},
            {"failed", failed},
            {"pending", pending}}},
          {"runs", runs}};
}

std::vector<RunStatus> scan(const Campaign& c, const fs::path& out_dir) {
  std::vector<RunStatus> st;
  for (const auto& s : c.runs) st.push_back(run_status(out_dir, s, "", false, false));
  return st;
}

// Runs the listed runs on a local pool; calls on_done(index, ok) in the calling thread for
// processes and under a lock for threads.
void run_pool(const Campaign& c, const fs::path& out_dir, const CaseFn& case_fn,
              const std::vector<std::size_t>& todo, int workers, WorkerMode mode,
              const std::string& job, bool force,
              const std::function<void(std::size_t, bool)>& on_done) {
  workers = std::max(1, workers);
  if (mode == WorkerMode::kThreads) {
    std::atomic<std::size_t> next{0};
    std::mutex m;
    std::vector<std::thread> pool;
    for (int w = 0; w < std::min<int>(workers, static_cast<int>(todo.size())); ++w) {
      pool.emplace_back([&] {
        for (std::size_t k = next++; k < todo.size(); k = next++) {
          const bool ok = execute_run(c.runs[todo[k]], out_dir, case_fn, job, force);
          std::lock_guard<std::mutex> lock(m);
          on_done(todo[k], ok);
        }
      });
    }
    for (auto& t : pool) t.join();
    return;
  }

  std::fflush(nullptr);  // nothing buffered may be written twice by the children
  const pid_t parent = ::getpid();
  std::deque<std::size_t> queue(todo.begin(), todo.end());
  std::map<pid_t, std::size_t> active;
  while (!queue.empty() || !active.empty()) {
    while (!queue.empty() && static_cast<int>(active.size()) < workers) {
      const std::size_t i = queue.front();
      queue.pop_front();
      const pid_t pid = ::fork();
      if (pid == 0) {
        ::prctl(PR_SET_PDEATHSIG, SIGKILL);
        if (::getppid() != parent) ::_exit(3);  // the parent died before prctl took effect
        const bool ok = execute_run(c.runs[i], out_dir, case_fn, job, force);
        std::cout.flush();  // _exit skips the buffers the case's output may sit in
        std::cerr.flush();
        std::fflush(nullptr);
        ::_exit(ok ? 0 : 1);
      }
      if (pid < 0) {
        const fs::path dir = out_dir / c.runs[i].relative_dir();
        std::error_code ec;
        fs::create_directories(dir, ec);
        write_json_atomic((dir / kErrorFile).string(),
                          {{"spec", to_json(c.runs[i])}, {"job", job}, {"error", "fork failed"}});
        on_done(i, false);
        continue;
      }
      active[pid] = i;
    }
    bool reaped = false;
    for (auto it = active.begin(); it != active.end();) {
      int st = 0;
      const pid_t r = ::waitpid(it->first, &st, WNOHANG);
      if (r == 0) {
        ++it;
        continue;
      }
      const std::size_t i = it->second;
      it = active.erase(it);
      reaped = true;
      const fs::path dir = out_dir / c.runs[i].relative_dir();
      std::error_code ec;
      const bool has_result = fs::is_regular_file(dir / kResultFile, ec);
      if (!has_result && !fs::is_regular_file(dir / kErrorFile, ec)) {
        std::string why = "worker ended without a result";
        if (r > 0 && WIFSIGNALED(st))
          why += " (killed by signal " + std::to_string(WTERMSIG(st)) + ")";
        if (r > 0 && WIFEXITED(st)) why += " (exit code " + std::to_string(WEXITSTATUS(st)) + ")";
        fs::create_directories(dir, ec);
        write_json_atomic((dir / kErrorFile).string(),
                          {{"spec", to_json(c.runs[i])}, {"job", job}, {"error", why}});
      }
      on_done(i, has_result);
    }
    if (!reaped) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

// An exclusive lock on the output folder for local runs, so two campaign processes cannot run
// into the same folder. Released by the kernel when the process ends, even by SIGKILL.
class FolderLock {
 public:
  explicit FolderLock(const fs::path& out_dir) {
    const std::string p = (out_dir / ".campaign.lock").string();
    fd_ = ::open(p.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw std::runtime_error(p + ": cannot open the campaign lock file");
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      ::close(fd_);
      throw std::runtime_error(out_dir.string() +
                               ": another campaign process is running in this folder");
    }
  }
  ~FolderLock() {
    if (fd_ >= 0) ::close(fd_);
  }
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace

nlohmann::json campaign_manifest(const Campaign& campaign, const std::string& out_dir) {
  return build_manifest(campaign, out_dir, scan(campaign, out_dir));
}

namespace {

// The runner behind run_campaign and run_batch. `manifest_name` is the summary file rank 0 writes;
// with `every_rank_waits` all MPI ranks (not only rank 0) wait for every run to end, so each can
// continue with the results (the calibration driver runs the same steps on every rank).
CampaignSummary run_impl(const Campaign& campaign, const std::string& out_dir_str,
                         const CaseFn& case_fn, const RunnerSettings& settings,
                         const std::string& manifest_name, bool every_rank_waits) {
  if (!case_fn) throw std::invalid_argument("run_campaign: no case function");
  for (std::size_t k = 0; k < campaign.runs.size(); ++k)
    if (campaign.runs[k].index != k)
      throw std::invalid_argument("run_campaign: run " + campaign.runs[k].id() + " has index " +
                                  std::to_string(campaign.runs[k].index) + ", expected " +
                                  std::to_string(k));
  const fs::path out_dir = fs::absolute(fs::path(out_dir_str)).lexically_normal();
  fs::create_directories(out_dir);
  const fs::path manifest_path = out_dir / manifest_name;
  for (const char* name : {kManifestFile, kBatchFile}) {
    if (auto m = read_json(out_dir / name)) {
      const std::string other = m->value("campaign", std::string());
      if (other != campaign.name)
        throw std::runtime_error(out_dir.string() + " holds campaign '" + other + "', not '" +
                                 campaign.name + "': use another output folder");
    }
  }
  const bool mpi = settings.rank.has_value() && settings.rank->size > 1;
  const RankInfo rank = settings.rank.value_or(RankInfo{});
  std::optional<FolderLock> lock;
  if (!mpi) lock.emplace(out_dir);
  const std::string tag =
      "[campaign " + campaign.name +
      (mpi ? " rank " + std::to_string(rank.rank) + "/" + std::to_string(rank.size)
           : std::string()) +
      "] ";
  auto say = [&](const std::string& line) {
    if (settings.progress) std::cerr << tag << line << std::endl;
  };

  // Which runs this process does; refuse to mix finished results made from other inputs.
  CampaignSummary summary;
  summary.total = static_cast<int>(campaign.runs.size());
  std::vector<std::size_t> todo;
  for (const auto& s : campaign.runs) {
    if (mpi && static_cast<int>(s.index % static_cast<std::size_t>(rank.size)) != rank.rank)
      continue;
    const fs::path dir = out_dir / s.relative_dir();
    if (auto r = read_json(dir / kResultFile)) {
      if (!settings.force) {
        if (!same_inputs(r->value("spec", nlohmann::json::object()), s))
          throw std::runtime_error((dir / kResultFile).string() + ": finished result of " + s.id() +
                                   " was made from different inputs than " + campaign.file +
                                   " now gives; use --force to redo it or another output folder");
        ++summary.skipped;
        continue;
      }
    }
    todo.push_back(s.index);
  }
  say(std::to_string(todo.size()) + " run(s) to do, " + std::to_string(summary.skipped) +
      " already finished, " + std::to_string(summary.total) + " in the campaign");

  std::vector<RunStatus> status = scan(campaign, out_dir);
  auto write_manifest = [&] {
    summary.manifest = build_manifest(campaign, out_dir, status);
    if (!mpi || rank.rank == 0) write_json_atomic(manifest_path.string(), summary.manifest);
  };
  if (!mpi) write_manifest();

  const auto t0 = std::chrono::steady_clock::now();
  int done_now = 0;
  auto on_done = [&](std::size_t i, bool ok) {
    ++done_now;
    ++summary.ran;
    status[i] = run_status(out_dir, campaign.runs[i], "", false, false);
    std::ostringstream os;
    os << campaign.runs[i].id() << (ok ? " finished" : " FAILED: " + status[i].error) << " ("
       << done_now << "/" << todo.size() << " done, " << static_cast<int>(seconds_since(t0))
       << " s)";
    say(os.str());
    if (!mpi) write_manifest();
  };
  run_pool(campaign, out_dir, case_fn, todo, mpi ? 1 : settings.workers, settings.mode, rank.job,
           settings.force, on_done);

  if (mpi && (rank.rank == 0 || every_rank_waits)) {
    // Wait for every other rank's runs: a result of this job (or an earlier finished one when not
    // forcing), or an error of this job. Without a job id, files newer than this rank's start.
    const auto wait_start = std::chrono::steady_clock::now();
    const auto file_start = fs::file_time_type::clock::now() - std::chrono::seconds(2);
    const bool have_job = !rank.job.empty();
    for (;;) {
      int pending = 0;
      for (const auto& s : campaign.runs) {
        const fs::path dir = out_dir / s.relative_dir();
        RunStatus st = run_status(out_dir, s, rank.job, settings.force && have_job, have_job);
        if (!have_job && st.status != "pending") {
          std::error_code ec;
          const fs::path f = dir / (st.status == "finished" ? kResultFile : kErrorFile);
          const bool fresh = fs::last_write_time(f, ec) >= file_start;
          if (!fresh && (st.status == "failed" || settings.force)) st = {"pending", "", 0.0};
        }
        status[s.index] = st;
        if (st.status == "pending") ++pending;
      }
      if (pending == 0) break;
      if (settings.wait_timeout_s > 0.0 && seconds_since(wait_start) > settings.wait_timeout_s) {
        say("gave up waiting for " + std::to_string(pending) + " run(s) of other ranks");
        break;
      }
      std::this_thread::sleep_for(std::chrono::duration<double>(settings.poll_interval_s));
    }
  }
  if (!mpi || rank.rank == 0) {
    write_manifest();
  } else {
    summary.manifest = build_manifest(campaign, out_dir, scan(campaign, out_dir));
  }
  const auto& counts = summary.manifest["counts"];
  summary.finished = counts["finished"].get<int>();
  summary.failed = counts["failed"].get<int>();
  if (mpi && rank.rank != 0) {
    say("this rank's " + std::to_string(summary.ran) + " run(s) done; rank 0 writes the manifest");
  } else {
    say(std::to_string(summary.finished) + " finished, " + std::to_string(summary.failed) +
        " failed, " + std::to_string(counts["pending"].get<int>()) + " pending of " +
        std::to_string(summary.total));
  }
  return summary;
}

}  // namespace

CampaignSummary run_campaign(const Campaign& campaign, const std::string& out_dir,
                             const CaseFn& case_fn, const RunnerSettings& settings) {
  return run_impl(campaign, out_dir, case_fn, settings, kManifestFile, false);
}

std::optional<nlohmann::json> read_run_result(const std::string& out_dir, const CaseSpec& spec) {
  return read_json(fs::path(out_dir) / spec.relative_dir() / kResultFile);
}

CaseSpec make_run(const Campaign& campaign, const std::string& case_name,
                  const toml::table& overrides, std::uint64_t seed) {
  if (!is_safe_name(case_name))
    throw std::invalid_argument(campaign.file + ": run name \"" + case_name +
                                "\" is not filesystem-safe");
  CaseSpec s;
  s.case_name = case_name;
  s.seed = seed;
  s.scene_path = campaign.scene_path;
  s.scene_hash = fnv1a_hex(read_file(campaign.scene_path));
  s.overrides = campaign.overrides;
  for (const auto& [k, v] : overrides)
    v.visit([&](const auto& x) { s.overrides.insert_or_assign(k, x); });
  toml::table check = parse_toml_file(campaign.scene_path);
  apply_overrides(check, s.overrides, campaign.file + ", run " + case_name);
  return s;
}

CaseSpec calibration_run(const Campaign& campaign, double mu_r, std::uint64_t seed) {
  if (!campaign.calibration)
    throw std::invalid_argument(campaign.file + ": no [calibration] table");
  const auto& key = campaign.calibration->key;
  const auto parts = split_dotted_key(key, campaign.file + ": key 'calibration.key'");
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, mu_r);
  toml::table ov;
  ov.insert_or_assign(key, mu_r);
  for (const auto& k : campaign.calibration->keys) ov.insert_or_assign(k, mu_r);
  return make_run(campaign, sanitize("calib_" + parts.back() + "_" + std::string(buf, r.ptr)), ov,
                  seed);
}

CaseSpec prediction_run(const Campaign& campaign, const PredictionCase& p, double mu_r,
                        std::uint64_t seed) {
  if (!campaign.calibration)
    throw std::invalid_argument(campaign.file + ": no [calibration] table");
  if (!std::isfinite(mu_r) || mu_r < 0.0)
    throw std::invalid_argument(campaign.file + ", prediction " + p.name +
                                ": mu_r = " + std::to_string(mu_r) + " must be finite and >= 0");
  const auto parts =
      split_dotted_key(campaign.calibration->key, campaign.file + ": key 'calibration.key'");
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, mu_r);
  const std::string name =
      sanitize("predict_" + p.name + "_" + parts.back() + "_" + std::string(buf, r.ptr));
  if (!is_safe_name(name))
    throw std::invalid_argument(campaign.file + ": run name \"" + name +
                                "\" is not filesystem-safe");
  CaseSpec s;
  s.case_name = name;
  s.seed = seed;
  s.scene_path = p.scene_path;
  s.scene_hash = fnv1a_hex(read_file(p.scene_path));
  s.overrides = p.overrides;
  for (const auto& k : campaign.calibration->keys) s.overrides.insert_or_assign(k, mu_r);
  toml::table check = parse_toml_file(p.scene_path);
  apply_overrides(check, s.overrides, campaign.file + ", prediction run " + name);
  return s;
}

std::vector<nlohmann::json> run_batch(const Campaign& campaign, const std::vector<CaseSpec>& runs,
                                      const std::string& out_dir, const CaseFn& case_fn,
                                      const RunnerSettings& settings) {
  Campaign batch = campaign;
  batch.runs = runs;
  std::set<std::string> ids;
  for (std::size_t k = 0; k < batch.runs.size(); ++k) {
    batch.runs[k].index = k;
    if (!ids.insert(batch.runs[k].id()).second)
      throw std::invalid_argument("run_batch: run " + batch.runs[k].id() + " appears twice");
  }
  run_impl(batch, out_dir, case_fn, settings, kBatchFile, true);
  std::vector<nlohmann::json> results;
  std::string failures;
  for (const auto& s : batch.runs) {
    const fs::path dir = fs::path(out_dir) / s.relative_dir();
    if (auto j = read_json(dir / kResultFile)) {
      results.push_back((*j)["result"]);
      continue;
    }
    const auto e = read_json(dir / kErrorFile);
    failures += (failures.empty() ? "" : "; ") + s.id() + ": " +
                (e ? e->value("error", std::string("unknown error")) : std::string("no result"));
  }
  if (!failures.empty()) throw std::runtime_error("run_batch: run(s) failed: " + failures);
  return results;
}

// ---------------------------------------------------------------------------------------------
// Calibrate, then predict.

namespace {

constexpr const char* kCalibrationFile = "calibration.json";
constexpr const char* kPredictionsFile = "predictions.json";

const CampaignCalibration& calibration_of(const Campaign& c) {
  if (!c.calibration)
    throw std::invalid_argument(c.file + ": [calibration] is missing (target_deg, mu_r_range)");
  return *c.calibration;
}

std::vector<std::string> keys_of(const CampaignCalibration& cc) {
  return cc.keys.empty() ? std::vector<std::string>{cc.key} : cc.keys;
}

// The rolling law behind the calibrated key: the scene's rolling_model beside the key (the
// scene format's default "epsd" when the scene does not say), described by sim::kRollingModels.
nlohmann::json rolling_model_of(const Campaign& c) {
  const auto& cc = calibration_of(c);
  const toml::table doc = build_case_scene(calibration_run(c, cc.settings.mu_r_lo, 1));
  const auto dot = cc.key.rfind('.');
  const std::string parent = dot == std::string::npos ? std::string() : cc.key.substr(0, dot);
  std::string keyword = "epsd";
  bool stated = false;
  if (!parent.empty()) {
    if (auto v = toml::at_path(doc, parent + ".rolling_model").value<std::string>()) {
      keyword = *v;
      stated = true;
    }
  }
  nlohmann::json j = {{"keyword", keyword}, {"stated_in_scene", stated}};
  if (const sim::RollingModelInfo* info = sim::find_rolling_model(keyword)) {
    j["torque"] = std::string(info->torque);
    j["radius"] = std::string(info->radius);
    j["angular_velocity"] = std::string(info->angular_velocity);
  }
  return j;
}

std::vector<Observation> observations_of(const nlohmann::json& cal, const std::string& file) {
  std::vector<Observation> obs;
  if (!cal.contains("observations") || !cal["observations"].is_array())
    throw std::runtime_error(file + ": field 'observations' is missing");
  for (const auto& o : cal["observations"])
    obs.push_back({o.at("mu_r").get<double>(), o.at("seed").get<std::uint64_t>(),
                   o.at("angle_deg").get<double>()});
  return obs;
}

// The first field in which a stored calibration.json answered another question than campaign `c`
// asks now ({field, stored, now}), or none. The angle is compared only when one is given.
struct FieldDifference {
  std::string field;
  nlohmann::json stored, now;
};
std::optional<FieldDifference> calibration_difference(const nlohmann::json& j, const Campaign& c,
                                                      const std::string& angle_method) {
  const CampaignCalibration& cc = calibration_of(c);
  const nlohmann::json target =
      j.contains("target") ? j["target"].value("angle_deg", nlohmann::json()) : nlohmann::json();
  const nlohmann::json stored_angle = j.value("angle_method", nlohmann::json());
  const std::vector<FieldDifference> fields = {
      {"campaign_name", j.value("campaign_name", nlohmann::json()), c.name},
      {"keys", j.value("keys", nlohmann::json()), keys_of(cc)},
      {"target.angle_deg", target, cc.target.angle_deg},
      {"mu_r_range", j.value("mu_r_range", nlohmann::json()),
       nlohmann::json{cc.settings.mu_r_lo, cc.settings.mu_r_hi}},
      {"angle_method", stored_angle,
       angle_method.empty() ? stored_angle : nlohmann::json(angle_method)}};
  for (const FieldDifference& f : fields)
    if (f.stored != f.now) return f;
  return std::nullopt;
}

// A finished calibration in OUT is a result: calibrating again with the same question rewrites it
// with the same numbers (every run is reused), but a different question (target, range, keys or
// angle) would silently replace it, so that needs --force.
void refuse_to_replace_other_calibration(const Campaign& c, const std::string& out_dir,
                                         const CalibrateOptions& options, bool force) {
  const std::string file = (fs::path(out_dir) / kCalibrationFile).string();
  if (force || !fs::exists(file)) return;
  nlohmann::json old;
  try {
    old = nlohmann::json::parse(read_file(file));
  } catch (const std::exception& e) {
    throw std::runtime_error(file + ": a calibration file that cannot be read (" + e.what() +
                             "); move it away or use --force");
  }
  if (const auto d = calibration_difference(old, c, options.angle_method))
    throw std::runtime_error(file + ": a finished calibration with " + d->field + " = " +
                             d->stored.dump() + " is here, and this one asks for " +
                             d->now.dump() +
                             "; give another --out, move the file away, or use --force");
}

}  // namespace

void keep_only_predictions(Campaign& c, const std::vector<std::string>& names) {
  std::vector<PredictionCase> kept;
  for (const std::string& name : names) {
    auto it = std::find_if(c.predictions.begin(), c.predictions.end(),
                           [&](const PredictionCase& p) { return p.name == name; });
    if (it == c.predictions.end()) {
      std::string list;
      for (const auto& p : c.predictions) list += (list.empty() ? "" : ", ") + p.name;
      throw std::invalid_argument(c.file + ": no [[predict]] named '" + name + "' (" +
                                  (list.empty() ? std::string("there are none") : list) + ")");
    }
    kept.push_back(*it);
  }
  c.predictions = std::move(kept);
}

nlohmann::json run_calibration(const Campaign& c, const std::string& out_dir, const CaseFn& case_fn,
                               const AngleFn& angle_of, const RunnerSettings& runner,
                               const CalibrateOptions& options) {
  const CampaignCalibration& cc = calibration_of(c);
  if (!angle_of) throw std::invalid_argument("run_calibration: no angle function");
  refuse_to_replace_other_calibration(c, out_dir, options, runner.force);
  auto simulate = [&](const std::vector<std::pair<double, std::uint64_t>>& points) {
    std::vector<CaseSpec> runs;
    for (const auto& [mu, seed] : points) runs.push_back(calibration_run(c, mu, seed));
    std::vector<double> angles;
    for (const nlohmann::json& r : run_batch(c, runs, out_dir, case_fn, runner))
      angles.push_back(angle_of(r));
    return angles;
  };
  const CalibrationResult r = calibrate_batch(simulate, cc.target, cc.settings);
  nlohmann::json j = to_json(r);
  j["campaign"] = c.file;
  j["campaign_name"] = c.name;
  j["key"] = cc.key;
  j["keys"] = keys_of(cc);
  j["mu_r_range"] = {cc.settings.mu_r_lo, cc.settings.mu_r_hi};
  j["tolerance_deg"] = cc.settings.tolerance_deg;
  j["seeds_per_point"] = cc.settings.seeds_per_point;
  j["table1_sample"] = cc.table1_sample ? nlohmann::json(*cc.table1_sample) : nlohmann::json();
  j["scene"] = c.scene_path;
  j["rolling_model"] = rolling_model_of(c);
  j["angle_method"] = options.angle_method;
  if (!cc.target_photos.is_null()) j["target_photos"] = cc.target_photos;
  j["created_utc"] = utc_now();
  if (options.extra.is_object())
    for (const auto& [k, v] : options.extra.items()) j[k] = v;
  const fs::path out = fs::path(out_dir);
  fs::create_directories(out);
  if (!runner.rank || runner.rank->rank == 0)
    write_json_atomic((out / kCalibrationFile).string(), j);
  return j;
}

nlohmann::json read_calibration(const Campaign& c, const std::string& out_dir,
                                const std::string& angle_method) {
  calibration_of(c);
  const std::string file = (fs::path(out_dir) / kCalibrationFile).string();
  std::error_code ec;
  if (!fs::is_regular_file(file, ec))
    throw std::runtime_error(file + ": no finished calibration here (run `reposetwin calibrate " +
                             c.file + "` first, or give its --out folder)");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(read_file(file));
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(file + ": not a calibration file (" + e.what() + ")");
  }
  if (const auto d = calibration_difference(j, c, angle_method))
    throw std::runtime_error(file + ": field '" + d->field + "' = " + d->stored.dump() +
                             " differs from the campaign file's " + d->now.dump() + " (" + c.file +
                             "): this calibration was made from other inputs");
  return j;
}

nlohmann::json run_predictions(const Campaign& c, const nlohmann::json& cal,
                               const std::string& out_dir, const CaseFn& case_fn,
                               const AngleFn& angle_of, const RunnerSettings& runner,
                               const CalibrateOptions& options) {
  calibration_of(c);
  if (!angle_of) throw std::invalid_argument("run_predictions: no angle function");
  const std::string cal_file = (fs::path(out_dir) / kCalibrationFile).string();
  if (!cal.contains("mu_r") || !cal["mu_r"].is_number())
    throw std::runtime_error(cal_file + ": status '" + cal.value("status", std::string("?")) +
                             "': no calibrated mu_r to predict with (" +
                             cal.value("message", std::string()) + ")");
  const double mu = cal["mu_r"].get<double>();
  const double lo = cal.at("mu_r_interval").at(0).get<double>();
  const double hi = cal.at("mu_r_interval").at(1).get<double>();
  const MonotoneFit fit = fit_monotone(observations_of(cal, cal_file));

  // One batch for every prediction: the calibrated mu_r first, then the interval ends.
  std::vector<CaseSpec> runs;
  std::set<std::string> ids;
  auto add = [&](const PredictionCase& p, double m) {
    for (auto seed : p.seeds) {
      CaseSpec s = prediction_run(c, p, m, seed);
      if (ids.insert(s.id()).second) runs.push_back(std::move(s));
    }
  };
  for (const auto& p : c.predictions) add(p, mu);
  for (const auto& p : c.predictions)
    if (p.interval_ends)
      for (double m : {lo, hi}) add(p, m);
  std::map<std::string, double> angle;
  if (!runs.empty()) {
    const auto results = run_batch(c, runs, out_dir, case_fn, runner);
    for (std::size_t i = 0; i < runs.size(); ++i) {
      const double a = angle_of(results[i]);
      if (std::isnan(a)) {  // no pile (a clogged outlet): an outcome, not an angle
        angle[runs[i].id()] = a;
        continue;
      }
      if (!std::isfinite(a) || a < 0.0 || a > 90.0)
        throw std::runtime_error("prediction run " + runs[i].id() + " returned angle " +
                                 std::to_string(a) + " outside [0, 90] deg");
      angle[runs[i].id()] = a;
    }
  }
  auto at = [&](const PredictionCase& p, double m) {
    nlohmann::json angles = nlohmann::json::array(), dirs = nlohmann::json::array();
    std::vector<double> v;
    int no_pile = 0;
    for (auto seed : p.seeds) {
      const CaseSpec s = prediction_run(c, p, m, seed);
      const double a = angle.at(s.id());
      if (std::isnan(a)) {
        ++no_pile;
        angles.push_back(nullptr);
      } else {
        v.push_back(a);
        angles.push_back(a);
      }
      dirs.push_back(s.relative_dir());
    }
    const SampleStats st = sample_stats(v);
    const auto or_null = [&](double x) { return st.n > 0 ? nlohmann::json(x) : nlohmann::json(); };
    return nlohmann::json{{"mu_r", m},
                          {"angles_deg", angles},
                          {"runs", dirs},
                          {"n", st.n},
                          {"no_pile", no_pile},
                          {"mean_deg", or_null(st.mean)},
                          {"seed_sd_deg", or_null(st.sd)},
                          {"sem_deg", or_null(st.n > 0 ? st.sd / std::sqrt(st.n) : 0.0)}};
  };

  nlohmann::json list = nlohmann::json::array();
  for (const auto& p : c.predictions) {
    nlohmann::json j = at(p, mu);
    const double mean = j["mean_deg"].is_number() ? j["mean_deg"].get<double>() : NAN;
    nlohmann::json seeds = nlohmann::json::array();
    for (auto s : p.seeds) seeds.push_back(s);
    j["name"] = p.name;
    j["description"] = p.description;
    j["scene"] = p.scene_path;
    j["table1_sample"] = p.table1_sample ? nlohmann::json(*p.table1_sample) : nlohmann::json();
    j["check"] = p.scene_path == c.scene_path && p.overrides == c.overrides;
    j["measured_deg"] = p.measured.angle_deg;
    j["measured_sd_deg"] = p.measured.sd_deg;
    j["seeds"] = seeds;
    const auto finite_or_null = [](double x) {
      return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json();
    };
    j["error_deg"] = finite_or_null(mean - p.measured.angle_deg);
    j["abs_error_deg"] = finite_or_null(std::abs(mean - p.measured.angle_deg));
    j["mu_r_interval"] = {lo, hi};
    nlohmann::json effect;
    if (p.interval_ends) {
      const nlohmann::json a = at(p, lo), b = at(p, hi);
      effect = {{"method", "runs"},
                {"note", "the test run with the same seeds at both ends of the 95% mu_r interval"},
                {"at_low", a},
                {"at_high", b},
                {"angle_range_deg", nullptr}};
      if (a["mean_deg"].is_number() && b["mean_deg"].is_number()) {
        const double x = a["mean_deg"].get<double>(), y = b["mean_deg"].get<double>();
        effect["angle_range_deg"] = {std::min(x, y), std::max(x, y)};
      }
    } else {
      const double f0 = evaluate(fit, mu);
      const double dl =
          evaluate(fit, std::clamp(lo, fit.points.front().mu_r, fit.points.back().mu_r)) - f0;
      const double dh =
          evaluate(fit, std::clamp(hi, fit.points.front().mu_r, fit.points.back().mu_r)) - f0;
      effect = {{"method", "calibration_slope"},
                {"note",
                 "not run: the prediction shifted by the calibration test's fitted angle change "
                 "over the 95% mu_r interval (assumes this test responds to mu_r as that one)"},
                {"angle_range_deg", {mean + std::min(dl, dh), mean + std::max(dl, dh)}}};
    }
    j["interval_effect"] = effect;
    list.push_back(j);
  }
  // Predictions made earlier from the same calibration (another --only selection) stay in the
  // file; an entry of the same name is replaced by the new one.
  const fs::path file = fs::path(out_dir) / kPredictionsFile;
  if (const auto old = read_json(file);
      old && old->value("mu_r", -1.0) == mu && (*old)["keys"] == keys_of(*c.calibration) &&
      (*old)["predictions"].is_array()) {
    std::set<std::string> fresh;
    for (const auto& p : list) fresh.insert(p.value("name", std::string()));
    nlohmann::json merged = nlohmann::json::array();
    for (const auto& p : (*old)["predictions"])
      if (!fresh.count(p.value("name", std::string()))) merged.push_back(p);
    for (auto& p : list) merged.push_back(std::move(p));
    list = std::move(merged);
  }
  nlohmann::json out = {{"campaign", c.file},
                        {"campaign_name", c.name},
                        {"calibration_file", kCalibrationFile},
                        {"calibration_status", cal.value("status", std::string())},
                        {"mu_r", mu},
                        {"mu_r_interval", {lo, hi}},
                        {"keys", keys_of(*c.calibration)},
                        {"angle_method", options.angle_method},
                        {"created_utc", utc_now()},
                        {"predictions", list}};
  if (options.extra.is_object())
    for (const auto& [k, v] : options.extra.items()) out[k] = v;
  if (!runner.rank || runner.rank->rank == 0)
    write_json_atomic(file.string(), out);
  return out;
}

}  // namespace reposetwin::experiments
