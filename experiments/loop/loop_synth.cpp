#include "experiments/loop/loop_synth.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <sstream>

#include "experiments/io/format.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/scene_overrides.hpp"
#include "experiments/io/synth_design_file.hpp"
#include "experiments/loop/loop_effects.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string num(double v) { return significant(v, 10); }

}  // namespace

SynthDesign read_synth_design(const std::string& path) {
  SynthDesign d;
  SynthDesignFile defaults;
  defaults.mu_key = d.mu_key;
  defaults.mu_r = d.mu_r;
  defaults.seeds = d.seeds;
  defaults.camera = {.distance_radii = d.camera.distance_radii,
                     .noise_sd = d.camera.noise_sd,
                     .width_px = d.camera.width_px,
                     .height_px = d.camera.height_px,
                     .side_views = d.camera.side_views,
                     .height_m = d.camera.camera_height_m,
                     .aim_at_axis_foot = d.camera.aim_at_axis_foot,
                     .k1 = d.camera.k1};
  SynthDesignRules rules;
  rules.check_effect = [](const std::string& name) { (void)find_effect(name); };
  for (const auto& c : condition_columns())
    (c.factor != 0.0 ? rules.numeric_columns : rules.text_columns).insert(c.column);
  SynthDesignFile f = read_synth_design_file(path, std::move(defaults), rules);
  d.scene = std::move(f.scene);
  d.mu_key = std::move(f.mu_key);
  d.mu_r = f.mu_r;
  d.seeds = std::move(f.seeds);
  d.camera.distance_radii = f.camera.distance_radii;
  d.camera.noise_sd = f.camera.noise_sd;
  d.camera.width_px = f.camera.width_px;
  d.camera.height_px = f.camera.height_px;
  d.camera.side_views = f.camera.side_views;
  // The sidecars declare the lab's camera level and undistorted (declared_height_m and
  // declared_k1 stay 0): the true height, aim and k1 are hidden.
  d.camera.camera_height_m = f.camera.height_m;
  d.camera.aim_at_axis_foot = f.camera.aim_at_axis_foot;
  d.camera.k1 = f.camera.k1;
  d.hidden = std::move(f.hidden);
  d.tests = std::move(f.tests);
  return d;
}

namespace {

// One design row as the lab's test: its conditions as scene overrides through the CSV reader's
// column table, on the scene copy `scene_copy`.
LabTest lab_test(const SynthTest& st, const fs::path& scene_copy) {
  LabTest t;
  t.id = st.id;
  const std::optional<Role> role = parse_role(st.role);
  if (!role)
    throw InputError("synthetic design: test " + st.id + ": role \"" + st.role +
                     "\" must be \"calibrate\" or \"validate\"");
  t.role = *role;
  t.scene_path = fs::absolute(scene_copy).lexically_normal().string();
  for (const auto& [col, v] : st.conditions) {
    std::string key;
    double factor = 1.0;
    if (col.rfind("set:", 0) == 0) {
      key = col.substr(4);
    } else {
      for (const auto& c : condition_columns())
        if (col == c.column) key = c.key, factor = c.factor;
    }
    if (key.empty()) throw InputError("synthetic design: unknown condition column " + col);
    t.overrides.emplace_back(key, num(factor * v));
    t.conditions[col] = v;
  }
  for (const auto& [col, v] : st.labels) {
    std::string key;
    for (const auto& c : condition_columns())
      if (col == c.column && c.factor == 0.0) key = c.key;
    if (key.empty()) throw InputError("synthetic design: unknown text condition column " + col);
    t.overrides.emplace_back(key, "\"" + v + "\"");
  }
  return t;
}

// Every test's piles, one per seed, with the hidden effects on, photographed through the
// design's camera (each seed its own image noise).
std::vector<SimOutcome> pour_piles(const SynthDesign& d, const std::vector<LabTest>& tests,
                                   const std::vector<EffectSetting>& effects, SimCache& cache) {
  std::vector<SimRequest> req;
  ImageVariant cam = d.camera;
  cam.keep_photos = true;
  for (const LabTest& t : tests)
    for (std::uint64_t seed : d.seeds) {
      ImageVariant v = cam;
      v.noise_seed = seed;
      req.push_back(make_request(t, d.mu_key, d.mu_r, seed, effects, v));
    }
  return cache.run(req);
}

// The side photographs of pile `k` (from 0) of `test` copied into OUT/photos; returns the PNGs'
// paths, relative to OUT, joined by ';'.
std::string copy_photos(const SimOutcome& o, const std::string& test, std::size_t k,
                        const std::string& out_dir) {
  std::string photos;
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(o.image_dir)) files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  for (const fs::path& file : files) {
    const std::string name = file.filename().string();
    if (name.rfind("side_az", 0) != 0) continue;
    const std::string to = test + "_pile" + std::to_string(k + 1) + "_" + name;
    fs::copy_file(file, fs::path(out_dir) / "photos" / to, fs::copy_options::overwrite_existing);
    if (file.extension() == ".png")
      photos += (photos.empty() ? "" : ";") + std::string("photos/") + to;
  }
  return photos;
}

// The CSV's numeric and text condition columns, in the order the design first names them.
void condition_columns_of(const SynthDesign& d, std::vector<std::string>& cols,
                          std::vector<std::string>& text_cols) {
  for (const SynthTest& st : d.tests) {
    for (const auto& [c, v] : st.conditions)
      if (std::find(cols.begin(), cols.end(), c) == cols.end()) cols.push_back(c);
    for (const auto& [c, v] : st.labels)
      if (std::find(text_cols.begin(), text_cols.end(), c) == text_cols.end())
        text_cols.push_back(c);
  }
}

// Test i's CSV row: its conditions, and the typed values averaged over its piles (out from q
// on). A pile whose photos vision refuses through the declared camera (a hidden tilt that the
// photo's base ellipse gives away) is still the lab's pile: its photos are written and the typed
// values average the piles vision did measure (none: left empty), so reading the dataset meets
// the refusal a lab would meet. No pile at all is an error.
void write_row(const SynthDesign& d, const LabTest& test, std::size_t i,
               const std::vector<SimOutcome>& out, std::size_t& q,
               const std::vector<std::string>& cols, const std::vector<std::string>& text_cols,
               const std::string& out_dir, std::ostringstream& csv) {
  double h = 0.0, dd = 0.0, a = 0.0;
  int measured = 0;
  std::string photos;
  for (std::size_t k = 0; k < d.seeds.size(); ++k, ++q) {
    const SimOutcome& o = out[q];
    if (!o.pile && o.no_pile.empty())
      throw std::runtime_error("synthetic dataset: test " + test.id + " seed " +
                               std::to_string(d.seeds[k]) + " formed no pile (" + o.sim_dir +
                               ")");
    if (o.pile) {
      h += o.height_mm;
      dd += o.diameter_mm;
      a += o.angle_deg;
      ++measured;
    }
    const std::string more = copy_photos(o, test.id, k, out_dir);
    if (!more.empty()) photos += (photos.empty() ? "" : ";") + more;
  }
  const double n = static_cast<double>(measured);
  auto mean = [&](double sum) { return measured > 0 ? num(sum / n) : std::string(); };
  csv << test.id << "," << role_name(test.role) << ",scene.toml";
  for (const auto& c : cols)
    csv << "," << (d.tests[i].conditions.count(c) ? num(d.tests[i].conditions.at(c)) : "");
  for (const auto& c : text_cols)
    csv << "," << (d.tests[i].labels.count(c) ? d.tests[i].labels.at(c) : "");
  csv << "," << d.seeds.size() << "," << mean(h) << "," << mean(dd) << "," << mean(a) << ",\""
      << photos << "\"\n";
}

}  // namespace

nlohmann::json synth_truth_json(const SynthDesign& d, const std::string& design_path) {
  nlohmann::json effects = nlohmann::json::array();
  for (const auto& [name, value] : d.hidden) {
    const CandidateEffect& e = find_effect(name);
    effects.push_back({{"name", name}, {"value", value}, {"units", e.units}, {"key", e.key}});
  }
  const ImageVariant& c = d.camera;
  return {{"design", design_path},
          {"scene", d.scene},
          {"mu_r", d.mu_r},
          {"mu_key", d.mu_key},
          {"hidden", effects},
          {"seeds", d.seeds},
          {"camera",
           {{"width_px", c.width_px}, {"height_px", c.height_px}, {"side_views", c.side_views},
            {"distance_radii", c.distance_radii}, {"height_m", c.camera_height_m},
            {"aim_at_axis_foot", c.aim_at_axis_foot}, {"k1", c.k1}, {"noise_sd", c.noise_sd}}}};
}

BatchPlan plan_synth_dataset(const SynthDesign& d, int workers) {
  std::vector<BatchPlan::Part> parts;
  const int runs = static_cast<int>(d.seeds.size());
  for (const SynthTest& st : d.tests) {
    const LabTest t = lab_test(st, d.scene);
    std::vector<std::string> sets;
    for (const auto& [key, value] : t.overrides) sets.push_back(key + "=" + value);
    parts.push_back({"hidden piles of test " + t.id + " (" + std::to_string(runs) + " seeds)",
                     plan_run(load_scene(t.scene_path, sets), 1), runs});
  }
  return plan_batch(std::move(parts), workers);
}

std::string make_synthetic_dataset(const SynthDesign& d, const std::string& out_dir,
                                   SimCache& cache) {
  fs::create_directories(fs::path(out_dir) / "photos");
  // The lab's scene file: a copy of the base scene (same text, so the cache is shared).
  const fs::path scene_copy = fs::path(out_dir) / "scene.toml";
  write_file_atomic(scene_copy.string(), read_file(d.scene));
  std::vector<EffectSetting> effects;
  for (const auto& [name, value] : d.hidden) effects.push_back({&find_effect(name), value});
  std::vector<LabTest> tests;
  for (const SynthTest& st : d.tests) tests.push_back(lab_test(st, scene_copy));
  // The same typical grain as the loop computes when it reads the CSV back (read_lab_csv), so a
  // hidden size-dependent effect means what the loop's candidate means.
  const double d_ref = reference_grain_diameter(tests);
  for (LabTest& t : tests) t.reference_diameter_m = d_ref;
  const std::vector<SimOutcome> out = pour_piles(d, tests, effects, cache);
  std::vector<std::string> cols, text_cols;
  condition_columns_of(d, cols, text_cols);
  std::ostringstream csv;
  csv << "# Synthetic lab dataset made by reposetwin loop-synth: conditions, measured values and "
         "photographs only.\n";
  csv << "id,role,scene";
  for (const auto& c : cols) csv << "," << c;
  for (const auto& c : text_cols) csv << "," << c;
  csv << ",repeats,H_mm,D_mm,angle_deg,photo\n";
  std::size_t q = 0;
  for (std::size_t i = 0; i < tests.size(); ++i)
    write_row(d, tests[i], i, out, q, cols, text_cols, out_dir, csv);
  const std::string path = (fs::path(out_dir) / "measured.csv").string();
  write_file_atomic(path, csv.str());
  return path;
}

namespace {

// `path` lies inside `folder` (both as they would resolve, existing or not).
bool inside(const std::string& path, const std::string& folder) {
  namespace fs = std::filesystem;
  const fs::path f = fs::weakly_canonical(fs::absolute(folder));
  const fs::path p = fs::weakly_canonical(fs::absolute(path));
  const auto [a, b] = std::mismatch(f.begin(), f.end(), p.begin(), p.end());
  return a == f.end();
}

}  // namespace

std::string synth_cache_dir(const std::string& out_dir, const std::string& cache,
                            const std::string& truth_file) {
  for (const auto& [option, path] : {std::pair{"--truth", truth_file}, std::pair{"--cache", cache}})
    if (!path.empty() && inside(path, out_dir))
      throw InputError(std::string(option) + " " + path + ": inside the dataset's folder " +
                       out_dir + ", where the loop would read the hidden settings; give a "
                       "path outside it");
  if (!cache.empty()) return cache;
  std::filesystem::path out = std::filesystem::path(out_dir).lexically_normal();
  if (!out.has_filename()) out = out.parent_path();  // "data/" -> "data"
  return out.string() + ".synth-cache";
}

}  // namespace reposetwin::experiments
