#include "experiments/io/campaign_file.hpp"

#include <cctype>
#include <charconv>
#include <filesystem>
#include <map>
#include <set>
#include <stdexcept>

#include "experiments/io/campaign_file_detail.hpp"
#include "experiments/io/campaign_keys.hpp"
#include "experiments/io/format.hpp"
#include "experiments/io/hash.hpp"
#include "experiments/io/overrides.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/toml_edit.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
namespace campaign_file {

InputError bad(const std::string& file, const std::string& key, const std::string& value,
               const std::string& why) {
  return InputError(file + ": key '" + key + "'" + (value.empty() ? std::string() : " = " + value) +
                    ": " + why);
}

std::string value_text(const toml::node& n) { return toml_value_text(n); }

std::string required_string(TableReader& t, const std::string& key) {
  if (!t.has(key)) throw bad(t.file(), t.where(key), "", "missing (a string is required)");
  return t.string(key);
}

std::optional<double> optional_number(TableReader& t, const std::string& key) {
  if (!t.has(key)) return std::nullopt;
  return t.number(key);
}

std::optional<std::int64_t> optional_integer(TableReader& t, const std::string& key) {
  if (!t.has(key)) return std::nullopt;
  return t.integer(key, 0);
}

std::optional<int> read_table1_sample(TableReader& t) {
  t.mark_used("table1_sample");
  const toml::node* n = t.raw().get("table1_sample");
  if (n == nullptr) return std::nullopt;
  if (!n->is_integer() || n->as_integer()->get() < 1 || n->as_integer()->get() > 4)
    throw bad(t.file(), t.where("table1_sample"), value_text(*n),
              "must be the paper's Table 1 sample number, an integer 1..4");
  return static_cast<int>(n->as_integer()->get());
}

const toml::table& SceneCache::get(const std::string& path) {
  auto it = scenes_.find(path);
  if (it == scenes_.end()) it = scenes_.emplace(path, parse_toml(read_file(path), path)).first;
  return it->second;
}

namespace {

std::string safe_name(TableReader& t, const std::string& key) {
  const std::string name = required_string(t, key);
  if (!is_safe_name(name))
    throw bad(t.file(), t.where(key), "\"" + name + "\"",
              "not filesystem-safe (use letters, digits, '.', '_', '-'; start with a letter or "
              "digit; at most 100 characters)");
  return name;
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

// Flattens an overrides table into dotted keys: { "a.b" = 1 } and { a.b = 1 } (a table made by a
// dotted key in TOML) both give "a.b" = 1. A table written as a value, { a = { b = 1 } } or
// { "a" = { b = 1 } }, is one override "a" = { b = 1 } that replaces or creates the whole table,
// as a person writing a table means it. Arrays are leaves.
void flatten(const toml::table& t, const std::string& prefix, toml::table& out) {
  for (const auto& [k, v] : t) {
    const std::string key =
        prefix.empty() ? std::string(k.str()) : prefix + "." + std::string(k.str());
    if (const auto* sub = v.as_table(); sub && !sub->is_inline()) {
      flatten(*sub, key, out);
    } else {
      v.visit([&](const auto& x) { out.insert_or_assign(key, x); });
    }
  }
}

std::vector<Override> read_overrides(TableReader& t) {
  toml::table flat;
  t.mark_used("overrides");
  const toml::node* n = t.raw().get("overrides");
  if (n == nullptr) return {};
  const std::string key = t.where("overrides");
  if (!n->is_table())
    throw bad(
        t.file(), key, value_text(*n),
        "must be a table of dotted keys, e.g. { \"contacts.rock-rock.rolling_friction\" = 0.1 }");
  flatten(*n->as_table(), "", flat);
  std::vector<Override> out;
  for (const auto& [k, v] : flat) {
    split_dotted_key(k.str(), t.file() + ": key '" + key + "'");
    // A path written in a file is relative to that file: a sieve sheet named here is found
    // beside the campaign file, wherever the scene is.
    const auto path = v.value<std::string>();
    if (k.str() == "sample.psd_file" && path && fs::path(*path).is_relative())
      set_override(
          out,
          string_override(
              std::string(k.str()),
              fs::absolute(fs::path(t.file()).parent_path() / *path).lexically_normal().string()));
    else
      set_override(out, override_of(std::string(k.str()), v));
  }
  return out;
}

void merge_overrides(std::vector<Override>& into, const std::vector<Override>& from) {
  for (const Override& o : from) set_override(into, o);
}

std::vector<std::uint64_t> read_seeds(TableReader& t, const std::string& key) {
  t.mark_used(key);
  const toml::node& s = *t.raw().get(key);
  const std::string& file = t.file();
  const std::string where = t.where(key);
  std::vector<std::uint64_t> seeds;
  if (s.is_integer()) {
    const auto n = s.as_integer()->get();
    if (n < 1 || n > 100000) throw bad(file, where, value_text(s), "a count must be 1..100000");
    for (std::int64_t i = 1; i <= n; ++i) seeds.push_back(static_cast<std::uint64_t>(i));
  } else if (const auto* a = s.as_array()) {
    std::set<std::int64_t> seen;
    for (const auto& e : *a) {
      if (!e.is_integer() || e.as_integer()->get() < 0)
        throw bad(file, where, value_text(s), "every seed must be an integer >= 0");
      if (!seen.insert(e.as_integer()->get()).second)
        throw bad(file, where, value_text(s), "seed " + value_text(e) + " is repeated");
      seeds.push_back(static_cast<std::uint64_t>(e.as_integer()->get()));
    }
    if (seeds.empty()) throw bad(file, where, "[]", "needs at least one seed");
  } else {
    throw bad(file, where, value_text(s), "must be a list of integers or a count");
  }
  return seeds;
}

std::vector<TableReader> array_of_tables(TableReader& t, const std::string& key,
                                         const std::string& what) {
  t.mark_used(key);
  const toml::node* n = t.raw().get(key);
  std::vector<TableReader> out;
  if (n == nullptr) return out;
  const auto* arr = n->as_array();
  if (arr == nullptr || !arr->is_array_of_tables() || arr->empty())
    throw bad(t.file(), t.where(key), value_text(*n), "must be one or more " + what + " tables");
  for (std::size_t i = 0; i < arr->size(); ++i)
    out.emplace_back(*arr->get(i)->as_table(), t.file(),
                     t.where(key) + "[" + std::to_string(i) + "]");
  return out;
}

std::string lower_case(const std::string& s) {
  std::string lower;
  for (char ch : s)
    lower.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(ch))));
  return lower;
}

}  // namespace
}  // namespace campaign_file

namespace {
using namespace campaign_file;

// A case before its seeds: the name, the scene and every override it runs with.
struct CaseDef {
  std::string name, scene;
  std::string name_key;  // the key that named it, for the message about a repeated name
  std::vector<Override> overrides;
};

// Text of a sweep value for a case name: shortest round-trip form for floats.
std::string name_text(const toml::node& v) {
  if (v.is_floating_point()) return shortest_text(v.as_floating_point()->get());
  if (v.is_integer()) return std::to_string(v.as_integer()->get());
  if (v.is_string()) return v.as_string()->get();
  if (v.is_boolean()) return v.as_boolean()->get() ? "true" : "false";
  return value_text(v);
}

// Stage 1: name, description, paper, scene, seeds, common overrides.
Campaign read_top_level(TableReader& root) {
  Campaign c;
  c.file = root.file();
  c.name = safe_name(root, "name");
  c.description = root.string("description", "");
  c.paper = root.string("paper", "");
  c.scene_path = resolve_scene(c.file, "scene", required_string(root, "scene"));
  if (root.has("seeds")) c.seeds = read_seeds(root, "seeds");
  c.overrides = read_overrides(root);
  return c;
}

std::vector<CaseDef> read_case_tables(TableReader& root, const Campaign& c) {
  std::vector<CaseDef> cases;
  for (TableReader& t : array_of_tables(root, "case", "[[case]]")) {
    t.known_keys(campaign_table_keys("case"));
    CaseDef d;
    d.name_key = t.where("name");
    d.name = safe_name(t, "name");
    t.string("description", "");
    d.scene =
        t.has("scene") ? resolve_scene(c.file, t.where("scene"), t.string("scene")) : c.scene_path;
    d.overrides = c.overrides;
    merge_overrides(d.overrides, read_overrides(t));
    cases.push_back(std::move(d));
  }
  return cases;
}

std::vector<CaseDef> read_sweep(TableReader& t, const Campaign& c) {
  const std::string& file = c.file;
  t.known_keys(campaign_table_keys("sweep"));
  const std::string key = required_string(t, "key");
  const auto parts = split_dotted_key(key, file + ": key 'sweep.key'");
  const std::string prefix = t.string("name", parts.back());
  t.mark_used("values");
  const toml::node* values = t.raw().get("values");
  if (values == nullptr) throw bad(file, "sweep.values", "", "missing (a list is required)");
  const auto* va = values->as_array();
  if (va == nullptr || va->empty())
    throw bad(file, "sweep.values", value_text(*values), "must be a non-empty list");
  std::vector<CaseDef> cases;
  for (const auto& v : *va) {
    CaseDef d;
    d.name_key = "sweep.values";
    d.name = sanitize_name(prefix + "_" + name_text(v));
    if (!is_safe_name(d.name))
      throw bad(file, "sweep.values", value_text(v),
                "gives case name \"" + d.name + "\", which is not filesystem-safe");
    d.scene = c.scene_path;
    d.overrides = c.overrides;
    set_override(d.overrides, override_of(key, v));
    cases.push_back(std::move(d));
  }
  return cases;
}

// Stage 2: the cases, from [[case]] tables or one [sweep], with unique names.
std::vector<CaseDef> read_cases(TableReader& root, const Campaign& c) {
  if (root.has("case") && root.has("sweep"))
    throw bad(c.file, "sweep", "",
              "a campaign has either [[case]] tables or one [sweep], not both");
  std::vector<CaseDef> cases;
  if (root.has("case")) {
    cases = read_case_tables(root, c);
  } else if (auto sweep = root.table("sweep", true)) {
    cases = read_sweep(*sweep, c);
  }
  // Unique names (case-insensitively, for case-insensitive file systems).
  std::set<std::string> seen;
  for (const auto& d : cases)
    if (!seen.insert(lower_case(d.name)).second)
      throw bad(c.file, d.name_key, "\"" + d.name + "\"", "case name is not unique");
  if (!cases.empty() && c.seeds.empty())
    throw bad(c.file, "seeds", "", "missing (cases run once per seed: give a list or a count)");
  return cases;
}

// Stage 3: cases x seeds, each override checked against its scene now, not hours into the
// campaign.
std::vector<CaseSpec> expand_runs(const Campaign& c, const std::vector<CaseDef>& cases,
                                  SceneCache& scenes) {
  std::map<std::string, std::string> hashes;
  for (const auto& d : cases) {
    toml::table copy = scenes.get(d.scene);
    apply_overrides(copy, d.overrides, c.file + ", case " + d.name + " (scene " + d.scene + ")");
    if (!hashes.count(d.scene)) hashes[d.scene] = fnv1a_hex(read_file(d.scene));
  }
  std::vector<CaseSpec> runs;
  for (const auto& d : cases) {
    for (auto seed : c.seeds) {
      CaseSpec s;
      s.index = runs.size();
      s.case_name = d.name;
      s.seed = seed;
      s.scene_path = d.scene;
      s.scene_hash = hashes[d.scene];
      s.overrides = d.overrides;
      runs.push_back(std::move(s));
    }
  }
  return runs;
}

// One [[predict]] table; `names` holds the lower-case names read so far (they must differ).
PredictionCase read_prediction(TableReader& t, const Campaign& c, SceneCache& scenes,
                               std::set<std::string>& names) {
  const std::string& file = c.file;
  t.known_keys(campaign_table_keys("predict"));
  PredictionCase pc;
  pc.name = safe_name(t, "name");
  if (!names.insert(lower_case(pc.name)).second)
    throw bad(file, t.where("name"), "\"" + pc.name + "\"", "prediction name is not unique");
  pc.description = t.string("description", "");
  pc.scene_path = resolve_scene(file, t.where("scene"), required_string(t, "scene"));
  const auto measured = optional_number(t, "measured_deg");
  if (!measured)
    throw bad(file, t.where("measured_deg"), "", "missing (the test's measured angle in deg)");
  pc.measured.angle_deg = *measured;
  pc.measured.sd_deg = optional_number(t, "measured_sd_deg").value_or(0.0);
  try {
    validate_target(pc.measured);
  } catch (const std::invalid_argument& err) {
    const std::string k = t.has("measured_sd_deg") && !(pc.measured.sd_deg >= 0.0)
                              ? "measured_sd_deg"
                              : "measured_deg";
    throw bad(file, t.where(k), value_text(*t.raw().get(k)), err.what());
  }
  if (t.has("seeds")) {
    pc.seeds = read_seeds(t, "seeds");
  } else if (!c.seeds.empty()) {
    pc.seeds = c.seeds;
  } else {
    for (int k = 0; k < c.calibration->settings.seeds_per_point; ++k)
      pc.seeds.push_back(c.calibration->settings.first_seed + static_cast<std::uint64_t>(k));
  }
  pc.interval_ends = t.boolean("interval_ends", true);
  pc.table1_sample = read_table1_sample(t);
  pc.overrides = c.overrides;
  merge_overrides(pc.overrides, read_overrides(t));
  toml::table check = scenes.get(pc.scene_path);
  std::vector<Override> with_mu = pc.overrides;
  for (const auto& k : c.calibration->keys)
    set_override(with_mu, number_override(k, c.calibration->settings.mu_r_lo));
  apply_overrides(check, with_mu,
                  file + ", prediction " + pc.name + " (scene " + pc.scene_path + ")");
  pc.scene_hash = fnv1a_hex(read_file(pc.scene_path));
  return pc;
}

// Stage 5: the [[predict]] tests, run at the calibrated mu_r (so only with a [calibration]).
std::vector<PredictionCase> read_predictions(TableReader& root, const Campaign& c,
                                             SceneCache& scenes) {
  std::vector<TableReader> tables = array_of_tables(root, "predict", "[[predict]]");
  if (!tables.empty() && !c.calibration)
    throw bad(c.file, "predict", "",
              "[[predict]] needs a [calibration] (it runs at the calibrated mu_r)");
  std::vector<PredictionCase> out;
  std::set<std::string> names;
  for (TableReader& t : tables) out.push_back(read_prediction(t, c, scenes, names));
  return out;
}

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

std::string sanitize_name(std::string_view text) {
  std::string out;
  for (char c : text)
    out.push_back(
        std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-' ? c : '_');
  return out;
}

Campaign read_campaign_file(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw std::runtime_error(path + ": campaign file not found");
  return parse_campaign(read_file(path), path);  // which names a folder, a pipe or a device
}

Campaign parse_campaign(std::string_view text, const std::string& path) {
  const std::string file = fs::absolute(fs::path(path)).lexically_normal().string();
  const toml::table doc = parse_toml(std::string(text), file);
  TableReader root(doc, file);
  root.known_keys(campaign_table_keys(""));
  SceneCache scenes;
  Campaign c = read_top_level(root);
  c.runs = expand_runs(c, read_cases(root, c), scenes);
  if (auto cal = root.table("calibration", true))
    c.calibration = read_calibration_table(*cal, c, scenes);
  c.predictions = read_predictions(root, c, scenes);
  if (c.runs.empty() && !c.calibration)
    throw bad(file, "case", "", "the campaign has no [[case]], no [sweep] and no [calibration]");
  return c;
}

}  // namespace reposetwin::experiments
