#include "experiments/campaign/case_runner.hpp"

#include <filesystem>
#include <set>
#include <stdexcept>

#include "experiments/io/json_fields.hpp"
#include "experiments/io/scene.hpp"
#include "experiments/pile/headline.hpp"
#include "experiments/pile/pile_run.hpp"

namespace reposetwin::experiments {
using nlohmann::json;

json to_json(const CaseResult& r) {
  json out = {{"stop", to_json(r.stop)},
              {"pile", to_json(r.pile)},
              {"particles", to_json(r.particles)},
              {"performance", to_json(r.performance)},
              {"provenance", to_json(r.provenance)},
              {"psd_fines_fraction", r.psd_fines_fraction},
              {"run_dir", r.run_dir}};
  if (r.image)
    out["image"] = {{"theta_deg", r.image->theta_deg}, {"theta_sd_deg", r.image->theta_sd_deg},
                    {"height_m", r.image->height_m},   {"diameter_m", r.image->diameter_m},
                    {"flank_deg", r.image->flank_deg}, {"images", r.image->images}};
  if (r.shape) out["shape"] = to_json(*r.shape);
  // The one headline angle, named as in a run's result.json (pile/headline.hpp), or null and
  // why there is none.
  if (const auto none = no_headline(r.stop, r.pile)) {
    out.update(to_json(*none));
  } else {
    Headline h = headline_from_particles(r.pile);
    if (r.image)
      h = {r.image->theta_deg, r.image->theta_sd_deg, r.image->height_m, r.image->diameter_m, 0,
           true, kHeadlineFromImages};
    json fields = to_json(h);
    fields.erase("headline_views");  // a case keeps only the views' mean and spread
    out.update(fields);
  }
  return out;
}

CaseResult case_result_from_json(const json& j) {
  const json& res = j.contains("result") ? j.at("result") : j;
  try {
    CaseResult r;
    r.stop = stop_from_json(res.at("stop"));
    r.pile = pile_measure_from_json(res.at("pile"));
    r.particles = particle_counts_from_json(res.value("particles", json::object()));
    r.performance = run_performance_from_json(res.value("performance", json::object()));
    r.provenance = run_provenance_from_json(res.value("provenance", json::object()));
    r.psd_fines_fraction = res.value("psd_fines_fraction", 0.0);
    r.run_dir = res.value("run_dir", std::string("run"));
    if (res.contains("image")) {
      const json& m = res.at("image");
      r.image =
          CaseImages{json_number(m, "theta_deg"), json_number(m, "theta_sd_deg"),
                     json_number(m, "height_m"),  json_number(m, "diameter_m"),
                     json_number(m, "flank_deg"), m.value("images", std::string("run/images"))};
    }
    if (res.contains("shape")) r.shape = shape_record_from_json(res.at("shape"));
    return r;
  } catch (const json::exception& e) {
    throw std::invalid_argument(std::string("not a pile case's result: ") + e.what());
  }
}

namespace {

CaseResult case_result_of(const PileRun& run) {
  CaseResult r;
  r.stop = run.stop;
  r.pile = run.pile;
  r.particles = run.particles;
  r.performance = run.performance;
  r.provenance = run.provenance;
  r.psd_fines_fraction = run.psd.fines_fraction_not_simulated;
  r.shape = run.shape;
  return r;
}

CaseImages case_images_of(const json& m) {
  return {json_number(m, "theta_deg"), json_number(m, "theta_sd_deg"), json_number(m, "height_m"),
          json_number(m, "diameter_m"), json_number(m, "flank_deg")};
}

}  // namespace

CaseFn pile_case_fn(const CaseRunSettings& settings) {
  return [settings](const CaseSpec& spec, const std::string& case_dir) -> json {
    SceneDoc doc = build_case_scene(spec);
    doc.set_seed(spec.seed);
    const SceneConfig scene = doc.config();
    RunOptions opt;
    opt.out_dir = (std::filesystem::path(case_dir) / "run").string();
    opt.progress = false;
    opt.threads = settings.threads;
    opt.extra_provenance = {{"campaign_case", spec.id()}};
    const std::optional<PileRun> run = run_pile_test_or_continue(scene, opt);
    if (!run) throw std::logic_error(opt.out_dir + ": a case run has no stop limit, yet stopped");
    CaseResult r = case_result_of(*run);
    // A run without a headline (not settled, jammed, ...) has nothing the photographs could
    // give an angle of.
    if (settings.images && !no_headline(run->stop, run->pile))
      r.image = case_images_of(render_and_measure_run(*run, opt.out_dir, settings.image));
    return to_json(r);
  };
}

namespace {

// Every distinct scene the campaign file can run, each named as its messages name it: the
// cases, the calibration at both ends of its mu_r range and every prediction at the range's
// ends (the calibrated mu_r lies between them; seeds do not change the scene read).
std::vector<std::pair<std::string, CaseSpec>> runs_to_check(const Campaign& c) {
  std::vector<std::pair<std::string, CaseSpec>> out;
  std::set<std::string> names;
  for (const CaseSpec& spec : c.runs)
    if (names.insert(spec.case_name).second) out.emplace_back("case " + spec.case_name, spec);
  if (!c.calibration) return out;
  const CalibrationSettings& cal = c.calibration->settings;
  for (const double mu : {cal.mu_r_lo, cal.mu_r_hi}) {
    out.emplace_back("calibration", calibration_run(c, mu, cal.first_seed));
    for (const PredictionCase& p : c.predictions)
      out.emplace_back("prediction " + p.name, prediction_run(c, p, mu, cal.first_seed));
  }
  return out;
}

}  // namespace

void check_pile_cases(const Campaign& campaign) {
  for (const auto& [what, spec] : runs_to_check(campaign)) {
    try {
      (void)build_case_scene(spec).config();
    } catch (const InputError& e) {
      throw InputError(campaign.file + ": " + what + ": " + e.what());
    }
  }
}

bool case_made_no_pile(const json& r) {
  const CaseResult c = case_result_from_json(r);
  const auto none = no_headline(c.stop, c.pile);
  return none && none->reason == NoHeadlineReason::kJammed;
}

std::string case_outcome(const json& j) {
  const CaseResult r = case_result_from_json(j);
  const auto none = no_headline(r.stop, r.pile);
  return none ? no_headline_word(none->reason) : "pile";
}

double case_angle_deg(const json& j, AngleMeasure measure) {
  const CaseResult r = case_result_from_json(j);
  if (const auto none = no_headline(r.stop, r.pile))
    throw std::runtime_error("the run has no angle (" +
                             std::string(no_headline_word(none->reason)) + ": " + none->message +
                             "); " + r.run_dir);
  switch (measure) {
    case AngleMeasure::kImage:
      return r.image ? r.image->theta_deg : r.pile.theta_hd_deg;
    case AngleMeasure::kImageFlank:
      if (!r.image)
        throw std::runtime_error("the image flank angle needs the run's photographs, and " +
                                 r.run_dir + " has none (run without --no-images)");
      return r.image->flank_deg;
    case AngleMeasure::kParticles:
      return r.pile.theta_hd_deg;
    case AngleMeasure::kSlice:
      return r.pile.slice_angle_mean_deg;
  }
  throw std::logic_error("case_angle_deg: unknown angle measure");
}

}  // namespace reposetwin::experiments
