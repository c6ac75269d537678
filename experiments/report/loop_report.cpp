// write_loop_html (loop_report.hpp): the loop's page, with the report's page skeleton and tables,
// from the LoopRecord loop.json reads into (loop_record_from_json): the errors before and after,
// the chosen effects, each iteration's trace and refit, the notes, the residuals with their plots
// (loop_plots.hpp), and each test's lab photo beside a twin photo at one scale. Reads loop.json
// and the files it names only (never simulates).
#include "experiments/report/loop_report.hpp"

#include <cmath>
#include <filesystem>
#include <optional>
#include <utility>

#include "experiments/io/provenance.hpp"
#include "experiments/report/format.hpp"
#include "experiments/report/html.hpp"
#include "experiments/report/loop_plots.hpp"
#include "experiments/report/templates.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;
using namespace report;

namespace {

Cell left(const std::string& text) {
  Cell c(text);
  c.left = true;
  return c;
}

Table numeric_table(std::vector<std::string> header) {
  Table t;
  t.header = std::move(header);
  t.numeric = true;
  return t;
}

// The width of the wider image of a pair on the page [px].
constexpr double kPairWidthPx = 560.0;

// A file the page names, as a link where it is in the page's folder, else as plain text that says
// so: a loop folder whose photos were left out (results/ keeps loop.json and the page, not the
// megabytes of photos the command re-makes) still opens without a broken image.
Cell file_cell(const fs::path& dir, const std::string& rel) {
  Cell c;
  c.left = true;
  const std::string name = fs::path(rel).filename().string();
  if (fs::is_regular_file(dir / rel))
    c.links = {{rel, name}};
  else
    c.text = name + " (not in this folder)";
  return c;
}

// One test's lab overlay beside the twin's at one mm per page pixel (CSS width from each image's
// own scale), and the files with their scales; the twin's alone where the lab gave no photo. An
// overlay missing from `dir` is not drawn; its numbers stay in the table.
mustache::data photo_pair_data(const PhotoPair& p, const fs::path& dir) {
  std::vector<std::pair<std::string, const PhotoView*>> views;
  if (p.lab) views.emplace_back("lab", &*p.lab);
  if (p.twin) views.emplace_back("twin", &*p.twin);
  std::vector<ScaledImage> images;
  for (const auto& view : views) images.push_back({view.second->width_px, view.second->mm_per_px});
  const double common = beside_scale(images, kPairWidthPx);
  std::vector<Figure> figures;
  int missing = 0;
  Table files = numeric_table(
      {"", "photo", "overlay", "mm per px", "size [px]", "on the page [px]", "atan(2H/D) [deg]"});
  for (std::size_t k = 0; k < views.size(); ++k) {
    const PhotoView& v = *views[k].second;
    const int width = static_cast<int>(std::lround(page_width(images[k], common)));
    std::string caption = views[k].first == "lab" ? "lab photo" : "twin photo";
    caption += ", vision atan(2H/D) " + sig3_or_dash(v.angle_deg) + " deg";
    if (views[k].first == "twin") {
      caption += "; mu_r " + sig3_or_dash(p.mu_r) + ", seed " + std::to_string(p.seed);
      for (const auto& [name, value] : p.effects)
        caption += ", " + name + " " + sig3_or_dash(value);
    }
    if (fs::is_regular_file(dir / v.overlay))
      figures.push_back({v.overlay, caption, width});
    else
      ++missing;
    files.rows.push_back({{left(views[k].first), file_cell(dir, v.photo), file_cell(dir, v.overlay),
                           sig3_or_dash(v.mm_per_px),
                           std::to_string(v.width_px) + " x " + std::to_string(v.height_px),
                           std::to_string(width), sig3_or_dash(v.angle_deg)}});
  }
  mustache::data x;
  x.set("id", p.id);
  std::string scale = views.size() > 1 ? "Both at " + sig3_or_dash(common) + " mm per page pixel."
                      : views.empty()  ? std::string()
                                       : "At " + sig3_or_dash(common) + " mm per page pixel.";
  if (!p.lab)
    scale += std::string(scale.empty() ? "" : " ") +
             "The lab gave no photo of this test (a typed angle).";
  x.set("scale", scale);
  x.set("any_figures", !figures.empty());
  x.set("figures", to_data(figures));
  std::string note = p.note;
  if (missing > 0)
    note += std::string(note.empty() ? "" : " ") + std::to_string(missing) +
            (missing == 1 ? " photo is" : " photos are") +
            " not in this folder (the loop's command makes them again); their scales and "
            "angles are in the table.";
  x.set("note", text_or_false(note));
  x.set("files", to_data(files));
  return x;
}

std::string loop_photos_section(const LoopRecord& loop, const fs::path& dir) {
  if (loop.photo_pairs.empty()) return "";
  mustache::data list(mustache::data::type::list);
  for (const PhotoPair& p : loop.photo_pairs) list.push_back(photo_pair_data(p, dir));
  mustache::data d;
  d.set("pairs", list);
  return render(templates::kLoopPhotos, d);
}

std::string intro_section(const LoopRecord& loop) {
  mustache::data d;
  d.set("data", path_for_page(loop.provenance.data));
  d.set("code", loop.provenance.code_version);
  d.set("finished", loop.provenance.finished);
  return render(templates::kLoopIntro, d);
}

std::string error_section(const LoopRecord& loop) {
  const LoopSummary& sum = loop.summary;
  Table t = numeric_table({"", "before (mu_r only)", "after"});
  t.rows.push_back(
      {{left("RMSE calibration tests [deg]"), sig3_or_dash(sum.rmse_calibrate_before_deg),
        sig3_or_dash(sum.rmse_calibrate_after_deg)}});
  t.rows.push_back({{left("RMSE held-out tests [deg]"), sig3_or_dash(sum.rmse_validate_before_deg),
                     sig3_or_dash(sum.rmse_validate_after_deg)}});
  // Held-out tests whose twin pours jammed are not in the RMSE: counted here, never dropped
  // silently.
  const std::size_t before = loop.baseline.rmse.n_no_pile, after = loop.final_model.rmse.n_no_pile;
  if (before + after > 0)
    t.rows.push_back({{left("held-out tests the twin forms no pile for"), std::to_string(before),
                       std::to_string(after)}});
  mustache::data d;
  d.set("errors", to_data(t));
  d.set("mu_r", sig3_or_dash(loop.baseline.fit.mu));
  d.set("mu_r_se", sig3_or_dash(loop.baseline.fit.mu_se));
  d.set("seed_sd", sig3_or_dash(loop.baseline.seed_sd_deg));
  return render(templates::kLoopError, d);
}

// Why no effect was chosen, from the last iteration.
std::string no_effect_reason(const LoopRecord& loop) {
  if (loop.not_traced) return "nothing was traced (the notes below say why).";
  if (loop.iterations.empty()) return "nothing was traced.";
  const IterationRecord& last = loop.iterations.back();
  const std::string n = std::to_string(last.iteration);
  if (last.not_confirmed)
    return last.not_confirmed->refit.name +
           " was refitted by simulation, and the simulations did not confirm it (iteration " + n +
           ").";
  if (last.refit_failed)
    return last.refit_failed->name + "'s refit could not be simulated (iteration " + n + ").";
  if (last.stopped) return *last.stopped + ".";
  const TraceVerdict v = last.decision.verdict;
  if (v == TraceVerdict::kMeasurementSuspected)
    return "the trace suspects a measurement or declared-condition error on every test and "
           "names no physical effect (the decision below).";
  // An iteration that could not trace (too few tests with a prediction) has no offset score.
  if (!last.offset) return last.decision.statement + ".";
  if (v == TraceVerdict::kIndistinguishable)
    return "the candidates that meet the rule explain the residual alike and none is named (the "
           "decision below).";
  return "no candidate beat the seed noise.";
}

std::string effects_section(const LoopRecord& loop) {
  mustache::data d;
  d.set("none", no_effect_reason(loop));
  if (loop.final_model.effects.empty()) {
    d.set("effects", false);
  } else {
    Table t = numeric_table({"effect", "kind", "value", "\u00b1 se", "units", "mu_r", "from"});
    for (const ChosenEffect& c : loop.final_model.effects)
      t.rows.push_back({{left(c.refit.name), left(c.kind), sig3_or_dash(c.value),
                         sig3_or_dash(c.value_se), left(c.units), sig3_or_dash(c.refit.mu_r),
                         left(c.declared ? "declared (--refit)" : "the trace")}});
    d.set("effects", to_data(t));
  }
  d.set("rule", std::string(acceptance_rule_text()));
  d.set("min_t", sig3_or_dash(loop.rule.min_t));
  d.set("margin", sig3_or_dash(loop.rule.loo_margin_factor * loop.baseline.seed_se_deg));
  return render(templates::kLoopEffects, d);
}

// The trials of a refit by simulation, with a column for the held-out tests that formed no pile
// at a trial's value when any did (loop_refit.cpp).
Table trials_table(const std::vector<RefitTrialRecord>& trials) {
  bool jams = false;
  for (const RefitTrialRecord& tr : trials) jams = jams || !tr.no_pile.empty();
  std::vector<std::string> header = {"simulated at", "response (probe = 1)", "t", "mu_r",
                                     "RMSE of the refit [deg]"};
  if (jams) header.push_back("no pile predicted (held out)");
  Table t = numeric_table(header);
  for (const RefitTrialRecord& tr : trials) {
    TableRow row{{sig3_or_dash(tr.simulated_at), sig3_or_dash(tr.response_fraction),
                  sig3_or_dash(tr.t), sig3_or_dash(tr.mu_r), sig3_or_dash(tr.rmse_calibrate_deg)}};
    if (jams) {
      std::string ids;
      for (const std::string& id : tr.no_pile) ids += (ids.empty() ? "" : ", ") + id;
      row.cells.push_back(left(ids.empty() ? "-" : ids));
    }
    t.rows.push_back(row);
  }
  return t;
}

// What became of an iteration's refit by simulation (loop.hpp's design note): its trials and
// the effect chosen, or why the simulations did not confirm it, or why none could be simulated.
// False when nothing was refitted (nothing named, or the effect limit stopped the loop).
mustache::data refit_data(const IterationRecord& it) {
  mustache::data d;
  d.set("trials", false);
  if (!it.not_confirmed && it.refit_failed) {
    const RefitFailed& f = *it.refit_failed;
    d.set("text", "Refit: " + f.name + " (linear estimate " + sig3_or_dash(f.linear_estimate) +
                      ") could not be simulated: " + paths_for_page(f.refit_failed) +
                      ". Nothing chosen.");
    return d;
  }
  const RefitSummary* r = it.not_confirmed ? &it.not_confirmed->refit
                          : it.chosen      ? &it.chosen->refit
                                           : nullptr;
  if (r == nullptr) return mustache::data(false);
  const Table t = trials_table(r->trials);
  std::string text = "Refit by simulation: " + r->name + ", linear estimate " +
                     sig3_or_dash(r->linear_estimate) + ", simulated on the whole grid";
  if (it.not_confirmed) {
    text += "; not confirmed: " + it.not_confirmed->reason + ". Nothing chosen.";
  } else {
    const ChosenEffect& c = *it.chosen;
    text += "; confirmed: " + r->name + " " + sig3_or_dash(c.value) + " \u00b1 " +
            sig3_or_dash(c.value_se) + (c.units == "-" ? "" : " " + c.units) + " at mu_r " +
            sig3_or_dash(r->mu_r) + ".";
  }
  if (!r->refit_notes.empty()) text += " Notes: " + paths_for_page(r->refit_notes);
  if (it.set_aside)
    text = "The trace named " + it.set_aside->refit.name +
           "; its simulated refit was set aside: " + it.set_aside->reason + ". " + text;
  d.set("text", text);
  if (!t.rows.empty()) d.set("trials", to_data(t));
  return d;
}

// The joint trace's table: each candidate, then the offset and the mu_r-only hypotheses, with
// the mu_r each was fitted at jointly.
mustache::data joint_data(const IterationRecord& it) {
  Table j = numeric_table(
      {"hypothesis", "c", "se", "|c|/se", "mu_r", "joint chi2", "LOO chi2", "values"});
  std::vector<JointScore> rows = it.joint;
  if (it.offset) rows.push_back(*it.offset);
  if (it.mu_only) rows.push_back(*it.mu_only);
  for (const JointScore& c : rows)
    j.rows.push_back({{left(c.name), sig3_or_dash(c.coef), sig3_or_dash(c.coef_se),
                       sig3_or_dash(c.t), sig3_or_dash(it.mu_r + c.mu_shift), sig3_or_dash(c.chi2),
                       sig3_or_dash(c.loo_chi2), sig3_or_dash(static_cast<double>(c.rows))}});
  std::string channels;
  for (const std::string& c : it.channels) channels += (channels.empty() ? "" : ", ") + c;
  mustache::data jd = to_data(j);
  jd.set("channels", channels);
  return jd;
}

mustache::data iteration_data(const IterationRecord& it) {
  Table t = numeric_table(
      {"candidate", "c", "se", "|c|/se", "LOO RMSE", "LOO gain", "explained", "accepted"});
  for (const CandidateScore& c : it.candidates)
    t.rows.push_back({{left(c.name), sig3_or_dash(c.coef), sig3_or_dash(c.coef_se),
                       sig3_or_dash(c.t), sig3_or_dash(c.loo_rmse), sig3_or_dash(c.loo_gain),
                       sig3_or_dash(c.explained), c.accepted ? "yes" : "no"}});
  auto optional_text = [](const std::optional<std::string>& s) {
    return s ? mustache::data(*s) : mustache::data(false);
  };
  mustache::data x;
  x.set("n", std::to_string(it.iteration));
  x.set("mu_r", sig3_or_dash(it.mu_r));
  x.set("loo", sig3_or_dash(it.null.loo_rmse));
  x.set("candidates", to_data(t));
  x.set("stopped", optional_text(it.stopped));
  x.set("declared", optional_text(it.declared));
  std::string decision = it.decision.statement;
  for (const std::string& why : it.tests_left_out) decision += "; not traced, " + why;
  x.set("decision", decision);
  x.set("joint", it.joint.empty() ? mustache::data(false) : joint_data(it));
  x.set("refit", refit_data(it));
  return x;
}

std::string iterations_section(const LoopRecord& loop) {
  mustache::data list(mustache::data::type::list);
  for (const IterationRecord& it : loop.iterations) list.push_back(iteration_data(it));
  mustache::data d;
  d.set("iterations", list);
  return render(templates::kLoopIterations, d);
}

// Pours that jammed in the baseline (repeated with new seeds; a lab reports none), the
// candidates the loop could not try, the design's statements and the grid.
std::string notes_section(const LoopRecord& loop) {
  mustache::data jams(mustache::data::type::list);
  for (const BaselineCurve& c : loop.baseline.curves) {
    int n = 0;
    for (int x : c.clogged_pours) n += x;
    if (n <= 0) continue;
    mustache::data j;
    j.set("id", c.id);
    j.set("n", std::to_string(n));
    jams.push_back(j);
  }
  mustache::data unavailable(mustache::data::type::list);
  for (const UnavailableCandidate& u : loop.unavailable) {
    mustache::data x;
    x.set("name", u.name);
    x.set("why", paths_for_page(u.why));
    unavailable.push_back(x);
  }
  auto listed = [](mustache::data items) {
    if (items.is_empty_list()) return mustache::data(false);
    mustache::data d;
    d.set("list", items);
    return d;
  };
  auto strings = [](const std::vector<std::string>& v) {
    mustache::data l(mustache::data::type::list);
    for (const std::string& s : v) l.push_back(mustache::data(s));
    return l;
  };
  mustache::data d;
  d.set("can", listed(strings(loop.design.can)));
  d.set("cannot", listed(strings(loop.design.cannot)));
  d.set("grid", loop.grid.statement);
  d.set("not_traced", loop.not_traced ? mustache::data(*loop.not_traced) : mustache::data(false));
  d.set("jams", listed(jams));
  d.set("unavailable", listed(unavailable));
  return render(templates::kLoopNotes, d);
}

// The residual table: each test measured, predicted before and after, its residuals and noise;
// the crest width (a fourth observable) gets its columns only where the lab measured it.
Table residual_table(const LoopRecord& loop) {
  const std::vector<LabTest>& tests = loop.tests;
  bool crest = false;
  for (const LabTest& t : tests) crest = crest || t.crest_mm.has_value();
  std::vector<std::string> header = {
      "test", "role", "measured", "before", "after", "residual before", "residual after", "sigma"};
  if (crest)
    for (const char* h : {"crest measured [mm]", "crest before [mm]", "crest after [mm]"})
      header.push_back(h);
  Table t = numeric_table(header);
  // A held-out test the twin's pours jammed for reads "no pile", not a number.
  auto predicted = [](const ResidualRow& r) {
    return r.no_pile.empty() ? Cell(sig3_or_dash(r.predicted_deg)) : left("no pile");
  };
  auto crest_cell = [](const std::optional<double>& v) {
    return v ? Cell(sig3_or_dash(*v)) : left("-");
  };
  for (std::size_t i = 0; i < tests.size(); ++i) {
    const ResidualRow& before = loop.baseline.residuals[i];
    const ResidualRow& after = loop.final_model.residuals[i];
    TableRow row{{left(tests[i].id), left(role_name(tests[i].role)),
                  sig3_or_dash(tests[i].angle_deg), predicted(before), predicted(after),
                  sig3_or_dash(before.residual_deg), sig3_or_dash(after.residual_deg),
                  sig3_or_dash(before.sigma_deg)}};
    if (crest)
      for (const std::optional<double>& v :
           {tests[i].crest_mm, before.predicted_crest_mm, after.predicted_crest_mm})
        row.cells.push_back(crest_cell(v));
    t.rows.push_back(row);
  }
  return t;
}

std::string residuals_section(const LoopRecord& loop, const fs::path& plot_dir) {
  std::string same;
  for (const auto& [k, v] : constant_conditions(loop.tests))
    same += std::string(same.empty() ? "" : ", ") + k + " " + v;
  mustache::data d;
  d.set(
      "constant",
      text_or_false(same.empty() ? same : "The same on every test, so not plotted: " + same + "."));
  d.set("plots", to_data(residual_figures(loop, plot_dir)));
  d.set("residuals", to_data(residual_table(loop)));
  mustache::data no_pile(mustache::data::type::list);
  for (const auto& [when, rows] : {std::pair{"Before", &loop.baseline.residuals},
                                   std::pair{"After", &loop.final_model.residuals}})
    for (const ResidualRow& r : *rows)
      if (!r.no_pile.empty())
        no_pile.push_back(mustache::data(std::string(when) + ", " + r.no_pile));
  d.set("no_pile", no_pile);
  return render(templates::kLoopResiduals, d);
}

}  // namespace

void write_loop_page(const LoopRecord& loop, const std::string& out_dir) {
  const fs::path plot_dir = fs::path(out_dir) / "plots";
  fs::create_directories(plot_dir);
  const Page page{
      "ReposeTwin loop",
      "Closing the loop",
      {intro_section(loop), error_section(loop), effects_section(loop), iterations_section(loop),
       notes_section(loop), residuals_section(loop, plot_dir), loop_photos_section(loop, out_dir)}};
  // Recorded as made by reposetwin (io/files.hpp): `loop -o .` then replaces only its own page.
  write_made_file((fs::path(out_dir) / "index.html").string(), render_page(page));
}

void write_loop_html(const json& loop, const std::string& out_dir) {
  write_loop_page(loop_record_from_json(loop, (fs::path(out_dir) / "loop.json").string()), out_dir);
}

}  // namespace reposetwin::experiments
