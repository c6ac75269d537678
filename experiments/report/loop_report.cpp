// write_loop_html (loop_report.hpp): the loop's page, with the report's page skeleton, tables and
// plotting. Tables from loop.json, gnuplot plots of the residuals against each condition (text
// conditions as categories, the size distribution as series and categories of its own), before
// and after the chosen effects, and each test's lab photo beside a twin photo at one scale.
// Reads loop.json and the files it names only (never simulates).
#include "experiments/report/loop_report.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "experiments/io/json_fields.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/loop/loop.hpp"
#include "experiments/report/format.hpp"
#include "experiments/report/gnuplot.hpp"
#include "experiments/report/html.hpp"
#include "experiments/report/templates.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;
using namespace report;

namespace {

Cell left(const json& v) {
  Cell c(v.is_string() ? v.get<std::string>() : v.dump());
  c.left = true;
  return c;
}

Table numeric_table(std::vector<std::string> header) {
  Table t;
  t.header = std::move(header);
  t.numeric = true;
  return t;
}

// One residual point: a test's residual before and after, at its value of one condition.
struct ResidualPoint {
  double x = 0.0;                                 // the condition's value, or its category's index
  double before = 0.0, after = 0.0, sigma = 0.0;  // [deg]
  bool calibrate = false;
};

// The residuals against one condition, in series (one per size distribution when the tests
// differ in it, so that a PSD is not lost on another condition's axis).
struct ResidualPlot {
  std::string condition;                // axis label
  std::vector<std::string> categories;  // the x tick labels of a text condition; empty: numbers
  std::vector<std::string> series;      // names (one unnamed series when there is one)
  std::vector<std::vector<ResidualPoint>> points;  // per series
};

// A test's size distribution in words: its size band (d_min_mm, d_max_mm) and any PSD scene
// key of a set: column (a sieve table file, its cut-offs); "" when the test declares none.
std::string psd_label(const json& test) {
  std::string label;
  auto add = [&label](const std::string& s) { label += (label.empty() ? "" : ", ") + s; };
  const json& c = test.at("conditions");
  if (c.contains("d_min_mm") || c.contains("d_max_mm"))
    add((c.contains("d_min_mm") ? sig3(c["d_min_mm"]) : std::string("?")) + "-" +
        (c.contains("d_max_mm") ? sig3(c["d_max_mm"]) : std::string("?")) + " mm");
  auto psd_key = [](const std::string& k) { return k.rfind("set:sample.psd", 0) == 0; };
  for (const auto& [k, v] : c.items())
    if (psd_key(k)) add(short_key(k.substr(4)) + " " + sig3(v));
  const json text = test.value("text_conditions", json::object());
  for (const auto& [k, v] : text.items())
    if (psd_key(k)) add(fs::path(v.get<std::string>()).filename().string());
  return label;
}

// A test's numeric conditions by column, with the declared camera height (a column the loop
// keeps apart from the scene's conditions).
json numeric_conditions(const json& test) {
  json c = test.at("conditions");
  if (test.contains("camera_height_m")) c["camera_height_m"] = test["camera_height_m"];
  return c;
}

// The conditions every test has at one value, as "name value": a residual plot against one is a
// single column of points that tells nothing, so the page names them instead of plotting them.
std::map<std::string, std::string> constant_conditions(const json& tests) {
  std::map<std::string, std::set<std::string>> values;
  std::map<std::string, std::size_t> count;
  for (const json& t : tests) {
    const json numbers = numeric_conditions(t);
    for (const auto& [k, v] : numbers.items()) {
      values[k].insert(sig3(v));
      ++count[k];
    }
    const json words = t.value("text_conditions", json::object());
    for (const auto& [k, v] : words.items()) {
      if (k.rfind("set:sample.psd", 0) == 0) continue;  // shown on the PSD's own plot
      values[k].insert(v.get<std::string>());
      ++count[k];
    }
  }
  std::map<std::string, std::string> constant;
  for (const auto& [k, v] : values)
    if (v.size() == 1 && count[k] == tests.size()) constant[k] = *v.begin();
  return constant;
}

// Every plot: each numeric condition on its axis, each text condition (a plate material) as
// categories, and the size distribution as categories of its own when the tests differ in it;
// none against a condition every test has at one value (constant_conditions).
std::vector<ResidualPlot> residual_plots(const json& loop) {
  const json& tests = loop.at("tests");
  const json& before = loop.at("baseline").at("residuals");
  const json& after = loop.at("final").at("residuals");
  std::vector<std::string> psd;
  std::set<std::string> psds;
  for (const json& t : tests) psds.insert(psd.emplace_back(psd_label(t)));
  const bool split = psds.size() > 1;
  const std::vector<std::string> psd_names(psds.begin(), psds.end());
  auto point = [&](std::size_t i, double x) {
    return ResidualPoint{x, json_number(before[i]["residual_deg"]),
                         json_number(after[i]["residual_deg"]), json_number(before[i]["sigma_deg"]),
                         tests[i]["role"] == "calibrate"};
  };
  auto series_of = [&](std::size_t i) -> std::size_t {
    if (!split) return 0;
    return static_cast<std::size_t>(std::find(psd_names.begin(), psd_names.end(), psd[i]) -
                                    psd_names.begin());
  };
  auto empty_plot = [&](const std::string& condition) {
    ResidualPlot p;
    p.condition = condition;
    if (split)
      for (const std::string& n : psd_names)
        p.series.push_back("PSD " + (n.empty() ? "of the scene" : n));
    else
      p.series.push_back("");
    p.points.resize(p.series.size());
    return p;
  };
  const std::map<std::string, std::string> constant = constant_conditions(tests);
  std::set<std::string> numeric, text;
  for (const json& t : tests) {
    const json numbers = numeric_conditions(t);
    for (const auto& [k, v] : numbers.items())
      if (!constant.count(k)) numeric.insert(k);
    const json words = t.value("text_conditions", json::object());
    for (const auto& [k, v] : words.items())
      if (k.rfind("set:sample.psd", 0) != 0 && !constant.count(k)) text.insert(k);
  }
  std::vector<ResidualPlot> plots;
  for (const std::string& c : numeric) {
    ResidualPlot& p = plots.emplace_back(empty_plot(c));
    for (std::size_t i = 0; i < tests.size(); ++i)
      if (const json v = numeric_conditions(tests[i]); v.contains(c))
        p.points[series_of(i)].push_back(point(i, json_number(v[c])));
  }
  // A category axis: the tests' values of `value_of` (empty: the test has none), sorted.
  auto categorical = [&](const std::string& c, auto value_of) {
    ResidualPlot p;
    p.condition = c;
    p.series = {std::string()};
    p.points.resize(1);
    std::set<std::string> values;
    for (std::size_t i = 0; i < tests.size(); ++i)
      if (!value_of(i).empty()) values.insert(value_of(i));
    p.categories.assign(values.begin(), values.end());
    for (std::size_t i = 0; i < tests.size(); ++i) {
      const std::string v = value_of(i);
      if (v.empty()) continue;
      const auto at = std::find(p.categories.begin(), p.categories.end(), v);
      p.points[0].push_back(point(i, static_cast<double>(at - p.categories.begin())));
    }
    plots.push_back(p);
  };
  for (const std::string& c : text)
    categorical(c, [&](std::size_t i) {
      return tests[i].value("text_conditions", json::object()).value(c, std::string());
    });
  if (split) categorical("PSD", [&](std::size_t i) { return psd[i].empty() ? "scene's" : psd[i]; });
  return plots;
}

// A string for a gnuplot single-quoted literal.
std::string gnuplot_quoted(const std::string& s) {
  std::string q = "'";
  for (char ch : s) q += ch == '\'' ? std::string("''") : std::string(1, ch);
  return q + "'";
}

// The plot's data (one block per series) and gnuplot script; its figure when gnuplot drew it.
std::optional<Figure> draw(const ResidualPlot& p, const fs::path& dir) {
  std::string safe = p.condition;
  for (char& ch : safe)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  const fs::path data = dir / ("residual_" + safe + ".dat");
  const fs::path png = dir / ("residual_" + safe + ".png");
  std::ostringstream d;
  d << "# " << p.condition << (p.categories.empty() ? "" : " (category index)")
    << " residual_before_deg residual_after_deg sigma_deg role(1=calibrate)\n";
  for (std::size_t s = 0; s < p.series.size(); ++s) {
    if (s > 0) d << "\n\n";
    d << "# series " << s << ": " << (p.series[s].empty() ? "all tests" : p.series[s]) << "\n";
    for (const ResidualPoint& q : p.points[s])
      d << q.x << " " << q.before << " " << q.after << " " << q.sigma << " "
        << (q.calibrate ? 1 : 0) << "\n";
  }
  write_file_atomic(data.string(), d.str());
  static const char* const kColours[] = {"#c0392b", "#2471a3", "#27ae60",
                                         "#8e44ad", "#d68910", "#555555"};
  std::string script = png_terminal(png, 640, 420) + "set xlabel " + gnuplot_quoted(p.condition) +
                       " noenhanced\nset ylabel 'measured - predicted angle [deg]'\n"
                       "set key outside top center horizontal noenhanced\nset grid\n"
                       "set offsets graph 0.05, graph 0.05, graph 0.05, graph 0.05\n"
                       "set xzeroaxis lt -1\n";
  if (!p.categories.empty()) {
    script += "set xrange [-0.5:" + std::to_string(p.categories.size()) + "-0.5]\nset xtics (";
    for (std::size_t k = 0; k < p.categories.size(); ++k)
      script += (k ? ", " : "") + gnuplot_quoted(p.categories[k]) + " " + std::to_string(k);
    script += ")\nset offsets 0, 0, graph 0.05, graph 0.05\n";
  }
  // Before and after side by side on a category; one colour per series when there are several.
  const std::string shift = p.categories.empty() ? "" : "0.08";
  std::string plot;
  for (std::size_t s = 0; s < p.series.size(); ++s) {
    if (p.points[s].empty()) continue;
    const std::string name = p.series[s].empty() ? "" : ", " + p.series[s];
    const std::string index = " index " + std::to_string(s);
    const bool one = p.series.size() == 1;
    const std::string c_before = one ? "#c0392b" : kColours[s % 6];
    const std::string c_after = one ? "#2471a3" : kColours[s % 6];
    plot += std::string(plot.empty() ? "plot " : ", ") + "'" + data.filename().string() + "'" +
            index + " u ($1" + (shift.empty() ? "" : "-" + shift) + "):2:4 w yerrorbars pt " +
            (one ? "7" : "6") + " lc rgb '" + c_before + "' t " + gnuplot_quoted("before" + name) +
            ", ''" + index + " u ($1" + (shift.empty() ? "" : "+" + shift) +
            "):3:4 w yerrorbars pt " + (one ? "5" : "7") + " lc rgb '" + c_after + "' t " +
            gnuplot_quoted("after" + name);
  }
  script += plot + "\n";
  if (!run_gnuplot(dir / ("residual_" + safe + ".gp"), script, png)) return std::nullopt;
  std::string caption = "Residual against " + p.condition;
  if (!p.categories.empty()) caption += " (a category each)";
  if (p.series.size() > 1)
    caption += ", one colour per size distribution (open: before, filled: after)";
  return Figure{"plots/" + png.filename().string(),
                caption + " (error bars: seed noise of one residual)", 0};
}

std::vector<Figure> residual_figures(const json& loop, const fs::path& dir) {
  // The folder's residual plots are this page's own: an earlier rendering's (against a condition
  // since found to be the same on every test) would otherwise stay beside the new ones.
  std::vector<fs::path> old;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename().string().rfind("residual_", 0) == 0) old.push_back(e.path());
  for (const fs::path& f : old) fs::remove(f);
  std::vector<Figure> figures;
  for (const ResidualPlot& p : residual_plots(loop))
    if (std::optional<Figure> f = draw(p, dir)) figures.push_back(*f);
  return figures;
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

// Per test, the lab's overlay beside the twin's at one mm per page pixel (CSS width from each
// image's own scale), and the files with their scales; the twin's alone where the lab gave no
// photo. An overlay missing from `dir` is not drawn; its numbers stay in the table.
std::string photos_section(const json& loop, const fs::path& dir) {
  const json pairs = loop.value("photo_pairs", json::array());
  if (pairs.empty()) return "";
  mustache::data list(mustache::data::type::list);
  for (const json& p : pairs) {
    std::vector<std::pair<std::string, const json*>> views;
    for (const char* who : {"lab", "twin"})
      if (!p.at(who).is_null()) views.emplace_back(who, &p.at(who));
    std::vector<ScaledImage> images;
    for (const auto& view : views)
      images.push_back(
          {view.second->at("width_px").get<int>(), json_number(view.second->at("mm_per_px"))});
    const double common = beside_scale(images, kPairWidthPx);
    std::vector<Figure> figures;
    int missing = 0;
    Table files = numeric_table(
        {"", "photo", "overlay", "mm per px", "size [px]", "on the page [px]", "atan(2H/D) [deg]"});
    for (std::size_t k = 0; k < views.size(); ++k) {
      const json& v = *views[k].second;
      const int width = static_cast<int>(std::lround(page_width(images[k], common)));
      std::string caption = views[k].first == "lab" ? "lab photo" : "twin photo";
      caption += ", vision atan(2H/D) " + sig3(v["angle_deg"]) + " deg";
      if (views[k].first == "twin") {
        caption += "; mu_r " + sig3(p["mu_r"]) + ", seed " + p["seed"].dump();
        const json effects = p.value("effects", json::object());
        for (const auto& [name, value] : effects.items())
          caption += ", " + name + " " + sig3(value);
      }
      const std::string overlay = v.at("overlay").get<std::string>();
      if (fs::is_regular_file(dir / overlay))
        figures.push_back({overlay, caption, width});
      else
        ++missing;
      files.rows.push_back({{left(views[k].first), file_cell(dir, v["photo"].get<std::string>()),
                             file_cell(dir, overlay), sig3(v["mm_per_px"]),
                             v["width_px"].dump() + " x " + v["height_px"].dump(),
                             std::to_string(width), sig3(v["angle_deg"])}});
    }
    mustache::data x;
    x.set("id", left(p["id"]).text);
    std::string scale = views.size() > 1 ? "Both at " + sig3(common) + " mm per page pixel."
                        : views.empty()  ? std::string()
                                         : "At " + sig3(common) + " mm per page pixel.";
    if (p.at("lab").is_null())
      scale += std::string(scale.empty() ? "" : " ") +
               "The lab gave no photo of this test (a typed angle).";
    x.set("scale", scale);
    x.set("any_figures", !figures.empty());
    x.set("figures", to_data(figures));
    std::string note = p.value("note", std::string());
    if (missing > 0)
      note += std::string(note.empty() ? "" : " ") + std::to_string(missing) +
              (missing == 1 ? " photo is" : " photos are") +
              " not in this folder (the loop's command makes them again); their scales and "
              "angles are in the table.";
    x.set("note", text_or_false(note));
    x.set("files", to_data(files));
    list.push_back(x);
  }
  mustache::data d;
  d.set("pairs", list);
  return render(templates::kLoopPhotos, d);
}

std::string intro_section(const json& loop) {
  mustache::data d;
  d.set("data", path_for_page(loop["provenance"]["data"].get<std::string>()));
  d.set("code", loop["provenance"]["code_version"].get<std::string>());
  d.set("finished", loop["provenance"]["finished"].get<std::string>());
  return render(templates::kLoopIntro, d);
}

std::string error_section(const json& loop) {
  const json& sum = loop.at("summary");
  Table t = numeric_table({"", "before (mu_r only)", "after"});
  t.rows.push_back({{left("RMSE calibration tests [deg]"), sig3(sum["rmse_calibrate_before_deg"]),
                     sig3(sum["rmse_calibrate_after_deg"])}});
  t.rows.push_back({{left("RMSE held-out tests [deg]"), sig3(sum["rmse_validate_before_deg"]),
                     sig3(sum["rmse_validate_after_deg"])}});
  // Held-out tests whose twin pours jammed are not in the RMSE: counted here, never dropped
  // silently (older loop.json files have no count).
  auto no_pile = [&](const char* model) {
    return loop.at(model).value("rmse", json::object()).value("n_no_pile", 0);
  };
  if (no_pile("baseline") + no_pile("final") > 0)
    t.rows.push_back({{left("held-out tests the twin forms no pile for"),
                       std::to_string(no_pile("baseline")), std::to_string(no_pile("final"))}});
  mustache::data d;
  d.set("errors", to_data(t));
  d.set("mu_r", sig3(loop["baseline"]["mu_r"]));
  d.set("mu_r_se", sig3(loop["baseline"]["mu_r_se"]));
  d.set("seed_sd", sig3(loop["baseline"]["seed_sd_deg"]));
  return render(templates::kLoopError, d);
}

// Why no effect was chosen, from the last iteration (older loop.json files have no decision).
std::string no_effect_reason(const json& loop) {
  const json its = loop.value("iterations", json::array());
  if (loop.contains("not_traced") && !loop["not_traced"].is_null())
    return "nothing was traced (the notes below say why).";
  if (its.empty()) return "nothing was traced.";
  const json& last = its.back();
  const json chosen = last.value("chosen", json());
  if (last.contains("not_confirmed"))
    return last["not_confirmed"]["name"].get<std::string>() +
           " was refitted by simulation, and the simulations did not confirm it (iteration " +
           last["iteration"].dump() + ").";
  if (chosen.is_object() && chosen.contains("refit_failed"))
    return chosen["name"].get<std::string>() + "'s refit could not be simulated (iteration " +
           last["iteration"].dump() + ").";
  if (last.contains("stopped")) return last["stopped"].get<std::string>() + ".";
  const std::string v = last.contains("decision")
                            ? last["decision"].value("verdict", std::string("nothing"))
                            : std::string("nothing");
  if (v == "measurement_suspected")
    return "the trace suspects a measurement or declared-condition error on every test and "
           "names no physical effect (the decision below).";
  // An iteration that could not trace (too few tests with a prediction) has no offset score.
  if (last.contains("offset") && last["offset"].is_null() && last.contains("decision"))
    return last["decision"].value("statement", std::string("nothing was traced")) + ".";
  if (v == "indistinguishable")
    return "the candidates that meet the rule explain the residual alike and none is named (the "
           "decision below).";
  return "no candidate beat the seed noise.";
}

std::string effects_section(const json& loop) {
  mustache::data d;
  d.set("none", no_effect_reason(loop));
  if (loop["final"]["effects"].empty()) {
    d.set("effects", false);
  } else {
    Table t = numeric_table({"effect", "kind", "value", "\u00b1 se", "units", "mu_r", "from"});
    for (const json& c : loop["final"]["effects"])
      t.rows.push_back({{left(c["name"]), left(c["kind"]), sig3(c["value"]), sig3(c["value_se"]),
                         left(c["units"]), sig3(c["mu_r"]),
                         left(c.value("declared", false) ? "declared (--refit)" : "the trace")}});
    d.set("effects", to_data(t));
  }
  d.set("rule", loop["rule"]["text"].get<std::string>());
  d.set("min_t", sig3(loop["rule"]["min_t"]));
  d.set("margin", sig3(loop["rule"]["loo_margin_deg"]));
  return render(templates::kLoopEffects, d);
}

// What became of an iteration's refit by simulation (loop.hpp's design note): its trials and
// the effect chosen, or why the simulations did not confirm it, or why none could be simulated.
// False when nothing was refitted (nothing named, or the effect limit stopped the loop).
mustache::data refit_data(const json& it) {
  const json chosen = it.value("chosen", json());
  const json* r = it.contains("not_confirmed") ? &it["not_confirmed"]
                  : chosen.is_object()         ? &chosen
                                               : nullptr;
  if (r == nullptr) return mustache::data(false);
  // A field an older loop.json lacks reads "?" rather than failing the page.
  auto num = [r](const char* k) { return r->contains(k) ? sig3((*r)[k]) : std::string("?"); };
  auto word = [r](const char* k) { return r->value(k, std::string("?")); };
  const std::string name = word("name");
  mustache::data d;
  d.set("trials", false);
  if (r->contains("refit_failed")) {
    d.set("text", "Refit: " + name + " (linear estimate " + num("linear_estimate") +
                      ") could not be simulated: " + word("refit_failed") + ". Nothing chosen.");
    return d;
  }
  const json trials = r->value("trials", json::array());
  // A held-out test that formed no pile at a trial's value gets a column (loop_refit.cpp).
  bool jams = false;
  for (const json& tr : trials) jams = jams || !tr.value("no_pile", json::array()).empty();
  std::vector<std::string> header = {"simulated at", "response (probe = 1)", "t", "mu_r",
                                     "RMSE of the refit [deg]"};
  if (jams) header.push_back("no pile predicted (held out)");
  Table t = numeric_table(header);
  for (const json& tr : trials) {
    TableRow row{{sig3(tr["simulated_at"]), sig3(tr["response_fraction"]), sig3(tr["t"]),
                  sig3(tr["mu_r"]), sig3(tr["rmse_calibrate_deg"])}};
    if (jams) {
      std::string ids;
      for (const json& id : tr.value("no_pile", json::array()))
        ids += (ids.empty() ? "" : ", ") + id.get<std::string>();
      row.cells.push_back(left(ids.empty() ? "-" : ids));
    }
    t.rows.push_back(row);
  }
  std::string text = "Refit by simulation: " + name + ", linear estimate " +
                     num("linear_estimate") + ", simulated on the whole grid";
  if (it.contains("not_confirmed")) {
    text += "; not confirmed: " + word("reason") + ". Nothing chosen.";
  } else {
    const std::string units = r->value("units", std::string("-"));
    text += "; confirmed: " + name + " " + num("value") + " \u00b1 " + num("value_se") +
            (units == "-" ? "" : " " + units) + " at mu_r " + num("mu_r") + ".";
  }
  const std::string notes = r->value("refit_notes", std::string());
  if (!notes.empty()) text += " Notes: " + notes;
  d.set("text", text);
  if (!t.rows.empty()) d.set("trials", to_data(t));
  return d;
}

std::string iterations_section(const json& loop) {
  mustache::data list(mustache::data::type::list);
  for (const json& it : loop["iterations"]) {
    Table t = numeric_table({"candidate", "c", "se", "|c|/se", "LOO RMSE", "LOO gain",
                             "explained", "accepted"});
    for (const json& c : it["candidates"])
      t.rows.push_back({{left(c["name"]), sig3(c["coef"]), sig3(c["coef_se"]), sig3(c["t"]),
                         sig3(c["loo_rmse_deg"]), sig3(c["loo_gain_deg"]), sig3(c["explained"]),
                         c["accepted"].get<bool>() ? "yes" : "no"}});
    mustache::data x;
    x.set("n", it["iteration"].dump());
    x.set("mu_r", sig3(it["mu_r"]));
    x.set("loo", sig3(it["null"]["loo_rmse_mu_only_deg"]));
    x.set("candidates", to_data(t));
    x.set("stopped", it.contains("stopped") ? mustache::data(left(it["stopped"]).text)
                                            : mustache::data(false));
    x.set("declared", it.contains("declared") ? mustache::data(left(it["declared"]).text)
                                              : mustache::data(false));
    // Written by a loop that traced jointly (older loop.json files have no decision).
    x.set("joint", false);
    std::string decision = it.contains("decision") ? left(it["decision"]["statement"]).text
                                                   : std::string("as ranked");
    for (const json& why : it.value("tests_left_out", json::array()))
      decision += "; not traced, " + left(why).text;
    x.set("decision", decision);
    if (it.contains("joint") && !it["joint"].empty()) {
      Table j = numeric_table({"hypothesis", "c", "se", "|c|/se", "joint chi2", "LOO chi2",
                               "values"});
      json rows = it["joint"];
      for (const char* k : {"offset", "mu_only"})
        if (!it[k].is_null()) rows.push_back(it[k]);
      for (const json& c : rows)
        j.rows.push_back({{left(c["name"]), sig3(c["coef"]), sig3(c["coef_se"]), sig3(c["t"]),
                           sig3(c["chi2"]), sig3(c["loo_chi2"]), sig3(c["values"])}});
      std::string channels;
      for (const json& c : it["channels"])
        channels += (channels.empty() ? "" : ", ") + c.get<std::string>();
      mustache::data jd = to_data(j);
      jd.set("channels", channels);
      x.set("joint", jd);
    }
    x.set("refit", refit_data(it));
    list.push_back(x);
  }
  mustache::data d;
  d.set("iterations", list);
  return render(templates::kLoopIterations, d);
}

// Pours that jammed in the baseline (repeated with new seeds; a lab reports none), and the
// candidates the loop could not try.
std::string notes_section(const json& loop) {
  mustache::data jams(mustache::data::type::list);
  for (const json& c : loop["baseline"].value("curves", json::array())) {
    int n = 0;
    for (const json& x : c["clogged_pours"]) n += x.get<int>();
    if (n <= 0) continue;
    mustache::data j;
    j.set("id", left(c["id"]).text);
    j.set("n", std::to_string(n));
    jams.push_back(j);
  }
  mustache::data unavailable(mustache::data::type::list);
  for (const json& u : loop["unavailable_candidates"]) {
    mustache::data x;
    x.set("name", left(u["name"]).text);
    x.set("why", left(paths_for_page(u["why"].get<std::string>())).text);
    unavailable.push_back(x);
  }
  auto listed = [](mustache::data items) {
    if (items.is_empty_list()) return mustache::data(false);
    mustache::data d;
    d.set("list", items);
    return d;
  };
  mustache::data d;
  mustache::data can(mustache::data::type::list), cannot(mustache::data::type::list);
  if (loop.contains("design")) {
    for (const json& c : loop["design"]["can"]) can.push_back(mustache::data(left(c).text));
    for (const json& c : loop["design"]["cannot"]) cannot.push_back(mustache::data(left(c).text));
  }
  d.set("can", listed(can));
  d.set("cannot", listed(cannot));
  d.set("grid", loop.contains("grid") ? mustache::data(left(loop["grid"]["statement"]).text)
                                      : mustache::data(false));
  d.set("not_traced", loop.contains("not_traced") && !loop["not_traced"].is_null()
                          ? mustache::data(left(loop["not_traced"]).text)
                          : mustache::data(false));
  d.set("jams", listed(jams));
  d.set("unavailable", listed(unavailable));
  return render(templates::kLoopNotes, d);
}

std::string residuals_section(const json& loop, const fs::path& plot_dir) {
  const json& tests = loop.at("tests");
  const json& before = loop.at("baseline").at("residuals");
  const json& after = loop.at("final").at("residuals");
  // The crest width (a fourth observable) gets its columns only where the lab measured it.
  bool crest = false;
  for (const json& t : tests) crest = crest || t.contains("crest_mm");
  std::vector<std::string> header = {
      "test", "role", "measured", "before", "after", "residual before", "residual after", "sigma"};
  if (crest)
    for (const char* h : {"crest measured [mm]", "crest before [mm]", "crest after [mm]"})
      header.push_back(h);
  Table t = numeric_table(header);
  for (std::size_t i = 0; i < tests.size(); ++i) {
    // A held-out test the twin's pours jammed for reads "no pile", not a number.
    auto predicted = [](const json& r) {
      return r.contains("no_pile") ? left("no pile") : Cell(sig3(r["predicted_deg"]));
    };
    TableRow row{{left(tests[i]["id"]), left(tests[i]["role"]), sig3(tests[i]["angle_deg"]),
                  predicted(before[i]), predicted(after[i]), sig3(before[i]["residual_deg"]),
                  sig3(after[i]["residual_deg"]), sig3(before[i]["sigma_deg"])}};
    if (crest) {
      auto cell = [](const json& j, const char* k) -> Cell {
        return j.contains(k) ? Cell(sig3(j[k])) : left("-");
      };
      row.cells.push_back(cell(tests[i], "crest_mm"));
      row.cells.push_back(cell(before[i], "predicted_crest_mm"));
      row.cells.push_back(cell(after[i], "predicted_crest_mm"));
    }
    t.rows.push_back(row);
  }
  std::string same;
  for (const auto& [k, v] : constant_conditions(tests))
    same += std::string(same.empty() ? "" : ", ") + k + " " + v;
  mustache::data d;
  d.set(
      "constant",
      text_or_false(same.empty() ? same : "The same on every test, so not plotted: " + same + "."));
  d.set("plots", to_data(residual_figures(loop, plot_dir)));
  d.set("residuals", to_data(t));
  mustache::data no_pile(mustache::data::type::list);
  for (const json* rows : {&before, &after})
    for (const json& r : *rows)
      if (r.contains("no_pile"))
        no_pile.push_back(mustache::data(
            left(std::string(rows == &before ? "Before" : "After") + ", " +
                 r["no_pile"].get<std::string>())
                .text));
  d.set("no_pile", no_pile);
  return render(templates::kLoopResiduals, d);
}

}  // namespace

void write_loop_html(const json& loop, const std::string& out_dir) {
  const fs::path plot_dir = fs::path(out_dir) / "plots";
  fs::create_directories(plot_dir);
  const Page page{
      "ReposeTwin loop",
      "Closing the loop",
      {intro_section(loop), error_section(loop), effects_section(loop), iterations_section(loop),
       notes_section(loop), residuals_section(loop, plot_dir), photos_section(loop, out_dir)}};
  write_file_atomic((fs::path(out_dir) / "index.html").string(), render_page(page));
}

}  // namespace reposetwin::experiments
