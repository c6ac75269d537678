#include "experiments/io/synth_design_file.hpp"

#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "experiments/io/format.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/toml_reader.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;

SynthDesignFile read_synth_design_file(const std::string& path, SynthDesignFile defaults,
                                       const SynthDesignRules& rules) {
  auto num = [](double v) { return significant(v, 10); };
  const toml::table doc = parse_toml(read_file(path), path);
  TableReader r(doc, path);
  SynthDesignFile d = std::move(defaults);
  const fs::path dir = fs::absolute(path).parent_path();
  d.scene = (dir / r.string("scene")).lexically_normal().string();
  if (!fs::exists(d.scene)) r.fail("scene", "= \"" + d.scene + "\" does not exist");
  d.mu_key = r.string("mu_key", d.mu_key);
  d.mu_r = r.number("mu_r", d.mu_r);
  if (!(d.mu_r >= 0.0)) r.fail("mu_r", "= " + num(d.mu_r) + " must not be negative");
  if (r.has("seeds")) {
    d.seeds.clear();
    for (double s : r.numbers("seeds")) {
      if (!(s >= 0.0) || s != std::floor(s)) r.fail("seeds", "must hold whole numbers >= 0");
      d.seeds.push_back(static_cast<std::uint64_t>(s));
    }
    if (d.seeds.empty()) r.fail("seeds", "must not be empty");
  }
  if (auto c = r.table("camera", true)) {
    SynthCamera& cam = d.camera;
    // Each value is checked as it is read, so the message names its key and the value given.
    auto number_in = [&](const char* key, double fallback, double lo, double hi,
                         const std::string& unit) {
      const double v = c->number(key, fallback);
      if (!std::isfinite(v) || !(v >= lo) || !(v <= hi))
        c->fail(key, "= " + num(v) + " must be in [" + num(lo) + ", " + num(hi) + "]" + unit);
      return v;
    };
    auto integer_in = [&](const char* key, int fallback, int lo, int hi) {
      const std::int64_t v = c->integer(key, fallback);
      if (v < lo || v > hi)
        c->fail(key, "= " + std::to_string(v) + " must be a whole number in [" +
                         std::to_string(lo) + ", " + std::to_string(hi) + "]");
      return static_cast<int>(v);
    };
    // The renderer's own floor (render::LabCameraSettings), named here at the design's key.
    cam.distance_radii = number_in("distance_radii", cam.distance_radii, 10.0, 1e3, " pile radii");
    cam.noise_sd = number_in("noise_sd", cam.noise_sd, 0.0, 128.0, " grey levels");
    cam.width_px = integer_in("width_px", cam.width_px, 64, 8192);
    cam.height_px = integer_in("height_px", cam.height_px, 64, 8192);
    cam.side_views = integer_in("side_views", cam.side_views, 1, 36);
    cam.height_m = number_in("height_m", cam.height_m, 0.0, 1.0, " m");
    cam.aim_at_axis_foot = c->boolean("aim_at_axis_foot", cam.aim_at_axis_foot);
    cam.k1 = number_in("k1", cam.k1, -0.5, 0.5, "");
    c->finish();
  }
  if (auto h = r.table("hidden", true)) {
    for (const std::string& k : h->keys()) {
      try {
        rules.check_effect(k);
      } catch (const std::invalid_argument& e) {
        h->fail(k, e.what());
      }
      d.hidden.emplace_back(k, h->number(k));
    }
    h->finish();
  }
  r.mark_used("test");
  const toml::array* tests = doc["test"].as_array();
  if (!tests || tests->empty()) r.fail("test", "at least one [[test]] table is required");
  const std::set<std::string>& columns = rules.numeric_columns;
  const std::set<std::string>& text_columns = rules.text_columns;
  for (std::size_t i = 0; i < tests->size(); ++i) {
    const toml::table* t = (*tests)[i].as_table();
    if (!t) r.fail("test", "entry " + std::to_string(i) + " must be a table");
    TableReader tr(*t, path, "test." + std::to_string(i));
    SynthTest st;
    st.id = tr.string("id");
    st.role = tr.string("role", st.role);
    for (const std::string& k : tr.keys()) {
      if (k == "id" || k == "role") continue;
      if (text_columns.count(k)) {
        st.labels[k] = tr.string(k);
        if (st.labels[k].empty() || st.labels[k].find_first_of(",\"\n") != std::string::npos)
          tr.fail(k, "= \"" + st.labels[k] + "\" must be a non-empty name without , or \"");
        continue;
      }
      if (!columns.count(k) && k.rfind("set:", 0) != 0)
        tr.fail(k, "is not a condition column (docs/loop.md)");
      st.conditions[k] = tr.number(k);
    }
    tr.finish();
    d.tests.push_back(st);
  }
  r.finish();
  return d;
}

}  // namespace reposetwin::experiments
