#include "experiments/report/run_summary.hpp"

#include <filesystem>
#include <map>

#include "experiments/io/format.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/pile/representativeness.hpp"
#include "experiments/pile/run_plan.hpp"
#include "experiments/report/format.hpp"
#include "experiments/report/html.hpp"
#include "experiments/report/templates.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;
using namespace report;

namespace {

std::string mm(double m, int digits = 1) { return fixed(1e3 * m, digits); }

std::string number_at(const json& j, const char* key, int digits = 2, double scale = 1.0) {
  return j.contains(key) && j[key].is_number() ? fixed(scale * j[key].get<double>(), digits)
                                               : std::string("-");
}

// The value of every measure of measure_definitions(), by its name, as the page prints it.
std::map<std::string, std::string> measure_values(const PileRun& run,
                                                  const std::optional<Headline>& h,
                                                  const std::optional<json>& images) {
  std::map<std::string, std::string> v;
  if (h) v["headline_angle_deg"] = mean_sd(h->angle_deg, h->angle_sd_deg) + " deg";
  if (images) {
    v["theta_deg"] = number_at(*images, "theta_deg") + " deg";
    v["flank_deg"] = number_at(*images, "flank_deg") + " deg";
    v["crest_width_m"] = number_at(*images, "crest_width_m", 1, 1e3) + " mm";
    v["height_m, diameter_m"] = number_at(*images, "height_m", 1, 1e3) + " mm, " +
                                number_at(*images, "diameter_m", 1, 1e3) + " mm";
    if (images->contains("top"))
      v["top.D_circle_m"] = number_at((*images)["top"], "D_circle_m", 1, 1e3) + " mm";
  }
  const PileMeasure& p = run.pile;
  if (!p.clogged && !p.not_measured) {
    v["pile.theta_hd_deg"] = fixed(p.theta_hd_deg) + " deg";
    v["pile.height_m, pile.base_diameter_m"] =
        mm(p.height_m) + " mm, " + mm(p.base_diameter_m) + " mm";
    v["pile.slice_angle_mean_deg"] = mean_sd(p.slice_angle_mean_deg, p.slice_angle_sd_deg) +
                                     " deg (" + std::to_string(p.valid_slices) + " slices)";
    v["pile.equal_area_angle_deg"] = fixed(p.equal_area_angle_deg) + " deg";
    v["pile.centre_of_mass_angle_deg"] = fixed(p.centre_of_mass_angle_deg) + " deg";
  }
  return v;
}

std::string measures_section(const PileRun& run, const std::optional<Headline>& h,
                             const std::optional<json>& images) {
  const auto values = measure_values(run, h, images);
  Table t;
  t.header = {"measure (field)", "value", "file", "definition"};
  for (const MeasureDefinition& d : measure_definitions()) {
    const auto it = values.find(d.name);
    Cell name;
    name.code = d.name;
    Cell def(d.definition);
    def.left = true;
    t.rows.push_back({{name, it == values.end() ? Cell("-") : Cell(it->second), Cell(d.where), def},
                      std::string(d.name) == "headline_angle_deg"});
  }
  mustache::data d;
  d.set("heading", std::string("Every measure, by name"));
  d.set("intro", std::string("Compare a lab's angle with headline_angle_deg only: the lab reads "
                             "atan(2H/D) from a side photo. The others differ on the same heap "
                             "by their definition, not by error (docs/measures.md)."));
  d.set("rows", to_data(t));
  return render(templates::kRunTable, d);
}

std::string run_photos_section(const RunSummaryInputs& in) {
  std::vector<Figure> figs;
  if (in.images) {
    for (const json& v : in.images->value("side_views", json::array())) {
      const std::string stem = fs::path(v.value("image", std::string())).stem().string();
      figs.push_back(
          {"images/" + stem + ".measured.png",
           "side, azimuth " + fixed(v.value("azimuth_deg", 0.0), 0) +
               " deg: atan(2H/D) = " + number_at(v, "theta_deg") + " deg, flank " +
               fixed(0.5 * (v.value("flank_left_deg", 0.0) + v.value("flank_right_deg", 0.0))) +
               " deg",
           560});
    }
    if (in.images->contains("top") && (*in.images)["top"].contains("D_circle_m"))
      figs.push_back(
          {"images/top.measured.png",
           "top: footprint circle " + number_at((*in.images)["top"], "D_circle_m", 1, 1e3) + " mm",
           560});
  }
  mustache::data d;
  d.set("photos", to_data(figs));
  d.set("none", text_or_false(in.images ? std::string() : "No photographs: " + in.images_note));
  return render(templates::kRunPhotos, d);
}

// A row of links to files of the run folder (relative, so a copied folder keeps them).
TableRow files_row(const std::vector<std::string>& files) {
  Cell k("files"), v;
  k.left = v.left = true;
  for (const std::string& f : files) v.links.push_back({f, f});
  return {{k, v}};
}

std::string table_section(const std::string& heading, std::vector<TableRow> rows) {
  Table t;
  t.header = {"what", "value"};
  t.rows = std::move(rows);
  mustache::data d;
  d.set("heading", heading);
  d.set("intro", false);
  d.set("rows", to_data(t));
  return render(templates::kRunTable, d);
}

std::string inputs_section(const PileRun& run, const SceneConfig& scene,
                           const RunSummaryInputs& in) {
  std::string sets;
  for (const std::string& s : in.overrides) sets += (sets.empty() ? "" : "  ") + s;
  const PsdRecord& psd = run.psd;
  const auto sample_pair = scene.contacts.find({scene.sample_material, scene.sample_material});
  std::string rolling = "-";
  if (sample_pair != scene.contacts.end()) {
    rolling = fixed(sample_pair->second.rolling_friction, 3);
    for (const auto& m : sim::kRollingModels)
      if (m.model == sample_pair->second.rolling_model)
        rolling += " (" + std::string(m.keyword) + ")";
  }
  return table_section(
      "Inputs", {text_row("scene", scene.name + " (" + path_for_page(scene.file) + ")"),
                 text_row("description", scene.description),
                 text_row("overrides (--set)", sets.empty() ? "none" : sets),
                 text_row("sample", fixed(scene.mass * 1e3, 1) + " g of " + scene.sample_material +
                                        ", seed " + std::to_string(scene.seed)),
                 text_row("sieve table", psd.name + " (" + path_for_page(psd.source) + ")"),
                 text_row("simulated sizes",
                          fixed(psd.d_min_drawn_mm, 2) + "-" + fixed(psd.d_max_drawn_mm, 2) +
                              " mm; " + fixed(100 * psd.fines_fraction_not_simulated, 1) +
                              "% of the mass finer than d_min = " + fixed(psd.d_min_mm, 2) +
                              " mm not simulated"),
                 text_row("container", scene.container.kind + ", outlet " +
                                           mm(scene.container.bottom_diameter, 0) + " mm, top " +
                                           mm(scene.container.top_diameter, 0) + " mm, height " +
                                           mm(scene.container.height, 0) + " mm, lifted at " +
                                           fixed(scene.procedure.lift_speed, 3) + " m/s"),
                 text_row("rolling friction (sample on sample)", rolling),
                 files_row({"scene.resolved.toml"})});
}

std::string provenance_section(const PileRun& run, const RunSummaryInputs& in) {
  const RunProvenance& p = run.provenance;
  std::vector<TableRow> rows = {
      text_row("code version", p.code_version),
      text_row("created (UTC)", p.created_utc),
      text_row("stop", stop_reason_text(run.stop) +
                           (run.stop.detail.empty() ? "" : ": " + run.stop.detail)),
      text_row("particles", std::to_string(run.particles.final) + " in the pile's world (" +
                                std::to_string(run.particles.initial) + " filled)"),
      text_row("time step", significant(p.time_step_s) + " s (Rayleigh time " +
                                significant(p.rayleigh_time_s) + " s)"),
      text_row("Young's modulus", p.softened_youngs_modulus_pa
                                      ? significant(*p.softened_youngs_modulus_pa) +
                                            " Pa (softened; real " +
                                            significant(p.youngs_modulus_real_pa) + " Pa)"
                                      : significant(p.youngs_modulus_real_pa) + " Pa"),
      text_row("steps, simulation wall time", std::to_string(run.performance.steps) + " steps, " +
                                                  duration_text(run.performance.wall_s) + " with " +
                                                  std::to_string(p.threads) + " thread(s)"),
      text_row("command wall time (photographs included)", duration_text(in.wall_s))};
  if (in.images) rows.push_back(text_row("renderer", in.images->value("gl", std::string("-"))));
  std::vector<std::string> files = {"result.json", "series.pvd", "final.vtp"};
  if (in.images) files.push_back("images/measurement.json");
  rows.push_back(files_row(files));
  return table_section("Provenance", std::move(rows));
}

std::string headline_section(const PileRun& run, const RunSummary& s, const RunSummaryInputs& in) {
  mustache::data d;
  if (!s.headline) {
    const NoHeadline& n = *s.no_headline;
    d.set("reason", n.message);
    d.set("advice", no_headline_advice(n.reason));
    d.set("particles", std::to_string(run.particles.final));
    return render(templates::kRunNoHeadline, d);
  }
  const Headline& h = *s.headline;
  d.set("angle", fixed(h.angle_deg));
  d.set("sd", h.from_images ? mustache::data(fixed(h.angle_sd_deg)) : mustache::data(false));
  d.set("measure", h.measure);
  d.set("views", h.views > 0 ? mustache::data(std::to_string(h.views) + " side views")
                             : mustache::data(false));
  d.set("H_mm", mm(h.height_m));
  d.set("D_mm", mm(h.diameter_m));
  d.set("particles", std::to_string(run.particles.final));
  d.set("note", text_or_false(!h.from_images ? "No photographs (" + in.images_note +
                                                   "): the headline is the particle "
                                                   "atan(2H/D), not the lab's measure."
                                             : std::string()));
  return render(templates::kRunHeadline, d);
}

// The run's representativeness (pile/representativeness.hpp): the height rule on the measured
// pile when there is one.
Representativeness run_representativeness(const PileRun& run, const SceneConfig& scene) {
  const bool measured =
      !run.pile.clogged && !run.pile.not_measured && run.pile.status != sim::PileStatus::kNoPile;
  return measured ? representativeness(scene, run.pile.height_m) : representativeness(scene);
}

std::string representativeness_section(const Representativeness& r) {
  mustache::data list(mustache::data::type::list);
  for (const std::string& w : r.warning_list()) {
    mustache::data item;
    item.set("text", w);
    list.push_back(item);
  }
  mustache::data d;
  d.set("warnings", list);
  d.set("rules", to_json(r)["rules"].get<std::string>());
  d.set("ok", r.warning_list().empty());
  return render(templates::kRunRepresentativeness, d);
}

}  // namespace

std::string run_summary_html(const PileRun& run, const SceneConfig& scene,
                             const RunSummaryInputs& in, const RunSummary& s) {
  const Page page{
      "ReposeTwin run: " + scene.name,
      "ReposeTwin run: " + scene.name,
      {headline_section(run, s, in), representativeness_section(run_representativeness(run, scene)),
       run_photos_section(in), measures_section(run, s.headline, in.images),
       inputs_section(run, scene, in), provenance_section(run, in)}};
  return render_page(page);
}

RunSummary run_headline(const PileRun& run, const RunSummaryInputs& in) {
  RunSummary s;
  s.no_headline = no_headline(run.stop, run.pile);
  if (!s.no_headline && !in.images_error.empty())
    s.no_headline = NoHeadline{NoHeadlineReason::kPhotographs,
                               "the photographs could not be taken: " + in.images_error};
  if (!s.no_headline)
    s.headline = in.images ? headline_from_images(*in.images) : headline_from_particles(run.pile);
  return s;
}

RunSummary summarise_run(const PileRun& run, const SceneConfig& scene, const RunSummaryInputs& in) {
  RunSummary s = run_headline(run, in);
  const fs::path dir(in.run_dir);
  const fs::path result = dir / "result.json";
  json r = read_json_file(result.string());
  // The fields a summary adds, all of them, so an earlier summary's (other views, a headline
  // that is now none) cannot survive beside this one.
  const json headline_fields = to_json(Headline{}), no_headline_fields = to_json(NoHeadline{});
  for (const json* fields : {&headline_fields, &no_headline_fields})
    for (const auto& [key, value] : fields->items()) r.erase(key);
  for (const char* key : {"representativeness", "image"}) r.erase(key);
  r.update(s.headline ? to_json(*s.headline) : to_json(*s.no_headline));
  r["representativeness"] = to_json(run_representativeness(run, scene));
  if (in.images && s.headline)
    r["image"] = {
        {"theta_deg", (*in.images)["theta_deg"]}, {"theta_sd_deg", (*in.images)["theta_sd_deg"]},
        {"height_m", (*in.images)["height_m"]},   {"diameter_m", (*in.images)["diameter_m"]},
        {"flank_deg", (*in.images)["flank_deg"]}, {"images", "images"}};
  if (in.images && s.headline && in.images->contains("crest_width_m"))
    r["image"]["crest_width_m"] = (*in.images)["crest_width_m"];
  write_json_atomic(result.string(), r);
  s.page = (dir / "summary.html").string();
  return s;
}

std::string write_run_summary_page(const PileRun& run, const SceneConfig& scene,
                                   const RunSummaryInputs& in, RunSummary& s) {
  s.page = (fs::path(in.run_dir) / "summary.html").string();
  write_file_atomic(s.page, run_summary_html(run, scene, in, s));
  return s.page;
}

RunSummary finish_run(const PileRun& run, const SceneConfig& scene, const RunSummaryInputs& in) {
  RunSummary s = summarise_run(run, scene, in);
  write_run_summary_page(run, scene, in, s);
  return s;
}

std::string headline_line(const PileRun& run, const RunSummary& s, double wall_s) {
  std::string line;
  if (s.headline) {
    const Headline& h = *s.headline;
    line = "angle of repose " + fixed(h.angle_deg) +
           (h.from_images ? " \u00b1 " + fixed(h.angle_sd_deg) : std::string()) + " deg (" +
           (h.from_images ? "image atan(2H/D), " + std::to_string(h.views) + " side views"
                          : "particle atan(2H/D): no photographs, --no-images") +
           "); H " + mm(h.height_m) + " mm, D " + mm(h.diameter_m) + " mm";
  } else {
    line = "no angle of repose: " + s.no_headline->message;
  }
  return line + "; " + std::to_string(run.particles.final) + " particles; wall " +
         duration_text(wall_s) + "; report " + s.page;
}

}  // namespace reposetwin::experiments
