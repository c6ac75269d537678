#include "experiments/report/calibration_section.hpp"

#include <cmath>
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
std::string file_name(const std::string& path) {
  return path.empty() ? std::string("-") : fs::path(path).filename().string();
}

std::string mu_r_text(const CalibrationRecord& cal) {
  if (!cal.mu_r) return "none (" + to_string(cal.status) + ")";
  return fixed(*cal.mu_r, 3) + " [" + (cal.interval_open_low ? "\u2264" : "") +
         fixed(cal.mu_r_lo, 3) + ", " + fixed(cal.mu_r_hi, 3) +
         (cal.interval_open_high ? "+" : "") + "]";
}

std::string range_text(double lo, double hi, int digits) {
  return fixed(lo, digits) + " to " + fixed(hi, digits);
}

std::string range_text(const json& v, int digits, const std::string& unit) {
  if (!v.is_array() || v.size() != 2) return "-";
  return fixed_or_dash(v[0], digits) + " to " + fixed_or_dash(v[1], digits) + unit;
}

// A number, or a dash for NaN (a noise the fit could not estimate).
std::string number_or_dash(double v, int digits = 2) {
  return std::isfinite(v) ? fixed(v, digits) : std::string("-");
}

Table summary_table(const CalibrationRecord& cal) {
  Table t;
  t.header = {"what", "value"};
  std::string keys;
  for (const std::string& k : cal.keys) keys += (keys.empty() ? "" : ", ") + k;
  const auto or_dash = [](const std::string& s) { return s.empty() ? std::string("-") : s; };
  t.rows = {
      text_row("calibrated mu_r [95% interval]", mu_r_text(cal)),
      text_row("status", to_string(cal.status)),
      text_row("target angle [deg]",
               fixed(cal.target.angle_deg) + " \u00b1 " + fixed(cal.target.sd_deg)),
      text_row("angle matched", (cal.angle ? angle_measure_name(*cal.angle) : std::string("-")) +
                                    ": " + or_dash(cal.angle_method)),
      text_row(
          "fitted angle at mu_r [deg]",
          (cal.fitted_angle_deg ? fixed(*cal.fitted_angle_deg) : std::string("-")) + " \u00b1 " +
              (cal.fitted_angle_deg ? fixed(cal.fitted_angle_halfwidth_deg) : std::string("-")) +
              " (95% half-width of the fitted mean)"),
      text_row("angles reachable in the mu_r range [deg]",
               range_text(cal.reachable_low_deg, cal.reachable_high_deg, 2)),
      text_row("mu_r range searched", range_text(cal.mu_r_range_lo, cal.mu_r_range_hi, 3)),
      text_row("pile runs (simulations)",
               std::to_string(cal.simulations) + ", " + std::to_string(cal.seeds_per_point) +
                   " seed(s) per point, tolerance " + fixed(cal.tolerance_deg) + " deg"),
      text_row("fit", or_dash(cal.fit_method) + "; seed noise sd " +
                          number_or_dash(cal.fit.noise_sd_deg) + " deg"),
      text_row("keys set to mu_r", or_dash(keys)),
      text_row("rolling model", or_dash(cal.rolling_model.keyword)),
      text_row("campaign, scene", file_name(cal.campaign) + ", " + file_name(cal.scene)),
      text_row("code version, created (UTC)",
               or_dash(cal.code_version) + ", " + or_dash(cal.created_utc)),
      text_row("message", or_dash(cal.message))};
  return t;
}

Table fit_table(const CalibrationRecord& cal) {
  Table t;
  t.numeric = true;
  t.header = {"mu_r", "seeds", "mean angle [deg] \u00b1 seed sd", "fitted angle [deg]"};
  for (const FitPoint& p : cal.fit.points)
    t.rows.push_back({{fixed(p.mu_r, 3), std::to_string(p.n),
                       fixed(p.mean_deg) + " \u00b1 " + fixed(p.sd_deg), fixed(p.fitted_deg)}});
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

bool calibration_plot(const CalibrationRecord& cal, const json& predictions, const fs::path& out,
                      const std::string& stem) {
  std::ostringstream runs, excluded, fit, checks;
  for (const Observation& o : cal.observations) runs << o.mu_r << " " << o.angle_deg << "\n";
  for (const Observation& o : cal.excluded) excluded << o.mu_r << " " << o.angle_deg << "\n";
  for (const FitPoint& p : cal.fit.points) fit << p.mu_r << " " << p.fitted_deg << "\n";
  for (double a : check_angles(predictions))
    if (cal.mu_r) checks << *cal.mu_r << " " << a << "\n";
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
  const std::string target = fixed(cal.target.angle_deg);
  plot += ", " + target + " with lines dt 2 lc rgb '#2ca02c' title 'target " + target + " deg'";
  if (cal.mu_r) {
    const std::string mu = fixed(*cal.mu_r, 4);
    marks += "set object 1 rect from " + fixed(cal.mu_r_lo, 4) + ", graph 0 to " +
             fixed(cal.mu_r_hi, 4) + ", graph 1 behind fc rgb '#dde8f5' fs solid noborder\n";
    marks += "set arrow 1 from " + mu + ", graph 0 to " + mu +
             ", graph 1 nohead dt 3 lw 2 lc rgb '#d62728'\nset label 1 'calibrated mu_r " +
             fixed(*cal.mu_r, 3) + " (95% band)' at " + mu +
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

std::string calibration_section(const CalibrationRecord& cal, const json& predictions,
                                const fs::path& out, const std::string& link) {
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
    const json& scene_path = p.value("scene", json());
    Cell scene(file_name(scene_path.is_string() ? scene_path.get<std::string>() : ""));
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
