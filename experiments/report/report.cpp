// build_report (report.hpp): read a folder's results, then its tables, plots and page. The paper
// comparison lives in paper_comparison.cpp, the page layout in templates.cpp.
#include "experiments/report/report.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <sstream>

#include "experiments/calibration/calibrate_campaign.hpp"
#include "experiments/calibration/calibration.hpp"
#include "experiments/io/format.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/loop/loop.hpp"
#include "experiments/pile/headline.hpp"
#include "experiments/photos/lab_photos.hpp"
#include "experiments/photos/photographs.hpp"
#include "experiments/pile/pile_record.hpp"
#include "experiments/report/calibration_section.hpp"
#include "experiments/report/folder_results.hpp"
#include "experiments/report/format.hpp"
#include "experiments/report/gnuplot.hpp"
#include "experiments/report/html.hpp"
#include "experiments/report/loop_report.hpp"
#include "experiments/report/paper_comparison.hpp"
#include "experiments/report/templates.hpp"
#include "vision/image.hpp"
#include "vision/measure.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;
using namespace report;

namespace {

// Angles per case: image and particle atan(2H/D) and the image flank angle, mean ± sd.
void angles_plot(const FolderResults& f, const fs::path& out) {
  const std::string data = angles_plot_data(f);
  write_file_atomic((out / "angles.dat").string(), data);
  run_gnuplot(out / "angles.gp",
              png_terminal(out / "angles.png", 900, 520, false) +
                  "set ylabel 'angle of repose [deg]'\nset xtics rotate by 30 right\n"
                  "set key outside top center horizontal\nset grid ytics\n"
                  "set offsets 0.5,0.5,2,2\nplot 'angles.dat'"
                  " using 1:2:3:xtic(6) with yerrorbars pt 7 title 'image atan(2H/D) "
                  "(vision on renders)', '' using ($1+0.1):4:5 with yerrorbars pt 5 "
                  "title 'particles atan(2H/D)', '' using ($1+0.2):7:8 with yerrorbars "
                  "pt 9 title 'image flank angle (vision on renders)'\n",
              out / "angles.png");
}

// A render shown beside the lab photo, with its caption; empty path when there is none.
struct RenderBeside {
  fs::path overlay;
  std::string caption;
  double mm_per_px = 0.0;  // the render's scale at the pile axis [mm/px]; 0 = not known
};

// The scale vision measured on a run's side view at azimuth 0 (images/measurement.json), 0 when
// the file or the view is missing.
double render_mm_per_px(const fs::path& overlay) {
  const fs::path m = overlay.parent_path() / "measurement.json";
  if (!fs::is_regular_file(m)) return 0.0;
  for (const json& v : read_json(m).value("side_views", json::array()))
    if (v.value("image", std::string()) == "side_az000.png" && v.contains("scale"))
      return v["scale"].value("mm_per_px", 0.0);
  return 0.0;
}

fs::path overlay_of(const FolderResults& f, const CaseRows& c) {
  for (const auto& d : c.image_dirs) {
    const fs::path p = f.dir / d / "side_az000.measured.png";
    if (fs::exists(p)) return p;
  }
  return {};
}

// For a calibration, the run of the calibration scene nearest the calibrated mu_r (a check run
// at it when there is one); otherwise the first case with a measured render.
RenderBeside render_beside_lab(const FolderResults& f) {
  RenderBeside b;
  if (f.calibration && f.calibration->mu_r) {
    const double mu = *f.calibration->mu_r;
    const std::string& key = f.calibration->keys.front();
    const std::string& scene = f.calibration->scene;
    double best = std::numeric_limits<double>::infinity();
    for (const CaseRows& c : f.cases) {
      if (!c.overrides.contains(key) || !c.overrides[key].is_number()) continue;
      if (!scene.empty() && !c.scene.empty() && c.scene != scene) continue;
      // The lab photographed the calibration test: a render beside it is of that test.
      if (!same_test_as_calibration(f, c)) continue;
      const fs::path p = overlay_of(f, c);
      if (p.empty()) continue;
      const double value = c.overrides[key].get<double>();
      const double d = std::abs(value - mu);
      const bool check_run = c.name.rfind("predict_", 0) == 0;  // a run at mu_r itself, preferred
      if (d < best || (d == best && check_run)) {
        best = d;
        b = {p,
             "simulated: " + case_label(c.name, c.overrides) + " (calibrated mu_r " +
                 fixed(mu, 3) + "; case " + c.name + "), azimuth 0",
             render_mm_per_px(p)};
      }
    }
  }
  for (std::size_t i = 0; b.overlay.empty() && i < f.cases.size(); ++i) {
    b.overlay = overlay_of(f, f.cases[i]);
    if (!b.overlay.empty()) {
      b.caption = "simulated: " + case_label(f.cases[i].name, f.cases[i].overrides) +
                  " (case " + f.cases[i].name + ", the first with a render), azimuth 0";
      b.mm_per_px = render_mm_per_px(b.overlay);
    }
  }
  return b;
}

// The width of the wider image of the pair on the page [px].
constexpr double kBesideWidthPx = 560.0;

// `img` resized by `f` (area averaging when it shrinks).
cv::Mat resized(const cv::Mat& img, double f) {
  cv::Mat out;
  cv::resize(img, out, cv::Size(), f, f, f < 1.0 ? cv::INTER_AREA : cv::INTER_LINEAR);
  return out;
}

// The lab photo measured by the same code as the renders, shown beside a render overlay at one
// scale: both resampled to the same mm per px (each image's own scale at the pile axis, the lab's
// from its scale bar or --lab-mm-per-px, the render's from its camera), the coarser of the two or
// coarser still so the wider one is kBesideWidthPx on the page. A pile of one size is then one
// size in both. "" when no lab photo is given.
// The lab's side photo as the page shows it: vision's overlay drawn on it, its scale at the pile
// axis and the caption with its measurement.
struct LabView {
  cv::Mat overlay;
  double mm_per_px = 0.0;  // [mm/px]
  std::string caption;
};

// The photo given to `report --lab-photo`, measured here (its scale bar or --lab-mm-per-px).
std::optional<LabView> given_lab_view(const ReportSettings& settings, json& summary) {
  if (settings.lab_photo.empty()) return std::nullopt;
  // vision's loader reads only a regular image file within its size limits (a FIFO named as the
  // photo would block cv::imread).
  cv::Mat photo;
  try {
    photo = vision::load_image(settings.lab_photo);
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("--lab-photo ") + e.what());
  }
  vision::ScaleSpec scale;
  if (settings.lab_mm_per_px > 0) scale.mm_per_px = settings.lab_mm_per_px;
  const vision::SideMeasurement m = vision::measure_side(photo, scale, {}, settings.lab_photo);
  summary["lab_photo"] = vision::to_json(m);
  return LabView{vision::draw_side_overlay(photo, m), m.mm_per_px,
                 "lab photo " + fs::path(settings.lab_photo).filename().string() +
                     ": theta = atan(2H/D) = " + mean_sd(m.theta_deg, m.sigma_theta_deg) +
                     " deg (vision, as the renders); its scale " + fixed(m.mm_per_px, 3) +
                     " mm/px (" + vision::to_string(m.scale_source) + ")"};
}

// A calibration's own target photo (its first measured one), measured again exactly as the
// calibration measured it (the same camera sidecar or declared scale), with its overlay; none when
// the calibration's target was typed, or when the photo is no longer where it was (said on the
// page through `note`).
std::optional<LabView> target_lab_view(const CalibrationRecord& cal, std::string& note) {
  if (!cal.target_photos) return std::nullopt;
  const TargetPhotosRecord& tp = *cal.target_photos;
  const std::string photo = tp.photos.front();
  LabPhotoScale scale;
  scale.camera_json = tp.camera_sidecar;
  if (tp.declared_mm_per_px) scale.mm_per_px = *tp.declared_mm_per_px;
  try {
    const LabPhotoMeasurement m = measure_lab_photos(
        {photo}, scale, {"calibration.json: target_photos", "target_photos.camera_sidecar",
                         "target_photos.declared_mm_per_px", "photo_camera", "mm_per_px"},
        true);
    const json& v = m.record.at("views").at(0);
    const double mm = v.at("scale").at("mm_per_px").get<double>();
    return LabView{m.overlays.at(0), mm,
                   "the lab's photo " + fs::path(photo).filename().string() +
                       " (the calibration's target): theta = atan(2H/D) = " +
                       mean_sd(v.at("theta_deg").get<double>(),
                               v.at("sigma_theta_deg").get<double>()) +
                       " deg (vision, as the renders); its scale " + fixed(mm, 3) + " mm/px"};
  } catch (const std::exception& e) {
    note = "The lab's photo " + photo + " could not be shown: " + e.what();
    return std::nullopt;
  }
}

std::string lab_photo_section(const std::optional<LabView>& given, const fs::path& out,
                              const RenderBeside& beside, json& summary,
                              const std::string& note = "") {
  if (!given) {
    if (note.empty()) return "";
    mustache::data d;
    d.set("photos", mustache::data::type::list);
    d.set("render", true);  // no "render missing" line: the note says why nothing is shown
    d.set("scale", false);
    d.set("note", note);
    return render(templates::kLabPhoto, d);
  }
  const LabView& view = *given;
  const cv::Mat& lab = view.overlay;
  const cv::Mat twin = beside.overlay.empty() || !fs::exists(beside.overlay)
                             ? cv::Mat()
                             : cv::imread(beside.overlay.string(), cv::IMREAD_COLOR);
  const bool has_render = !twin.empty();
  const double lab_mm = view.mm_per_px;
  const bool same_scale = has_render && beside.mm_per_px > 0 && lab_mm > 0;
  double common = lab_mm;  // [mm/px]
  if (same_scale)
    common = beside_scale({{lab.cols, lab_mm}, {twin.cols, beside.mm_per_px}}, kBesideWidthPx);
  else
    common = beside_scale({{lab.cols, lab_mm}}, kBesideWidthPx);
  write_image_atomic((out / "lab_photo.measured.png").string(), resized(lab, lab_mm / common));
  std::vector<Figure> photos = {{"lab_photo.measured.png", view.caption, 0}};
  std::string scale_text;
  if (has_render) {
    // A render of unknown scale is shown at the lab photo's width on the page, and said so.
    const double lab_width_px = lab.cols * lab_mm / common;
    write_image_atomic((out / "render_beside_lab.png").string(),
                       resized(twin, same_scale ? beside.mm_per_px / common : lab_width_px / twin.cols));
    photos.push_back({"render_beside_lab.png",
                      beside.caption + (same_scale ? "; its scale " +
                                                         fixed(beside.mm_per_px, 3) + " mm/px"
                                                   : std::string()),
                      0});
    summary["lab_photo_render"] = beside.caption;
    scale_text = same_scale ? "Both images at " + fixed(common, 3) +
                                  " mm per px at the pile axis, each with vision's measurement "
                                  "drawn on it: a pile of one size is one size in both."
                            : "The render's scale is not known (no images/measurement.json "
                              "beside it): the two are shown at one width, not at one scale.";
  }
  summary["lab_photo_common_mm_per_px"] = same_scale ? json(common) : json();
  mustache::data d;
  d.set("photos", to_data(photos));
  d.set("render", has_render);
  d.set("scale", text_or_false(scale_text));
  d.set("note", text_or_false(note));
  return render(templates::kLabPhoto, d);
}

// A case's overrides, one "key = value" per line (spaces let the table wrap them).
std::string overrides_text(const json& overrides) {
  std::string t;
  for (const auto& [key, value] : overrides.items())
    t += (t.empty() ? "" : "; ") + key + " = " + (value.is_number() ? as_printed(value) : value.dump());
  return t.empty() ? "none" : t;
}

// Links to a case's run records: each seed's result.json, and its ParaView series when the run
// folder is still there (committed results keep the records, not the runs).
std::vector<Link> run_links(const FolderResults& f, const CaseRows& c) {
  std::vector<Link> links;
  for (std::size_t k = 0; k < c.run_dirs.size(); ++k) {
    const fs::path run(c.run_dirs[k]);
    const fs::path record(c.records[k]);
    const bool campaign = record.parent_path().filename().string().rfind("seed_", 0) == 0;
    const std::string seed = campaign ? record.parent_path().filename().string() : "run";
    if (fs::exists(f.dir / record))
      links.push_back({("../" / record).lexically_normal().string(), seed});
    if (fs::exists(f.dir / run / "series.pvd"))
      links.push_back({("../" / run / "series.pvd").lexically_normal().string(), "pvd"});
  }
  return links;
}

TableRow case_row(const FolderResults& f, const CaseRows& c) {
  const CaseStats s = case_stats(c);
  std::map<std::string, int> stops;
  for (const auto& r : c.stops) ++stops[r];
  std::string stop_text;
  for (const auto& [r, n] : stops) stop_text += r + " x" + std::to_string(n) + " ";
  Cell prov;
  prov.small = "dt " + sig3(c.provenance.value("time_step_s", json())) + " s, E " +
               sig3(c.provenance.value("softened_youngs_modulus_pa", json())) + " Pa, " +
               c.provenance.value("code_version", std::string("?"));
  Cell name;
  name.bold = case_label(c.name, c.overrides);
  name.note = c.name;
  name.left = true;
  Cell overrides;
  overrides.small = overrides_text(c.overrides);
  overrides.left = true;
  Cell files;
  files.links = run_links(f, c);
  int without = 0;
  std::string runs_text;
  for (const auto& [reason, n] : c.without_pile) {
    without += n;
    runs_text += ", " + std::to_string(n) + " " + reason;
  }
  runs_text = std::to_string(static_cast<int>(c.run_dirs.size()) - without) + " of " +
              std::to_string(c.run_dirs.size()) + runs_text;
  return {{name, overrides, runs_text, s.image.n ? mean_sd(s.image.mean, s.image.sd) : "-",
           s.flank.n ? mean_sd(s.flank.mean, s.flank.sd) : "-",
           s.particle.n ? mean_sd(s.particle.mean, s.particle.sd) : "-",
           s.slice.n ? fixed(s.slice.mean) : "-", stop_text, prov, files}};
}

// The cases table and each case's first render with its measurement overlay, copied into the
// report folder so the page travels with it. A copy made when the run folder was still there is
// kept when a later build finds the run folder gone (committed results keep the report's copy).
std::string cases_section(const FolderResults& f, const fs::path& out) {
  Table t;
  t.header = {"case",
              "inputs (overrides)",
              "piles of runs (the others by reason)",
              "image angle [deg] mean \u00b1 sd (runs without a pile left out)",
              "image flank angle [deg]",
              "particle atan(2H/D) [deg]",
              "slice (protractor) [deg]",
              "stop reasons",
              "provenance",
              "run records"};
  std::vector<Figure> renders;
  for (const CaseRows& c : f.cases) {
    t.rows.push_back(case_row(f, c));
    const fs::path overlay = f.dir / c.image_dirs.front() / "side_az000.measured.png";
    const std::string local = c.name + "_side.png";
    if (fs::exists(overlay))
      fs::copy_file(overlay, out / local, fs::copy_options::overwrite_existing);
    if (!fs::exists(out / local)) continue;
    renders.push_back({local, case_label(c.name, c.overrides) + " (first run, azimuth 0)", 480});
  }
  mustache::data d;
  d.set("cases", to_data(t));
  d.set("renders", to_data(renders));
  d.set("no_renders", text_or_false(renders.empty() ? "No renders: the runs of this folder were "
                                                      "made without images, or their folders "
                                                      "are not here."
                                                    : std::string()));
  return render(templates::kCases, d);
}

// A folder's own name ("results/x/" and "results/x" both give "x"): the page names the folder it
// was built from without the path on the machine that built it.
std::string folder_name(const fs::path& dir) {
  fs::path p = fs::absolute(dir).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  return p.filename().string();
}

// A calibration folder without its run records: the folder's own lists of its runs, linked,
// and the renders an earlier build copied into the report, by case name.
std::string no_cases_section(const FolderResults& f, const fs::path& out) {
  mustache::data links(mustache::data::type::list);
  for (const char* file : {"runs.csv", "README.md"})
    if (fs::is_regular_file(f.dir / file)) {
      mustache::data l;
      l.set("href", std::string("../") + file);
      l.set("label", std::string(file));
      links.push_back(l);
    }
  std::vector<fs::path> kept;
  for (const auto& e : fs::directory_iterator(out)) {
    const std::string n = e.path().filename().string();
    if (n.size() > 9 && n.compare(n.size() - 9, 9, "_side.png") == 0) kept.push_back(e.path());
  }
  std::sort(kept.begin(), kept.end());
  std::vector<Figure> renders;
  for (const fs::path& p : kept) {
    const std::string name = p.filename().string();
    renders.push_back({name, "case " + name.substr(0, name.size() - 9) + " (azimuth 0)", 480});
  }
  mustache::data listed;
  listed.set("links", links);
  mustache::data d;
  d.set("listed", links.is_empty_list() ? mustache::data(false) : listed);
  d.set("kept", !renders.empty());
  d.set("renders", to_data(renders));
  return render(templates::kNoCases, d);
}

std::string built_section(const std::string& dir, std::size_t folders) {
  mustache::data d;
  d.set("built", utc_now());
  d.set("version", code_version());
  d.set("dir", text_or_false(dir));
  d.set("folders", std::to_string(folders));
  return render(templates::kBuilt, d);
}

// What to run after a calibration: export its material (or, without a mu_r, calibrate again as
// its advice says), and rebuild this page. A page is read in a copied folder too, so it names no
// absolute path: the folder as the report was given it when that is relative (a command run
// where the report was built), else its name (run from the folder that holds it), and the page
// says which.
std::string next_steps_section(const FolderResults& f) {
  const bool reached = f.calibration && f.calibration->reached();
  const fs::path given = f.dir.lexically_normal();
  const bool relative = given.is_relative() && !given.empty();
  fs::path whole = fs::absolute(f.dir).lexically_normal();
  if (whole.filename().empty()) whole = whole.parent_path();  // "/runs/cal1/"
  const std::string folder = relative ? given.string() : whole.filename().string();
  const std::vector<NextStep> steps = calibration_next_steps(folder, reached);
  mustache::data d;
  d.set("where", relative ? "where this report was built" : "in the folder that holds " + folder);
  d.set("export", reached ? mustache::data(steps.back().command) : mustache::data(false));
  d.set("again", "the calibrate command printed why and what to try (a wider mu_r range, the "
                 "grain shape, the plate friction); its runs are reused when it is run again into "
                 "the same folder");
  d.set("report", steps.front().command + " --force");
  return render(templates::kNextSteps, d);
}

void write_page(const fs::path& out, const std::string& title, std::vector<std::string> sections,
                const json& summary) {
  std::erase(sections, std::string());
  const Page page{title, "ReposeTwin report: " + title, std::move(sections)};
  write_file_atomic((out / "index.html").string(), render_page(page));
  write_json_atomic((out / "summary.json").string(), summary);
}

// The sub-folders holding results of a folder that holds none itself, sorted.
std::vector<std::string> result_subfolders(const fs::path& dir) {
  std::vector<std::string> subs;
  if (!fs::is_directory(dir) || holds_results(dir)) return subs;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.is_directory() && holds_results(e.path())) subs.push_back(e.path().string());
  std::sort(subs.begin(), subs.end());
  return subs;
}

// A loop folder: loop.json and no run, campaign or calibration results.
bool is_loop_dir(const fs::path& d) {
  return !holds_results(d) && fs::is_regular_file(d / "loop.json");
}

}  // namespace

namespace {

// "jam 2, not_settled 1": the runs without an angle by reason.
std::string reasons_of(const json& without) {
  std::string t;
  for (const auto& [reason, n] : without.items())
    t += (t.empty() ? "" : ", ") + std::to_string(n.get<int>()) + " " + reason;
  return t;
}

std::string calibration_line(const CalibrationRecord& c) {
  if (!c.mu_r) return "no calibrated mu_r (" + to_string(c.status) + "): " + c.message;
  return "calibrated mu_r " + fixed(*c.mu_r, 3) + " (" + fixed(100.0 * c.interval_level, 0) +
         "% interval " + fixed(c.mu_r_lo, 3) + "-" + fixed(c.mu_r_hi, 3) + ") for the target " +
         fixed(c.target.angle_deg, 2) + " deg, " + std::to_string(c.simulations) + " simulations";
}

std::string cases_line(const json& cases) {
  int runs = 0, piles = 0;
  json without = json::object();
  for (const json& c : cases) {
    runs += c.value("runs", 0);
    piles += c.value("piles", 0);
    const json by_reason = c.value("without_pile", json::object());
    for (const auto& [reason, n] : by_reason.items())
      without[reason] = without.value(reason, 0) + n.get<int>();
  }
  std::string line;
  if (cases.size() == 1 && piles > 0) {
    const json& c = cases[0];
    const bool images = c.value("image_runs", 0) > 0;
    line = c.value("case", std::string()) + ": angle of repose " +
           fixed_or_dash(c[images ? "image_theta_mean_deg" : "particle_theta_mean_deg"], 2) +
           (piles > 1
                ? " \u00b1 " +
                      fixed_or_dash(c[images ? "image_theta_sd_deg" : "particle_theta_sd_deg"], 2)
                : std::string()) +
           " deg (" + (images ? "image" : "particle") + " atan(2H/D), " + std::to_string(piles) +
           (piles == 1 ? " run)" : " runs)");
  } else {
    line = std::to_string(cases.size()) + (cases.size() == 1 ? " case, " : " cases, ") +
           std::to_string(runs) + (runs == 1 ? " run, " : " runs, ") + std::to_string(piles) +
           " with an angle";
  }
  if (!without.empty()) line += "; without an angle: " + reasons_of(without);
  return line;
}

}  // namespace

std::string report_line(const json& summary, const std::string& page) {
  std::string what;
  if (summary.contains("incomplete"))
    what = summary.value("title", std::string("run")) + ": incomplete run, no headline: " +
           summary["incomplete"].get<std::string>() + "; finish it with run --resume";
  else if (summary.contains("calibration") && summary["calibration"].is_object())
    what = calibration_line(
        calibration_record_from_json(summary["calibration"], "the report's calibration"));
  else if (summary.contains("cases") && !summary["cases"].empty())
    what = cases_line(summary["cases"]);
  else if (summary.contains("folders"))
    what = std::to_string(summary["folders"].size()) + " folders, each with its own report";
  else
    what = summary.value("title", std::string("report"));
  return what + "; report " + page;
}

std::string report_page(const std::string& dir) {
  return ((is_loop_dir(dir) ? fs::path(dir) : fs::path(dir) / "report") / "index.html").string();
}

json build_report(const std::string& dir, const ReportSettings& settings) {
  // A loop folder's page is rebuilt from its loop.json, in the place the loop wrote it.
  if (is_loop_dir(dir)) {
    const json loop = read_json(fs::path(dir) / "loop.json");
    write_loop_html(loop, dir);
    return {{"title", "loop"}, {"page", (fs::path(dir) / "index.html").string()}};
  }
  if (const auto subs = result_subfolders(dir); !subs.empty())
    return build_report(subs, dir, settings);
  const FolderResults f = read_folder_results(dir, settings.title);
  const fs::path out = f.dir / "report";
  fs::create_directories(out);
  json summary = case_summary(f);
  std::vector<std::string> sections = {built_section(folder_name(f.dir), 1)};
  if (!f.incomplete.empty()) {
    mustache::data d;
    d.set("reason", f.incomplete);
    sections.push_back(render(templates::kIncompleteRun, d));
    summary["incomplete"] = f.incomplete;
  }
  // A calibration's page leads with its answer: the calibrated value, its interval and curve,
  // then the lab's photo (the one given, else the calibration's own target photo) beside the
  // twin's at that value; the runs follow, and the paper's Table 3 comes last, on a paper
  // sample's calibration only.
  std::string photo_note;
  std::optional<LabView> lab = given_lab_view(settings, summary);
  if (!lab && f.calibration) lab = target_lab_view(*f.calibration, photo_note);
  if (f.calibration) {
    sections.push_back(calibration_section(*f.calibration, f.predictions ? *f.predictions : json(),
                                           out, "../calibration.json"));
    summary["calibration"] = to_json(*f.calibration);
    sections.push_back(next_steps_section(f));
  }
  sections.push_back(lab_photo_section(lab, out, render_beside_lab(f), summary, photo_note));
  if (f.predictions) {
    sections.push_back(predictions_section(*f.predictions, "../predictions.json"));
    summary["predictions"] = *f.predictions;
  }
  if (!f.cases.empty()) {
    // A plot needs a point: when no case has an angle (an incomplete run, jams only), the cases
    // are listed in the table alone, and gnuplot, which refuses a plot of no points, is not run.
    const bool any_angle = std::any_of(f.cases.begin(), f.cases.end(), [](const CaseRows& c) {
      const CaseStats s = case_stats(c);
      return s.image.n + s.particle.n + s.flank.n > 0;
    });
    if (any_angle) {
      angles_plot(f, out);
      sections.push_back(templates::kAngles);
    }
    sections.push_back(cases_section(f, out));
  } else if (is_calibration_dir(f.dir)) {
    sections.push_back(no_cases_section(f, out));
  }
  if (is_calibration_dir(f.dir) && f.calibration && f.calibration->table1_sample) {
    const json cmp = paper_comparison({dir}, settings.paper_dir);
    sections.push_back(comparison_section(cmp, out));
    summary["paper_comparison"] = cmp;
  }
  write_page(out, f.title, std::move(sections), summary);
  return summary;
}

json build_report(const std::vector<std::string>& dirs, const std::string& out_dir,
                  const ReportSettings& settings) {
  if (dirs.empty()) throw InputError("report: no folders given");
  if (dirs.size() == 1 && (out_dir.empty() || fs::equivalent(dirs[0], out_dir)) &&
      holds_results(dirs[0]))
    return build_report(dirs[0], settings);
  const fs::path out = fs::path(out_dir) / "report";
  fs::create_directories(out);
  const std::string title = settings.title.empty() ? std::string("paper comparison") : settings.title;
  json summary = {{"title", title}, {"folders", json::array()}};
  ReportSettings sub = settings;
  // Each folder's own report shows the lab photo beside its render; this page shows it alone.
  sub.title.clear();
  std::vector<std::string> cal_dirs;
  mustache::data folders(mustache::data::type::list);
  for (const std::string& d : dirs) {
    if (!holds_results(d))
      throw InputError(d + ": no run, campaign or calibration results to report");
    const json s = build_report(d, sub);
    if (is_calibration_dir(d)) cal_dirs.push_back(d);
    const fs::path page = fs::absolute(fs::path(d) / "report" / "index.html");
    mustache::data link;
    link.set("href", fs::relative(page, fs::absolute(out)).string());
    link.set("dir", fs::relative(fs::absolute(d), fs::absolute(out)).lexically_normal().string());
    link.set("title", s.value("title", std::string()));
    folders.push_back(link);
    summary["folders"].push_back({{"dir", d}, {"title", s.value("title", std::string())}});
  }
  std::vector<std::string> sections = {built_section("", dirs.size())};
  if (!cal_dirs.empty()) {
    const json cmp = paper_comparison(cal_dirs, settings.paper_dir);
    sections.push_back(comparison_section(cmp, out));
    summary["paper_comparison"] = cmp;
  }
  sections.push_back(lab_photo_section(given_lab_view(settings, summary), out, {}, summary));
  mustache::data list;
  list.set("folders", folders);
  sections.push_back(render(templates::kFolders, list));
  write_page(out, title, std::move(sections), summary);
  return summary;
}

}  // namespace reposetwin::experiments
