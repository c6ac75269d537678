#include "experiments/campaign/case_runner.hpp"

#include <unistd.h>

#include <filesystem>
#include <set>
#include <stdexcept>

#include "experiments/io/input_error.hpp"
#include "experiments/io/json_fields.hpp"
#include "experiments/io/scene.hpp"
#include "experiments/pile/headline.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
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
  } catch (const JsonFieldError& e) {  // a field of the wrong type, at its JSON pointer
    throw std::invalid_argument(std::string("not a pile case's result: ") + e.what());
  }
}

PileRequest case_request(const CaseSpec& spec, const CaseRunSettings& settings) {
  PileRequest r{spec.scene_path, spec.overrides, spec.seed, std::nullopt};
  if (settings.images) r.photo = PhotoRequest{settings.image, true, PhotographWhen::kHeadline};
  return r;
}

namespace {

// The case folder's run/ as a campaign has always laid it out (result.json, final.vtp, the
// frame series, images/), made of links into the store: each entry of the pile's run folder,
// and images/ to its photographs. A user opens CASE/run/result.json or run/images/ as before,
// and the pile stays one pile in the store, shared with any other caller. Relative links, so an
// output folder moved whole with its store keeps them. Made beside and renamed into place, so
// a killed worker leaves no half-made run/ (an earlier one, from an interrupted attempt, is
// replaced).
void link_case_run(const PileOutcome& o, const fs::path& case_dir) {
  const fs::path run = case_dir / "run";
  const fs::path tmp = case_dir / ("run.tmp." + std::to_string(::getpid()));
  fs::remove_all(tmp);
  fs::create_directories(tmp);
  for (const fs::directory_entry& e : fs::directory_iterator(o.run_dir)) {
    const std::string name = e.path().filename().string();
    if (name.rfind('.', 0) == 0) continue;  // the store's lock files
    fs::create_symlink(fs::relative(e.path(), run), tmp / name);
  }
  if (o.photo && o.photo->measured)
    fs::create_directory_symlink(fs::relative(o.photo->dir, run), tmp / "images");
  fs::remove_all(run);
  fs::rename(tmp, run);
}

// The case's record of the service's answer: its run/ and run/images/ (links into the store,
// link_case_run), relative to the case folder as a campaign has always written them.
CaseResult case_result_of(const PileOutcome& o) {
  CaseResult r;
  r.stop = o.stop;
  r.pile = o.pile;
  r.particles = o.particles;
  r.performance = o.performance;
  r.provenance = o.provenance;
  r.psd_fines_fraction = o.psd_fines_fraction;
  r.shape = o.shape;
  r.run_dir = "run";
  if (o.photo && o.photo->measured) {
    const PhotoMeasure& m = *o.photo->measured;
    r.image = CaseImages{m.theta_deg,  m.theta_sd_deg, m.height_m, m.diameter_m, m.flank_deg,
                         "run/images"};
  }
  return r;
}

}  // namespace

CaseFn pile_case_fn(const CaseRunSettings& settings) {
  return [settings](const CaseSpec& spec, const std::string& case_dir) -> json {
    // Read here first so that a scene the override breaks is an error naming the case.
    (void)build_case_scene(spec).config();
    // case_dir is OUT/cases/<case>/seed_<n>: the default store is OUT/cache.
    const fs::path dir = fs::absolute(case_dir);
    const fs::path store = settings.store.empty()
                               ? dir.parent_path().parent_path().parent_path() / "cache"
                               : fs::path(settings.store);
    PileServiceSettings ps;
    ps.workers = 1;
    ps.threads = settings.threads;
    ps.frames = true;  // a campaign's run keeps the scene's frame series
    PileService service(store.string(), ps);
    const PileOutcome o = service.run_one(case_request(spec, settings));
    link_case_run(o, dir);
    return to_json(case_result_of(o));
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

bool case_made_no_pile(const json& r) { return case_outcome(r) == PileStatus::kJam; }

PileStatus case_outcome(const json& j) {
  const CaseResult r = case_result_from_json(j);
  return pile_status_of(r.stop, r.pile);
}

std::string case_outcome_word(const json& j) { return pile_status_word(case_outcome(j)); }

double select_angle_deg(const PileMeasure& pile, const std::optional<PhotoMeasure>& photo,
                        AngleMeasure measure, const std::string& where) {
  switch (measure) {
    case AngleMeasure::kImage:
      return photo ? photo->theta_deg : pile.theta_hd_deg;
    case AngleMeasure::kImageFlank:
      if (!photo)
        throw std::runtime_error("the image flank angle needs the run's photographs, and " +
                                 where + " has none (run without --no-images)");
      return photo->flank_deg;
    case AngleMeasure::kParticles:
      return pile.theta_hd_deg;
    case AngleMeasure::kSlice:
      return pile.slice_angle_mean_deg;
  }
  throw std::logic_error("select_angle_deg: unknown angle measure");
}

double case_angle_deg(const json& j, AngleMeasure measure) {
  const CaseResult r = case_result_from_json(j);
  if (const auto none = no_headline(r.stop, r.pile))
    throw std::runtime_error("the run has no angle (" +
                             std::string(no_headline_word(none->reason)) + ": " + none->message +
                             "); " + r.run_dir);
  std::optional<PhotoMeasure> photo;
  if (r.image)
    photo = PhotoMeasure{r.image->theta_deg,  r.image->theta_sd_deg, r.image->height_m,
                         r.image->diameter_m, r.image->flank_deg,    0.0};
  return select_angle_deg(r.pile, photo, measure, r.run_dir);
}

}  // namespace reposetwin::experiments
