#include "experiments/calibration/calibrate_campaign.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>

#include "experiments/calibration/bracket_calibration.hpp"
#include "experiments/calibration/calibration.hpp"
#include "experiments/campaign/case_runner.hpp"
#include "experiments/io/calibration_record.hpp"
#include "experiments/io/format.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/pile/headline.hpp"
#include "sim/contact.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
namespace {

constexpr const char* kCalibrationFile = "calibration.json";
constexpr const char* kPredictionsFile = "predictions.json";

const CampaignCalibration& calibration_of(const Campaign& c) {
  if (!c.calibration)
    throw std::invalid_argument(c.file + ": [calibration] is missing (target_deg, mu_r_range)");
  return *c.calibration;
}

std::vector<std::string> keys_of(const CampaignCalibration& cc) {
  return cc.keys.empty() ? std::vector<std::string>{cc.key} : cc.keys;
}

// The rolling law behind the calibrated key: the scene's rolling_model beside the key (the
// scene format's default "epsd" when the scene does not say), described by sim::kRollingModels.
RollingModelRecord rolling_model_of(const Campaign& c) {
  const auto& cc = calibration_of(c);
  const SceneDoc doc = build_case_scene(calibration_run(c, cc.settings.mu_r_lo, 1));
  const auto dot = cc.key.rfind('.');
  const std::string parent = dot == std::string::npos ? std::string() : cc.key.substr(0, dot);
  std::string keyword = "epsd";
  bool stated = false;
  if (!parent.empty()) {
    if (auto v = doc.string(parent + ".rolling_model")) {
      keyword = *v;
      stated = true;
    }
  }
  RollingModelRecord m{keyword, stated, "", "", ""};
  if (const sim::RollingModelInfo* info = sim::find_rolling_model(keyword)) {
    m.torque = info->torque;
    m.radius = info->radius;
    m.angular_velocity = info->angular_velocity;
  }
  return m;
}

// The first field in which a stored calibration.json answered another question than campaign `c`
// asks now ({field, stored, now}), or none. The angle is compared only when one is given.
struct FieldDifference {
  std::string field;
  nlohmann::json stored, now;
};
std::optional<FieldDifference> calibration_difference(const CalibrationRecord& r, const Campaign& c,
                                                      const std::string& angle_method) {
  const CampaignCalibration& cc = calibration_of(c);
  const auto method = [](CalibrationMethod m) {
    return m == CalibrationMethod::kBracket ? "bracket" : "sequential";
  };
  const std::vector<FieldDifference> fields = {
      {"campaign_name", r.campaign_name, c.name},
      {"keys", r.keys, keys_of(cc)},
      {"target.angle_deg", r.target.angle_deg, cc.target.angle_deg},
      {"mu_r_range",
       {r.mu_r_range_lo, r.mu_r_range_hi},
       nlohmann::json{cc.settings.mu_r_lo, cc.settings.mu_r_hi}},
      {"angle_method", r.angle_method, angle_method.empty() ? r.angle_method : angle_method},
      {"method", method(r.method), method(cc.method)}};
  for (const FieldDifference& f : fields)
    if (f.stored != f.now) return f;
  return std::nullopt;
}

// A finished calibration in OUT is a result: calibrating again with the same question rewrites it
// with the same numbers (every run is reused), but a different question (target, range, keys or
// angle) would silently replace it, so that needs --force.
void refuse_to_replace_other_calibration(const Campaign& c, const std::string& out_dir,
                                         const CalibrateOptions& options, bool force) {
  const std::string file = (fs::path(out_dir) / kCalibrationFile).string();
  if (force || !fs::exists(file)) return;
  CalibrationRecord old;
  try {
    old = read_calibration_record(file);
  } catch (const std::exception& e) {
    throw std::runtime_error(file + ": a calibration file that cannot be read (" + e.what() +
                             "); move it away or use --force");
  }
  if (const auto d = calibration_difference(old, c, options.angle_method))
    throw std::runtime_error(file + ": a finished calibration with " + d->field + " = " +
                             d->stored.dump() + " is here, and this one asks for " + d->now.dump() +
                             "; give another --out, move the file away, or use --force");
}

// Writes `j` to OUT/NAME on rank 0 (or without MPI).
void write_result(const nlohmann::json& j, const std::string& out_dir, const char* name,
                  const RunnerSettings& runner) {
  if (!runner.rank || runner.rank->rank == 0)
    write_json_atomic((fs::path(out_dir) / name).string(), j);
}

// The calibrated mu_r and its 95% interval.
struct CalibratedMu {
  double mu = 0.0, lo = 0.0, hi = 0.0;
};
CalibratedMu calibrated_mu_of(const CalibrationRecord& cal, const std::string& cal_file) {
  if (!cal.mu_r)
    throw std::runtime_error(cal_file + ": status '" + to_string(cal.status) +
                             "': no calibrated mu_r to predict with (" + cal.message + ")");
  return {*cal.mu_r, cal.mu_r_lo, cal.mu_r_hi};
}

// The angle of every prediction run, by run id: one batch for every prediction, the calibrated
// mu_r first, then the interval ends. NaN marks a run that made no pile.
std::map<std::string, double> prediction_angles(const Campaign& c, const CalibratedMu& m,
                                                const std::string& out_dir, const CaseFn& case_fn,
                                                const AngleFn& angle_of,
                                                const RunnerSettings& runner) {
  std::vector<CaseSpec> runs;
  std::set<std::string> ids;
  auto add = [&](const PredictionCase& p, double mu) {
    for (auto seed : p.seeds) {
      CaseSpec s = prediction_run(c, p, mu, seed);
      if (ids.insert(s.id()).second) runs.push_back(std::move(s));
    }
  };
  for (const auto& p : c.predictions) add(p, m.mu);
  for (const auto& p : c.predictions)
    if (p.interval_ends)
      for (double mu : {m.lo, m.hi}) add(p, mu);
  std::map<std::string, double> angle;
  if (runs.empty()) return angle;
  const auto results = run_batch(c, runs, out_dir, case_fn, runner);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const double a = angle_of(results[i]);
    if (!std::isnan(a) && (!std::isfinite(a) || a < 0.0 || a > 90.0))
      throw std::runtime_error("prediction run " + runs[i].id() + " returned angle " +
                               std::to_string(a) + " outside [0, 90] deg");
    angle[runs[i].id()] = a;  // NaN: no pile (a clogged outlet), an outcome, not an angle
  }
  return angle;
}

// Prediction p's runs at one mu_r: the angle per seed (null for no pile) and their statistics.
nlohmann::json prediction_at(const Campaign& c, const PredictionCase& p, double mu,
                             const std::map<std::string, double>& angle) {
  nlohmann::json angles = nlohmann::json::array(), dirs = nlohmann::json::array();
  std::vector<double> v;
  int no_pile = 0;
  for (auto seed : p.seeds) {
    const CaseSpec s = prediction_run(c, p, mu, seed);
    const double a = angle.at(s.id());
    if (std::isnan(a)) {
      ++no_pile;
      angles.push_back(nullptr);
    } else {
      v.push_back(a);
      angles.push_back(a);
    }
    dirs.push_back(s.relative_dir());
  }
  const SampleStats st = sample_stats(v);
  const auto or_null = [&](double x) { return st.n > 0 ? nlohmann::json(x) : nlohmann::json(); };
  return nlohmann::json{{"mu_r", mu},
                        {"angles_deg", angles},
                        {"runs", dirs},
                        {"n", st.n},
                        {"no_pile", no_pile},
                        {"mean_deg", or_null(st.mean)},
                        {"seed_sd_deg", or_null(st.sd)},
                        {"sem_deg", or_null(st.n > 0 ? st.sd / std::sqrt(st.n) : 0.0)}};
}

// How far the mu_r interval moves prediction p: run at both ends, or (interval_ends = false)
// estimated from the calibration test's fitted curve.
nlohmann::json interval_effect(const Campaign& c, const PredictionCase& p, const CalibratedMu& m,
                               double mean, const MonotoneFit& fit,
                               const std::map<std::string, double>& angle) {
  if (p.interval_ends) {
    const nlohmann::json a = prediction_at(c, p, m.lo, angle), b = prediction_at(c, p, m.hi, angle);
    nlohmann::json effect = {
        {"method", "runs"},
        {"note", "the test run with the same seeds at both ends of the 95% mu_r interval"},
        {"at_low", a},
        {"at_high", b},
        {"angle_range_deg", nullptr}};
    if (a["mean_deg"].is_number() && b["mean_deg"].is_number()) {
      const double x = a["mean_deg"].get<double>(), y = b["mean_deg"].get<double>();
      effect["angle_range_deg"] = {std::min(x, y), std::max(x, y)};
    }
    return effect;
  }
  const double f0 = evaluate(fit, m.mu);
  const double lo = fit.points.front().mu_r, hi = fit.points.back().mu_r;
  const double dl = evaluate(fit, std::clamp(m.lo, lo, hi)) - f0;
  const double dh = evaluate(fit, std::clamp(m.hi, lo, hi)) - f0;
  return {{"method", "calibration_slope"},
          {"note",
           "not run: the prediction shifted by the calibration test's fitted angle change "
           "over the 95% mu_r interval (assumes this test responds to mu_r as that one)"},
          {"angle_range_deg", {mean + std::min(dl, dh), mean + std::max(dl, dh)}}};
}

// The predictions.json entry of prediction p.
nlohmann::json prediction_entry(const Campaign& c, const PredictionCase& p, const CalibratedMu& m,
                                const MonotoneFit& fit,
                                const std::map<std::string, double>& angle) {
  nlohmann::json j = prediction_at(c, p, m.mu, angle);
  const double mean = j["mean_deg"].is_number() ? j["mean_deg"].get<double>() : NAN;
  nlohmann::json seeds = nlohmann::json::array();
  for (auto s : p.seeds) seeds.push_back(s);
  j["name"] = p.name;
  j["description"] = p.description;
  j["scene"] = p.scene_path;
  j["table1_sample"] = p.table1_sample ? nlohmann::json(*p.table1_sample) : nlohmann::json();
  j["check"] = p.scene_path == c.scene_path && p.overrides == c.overrides;
  j["measured_deg"] = p.measured.angle_deg;
  j["measured_sd_deg"] = p.measured.sd_deg;
  j["seeds"] = seeds;
  const auto finite_or_null = [](double x) {
    return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json();
  };
  j["error_deg"] = finite_or_null(mean - p.measured.angle_deg);
  j["abs_error_deg"] = finite_or_null(std::abs(mean - p.measured.angle_deg));
  j["mu_r_interval"] = {m.lo, m.hi};
  j["interval_effect"] = interval_effect(c, p, m, mean, fit, angle);
  return j;
}

// Predictions made earlier from the same calibration (another --only selection) stay in the
// file; an entry of the same name is replaced by the new one.
nlohmann::json merge_with_earlier(const fs::path& file, double mu,
                                  const std::vector<std::string>& keys, nlohmann::json list) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) return list;
  nlohmann::json old;
  try {
    old = read_json_file(file.string());
  } catch (const std::exception&) {
    return list;
  }
  if (old.value("mu_r", -1.0) != mu || old["keys"] != keys || !old["predictions"].is_array())
    return list;
  std::set<std::string> fresh;
  for (const auto& p : list) fresh.insert(p.value("name", std::string()));
  nlohmann::json merged = nlohmann::json::array();
  for (const auto& p : old["predictions"])
    if (!fresh.count(p.value("name", std::string()))) merged.push_back(p);
  for (auto& p : list) merged.push_back(std::move(p));
  return merged;
}

// A calibration run's result as the bracketing driver sees it: a pile with its angle, a jam (the
// outlet arched, or no pile), a physics stop, or a run a time limit stopped before its pile
// settled; only the first gives an angle (pile/headline.hpp's no_headline decides).
Pour pour_of(const nlohmann::json& run, const AngleFn& angle_of) {
  const nlohmann::json& res = run.contains("result") ? run.at("result") : run;
  Pour p;
  const CaseResult r = case_result_from_json(res);
  const std::optional<NoHeadline> none = no_headline(r.stop, r.pile);
  if (!none) {
    p.angle_deg = angle_of(run);
    return p;
  }
  p.detail = none->message;
  switch (none->reason) {
    case NoHeadlineReason::kPhysicsStop:
      p.outcome = PourOutcome::kPhysicsStop;
      break;
    case NoHeadlineReason::kTimeLimit:
      p.outcome = PourOutcome::kTimeLimit;
      break;
    case NoHeadlineReason::kNotSettled:
      p.outcome = PourOutcome::kNotSettled;
      break;
    default:
      p.outcome = PourOutcome::kJam;
      break;
  }
  return p;
}

// The bracketing driver (method = "bracket") over the campaign's runs.
CalibrationRecord bracket_calibration_record(const Campaign& c, const std::string& out_dir,
                                             const CaseFn& case_fn, const AngleFn& angle_of,
                                             const RunnerSettings& runner) {
  const CampaignCalibration& cc = calibration_of(c);
  auto pour = [&](const std::vector<std::pair<double, std::uint64_t>>& points) {
    std::vector<CaseSpec> runs;
    for (const auto& [mu, seed] : points) runs.push_back(calibration_run(c, mu, seed));
    std::vector<Pour> out;
    for (const nlohmann::json& r : run_batch(c, runs, out_dir, case_fn, runner))
      out.push_back(pour_of(r, angle_of));
    return out;
  };
  return calibration_record(calibrate_bracket(pour, cc.target, cc.bracket), cc.bracket);
}

// The calibrated material (io/calibration_record.hpp) of a calibration that reached mu_r: the
// calibration test as its runs were built (calibration_run), its keys apart, so a later command
// rebuilds the same scene at mu_r.
CalibratedMaterial calibrated_material(const Campaign& c, const CalibrationRecord& cal,
                                       AngleMeasure angle) {
  const CampaignCalibration& cc = calibration_of(c);
  const CaseSpec run = calibration_run(c, *cal.mu_r, cc.settings.first_seed);
  CalibratedMaterial m;
  m.scene = run.scene_path;
  m.scene_fnv1a = run.scene_hash;
  m.keys = keys_of(cc);
  for (const Override& o : run.overrides) {
    if (o.key == cc.key || std::find(m.keys.begin(), m.keys.end(), o.key) != m.keys.end())
      continue;
    m.overrides.push_back(o);
    if (o.key == "sample.psd_file")
      m.sieve_sheet = overrides_to_json({o}).at(o.key).get<std::string>();
  }
  m.mu_r = *cal.mu_r;
  m.mu_r_lo = cal.mu_r_lo;
  m.mu_r_hi = cal.mu_r_hi;
  m.target_deg = cc.target.angle_deg;
  m.angle = angle_measure_name(angle);
  return m;
}

}  // namespace

void keep_only_predictions(Campaign& c, const std::vector<std::string>& names) {
  std::vector<PredictionCase> kept;
  for (const std::string& name : names) {
    auto it = std::find_if(c.predictions.begin(), c.predictions.end(),
                           [&](const PredictionCase& p) { return p.name == name; });
    if (it == c.predictions.end()) {
      std::string list;
      for (const auto& p : c.predictions) list += (list.empty() ? "" : ", ") + p.name;
      throw std::invalid_argument(c.file + ": no [[predict]] named '" + name + "' (" +
                                  (list.empty() ? std::string("there are none") : list) + ")");
    }
    kept.push_back(*it);
  }
  c.predictions = std::move(kept);
}

CalibrationRecord run_calibration(const Campaign& c, const std::string& out_dir,
                                  const CaseFn& case_fn, const AngleFn& angle_of,
                                  const RunnerSettings& runner, const CalibrateOptions& options) {
  const CampaignCalibration& cc = calibration_of(c);
  if (!angle_of) throw std::invalid_argument("run_calibration: no angle function");
  refuse_to_replace_other_calibration(c, out_dir, options, runner.force);
  auto simulate = [&](const std::vector<std::pair<double, std::uint64_t>>& points) {
    std::vector<CaseSpec> runs;
    for (const auto& [mu, seed] : points) runs.push_back(calibration_run(c, mu, seed));
    std::vector<double> angles;
    for (const nlohmann::json& r : run_batch(c, runs, out_dir, case_fn, runner))
      angles.push_back(angle_of(r));
    return angles;
  };
  CalibrationRecord r = cc.method == CalibrationMethod::kBracket
                            ? bracket_calibration_record(c, out_dir, case_fn, angle_of, runner)
                            : calibration_record(calibrate_batch(simulate, cc.target, cc.settings));
  r.campaign = c.file;
  r.campaign_name = c.name;
  r.keys = keys_of(cc);
  r.mu_r_range_lo = cc.settings.mu_r_lo;
  r.mu_r_range_hi = cc.settings.mu_r_hi;
  r.tolerance_deg = cc.settings.tolerance_deg;
  r.seeds_per_point = cc.settings.seeds_per_point;
  r.table1_sample = cc.table1_sample;
  r.scene = c.scene_path;
  r.rolling_model = rolling_model_of(c);
  r.angle_method = options.angle_method;
  r.angle = options.angle;
  r.code_version = options.code_version;
  if (!cc.target_photos.is_null())
    r.target_photos = target_photos_from_json(cc.target_photos, c.file);
  if (r.mu_r) r.material = calibrated_material(c, r, options.angle.value_or(cc.angle));
  r.created_utc = utc_now();
  fs::create_directories(fs::path(out_dir));
  write_result(to_json(r), out_dir, kCalibrationFile, runner);
  return r;
}

CalibrationRecord read_calibration(const Campaign& c, const std::string& out_dir,
                                   const std::string& angle_method) {
  calibration_of(c);
  const std::string file = (fs::path(out_dir) / kCalibrationFile).string();
  std::error_code ec;
  if (!fs::is_regular_file(file, ec))
    throw std::runtime_error(file + ": no finished calibration here (run `reposetwin calibrate " +
                             c.file + "` first, or give its --out folder)");
  const CalibrationRecord j = read_calibration_record(file);
  if (const auto d = calibration_difference(j, c, angle_method))
    throw std::runtime_error(file + ": field '" + d->field + "' = " + d->stored.dump() +
                             " differs from the campaign file's " + d->now.dump() + " (" + c.file +
                             "): this calibration was made from other inputs");
  return j;
}

nlohmann::json run_predictions(const Campaign& c, const CalibrationRecord& cal,
                               const std::string& out_dir, const CaseFn& case_fn,
                               const AngleFn& angle_of, const RunnerSettings& runner,
                               const CalibrateOptions& options) {
  const CampaignCalibration& cc = calibration_of(c);
  if (!angle_of) throw std::invalid_argument("run_predictions: no angle function");
  const std::string cal_file = (fs::path(out_dir) / kCalibrationFile).string();
  const CalibratedMu m = calibrated_mu_of(cal, cal_file);
  const MonotoneFit fit = fit_monotone(cal.observations);
  const std::map<std::string, double> angle =
      prediction_angles(c, m, out_dir, case_fn, angle_of, runner);
  nlohmann::json list = nlohmann::json::array();
  for (const auto& p : c.predictions) list.push_back(prediction_entry(c, p, m, fit, angle));
  const fs::path file = fs::path(out_dir) / kPredictionsFile;
  nlohmann::json out = {{"campaign", c.file},
                        {"campaign_name", c.name},
                        {"calibration_file", kCalibrationFile},
                        {"calibration_status", to_string(cal.status)},
                        {"mu_r", m.mu},
                        {"mu_r_interval", {m.lo, m.hi}},
                        {"keys", keys_of(cc)},
                        {"angle_method", options.angle_method},
                        {"created_utc", utc_now()},
                        {"predictions", merge_with_earlier(file, m.mu, keys_of(cc), list)}};
  if (!options.code_version.empty()) out["code_version"] = options.code_version;
  if (options.angle) out["angle"] = angle_measure_name(*options.angle);
  write_result(out, out_dir, kPredictionsFile, runner);
  return out;
}

AngleFn calibration_angle(AngleMeasure measure) {
  // A clogged run ("no pile", angle 0 in a Fig. 10 report) measures no pile angle: averaged
  // into a mu_r point it would drag the fit down, so the sequential calibration stops on it.
  return [measure](const nlohmann::json& r) {
    const nlohmann::json& res = r.contains("result") ? r.at("result") : r;
    const CaseResult c = case_result_from_json(res);
    const std::optional<NoHeadline> none = no_headline(c.stop, c.pile);
    if (none && none->reason != NoHeadlineReason::kJammed)
      throw std::runtime_error("a calibration run has no angle (" + none->message +
                               "): it cannot enter the fit; " + no_headline_advice(none->reason));
    if (none)
      throw std::runtime_error(
          "a calibration run clogged the outlet (" +
          res.value("stop", nlohmann::json::object()).value("detail", std::string("lodged")) +
          "): it has no pile angle to fit (its folder: cases/calib_*/seed_*/ with "
          "result.pile.status \"no pile\"). Narrow mu_r_range below the mu_r that arches "
          "the outlet, widen the outlet, or calibrate with method = \"bracket\", which counts "
          "such pours as a jam rate");
    return case_angle_deg(r, measure);
  };
}

AngleFn prediction_angle(AngleMeasure measure) {
  return [measure](const nlohmann::json& r) {
    const nlohmann::json& res = r.contains("result") ? r.at("result") : r;
    const CaseResult c = case_result_from_json(res);
    if (no_headline(c.stop, c.pile)) return std::numeric_limits<double>::quiet_NaN();
    return case_angle_deg(r, measure);
  };
}

BatchPlan plan_calibration(const Campaign& c, int workers) {
  const CampaignCalibration& cc = calibration_of(c);
  const bool bracket = cc.method == CalibrationMethod::kBracket;
  std::vector<BatchPlan::Part> parts;
  const SceneConfig cal_scene =
      build_case_scene(calibration_run(c, cc.settings.mu_r_lo, cc.settings.first_seed)).config();
  parts.push_back({"calibration runs (" + c.name + ")", plan_run(cal_scene, 1),
                   bracket ? cc.bracket.max_runs : cc.settings.max_simulations});
  for (const PredictionCase& p : c.predictions) {
    if (p.seeds.empty()) continue;
    const SceneConfig scene =
        build_case_scene(prediction_run(c, p, cc.settings.mu_r_lo, p.seeds.front())).config();
    const int runs = static_cast<int>(p.seeds.size()) * (p.interval_ends ? 3 : 1);
    parts.push_back({"runs of the prediction " + p.name, plan_run(scene, 1), runs});
  }
  return plan_batch(std::move(parts), workers);
}

std::string calibration_order_text(const Campaign& c) {
  const CampaignCalibration& cc = calibration_of(c);
  const std::string range = "mu_r " + significant(cc.settings.mu_r_lo, 3) + " to " +
                            significant(cc.settings.mu_r_hi, 3);
  std::string t = "calibrate: " + keys_of(cc).front() + " over " + range + " to match " +
                  significant(cc.target.angle_deg, 4) + " deg; ";
  if (cc.method == CalibrationMethod::kBracket) {
    const BracketSettings& b = cc.bracket;
    t += std::to_string(b.seeds.size()) + " seeds a point, ";
    t += b.ends_first ? "the two ends of the range first (a target out of reach is known after "
                        "them), then the fitted crossing"
                      : "first at mu_r " +
                            significant(b.mu_r_start.value_or(0.5 * (b.mu_r_lo + b.mu_r_hi)), 3) +
                            ", then bracketing";
    t += "; at most " + std::to_string(b.max_runs) + " runs\n";
  } else {
    t += std::to_string(cc.settings.seeds_per_point) +
         " seeds a point, the two ends of the range first, then a secant; at most " +
         std::to_string(cc.settings.max_simulations) + " runs\n";
  }
  if (!c.predictions.empty())
    t += "calibrate: then " + std::to_string(c.predictions.size()) +
         " [[predict]] test(s) at the calibrated mu_r\n";
  return t;
}

std::string cannot_reach_advice(const Campaign& c, const CalibrationRecord& cal,
                                AngleMeasure measure) {
  if (cal.mu_r) return "";
  const CampaignCalibration& cc = calibration_of(c);
  const double target = cc.target.angle_deg;
  const std::string lo = significant(cc.settings.mu_r_lo, 3), hi = significant(cc.settings.mu_r_hi, 3);
  const std::string angle = angle_measure_name(measure);
  const bool high = cal.status == CalibrationStatus::kCannotReachHigh;
  const bool low = cal.status == CalibrationStatus::kCannotReachLow;
  const int runs = cal.simulations;
  std::string t;
  const bool have_reach = !cal.observations.empty();
  if (have_reach) {
    const double a = cal.reachable_low_deg, b = cal.reachable_high_deg;
    t = "cannot reach: the target " + significant(target, 4) + " deg (angle '" + angle + "') is " +
        (high ? "above" : low ? "below" : "outside") + " what mu_r " + lo + " to " + hi +
        " reaches, " + significant(a, 4) + " to " + significant(b, 4) + " deg (" +
        significant(high ? target - b : a - target, 3) + " deg short, after " +
        std::to_string(runs) + " pile runs)\n";
  } else {
    t = "cannot reach: no pour formed a pile to measure in " + std::to_string(runs) +
        " pile runs between mu_r " + lo + " and " + hi + " (" + cal.message + ")\n";
  }
  // Without a pile, the advice is on the stop that took the pours: a time limit is cured by
  // time, not by the grain shape.
  std::map<NoHeadlineReason, int> stopped;
  for (const PourCount& q : cal.pour_counts) {
    stopped[NoHeadlineReason::kJammed] += q.jams;
    stopped[NoHeadlineReason::kTimeLimit] += q.time_limits;
    stopped[NoHeadlineReason::kNotSettled] += q.not_settled;
    stopped[NoHeadlineReason::kPhysicsStop] += q.physics_stops;
  }
  if (!have_reach && (stopped[NoHeadlineReason::kTimeLimit] > 0 ||
                      stopped[NoHeadlineReason::kNotSettled] > 0 ||
                      stopped[NoHeadlineReason::kPhysicsStop] > 0)) {
    t += "what to try:\n";
    for (const auto& [reason, n] : stopped)
      if (n > 0)
        t += "  - " + std::string(no_headline_word(reason)) + " (" + std::to_string(n) +
             " pour(s)): " + no_headline_advice(reason) + "\n";
    return t;
  }
  t += "what to try:\n";
  if (high || !have_reach) {
    t += "  - the grain shape: spheres roll where angular rock locks; blocky grains build steeper "
         "piles: in the scene, [sample.shape] kind = \"blocky\" with your grains' elongation, "
         "flatness and angularity (README, grain shapes; experiments/io/grain_shape.hpp)\n";
    t += "  - the plate friction: the pile's toe slides on the base plate; set the plate "
         "material's contacts (contacts.rock-plate.friction, rolling_friction), or calibrate "
         "both rolling keys: calibration.key = [\"contacts.rock-rock.rolling_friction\", "
         "\"contacts.rock-plate.rolling_friction\"]\n";
    if (stopped[NoHeadlineReason::kJammed] > 0)
      t += "  - the pours jam near the top of the range: a wider funnel outlet (W_mm, "
           "container.bottom_diameter_m) lets a higher mu_r flow\n";
    else
      t += "  - a wider mu_r range (now " + lo + " to " + hi +
           ") when the angle still rises at its top end\n";
    if (measure == AngleMeasure::kImage || measure == AngleMeasure::kParticles)
      t += "  - as a declared fallback, the flank measure: --angle image_flank matches the twin's "
           "flank angle (steeper than its atan(2H/D) on a flat-topped pile, 5-7 deg on the "
           "shipped scenes) to the lab's; say so beside the result (docs/measures.md)\n";
  } else {
    t += "  - a lower start of the mu_r range (now " + lo + ")" +
         (cc.settings.mu_r_lo > 0.0 ? std::string() : std::string(": it is 0 already")) + "\n";
    t += "  - the sliding friction contacts.rock-rock.friction, or spheres instead of shaped "
         "grains ([sample.shape]), if the scene has them\n";
    t += "  - the lab's angle: a lab photo read as atan(2H/D) (reposetwin measure) is the "
         "twin's 'image' measure; a protractor angle is steeper (--angle image_flank)\n";
  }
  return t;
}

std::vector<NextStep> calibration_next_steps(const std::string& folder, bool reached) {
  const std::string dir = shell_word(folder);
  std::vector<NextStep> steps = {{"reposetwin report " + dir, "the page"}};
  if (reached) steps.push_back({"reposetwin export " + dir, "the LIGGGHTS deck"});
  return steps;
}

CalibrateOutcome calibrate_and_predict(const Campaign& c, const std::string& out,
                                       AngleMeasure measure, const CaseFn& fn,
                                       const RunnerSettings& rs, bool predict_only) {
  CalibrateOptions opt;
  opt.angle_method = angle_measure_method(measure);
  opt.code_version = code_version();
  opt.angle = measure;
  CalibrateOutcome o;
  o.calibration = predict_only
                      ? read_calibration(c, out, opt.angle_method)
                      : run_calibration(c, out, fn, calibration_angle(measure), rs, opt);
  o.reached = o.calibration.reached();
  if (o.reached && !c.predictions.empty())
    o.predictions = run_predictions(c, o.calibration, out, fn, prediction_angle(measure), rs, opt);
  return o;
}

}  // namespace reposetwin::experiments
