// write_loop_html (loop_report.hpp): the loop's page, with the report's page skeleton, tables and
// plotting. Tables from loop.json and gnuplot plots of the residuals against each condition,
// before and after the chosen effects. Reads loop.json only (never simulates).
#include "experiments/report/loop_report.hpp"

#include <filesystem>
#include <set>
#include <sstream>

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

// One plot per condition: the residual of every test before and after, against the condition.
std::vector<Figure> residual_plots(const json& loop, const fs::path& dir) {
  const json& tests = loop.at("tests");
  const json& before = loop.at("baseline").at("residuals");
  const json& after = loop.at("final").at("residuals");
  std::set<std::string> conditions;
  for (const json& t : tests)
    for (const auto& [k, v] : t.at("conditions").items()) conditions.insert(k);
  std::vector<Figure> figures;
  for (const std::string& c : conditions) {
    std::string safe = c;
    for (char& ch : safe)
      if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
    const fs::path data = dir / ("residual_" + safe + ".dat");
    const fs::path png = dir / ("residual_" + safe + ".png");
    std::ostringstream d;
    d << "# " << c << " residual_before_deg residual_after_deg sigma_deg role(1=calibrate)\n";
    for (std::size_t i = 0; i < tests.size(); ++i) {
      if (!tests[i]["conditions"].contains(c)) continue;
      d << tests[i]["conditions"][c].get<double>() << " " << before[i]["residual_deg"] << " "
        << after[i]["residual_deg"] << " " << before[i]["sigma_deg"] << " "
        << (tests[i]["role"] == "calibrate" ? 1 : 0) << "\n";
    }
    write_file_atomic(data.string(), d.str());
    const std::string script =
        png_terminal(png, 640, 420) + "set xlabel '" + c +
        "' noenhanced\nset ylabel 'measured - predicted angle [deg]'\n"
        "set key outside top center horizontal\nset grid\nset offsets graph 0.05, graph 0.05, "
        "graph 0.05, graph 0.05\nset xzeroaxis lt -1\nplot '" + data.filename().string() +
        "' u ($1):2:4 w yerrorbars pt 7 lc rgb '#c0392b' t 'before', "
        "'' u ($1):3:4 w yerrorbars pt 5 lc rgb '#2471a3' t 'after'\n";
    if (run_gnuplot(dir / ("residual_" + safe + ".gp"), script, png))
      figures.push_back({"plots/" + png.filename().string(),
                         "Residual against " + c + " (error bars: seed noise of one residual)", 0});
  }
  return figures;
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
  mustache::data d;
  d.set("errors", to_data(t));
  d.set("mu_r", sig3(loop["baseline"]["mu_r"]));
  d.set("mu_r_se", sig3(loop["baseline"]["mu_r_se"]));
  d.set("seed_sd", sig3(loop["baseline"]["seed_sd_deg"]));
  return render(templates::kLoopError, d);
}

std::string effects_section(const json& loop) {
  mustache::data d;
  if (loop["final"]["effects"].empty()) {
    d.set("effects", false);
  } else {
    Table t = numeric_table({"effect", "kind", "value", "\u00b1 se", "units", "mu_r"});
    for (const json& c : loop["final"]["effects"])
      t.rows.push_back({{left(c["name"]), left(c["kind"]), sig3(c["value"]), sig3(c["value_se"]),
                         left(c["units"]), sig3(c["mu_r"])}});
    d.set("effects", to_data(t));
  }
  d.set("rule", loop["rule"]["text"].get<std::string>());
  d.set("min_t", sig3(loop["rule"]["min_t"]));
  d.set("margin", sig3(loop["rule"]["loo_margin_deg"]));
  return render(templates::kLoopEffects, d);
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
    // Written by a loop that traced jointly (older loop.json files have no decision).
    x.set("joint", false);
    x.set("decision", it.contains("decision") ? left(it["decision"]["statement"]).text
                                              : std::string("as ranked"));
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
    x.set("why", left(u["why"]).text);
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
    TableRow row{{left(tests[i]["id"]), left(tests[i]["role"]), sig3(tests[i]["angle_deg"]),
                  sig3(before[i]["predicted_deg"]), sig3(after[i]["predicted_deg"]),
                  sig3(before[i]["residual_deg"]), sig3(after[i]["residual_deg"]),
                  sig3(before[i]["sigma_deg"])}};
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
  mustache::data d;
  d.set("plots", to_data(residual_plots(loop, plot_dir)));
  d.set("residuals", to_data(t));
  return render(templates::kLoopResiduals, d);
}

}  // namespace

void write_loop_html(const json& loop, const std::string& out_dir) {
  const fs::path plot_dir = fs::path(out_dir) / "plots";
  fs::create_directories(plot_dir);
  const Page page{"ReposeTwin loop",
                  "Closing the loop",
                  {intro_section(loop), error_section(loop), effects_section(loop),
                   iterations_section(loop), notes_section(loop),
                   residuals_section(loop, plot_dir)}};
  write_file_atomic((fs::path(out_dir) / "index.html").string(), render_page(page));
}

}  // namespace reposetwin::experiments
