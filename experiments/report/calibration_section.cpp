#include "experiments/report/calibration_section.hpp"

#include <sstream>

#include "experiments/io/provenance.hpp"
#include "experiments/report/format.hpp"
#include "experiments/report/gnuplot.hpp"
#include "experiments/report/html.hpp"
#include "experiments/report/templates.hpp"

namespace reposetwin::experiments::report {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// A file path of a record as the page shows it: its name only (the record holds the path on the
// machine that made it, which means nothing to a reader of a copied report).
std::string file_name(const json& v) {
  return v.is_string() ? fs::path(v.get<std::string>()).filename().string() : std::string("-");
}

std::string mu_r_text(const json& cal) {
  if (!cal.value("mu_r", json()).is_number()) return "none (" + cal.value("status", std::string("-")) + ")";
  std::string t = fixed(cal["mu_r"].get<double>(), 3);
  if (cal.contains("mu_r_interval") && cal["mu_r_interval"].is_array())
    t += " [" + std::string(interval_open_at(cal, 0) ? "\u2264" : "") +
         fixed_or_dash(cal["mu_r_interval"][0], 3) + ", " +
         fixed_or_dash(cal["mu_r_interval"][1], 3) + (interval_open_at(cal, 1) ? "+" : "") + "]";
  return t;
}

std::string range_text(const json& v, int digits, const std::string& unit) {
  if (!v.is_array() || v.size() != 2) return "-";
  return fixed_or_dash(v[0], digits) + " to " + fixed_or_dash(v[1], digits) + unit;
}

Table summary_table(const json& cal) {
  Table t;
  t.header = {"what", "value"};
  const json target = cal.value("target", json::object());
  std::string keys;
  for (const json& k : cal.value("keys", json::array()))
    keys += (keys.empty() ? "" : ", ") + k.get<std::string>();
  t.rows = {
      text_row("calibrated mu_r [95% interval]", mu_r_text(cal)),
      text_row("status", cal.value("status", std::string("-"))),
      text_row("target angle [deg]", fixed_or_dash(target.value("angle_deg", json())) + " \u00b1 " +
                                         fixed_or_dash(target.value("sd_deg", json()))),
      text_row("angle matched", cal.value("angle", std::string("-")) + ": " +
                                    cal.value("angle_method", std::string("-"))),
      text_row("fitted angle at mu_r [deg]",
               fixed_or_dash(cal.value("fitted_angle_deg", json())) + " \u00b1 " +
                   fixed_or_dash(cal.value("fitted_angle_halfwidth_deg", json())) +
                   " (95% half-width of the fitted mean)"),
      text_row("angles reachable in the mu_r range [deg]",
               range_text(cal.value("reachable_deg", json()), 2, "")),
      text_row("mu_r range searched", range_text(cal.value("mu_r_range", json()), 3, "")),
      text_row("pile runs (simulations)", std::to_string(cal.value("simulations", 0)) + ", " +
                                              std::to_string(cal.value("seeds_per_point", 0)) +
                                              " seed(s) per point, tolerance " +
                                              fixed_or_dash(cal.value("tolerance_deg", json())) +
                                              " deg"),
      text_row("fit",
               cal.value("fit", json::object()).value("method", std::string("-")) +
                   "; seed noise sd " +
                   fixed_or_dash(cal.value("fit", json::object()).value("noise_sd_deg", json())) +
                   " deg"),
      text_row("keys set to mu_r", keys.empty() ? cal.value("key", std::string("-")) : keys),
      text_row("rolling model",
               cal.value("rolling_model", json::object()).value("keyword", std::string("-"))),
      text_row("campaign, scene", file_name(cal.value("campaign", json())) + ", " +
                                      file_name(cal.value("scene", json()))),
      text_row("code version, created (UTC)", cal.value("code_version", std::string("-")) + ", " +
                                                  cal.value("created_utc", std::string("-"))),
      text_row("message", cal.value("message", std::string("-")))};
  return t;
}

Table fit_table(const json& cal) {
  Table t;
  t.numeric = true;
  t.header = {"mu_r", "seeds", "mean angle [deg] \u00b1 seed sd", "fitted angle [deg]"};
  for (const json& p : cal.value("fit", json::object()).value("points", json::array()))
    t.rows.push_back({{fixed_or_dash(p.value("mu_r", json()), 3),
                       std::to_string(p.value("n", 0)),
                       fixed_or_dash(p.value("mean_deg", json())) + " \u00b1 " +
                           fixed_or_dash(p.value("sd_deg", json())),
                       fixed_or_dash(p.value("fitted_deg", json()))}});
  return t;
}

// The check runs at the calibrated mu_r: the predictions marked "check".
std::vector<double> check_angles(const json& predictions) {
  std::vector<double> a;
  if (!predictions.is_object()) return a;
  for (const json& p : predictions.value("predictions", json::array()))
    if (p.value("check", false))
      for (const json& x : p.value("angles_deg", json::array()))
        if (x.is_number()) a.push_back(x.get<double>());
  return a;
}

// Writes `rows` to out/name; returns the plot clause for it, or "" when there are no rows.
std::string series(const fs::path& out, const std::string& name, const std::string& rows,
                   const std::string& how) {
  if (rows.empty()) return "";
  write_file_atomic((out / name).string(), rows);
  return "'" + name + "' " + how;
}

}  // namespace

bool calibration_plot(const json& cal, const json& predictions, const fs::path& out,
                      const std::string& stem) {
  std::ostringstream runs, excluded, fit, checks;
  for (const json& o : cal.value("observations", json::array()))
    runs << o.value("mu_r", 0.0) << " " << o.value("angle_deg", 0.0) << "\n";
  for (const json& o : cal.value("excluded_search_observations", json::array()))
    excluded << o.value("mu_r", 0.0) << " " << o.value("angle_deg", 0.0) << "\n";
  for (const json& p : cal.value("fit", json::object()).value("points", json::array()))
    fit << p.value("mu_r", 0.0) << " " << p.value("fitted_deg", 0.0) << "\n";
  const bool calibrated = cal.value("mu_r", json()).is_number();
  for (double a : check_angles(predictions))
    if (calibrated) checks << cal["mu_r"].get<double>() << " " << a << "\n";
  std::vector<std::string> clauses = {
      series(out, stem + "_fit.dat", fit.str(),
             "using 1:2 with linespoints lw 2 pt 6 lc rgb '#1f77b4' title 'monotone fit'"),
      series(out, stem + "_runs.dat", runs.str(),
             "using 1:2 with points pt 7 lc rgb '#333333' title 'runs in the fit (one per seed)'"),
      series(out, stem + "_excluded.dat", excluded.str(),
             "using 1:2 with points pt 6 lc rgb '#999999' title 'search runs replaced by fresh "
             "seeds'"),
      series(out, stem + "_checks.dat", checks.str(),
             "using 1:2 with points pt 9 ps 1.3 lc rgb '#d62728' title 'check runs at the "
             "calibrated mu_r'")};
  std::string plot;
  for (const std::string& c : clauses)
    if (!c.empty()) plot += (plot.empty() ? "plot " : ", ") + c;
  if (plot.empty()) return false;
  std::string marks;
  if (cal.contains("target") && cal["target"].value("angle_deg", json()).is_number()) {
    const std::string target = fixed(cal["target"]["angle_deg"].get<double>());
    plot += ", " + target + " with lines dt 2 lc rgb '#2ca02c' title 'target " + target + " deg'";
  }
  if (calibrated) {
    const std::string mu = fixed(cal["mu_r"].get<double>(), 4);
    if (cal.contains("mu_r_interval") && cal["mu_r_interval"].is_array() &&
        cal["mu_r_interval"][0].is_number() && cal["mu_r_interval"][1].is_number())
      marks += "set object 1 rect from " + fixed(cal["mu_r_interval"][0].get<double>(), 4) +
               ", graph 0 to " + fixed(cal["mu_r_interval"][1].get<double>(), 4) +
               ", graph 1 behind fc rgb '#dde8f5' fs solid noborder\n";
    marks += "set arrow 1 from " + mu + ", graph 0 to " + mu +
             ", graph 1 nohead dt 3 lw 2 lc rgb '#d62728'\nset label 1 'calibrated mu_r " +
             fixed(cal["mu_r"].get<double>(), 3) + " (95% band)' at " + mu +
             ", graph 0.05 offset 0.5,0 tc rgb '#d62728'\n";
  }
  run_gnuplot(out / (stem + ".gp"),
              png_terminal(out / (stem + ".png"), 760, 560, false) +
                  "set xlabel 'mu_r (rolling friction)'\nset ylabel 'angle of repose "
                  "[deg]'\nset key below maxrows 3\nset grid\nset offsets graph 0.03, graph "
                  "0.03, 1, 1\n" +
                  marks + plot + "\n",
              out / (stem + ".png"));
  return true;
}

std::string calibration_section(const json& cal, const json& predictions, const fs::path& out,
                                const std::string& link) {
  mustache::data d;
  d.set("plot",
        text_or_false(calibration_plot(cal, predictions, out, "calibration") ? "calibration.png"
                                                                               : ""));
  d.set("summary", to_data(summary_table(cal)));
  const Table fit = fit_table(cal);
  d.set("fit", fit.rows.empty() ? mustache::data(false) : to_data(fit));
  d.set("link", link);
  return render(templates::kCalibration, d);
}

std::string predictions_section(const json& predictions, const std::string& link) {
  Table t;
  t.numeric = true;
  t.header = {"test",       "mu_r",    "piles (of runs)", "angle [deg] mean \u00b1 seed sd",
              "measured [deg]", "error [deg]", "over the mu_r interval [deg]", "scene"};
  for (const json& p : predictions.value("predictions", json::array())) {
    Cell name(p.value("name", std::string("-")));
    name.left = true;
    if (p.value("check", false)) name.small = "(the calibration test, fresh seeds)";
    const json effect = p.value("interval_effect", json::object());
    Cell range(range_text(effect.value("angle_range_deg", json()), 2, ""));
    range.small = effect.value("method", std::string()) == "runs" ? "(run at both ends)"
                                                                  : "(from the calibration slope)";
    const int n = p.value("n", 0);
    Cell scene(file_name(p.value("scene", json())));
    scene.left = true;
    t.rows.push_back(
        {{name, fixed_or_dash(p.value("mu_r", json()), 3),
          std::to_string(n) + " (" + std::to_string(n + p.value("no_pile", 0)) + ")",
          p.value("mean_deg", json()).is_number()
              ? fixed(p["mean_deg"].get<double>()) + " \u00b1 " +
                    fixed_or_dash(p.value("seed_sd_deg", json()))
              : std::string("no pile"),
          fixed_or_dash(p.value("measured_deg", json())) + " \u00b1 " +
              fixed_or_dash(p.value("measured_sd_deg", json())),
          fixed_or_dash(p.value("error_deg", json())), range, scene},
         p.value("check", false)});
  }
  mustache::data d;
  d.set("predictions", to_data(t));
  d.set("link", link);
  return render(templates::kPredictions, d);
}

}  // namespace reposetwin::experiments::report
