#include "experiments/calibration/campaign_target.hpp"
#include "experiments/reproduce/paper_index.hpp"

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>

#include "experiments/calibration/calibration_file.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/scene_overrides.hpp"
#include "experiments/io/toml_reader.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
namespace {

// "FILE: key 'KEY' = VALUE: why", the shape of every input message.
InputError bad(const std::string& file, const std::string& key, const std::string& value,
               const std::string& why) {
  return InputError(file + ": key '" + key + "'" + (value.empty() ? "" : " = " + value) + ": " +
                    why);
}

std::string in_quotes(const std::string& s) { return "\"" + s + "\""; }

PaperPoints read_points(TableReader& t, const std::string& file) {
  t.known_keys({"x_label", "y_label", "x", "y", "source"});
  PaperPoints p;
  p.x_label = t.string("x_label", "");
  p.y_label = t.string("y_label", p.y_label);
  p.x = t.numbers("x");
  p.y = t.numbers("y");
  p.source = t.string("source");
  if (p.x.empty() || p.x.size() != p.y.size())
    throw bad(file, t.where("y"), show_node(*t.raw().get("y")),
              "needs one value per x (" + std::to_string(p.x.size()) + " x values)");
  for (double a : p.y)
    if (!(a >= 0.0 && a <= 90.0))
      throw bad(file, t.where("y"), show_node(*t.raw().get("y")), "values must lie in [0, 90]");
  return p;
}

PaperLevels read_levels(TableReader& t, const std::string& file) {
  t.known_keys({"y", "source"});
  PaperLevels p;
  p.y = t.numbers("y");
  p.source = t.string("source");
  if (p.y.empty()) throw bad(file, t.where("y"), "[]", "needs at least one level");
  for (double a : p.y)
    if (!(a >= 0.0 && a <= 90.0))
      throw bad(file, t.where("y"), show_node(*t.raw().get("y")), "values must lie in [0, 90]");
  return p;
}

// The item's campaign or calibration file, loaded to check it; the load's own message (which
// names that file, its key and value) is kept behind the index's key.
void check_item_file(const PaperItem& item, TableReader& t, const std::string& written) {
  const std::string key = t.where("file");
  std::error_code ec;
  if (!fs::is_regular_file(item.file, ec))
    throw bad(t.file(), key, in_quotes(written), "no such file (" + item.file + ")");
  Campaign c;
  try {
    c = load_campaign(item.file);
  } catch (const std::exception& e) {
    throw bad(t.file(), key, in_quotes(written), std::string("does not load: ") + e.what());
  }
  if (item.kind == PaperItemKind::kCalibration && !c.calibration)
    throw bad(t.file(), key, in_quotes(written),
              "kind = \"calibration\" but the file has no [calibration]");
  if (item.kind == PaperItemKind::kCampaign && c.runs.empty())
    throw bad(t.file(), key, in_quotes(written),
              "kind = \"campaign\" but the file has no [[case]] or [sweep]");
}

PaperItem read_item(TableReader& t, const fs::path& base) {
  const std::string& file = t.file();
  t.known_keys({"name", "paper", "kind", "file", "from", "calibrated_by", "reductions", "x_key",
                "x_label", "x_scale", "x_range", "trend", "paper_points", "paper_levels", "angle",
                "if_not_calibrated"});
  PaperItem item;
  item.name = t.string("name");
  if (!is_safe_name(item.name))
    throw bad(file, t.where("name"), in_quotes(item.name),
              "must be a folder name ([A-Za-z0-9][A-Za-z0-9._-]*)");
  item.paper = t.string("paper");
  const std::string kind = t.string("kind");
  if (kind == "campaign") {
    item.kind = PaperItemKind::kCampaign;
  } else if (kind == "calibration") {
    item.kind = PaperItemKind::kCalibration;
  } else if (kind == "derived") {
    item.kind = PaperItemKind::kDerived;
  } else {
    throw bad(file, t.where("kind"), in_quotes(kind),
              "must be \"campaign\", \"calibration\" or \"derived\"");
  }
  std::string written;
  if (item.kind == PaperItemKind::kDerived) {
    if (t.has("file"))
      throw bad(file, t.where("file"), show_node(*t.raw().get("file")),
                "a derived item runs nothing: it names its sources in `from`");
    t.mark_used("from");
    const toml::node* f = t.raw().get("from");
    const toml::array* a = f ? f->as_array() : nullptr;
    if (!a || a->empty())
      throw bad(file, t.where("from"), f ? show_node(*f) : "",
                "a derived item needs a list of the calibration items it is drawn from");
    for (const auto& e : *a) {
      if (!e.is_string())
        throw bad(file, t.where("from"), show_node(*f), "must be a list of item names");
      item.from.push_back(e.as_string()->get());
    }
  } else {
    written = t.string("file");
    item.file = (base / written).lexically_normal().string();
  }
  item.reductions = t.string("reductions");
  if (item.reductions.empty())
    throw bad(file, t.where("reductions"), "\"\"", "state the reductions (or \"none\")");
  item.x_key = t.string("x_key", "");
  item.x_label = t.string("x_label", item.x_key);
  item.x_scale = t.number("x_scale", 1.0);
  if (!(item.x_scale > 0.0))
    throw bad(file, t.where("x_scale"), show_node(*t.raw().get("x_scale")), "must be > 0");
  if (t.has("x_range")) {
    const std::vector<double> r = t.numbers("x_range");
    if (r.size() != 2 || !(r[1] > r[0]))
      throw bad(file, t.where("x_range"), show_node(*t.raw().get("x_range")),
                "must be [lo, hi] with lo < hi");
    item.x_range = std::pair{r[0], r[1]};
  }
  item.trend = t.string("trend", "");
  if (auto pts = t.table("paper_points", true)) item.paper_points = read_points(*pts, file);
  if (auto lv = t.table("paper_levels", true)) item.paper_levels = read_levels(*lv, file);
  item.calibrated_by = t.string("calibrated_by", "");
  if (!item.calibrated_by.empty() && item.kind != PaperItemKind::kCalibration)
    throw bad(file, t.where("calibrated_by"), in_quotes(item.calibrated_by),
              "only a calibration item reuses another's calibration");
  const std::string if_not = t.string("if_not_calibrated", "skip");
  if (if_not != "skip" && if_not != "closest_point")
    throw bad(file, t.where("if_not_calibrated"), in_quotes(if_not),
              "must be \"skip\" or \"closest_point\"");
  if (t.has("if_not_calibrated") && item.calibrated_by.empty())
    throw bad(file, t.where("if_not_calibrated"), in_quotes(if_not),
              "only an item with calibrated_by reuses another's calibration");
  item.closest_if_not_calibrated = if_not == "closest_point";
  item.angle = t.string("angle", "image");
  parse_angle_measure(item.angle, file + ": key '" + t.where("angle") + "'");
  t.finish();
  if (item.kind != PaperItemKind::kDerived) check_item_file(item, t, written);
  return item;
}

// An item reusing another's calibration must ask the same question, or predict-only would refuse
// it after hours: same campaign name, keys, target, mu_r range and angle.
void check_same_calibration(const PaperIndex& idx, const PaperItem& item, TableReader& t) {
  const auto it = std::find_if(idx.items.begin(), idx.items.end(),
                               [&](const PaperItem& p) { return p.name == item.calibrated_by; });
  if (it == idx.items.end() || it->kind != PaperItemKind::kCalibration ||
      !it->calibrated_by.empty())
    throw bad(idx.file, t.where("calibrated_by"), in_quotes(item.calibrated_by),
              "must name a calibration item listed before this one that calibrates itself");
  const Campaign a = load_campaign(it->file), b = load_campaign(item.file);
  const CampaignCalibration &ca = *a.calibration, &cb = *b.calibration;
  std::string differs;
  if (a.name != b.name)
    differs = "campaign name (" + a.name + " / " + b.name + ")";
  else if (ca.keys != cb.keys)
    differs = "calibration.key";
  else if (ca.target.angle_deg != cb.target.angle_deg)
    differs = "calibration.target_deg";
  else if (ca.settings.mu_r_lo != cb.settings.mu_r_lo || ca.settings.mu_r_hi != cb.settings.mu_r_hi)
    differs = "calibration.mu_r_range";
  else if (ca.angle != cb.angle)
    differs = "calibration.angle";
  else if (ca.method != cb.method)
    differs = "calibration.method";
  if (!differs.empty())
    throw bad(idx.file, t.where("calibrated_by"), in_quotes(item.calibrated_by),
              "its file and " + item.file + " differ in " + differs +
                  ": the calibration would not carry over");
}

}  // namespace

PaperIndex load_paper_index(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError(path + ": paper index file not found");
  PaperIndex idx;
  idx.file = fs::absolute(fs::path(path)).lexically_normal().string();
  const toml::table doc = parse_toml(read_file(idx.file), idx.file);
  TableReader root(doc, idx.file);
  root.known_keys({"title", "budget_cpu_hours", "item"});
  idx.title = root.string("title", "");
  idx.budget_cpu_hours = root.number("budget_cpu_hours", idx.budget_cpu_hours);
  if (!(idx.budget_cpu_hours > 0.0))
    throw bad(idx.file, "budget_cpu_hours", show_node(*doc.get("budget_cpu_hours")), "must be > 0");
  root.mark_used("item");
  const toml::node* n = doc.get("item");
  const toml::array* arr = n ? n->as_array() : nullptr;
  if (!arr || !arr->is_array_of_tables() || arr->empty())
    throw bad(idx.file, "item", n ? show_node(*n) : "", "needs one or more [[item]] tables");
  root.finish();
  const fs::path base = fs::path(idx.file).parent_path();
  std::set<std::string> names;
  for (std::size_t i = 0; i < arr->size(); ++i) {
    TableReader t(*arr->get(i)->as_table(), idx.file, "item[" + std::to_string(i) + "]");
    PaperItem item = read_item(t, base);
    if (!names.insert(item.name).second)
      throw bad(idx.file, t.where("name"), in_quotes(item.name), "another item has this name");
    if (!item.calibrated_by.empty()) check_same_calibration(idx, item, t);
    for (const std::string& src : item.from) {
      const auto it = std::find_if(idx.items.begin(), idx.items.end(),
                                   [&](const PaperItem& p) { return p.name == src; });
      if (it == idx.items.end() || it->kind != PaperItemKind::kCalibration)
        throw bad(idx.file, t.where("from"), in_quotes(src),
                  "must name a calibration item listed before this one");
    }
    idx.items.push_back(std::move(item));
  }
  return idx;
}

namespace {

PlanGroup plan_group(const std::string& label, const CaseSpec& spec, int runs,
                     const PlanSettings& settings) {
  SceneDoc doc = build_case_scene(spec);
  doc.set_seed(spec.seed);
  const SceneConfig scene = doc.config();
  PlanGroup g;
  g.label = label;
  g.runs = runs;
  g.plan = plan_run(scene, 1, settings);
  g.softened_e_pa = scene.settings.softened_youngs_modulus;
  g.rayleigh_fraction = scene.settings.rayleigh_fraction;
  g.clumps = !scene.shapes.empty();
  return g;
}

}  // namespace

ItemPlan plan_item(const PaperItem& item, const PlanSettings& settings) {
  ItemPlan p;
  if (item.kind == PaperItemKind::kDerived) return p;
  const Campaign c = load_campaign(item.file);
  if (item.kind == PaperItemKind::kCampaign) {
    std::map<std::string, std::size_t> group_of;
    for (const CaseSpec& s : c.runs) {
      if (auto it = group_of.find(s.case_name); it != group_of.end()) {
        ++p.groups[it->second].runs;
        continue;
      }
      group_of[s.case_name] = p.groups.size();
      p.groups.push_back(plan_group(s.case_name, s, 1, settings));
    }
  } else {
    const CampaignCalibration& cc = *c.calibration;
    const double mid = 0.5 * (cc.settings.mu_r_lo + cc.settings.mu_r_hi);
    const double mu =
        cc.method == CalibrationMethod::kBracket ? cc.bracket.mu_r_start.value_or(mid) : mid;
    if (item.calibrated_by.empty())
      p.groups.push_back(plan_group("calibration", calibration_run(c, mu, cc.settings.first_seed),
                                    cc.settings.max_simulations, settings));
    for (const PredictionCase& q : c.predictions) {
      const int runs = static_cast<int>(q.seeds.size()) * (q.interval_ends ? 3 : 1);
      if (runs > 0)
        p.groups.push_back(plan_group("predict " + q.name,
                                      prediction_run(c, q, mu, q.seeds.front()), runs, settings));
    }
  }
  for (const PlanGroup& g : p.groups) {
    p.runs += g.runs;
    p.cpu_hours += g.runs * g.plan.wall_s / 3600.0;
  }
  return p;
}

ItemStatus item_status(const PaperItem& item, const std::string& out_dir) {
  ItemStatus st{"not started", 0, ""};
  const fs::path dir = out_dir;
  std::error_code ec;
  if (item.kind == PaperItemKind::kDerived) return {"derived", 0, "drawn from its sources"};
  if (!fs::is_directory(dir, ec)) return st;
  const Campaign c = load_campaign(item.file);
  if (item.kind == PaperItemKind::kCampaign) {
    const nlohmann::json m = campaign_manifest(c, out_dir);
    const auto& n = m["counts"];
    st.finished = n["finished"].get<int>();
    const int failed = n["failed"].get<int>(), total = n["total"].get<int>();
    st.state = st.finished == total ? "done" : failed > 0 ? "failed" : "partial";
    st.detail = std::to_string(st.finished) + " of " + std::to_string(total) + " runs finished" +
                (failed ? ", " + std::to_string(failed) + " failed" : "");
    return st;
  }
  if (fs::is_directory(dir / "cases", ec))
    for (const auto& e : fs::recursive_directory_iterator(dir / "cases", ec))
      if (e.path().filename() == "result.json") ++st.finished;
  const fs::path cal = dir / "calibration.json";
  if (!fs::is_regular_file(cal, ec)) {
    st.state = st.finished > 0 ? "partial" : "not started";
    st.detail = std::to_string(st.finished) + " runs finished, calibration not finished";
    return st;
  }
  const CalibrationRecord j = read_calibration_record(cal.string());
  if (!j.mu_r) {
    st.state = "cannot reach";
    st.detail = j.message;
    return st;
  }
  std::set<std::string> predicted;
  if (fs::is_regular_file(dir / "predictions.json", ec)) {
    const nlohmann::json p = read_json_file((dir / "predictions.json").string());
    for (const auto& q : p.value("predictions", nlohmann::json::array()))
      predicted.insert(q.value("name", std::string()));
  }
  int missing = 0;
  for (const PredictionCase& q : c.predictions) missing += predicted.count(q.name) ? 0 : 1;
  st.state = missing == 0 ? "done" : "partial";
  st.detail = "mu_r " + std::to_string(*j.mu_r) + " (" + to_string(j.status) + ", " +
              std::to_string(j.simulations) + " pile runs)" +
              (missing ? ", " + std::to_string(missing) + " prediction(s) to run" : std::string());
  return st;
}

nlohmann::json to_json(const PaperItem& item, const ItemPlan& plan) {
  nlohmann::json groups = nlohmann::json::array();
  for (const PlanGroup& g : plan.groups)
    groups.push_back({{"label", g.label},
                      {"runs", g.runs},
                      {"particles", g.plan.particles},
                      {"d_min_mm", g.plan.d_min_mm},
                      {"d_max_mm", g.plan.d_max_mm},
                      {"fines_fraction_not_simulated", g.plan.fines_fraction},
                      {"softened_youngs_modulus_pa", g.softened_e_pa},
                      {"time_step_s", g.plan.time_step_s},
                      {"rayleigh_fraction", g.rayleigh_fraction},
                      {"steps", g.plan.steps},
                      {"clumps", g.clumps},
                      {"cpu_hours_per_run", g.plan.wall_s / 3600.0}});
  nlohmann::json j = {{"name", item.name},
                      {"paper", item.paper},
                      {"kind", item.kind == PaperItemKind::kCampaign      ? "campaign"
                               : item.kind == PaperItemKind::kCalibration ? "calibration"
                                                                          : "derived"},
                      {"from", item.from},
                      {"file", item.file},
                      {"reductions", item.reductions},
                      {"x_key", item.x_key},
                      {"x_label", item.x_label},
                      {"x_scale", item.x_scale},
                      {"angle", item.angle},
                      {"trend", item.trend},
                      {"planned_runs", plan.runs},
                      {"planned_cpu_hours", plan.cpu_hours},
                      {"rate_particle_steps_per_s", PlanSettings{}.particle_steps_per_s_per_thread},
                      {"groups", groups}};
  if (item.paper_points)
    j["paper_points"] = {{"x_label", item.paper_points->x_label},
                         {"y_label", item.paper_points->y_label},
                         {"x", item.paper_points->x},
                         {"y", item.paper_points->y},
                         {"source", item.paper_points->source}};
  if (item.paper_levels)
    j["paper_levels"] = {{"y", item.paper_levels->y}, {"source", item.paper_levels->source}};
  return j;
}

CodeCommit code_commit(const std::string& version) {
  CodeCommit c;
  const auto plus = version.find('+');
  std::string rest = plus == std::string::npos ? version : version.substr(plus + 1);
  const std::string tag = "-dirty";
  if (rest.size() >= tag.size() && rest.compare(rest.size() - tag.size(), tag.size(), tag) == 0) {
    c.dirty = true;
    rest.resize(rest.size() - tag.size());
  }
  c.commit = rest;
  return c;
}

}  // namespace reposetwin::experiments
