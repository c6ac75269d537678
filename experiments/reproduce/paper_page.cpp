#include "experiments/reproduce/paper_page.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <sstream>

#include "experiments/calibration/calibration.hpp"
#include "experiments/calibration/calibration_file.hpp"
#include "experiments/campaign/case_runner.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/report/calibration_section.hpp"
#include "experiments/report/format.hpp"
#include "experiments/report/gnuplot.hpp"
#include "experiments/io/scene_overrides.hpp"
#include "sim/psd.hpp"
#include "experiments/report/html.hpp"
#include "experiments/report/templates.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;
using namespace report;

namespace {

std::optional<json> json_if_present(const fs::path& p) {
  std::error_code ec;
  if (!fs::is_regular_file(p, ec)) return std::nullopt;
  try {
    return experiments::read_json_file(p.string());
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

// One of our points: a case's angles over the runs that formed a pile.
struct OurPoint {
  std::string label;     // the case's name
  std::string readable;  // its inputs as a person reads them (report::case_label)
  double x = 0.0;
  std::vector<double> angles;
  std::map<std::string, int> without_pile;  // the other runs, by reason
};

// Our points of a campaign item: every finished run under DIR/cases, grouped by case, x from the
// item's x_key (the case's override) or the case's position.
std::vector<OurPoint> campaign_points(const PaperItem& item, const fs::path& dir) {
  std::vector<OurPoint> pts;
  std::error_code ec;
  if (!fs::is_directory(dir / "cases", ec)) return pts;
  std::vector<fs::path> files;
  for (const auto& e : fs::recursive_directory_iterator(dir / "cases", ec))
    if (e.path().filename() == "result.json") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  const AngleMeasure measure = parse_angle_measure(item.angle, item.name);
  for (const fs::path& f : files) {
    auto meta = json_if_present(f);
    if (!meta || !meta->contains("result") || !meta->contains("spec")) continue;
    const std::string name = (*meta)["spec"].value("case", std::string("?"));
    auto it =
        std::find_if(pts.begin(), pts.end(), [&](const OurPoint& p) { return p.label == name; });
    if (it == pts.end()) {
      OurPoint p;
      p.label = name;
      p.x = static_cast<double>(pts.size());
      const json ov = (*meta)["spec"].value("overrides", json::object());
      p.readable = case_label(name, ov);
      if (!item.x_key.empty() && ov.contains(item.x_key) && ov[item.x_key].is_number())
        p.x = ov[item.x_key].get<double>() * item.x_scale;
      pts.push_back(p);
      it = pts.end() - 1;
    }
    const json& res = (*meta)["result"];
    const PileStatus outcome = case_outcome(res);
    if (outcome != PileStatus::kPile) {
      ++it->without_pile[pile_status_word(outcome)];
      continue;
    }
    try {
      it->angles.push_back(case_angle_deg(res, measure));
    } catch (const std::exception&) {
      ++it->without_pile["not measured (" + item.angle + ")"];
    }
  }
  std::sort(pts.begin(), pts.end(), [](const OurPoint& a, const OurPoint& b) { return a.x < b.x; });
  return pts;
}

std::string reasons_text(const std::map<std::string, int>& m) {
  std::string t;
  for (const auto& [r, n] : m) t += (t.empty() ? "" : ", ") + std::to_string(n) + " " + r;
  return t.empty() ? "-" : t;
}

// One series of ours on an item's figure: (x, y, error bar) rows, written to
// PAGE/<item>_<suffix>.dat.
struct Series {
  std::string title;
  std::string suffix;
  std::vector<std::array<double, 3>> rows;
  std::vector<std::string> tics;  // x tic labels, one per row (x is then the position)
  int point_type = 7;             // gnuplot's pt: 7 a filled circle, 6 an open one
};

// The figure of an item on its own axes: our series with error bars, the paper's points beside
// them and its stated levels as dashed lines. A data file is written only for what is drawn, so
// no figure reads an empty one.
bool item_figure(const PaperItem& item, const std::vector<Series>& ours, const std::string& x_label,
                 const std::string& y_label, const fs::path& page_dir) {
  std::vector<std::string> parts;
  bool tics = false;
  for (const Series& s : ours) {
    if (s.rows.empty()) continue;
    std::ostringstream o;
    for (std::size_t i = 0; i < s.rows.size(); ++i)
      o << s.rows[i][0] << " " << s.rows[i][1] << " " << s.rows[i][2] << " \""
        << (i < s.tics.size() ? s.tics[i] : std::string()) << "\"\n";
    const fs::path f = page_dir / (item.name + "_" + s.suffix + ".dat");
    write_file_atomic(f.string(), o.str());
    tics = tics || !s.tics.empty();
    parts.push_back(gnuplot_string(f.filename().string()) + " using 1:2:3" +
                    (s.tics.empty() ? std::string() : std::string(":xtic(4)")) +
                    " with yerrorbars pt " + std::to_string(s.point_type) + " ps 1.5 title " +
                    gnuplot_string(s.title));
  }
  if (parts.empty()) return false;
  // The paper's points first, so that ours are drawn over them where both lie at one place.
  std::vector<std::string> paper;
  if (item.paper_points) {
    std::ostringstream p;
    for (std::size_t i = 0; i < item.paper_points->x.size(); ++i)
      p << item.paper_points->x[i] << " " << item.paper_points->y[i] << "\n";
    const fs::path f = page_dir / (item.name + "_paper.dat");
    write_file_atomic(f.string(), p.str());
    paper.push_back(gnuplot_string(f.filename().string()) +
                    " using 1:2 with points pt 5 ps 1.5 title " +
                    gnuplot_string("paper (" + item.paper_points->source + ")"));
  }
  if (item.paper_levels)
    for (std::size_t i = 0; i < item.paper_levels->y.size(); ++i)
      paper.push_back(as_printed(item.paper_levels->y[i]) + " with lines dt 2 lw 2 title " +
                      gnuplot_string(i == 0 ? "paper: " + item.paper_levels->source : ""));
  parts.insert(parts.begin(), paper.begin(), paper.end());
  std::string plot = "plot ";
  for (std::size_t i = 0; i < parts.size(); ++i) plot += (i ? ", " : "") + parts[i];
  const fs::path png = page_dir / (item.name + ".png");
  // Offsets in graph units: an axis of mu_r (0.1-0.4) and one of degrees get the same margin.
  const std::string script =
      png_terminal(png, 900, 540, false) + "set xlabel " + gnuplot_string(x_label) +
      "\nset ylabel " + gnuplot_string(y_label) +
      // Below the plot: the key's sentences (the paper's source) are wider than a corner.
      "\nset key below left Left reverse\n"
      "set offsets graph 0.05, graph 0.05, graph 0.1, graph 0.1\n" +
      (tics ? std::string("set xtics rotate by 30 right\n") : std::string()) +
      (item.x_range ? "set xrange [" + as_printed(item.x_range->first) + ":" +
                          as_printed(item.x_range->second) + "]\n"
                    : std::string()) +
      plot + "\n";
  run_gnuplot(page_dir / (item.name + ".gp"), script, png);
  return true;
}

struct ItemSection {
  std::string html;
  std::string ours_text;  // one line for the summary table
};

Table plan_table(const ItemPlan& plan) {
  Table t;
  t.numeric = true;
  t.header = {"runs of",      "runs", "particles", "d [mm]", "fines not simulated",
              "E (softened)", "dt",   "CPU-h"};
  for (const PlanGroup& g : plan.groups) {
    Cell label(g.label);
    label.left = true;
    std::ostringstream e, dt;
    e << (g.softened_e_pa > 0 ? fixed(g.softened_e_pa / 1e6, 3) + " MPa" : "real E");
    dt << sig3(g.plan.time_step_s) << " s (" << fixed(g.rayleigh_fraction, 2) << " T_R)";
    t.rows.push_back({{label, std::to_string(g.runs),
                       std::to_string(g.plan.particles) + (g.clumps ? " (clumps)" : ""),
                       fixed(g.plan.d_min_mm, 2) + "-" + fixed(g.plan.d_max_mm, 2),
                       fixed(100.0 * g.plan.fines_fraction, 1) + "%", e.str(), dt.str(),
                       fixed(g.runs * g.plan.wall_s / 3600.0, 2)}});
  }
  return t;
}

// Our part of a campaign item: the table of points and the plot.
void campaign_part(const PaperItem& item, const fs::path& dir, const fs::path& page_dir,
                   mustache::data& d, ItemSection& s) {
  const std::vector<OurPoint> pts = campaign_points(item, dir);
  if (pts.empty()) return;
  Table t;
  t.numeric = true;
  t.header = {"case", item.x_label.empty() ? "x" : item.x_label,
              "ours: " + item.angle + " angle [deg], mean \u00b1 seed sd", "piles",
              "runs without a pile"};
  std::vector<std::array<double, 3>> plotted;
  std::vector<std::string> tics;
  for (const OurPoint& p : pts) {
    const SampleStats st = sample_stats(p.angles);
    Cell c;
    c.bold = p.readable;
    if (p.readable != p.label) c.note = p.label;
    c.left = true;
    t.rows.push_back({{c, fixed(p.x, 3), st.n ? mean_sd(st.mean, st.sd) : "-", std::to_string(st.n),
                       reasons_text(p.without_pile)}});
    if (st.n) {
      plotted.push_back({p.x, st.mean, st.sd});
      tics.push_back(p.readable);
    }
    s.ours_text += (s.ours_text.empty() ? "" : "; ") + p.readable + ": " +
                   (st.n ? mean_sd(st.mean, st.sd) : "no pile");
  }
  d.set("ours", to_data(t));
  Series series{"ours (" + item.angle + ")", "ours", plotted,
                item.x_key.empty() ? tics : std::vector<std::string>{}};
  if (item_figure(item, {series}, item.x_label.empty() ? "case" : item.x_label,
                  item.paper_points ? item.paper_points->y_label : "angle of repose [deg]",
                  page_dir))
    d.set("plot", item.name + ".png");
}

// The value of the item's x key in a built scene [the key's unit]: the key as the scene (with
// its overrides) gives it, or, for sample.d_max_mm set by the sieve table, the table's d_max.
std::optional<double> scene_x(const SceneDoc& doc, const std::string& key) {
  if (auto v = doc.number(key)) return v;
  if (key == "sample.d_max_mm") return 1e3 * sim::resolve_psd(doc.config().psd.spec).d_max;
  return std::nullopt;
}

// The figure of an item whose [[predict]] tests run at another item's calibrated mu_r: each
// test's angle (mean and seed sd) against its x, the tests that made no pile at angle 0 (as the
// paper draws a lodged funnel), and the calibration test itself at its fitted angle.
bool prediction_figure(const PaperItem& item, const CalibrationRecord& cal, const fs::path& dir,
                       const fs::path& page_dir) {
  const auto pred = json_if_present(dir / "predictions.json");
  if (!pred || !cal.mu_r) return false;
  const Campaign c = read_campaign_file(item.file);
  const double mu = *cal.mu_r;
  const std::string angle = pred->value("angle", item.angle);
  Series piles{"ours: predicted at mu_r " + fixed(mu, 3) + " (" + angle + ", mean and seed sd)",
               "ours", {}, {}};
  Series none{"ours: no pile in any seed (drawn at angle 0)", "nopile", {}, {}, 6};
  for (const json& q : (*pred)["predictions"]) {
    const std::string name = q.value("name", std::string());
    const auto p = std::find_if(c.predictions.begin(), c.predictions.end(),
                                [&](const PredictionCase& x) { return x.name == name; });
    if (p == c.predictions.end() || p->seeds.empty()) continue;
    const auto x = scene_x(build_case_scene(prediction_run(c, *p, mu, p->seeds.front())),
                           item.x_key);
    if (!x) continue;
    if (q["mean_deg"].is_number())
      piles.rows.push_back({*x * item.x_scale, q["mean_deg"].get<double>(),
                            q["seed_sd_deg"].is_number() ? q["seed_sd_deg"].get<double>() : 0.0});
    else
      none.rows.push_back({*x * item.x_scale, 0.0, 0.0});
  }
  Series fit{"ours: the calibration test, its fit at mu_r (95% half-width)", "calibration",
             {}, {}, 9};
  if (cal.fitted_angle_deg && c.calibration)
    if (const auto x = scene_x(build_case_scene(calibration_run(c, mu, c.calibration->settings.first_seed)),
                               item.x_key))
      fit.rows.push_back(
          {*x * item.x_scale, *cal.fitted_angle_deg, cal.fitted_angle_halfwidth_deg});
  const std::string x_label = item.x_label.empty() ? item.x_key : item.x_label;
  return item_figure(item, {piles, none, fit}, x_label, "angle of repose [deg]", page_dir);
}

// Our part of a calibration item: mu_r, runs, jam rates, predictions.
void calibration_part(const PaperItem& item, const fs::path& dir, const fs::path& page_dir,
                      mustache::data& d, ItemSection& s) {
  const fs::path file = dir / "calibration.json";
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) return;
  const CalibrationRecord cal = read_calibration_record(file.string());
  Table t;
  t.numeric = true;
  t.header = {"what", "ours", "detail"};
  std::string mu = "cannot reach";
  if (cal.mu_r)
    mu = fixed(*cal.mu_r, 3) + " [" + fixed(cal.mu_r_lo, 3) + ", " + fixed(cal.mu_r_hi, 3) + "]";
  if (cal.not_calibrated) {
    // Predictions at the closest usable point of a calibration that found no mu_r.
    mu = fixed(*cal.mu_r, 3) + " (not calibrated)";
    t.rows.push_back(
        {{Cell("mu_r used"), mu,
          cal.not_calibrated->mu_r_basis + "; the calibration: " + cal.not_calibrated->message}});
  } else {
    t.rows.push_back(
        {{Cell("calibrated mu_r (95% interval)"), mu,
          to_string(cal.status) + ", " + std::to_string(cal.simulations) + " pile runs (" +
              (cal.method == CalibrationMethod::kBracket ? "bracket" : "sequential") + ")"}});
  }
  for (const PourCount& q : cal.pour_counts)
    t.rows.push_back({{Cell("pours at mu_r " + fixed(q.mu_r, 3)),
                       std::to_string(q.piles) + " piles of " + std::to_string(q.pours),
                       "jam rate " + fixed(q.jam_rate, 2)}});
  if (auto pred = json_if_present(dir / "predictions.json"))
    for (json& q : (*pred)["predictions"])
      t.rows.push_back(
          {{Cell("predicted: " + q.value("name", std::string())),
            q["mean_deg"].is_number()
                ? mean_sd(q["mean_deg"].get<double>(),
                          q["seed_sd_deg"].is_number() ? q["seed_sd_deg"].get<double>() : 0.0) +
                      " deg (" + std::to_string(q.value("n", 0)) + " piles)"
                : "no pile",
            "measured " + fixed_or_dash(q["measured_deg"]) + ", error " +
                fixed_or_dash(q["error_deg"])}});
  d.set("ours", to_data(t));
  s.ours_text = "mu_r " + mu + ", " + std::to_string(cal.simulations) + " pile runs";
  // An item that predicts at another item's calibration is drawn on its own axes (angle
  // against mass, W/d_max, d_max); the calibration plot (angle against mu_r) is its source's.
  const bool own_axes = !item.calibrated_by.empty() && !item.x_key.empty();
  if (own_axes ? prediction_figure(item, cal, dir, page_dir)
               : calibration_plot(cal, json_if_present(dir / "predictions.json").value_or(json()),
                                  page_dir, item.name))
    d.set("plot", item.name + ".png");
}

// A derived item: its sources' calibrated mu_r against their d_max.
void derived_part(const PaperItem& item, const PaperIndex& index, const fs::path& out,
                  const fs::path& page_dir, mustache::data& d, ItemSection& s) {
  Table t;
  t.numeric = true;
  t.header = {"calibration", "d_max [mm]", "mu_r", "95% interval", "model"};
  std::map<std::string, std::vector<std::array<double, 3>>> pts;  // by rolling model
  for (const std::string& src : item.from) {
    const auto it = std::find_if(index.items.begin(), index.items.end(),
                                 [&](const PaperItem& p) { return p.name == src; });
    const fs::path file = out / src / "calibration.json";
    std::error_code ec;
    if (it == index.items.end() || !fs::is_regular_file(file, ec)) continue;
    const CalibrationRecord cal = read_calibration_record(file.string());
    if (!cal.mu_r) continue;
    const ItemPlan plan = plan_item(*it);
    const double dmax = plan.groups.empty() ? 0.0 : plan.groups.front().plan.d_max_mm;
    const double mu = *cal.mu_r, lo = cal.mu_r_lo, hi = cal.mu_r_hi;
    Cell c(src);
    c.left = true;
    const std::string& model = cal.rolling_model.keyword;
    t.rows.push_back({{c, fixed(dmax, 2), fixed(mu, 3),
                       "[" + fixed(lo, 3) + ", " + fixed(hi, 3) + "]", model}});
    pts[model].push_back({dmax, mu, 0.5 * (hi - lo)});
    s.ours_text += (s.ours_text.empty() ? "" : "; ") + src + " " + fixed(mu, 3);
  }
  if (t.rows.empty()) return;
  d.set("ours", to_data(t));
  // One series per rolling law: an epsd mu_r is about twice a cdt (EDEM's) one for the same
  // torque, so they are not one curve.
  std::vector<Series> series;
  for (const auto& [model, rows] : pts)
    series.push_back({"ours, " + model + " (calibrated mu_r, 95% half-width)", model, rows, {}});
  if (item_figure(item, series, "d_max [mm]", "mu_r", page_dir)) d.set("plot", item.name + ".png");
}

std::string paper_text(const PaperItem& item) {
  std::ostringstream o;
  if (item.paper_points) {
    const PaperPoints& p = *item.paper_points;
    for (std::size_t i = 0; i < p.x.size(); ++i)
      o << (i ? "; " : "") << p.x_label << " " << as_printed(p.x[i]) << ": " << as_printed(p.y[i]);
    o << " (" << p.source << ")";
  }
  if (item.paper_levels) {
    const PaperLevels& l = *item.paper_levels;
    o << (item.paper_points ? "; " : "") << "level";
    for (std::size_t i = 0; i < l.y.size(); ++i) o << (i ? ", " : " ") << as_printed(l.y[i]);
    o << " deg (" << l.source << ")";
  }
  return o.str();
}

ItemSection item_section(const PaperItem& item, const PaperIndex& index, const fs::path& out,
                         const fs::path& page_dir, const ItemPlan& plan, const ItemStatus& st) {
  ItemSection s;
  mustache::data d;
  d.set("anchor", item.name);
  d.set("heading", item.paper + " (" + item.name + ")");
  d.set("status", st.state + (st.detail.empty() ? "" : ": " + st.detail));
  d.set("reductions", item.reductions);
  d.set("paper_text", text_or_false(paper_text(item)));
  d.set("trend", text_or_false(item.trend));
  d.set("plot", false);
  d.set("ours", false);
  const fs::path dir = out / item.name;
  if (item.kind == PaperItemKind::kCampaign) campaign_part(item, dir, page_dir, d, s);
  if (item.kind == PaperItemKind::kCalibration) calibration_part(item, dir, page_dir, d, s);
  if (item.kind == PaperItemKind::kDerived) derived_part(item, index, out, page_dir, d, s);
  d.set("not_run", s.ours_text.empty());
  if (s.ours_text.empty()) s.ours_text = "not yet run";
  if (!plan.groups.empty()) {
    d.set("plan", to_data(plan_table(plan)));
  } else {
    d.set("plan", false);
  }
  s.html = render(templates::kPaperItem, d);
  return s;
}

}  // namespace

std::string build_paper_page(const PaperIndex& index, const std::string& out_dir, bool force) {
  const fs::path out = fs::absolute(out_dir).lexically_normal();
  const fs::path page_dir = out / "paper_page";
  const fs::path page = page_dir / "index.html";
  std::error_code ec;
  if (fs::exists(page, ec) && !force)
    throw InputError(page.string() + ": a paper page is already there (rebuild it with --force)");
  fs::create_directories(page_dir);
  Table summary;
  summary.header = {"paper", "item", "the paper", "ours", "reductions", "runs", "CPU-h", "status"};
  std::vector<std::string> sections;
  double planned = 0.0;
  for (const PaperItem& item : index.items) {
    const ItemPlan plan = plan_item(item);
    const ItemStatus st = item_status(item, (out / item.name).string());
    const ItemSection s = item_section(item, index, out, page_dir, plan, st);
    sections.push_back(s.html);
    planned += plan.cpu_hours;
    Cell name;
    name.links.push_back({"#" + item.name, item.name});
    const std::string paper =
        item.paper_points || item.paper_levels ? paper_text(item) : item.trend;
    summary.rows.push_back(
        {{Cell(item.paper), name, paper.empty() ? "-" : paper, s.ours_text, item.reductions,
          std::to_string(plan.runs), fixed(plan.cpu_hours, 2), st.state}});
  }
  mustache::data intro;
  intro.set("built", utc_now());
  intro.set("version", code_version());
  intro.set("index", path_for_page(index.file));
  intro.set("planned", fixed(planned, 1));
  intro.set("budget", fixed(index.budget_cpu_hours, 1));
  intro.set("within", planned <= index.budget_cpu_hours);
  intro.set("summary", to_data(summary));
  Page p;
  p.title = index.title.empty() ? "The paper beside ours" : index.title;
  p.heading = p.title;
  p.sections.push_back(render(templates::kPaperIntro, intro));
  for (auto& s : sections) p.sections.push_back(std::move(s));
  write_file_atomic(page.string(), render_page(p));
  return page.string();
}

}  // namespace reposetwin::experiments
