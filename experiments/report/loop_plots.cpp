// The loop page's residual plots (loop_plots.hpp): one per condition the tests differ in.
#include "experiments/report/loop_plots.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <optional>
#include <set>
#include <sstream>

#include "experiments/io/provenance.hpp"
#include "experiments/report/format.hpp"
#include "experiments/report/gnuplot.hpp"

namespace reposetwin::experiments::report {
namespace fs = std::filesystem;

namespace {

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

bool is_psd_key(const std::string& k) { return k.rfind("set:sample.psd", 0) == 0; }

// A test's size distribution in words: its size band (d_min_mm, d_max_mm) and any PSD scene
// key of a set: column (a sieve table file, its cut-offs); "" when the test declares none.
std::string psd_label(const LabTest& test) {
  std::string label;
  auto add = [&label](const std::string& s) { label += (label.empty() ? "" : ", ") + s; };
  const std::map<std::string, double>& c = test.conditions;
  auto value = [&c](const char* k) {
    return c.count(k) ? sig3_or_dash(c.at(k)) : std::string("?");
  };
  if (c.count("d_min_mm") || c.count("d_max_mm"))
    add(value("d_min_mm") + "-" + value("d_max_mm") + " mm");
  for (const auto& [k, v] : c)
    if (is_psd_key(k)) add(short_key(k.substr(4)) + " " + sig3_or_dash(v));
  for (const auto& [k, v] : test.text_conditions)
    if (is_psd_key(k)) add(fs::path(v).filename().string());
  return label;
}

// A test's numeric conditions by column, with the declared camera height (a column the loop
// keeps apart from the scene's conditions).
std::map<std::string, double> numeric_conditions(const LabTest& test) {
  std::map<std::string, double> c = test.conditions;
  if (test.camera_height_m) c["camera_height_m"] = *test.camera_height_m;
  return c;
}

}  // namespace

// The conditions every test has at one value, as "name value": a residual plot against one is a
// single column of points that tells nothing, so the page names them instead of plotting them.
std::map<std::string, std::string> constant_conditions(const std::vector<LabTest>& tests) {
  std::map<std::string, std::set<std::string>> values;
  std::map<std::string, std::size_t> count;
  for (const LabTest& t : tests) {
    for (const auto& [k, v] : numeric_conditions(t)) {
      values[k].insert(sig3_or_dash(v));
      ++count[k];
    }
    for (const auto& [k, v] : t.text_conditions) {
      if (is_psd_key(k)) continue;  // shown on the PSD's own plot
      values[k].insert(v);
      ++count[k];
    }
  }
  std::map<std::string, std::string> constant;
  for (const auto& [k, v] : values)
    if (v.size() == 1 && count[k] == tests.size()) constant[k] = *v.begin();
  return constant;
}

namespace {

// What the residual plots are drawn from: the tests, their rows before and after, and their
// size distributions (series of their own when the tests differ in it).
struct PlotData {
  const LoopRecord& loop;
  std::vector<std::string> psd;        // per test
  std::vector<std::string> psd_names;  // distinct, sorted
  bool split = false;

  explicit PlotData(const LoopRecord& l) : loop(l) {
    std::set<std::string> psds;
    for (const LabTest& t : loop.tests) psds.insert(psd.emplace_back(psd_label(t)));
    split = psds.size() > 1;
    psd_names.assign(psds.begin(), psds.end());
  }
  ResidualPoint point(std::size_t i, double x) const {
    const ResidualRow& before = loop.baseline.residuals[i];
    return {x, before.residual_deg, loop.final_model.residuals[i].residual_deg, before.sigma_deg,
            loop.tests[i].role == Role::kCalibrate};
  }
  std::size_t series_of(std::size_t i) const {
    if (!split) return 0;
    return static_cast<std::size_t>(std::find(psd_names.begin(), psd_names.end(), psd[i]) -
                                    psd_names.begin());
  }
  ResidualPlot empty_plot(const std::string& condition) const {
    ResidualPlot p;
    p.condition = condition;
    if (split)
      for (const std::string& n : psd_names)
        p.series.push_back("PSD " + (n.empty() ? "of the scene" : n));
    else
      p.series.push_back("");
    p.points.resize(p.series.size());
    return p;
  }
};

// A category axis: the tests' values of `value_of` (empty: the test has none), sorted.
template <class F>
ResidualPlot categorical(const PlotData& d, const std::string& condition, F value_of) {
  ResidualPlot p;
  p.condition = condition;
  p.series = {std::string()};
  p.points.resize(1);
  const std::size_t n = d.loop.tests.size();
  std::set<std::string> values;
  for (std::size_t i = 0; i < n; ++i)
    if (!value_of(i).empty()) values.insert(value_of(i));
  p.categories.assign(values.begin(), values.end());
  for (std::size_t i = 0; i < n; ++i) {
    const std::string v = value_of(i);
    if (v.empty()) continue;
    const auto at = std::find(p.categories.begin(), p.categories.end(), v);
    p.points[0].push_back(d.point(i, static_cast<double>(at - p.categories.begin())));
  }
  return p;
}

// Every plot: each numeric condition on its axis, each text condition (a plate material) as
// categories, and the size distribution as categories of its own when the tests differ in it;
// none against a condition every test has at one value (constant_conditions).
std::vector<ResidualPlot> residual_plots(const LoopRecord& loop) {
  const PlotData d(loop);
  const std::vector<LabTest>& tests = loop.tests;
  const std::map<std::string, std::string> constant = constant_conditions(tests);
  std::set<std::string> numeric, text;
  for (const LabTest& t : tests) {
    for (const auto& [k, v] : numeric_conditions(t))
      if (!constant.count(k)) numeric.insert(k);
    for (const auto& [k, v] : t.text_conditions)
      if (!is_psd_key(k) && !constant.count(k)) text.insert(k);
  }
  std::vector<ResidualPlot> plots;
  for (const std::string& c : numeric) {
    ResidualPlot& p = plots.emplace_back(d.empty_plot(c));
    for (std::size_t i = 0; i < tests.size(); ++i) {
      const std::map<std::string, double> v = numeric_conditions(tests[i]);
      if (const auto it = v.find(c); it != v.end())
        p.points[d.series_of(i)].push_back(d.point(i, it->second));
    }
  }
  for (const std::string& c : text)
    plots.push_back(categorical(d, c, [&](std::size_t i) {
      const auto it = tests[i].text_conditions.find(c);
      return it == tests[i].text_conditions.end() ? std::string() : it->second;
    }));
  if (d.split)
    plots.push_back(categorical(d, "PSD", [&](std::size_t i) {
      return d.psd[i].empty() ? std::string("scene's") : d.psd[i];
    }));
  return plots;
}

// A string for a gnuplot single-quoted literal.
std::string gnuplot_quoted(const std::string& s) {
  std::string q = "'";
  for (char ch : s) q += ch == '\'' ? std::string("''") : std::string(1, ch);
  return q + "'";
}

// The gnuplot script of a residual plot whose data are in `data`, drawing `png`.
std::string plot_script(const ResidualPlot& p, const fs::path& data, const fs::path& png) {
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
  // Every point at one value of a numeric condition: gnuplot cannot autoscale an x range of
  // zero width ("x range is invalid"), so the range is set around the value.
  if (p.categories.empty()) {
    double lo = INFINITY, hi = -INFINITY;
    for (const auto& series : p.points)
      for (const ResidualPoint& q : series) lo = std::min(lo, q.x), hi = std::max(hi, q.x);
    if (lo == hi) {
      const double w = lo != 0.0 ? 0.1 * std::abs(lo) : 1.0;
      std::ostringstream r;
      r.precision(12);
      r << "set xrange [" << lo - w << ":" << hi + w << "]\n";
      script += r.str();
    }
  }
  // Before and after side by side on a category; one colour per series when there are several.
  const std::string shift = p.categories.empty() ? "" : "0.08";
  std::string plot;
  int block = 0;  // the series' block in the data file: empty series have none (draw)
  for (std::size_t s = 0; s < p.series.size(); ++s) {
    if (p.points[s].empty()) continue;
    const std::string name = p.series[s].empty() ? "" : ", " + p.series[s];
    const std::string index = " index " + std::to_string(block++);
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
  return script + plot + "\n";
}

// The plot's data (one block per series), gnuplot script and figure; none without a point.
std::optional<Figure> draw(const ResidualPlot& p, const fs::path& dir) {
  bool any = false;
  for (const auto& series : p.points) any = any || !series.empty();
  if (!any) return std::nullopt;  // nothing to draw: no figure, and no gnuplot run to fail
  std::string safe = p.condition;
  for (char& ch : safe)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  const fs::path data = dir / ("residual_" + safe + ".dat");
  const fs::path png = dir / ("residual_" + safe + ".png");
  std::ostringstream d;
  d << "# " << p.condition << (p.categories.empty() ? "" : " (category index)")
    << " residual_before_deg residual_after_deg sigma_deg role(1=calibrate)\n";
  // A block per series with points only: gnuplot does not count a block without data in its
  // `index`, so an empty series would shift every later one (plot_script numbers the same way).
  bool first = true;
  for (std::size_t s = 0; s < p.series.size(); ++s) {
    if (p.points[s].empty()) continue;
    if (!first) d << "\n\n";
    first = false;
    d << "# series " << s << ": " << (p.series[s].empty() ? "all tests" : p.series[s]) << "\n";
    for (const ResidualPoint& q : p.points[s])
      d << q.x << " " << q.before << " " << q.after << " " << q.sigma << " "
        << (q.calibrate ? 1 : 0) << "\n";
  }
  write_file_atomic(data.string(), d.str());
  const std::string script = plot_script(p, data, png);
  run_gnuplot(dir / ("residual_" + safe + ".gp"), script, png);
  std::string caption = "Residual against " + p.condition;
  if (!p.categories.empty()) caption += " (a category each)";
  if (p.series.size() > 1)
    caption += ", one colour per size distribution (open: before, filled: after)";
  return Figure{"plots/" + png.filename().string(),
                caption + " (error bars: seed noise of one residual)", 0};
}

}  // namespace

std::vector<Figure> residual_figures(const LoopRecord& loop, const fs::path& dir) {
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

}  // namespace reposetwin::experiments::report
