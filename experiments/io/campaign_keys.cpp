#include "experiments/io/campaign_keys.hpp"

#include "experiments/io/calibration_settings.hpp"
#include "experiments/io/format.hpp"

namespace reposetwin::experiments {
namespace {

std::vector<SceneKey> build() {
  const CalibrationSettings cs;
  const BracketSettings bs;
  const std::string paths = " (relative to the campaign file's folder)";
  return {
      {"name", "string", "required", "-", "the campaign's name, safe as a folder name"},
      {"description", "string", "-", "-", "free text"},
      {"paper", "string", "-", "-", "the paper item it reproduces, e.g. \"Fig. 8\""},
      {"scene", "string", "required", "-", "the base scene file" + paths},
      {"seeds", "array of integers or integer", "-", "-",
       "run seeds: a list, or a count n meaning 1..n"},
      {"overrides", "table", "-", "-",
       "dotted scene keys set for every run, e.g. { \"sample.mass_kg\" = 0.2 }; a "
       "sample.psd_file here replaces the scene's sieve table" +
           paths},
      {"case[].name", "string", "required", "-", "a case of [[case]], safe as a folder name"},
      {"case[].description", "string", "-", "-", "free text"},
      {"case[].scene", "string", "the campaign's", "-", "the case's own scene" + paths},
      {"case[].overrides", "table", "-", "-", "the case's dotted scene keys, on the common ones"},
      {"sweep.key", "string", "required", "-", "the dotted scene key swept (instead of cases)"},
      {"sweep.values", "array", "required", "-", "its values, one case each"},
      {"sweep.name", "string", "the key's leaf", "-", "prefix of the case names"},
      {"calibration.key", "string or array of strings", "contacts.rock-rock.rolling_friction", "-",
       "the scene key(s) set to the calibrated mu_r"},
      {"calibration.target_deg", "number", "required*", "deg",
       "the lab's measured angle atan(2H/D), in (0, 90); *or target_photos"},
      {"calibration.target_sd_deg", "number", "-", "deg",
       "its 1-sigma uncertainty (with photos: replaces the measured one)"},
      {"calibration.target_photos", "string or array of strings", "-", "-",
       "the lab's side photos of the pile, measured by vision as the twin's renders" + paths},
      {"calibration.target_photo_camera", "string", "-", "-",
       "a camera sidecar JSON for every photo (else mm_per_px, a STEM.json beside each photo, "
       "or the scale marker)" +
           paths},
      {"calibration.target_mm_per_px", "number", "-", "mm/px",
       "the photos' scale at the pile axis (orthographic view assumed)"},
      {"calibration.mu_r_range", "array of 2 numbers", "required", "-",
       "the mu_r range searched [lo, hi], 0 <= lo < hi"},
      {"calibration.angle", "string", "image", "-",
       "the twin's angle matched: image, image_flank, particles or slice (docs/measures.md)"},
      {"calibration.method", "string", "sequential", "-",
       "\"sequential\" (range ends, secant, confirmation seeds) or \"bracket\" (few runs, jams "
       "counted as a jam rate)"},
      {"calibration.seeds_per_point", "integer",
       std::to_string(cs.seeds_per_point) + " (bracket: 2)", "-",
       "runs per mu_r point, seeds first_seed, first_seed + 1, ..."},
      {"calibration.first_seed", "integer", std::to_string(cs.first_seed), "-", "first run seed"},
      {"calibration.max_simulations", "integer",
       std::to_string(cs.max_simulations) + " (bracket: 3 x seeds_per_point)", "-",
       "budget of pile runs of the calibration"},
      {"calibration.bootstrap_replicates", "integer", std::to_string(cs.bootstrap.replicates), "-",
       "bootstrap replicates of the 95% interval"},
      {"calibration.table1_sample", "integer", "-", "-",
       "the paper's Table 1 sample it calibrates on (reports)"},
      {"calibration.tolerance_deg", "number", significant(cs.tolerance_deg), "deg",
       "sequential only: the angle tolerance (95% level)"},
      {"calibration.confirm", "boolean", cs.confirm_bracket ? "true" : "false", "-",
       "sequential only: finish with fresh seeds at the bracket points"},
      {"calibration.mu_r_start", "number", "the middle of the range", "-",
       "bracket only: the first point"},
      {"calibration.ends_first", "boolean", bs.ends_first ? "true" : "false", "-",
       "bracket only: run both range ends first, so a target out of reach is known after two "
       "points (a calibration from the lab's sheets does)"},
      {"calibration.slope_guess_deg", "number", significant(bs.slope_guess_deg),
       "deg per unit mu_r", "bracket only: expected d(angle)/d(mu_r) before two points exist"},
      {"calibration.mu_r_tolerance", "number", significant(bs.mu_r_tolerance), "-",
       "bracket only: stop when the mu_r uncertainty is below"},
      {"calibration.max_jam_rate", "number", significant(bs.max_jam_rate), "-",
       "bracket only: a point whose pours jam more often is beyond the usable range"},
      {"predict[].name", "string", "required", "-",
       "a [[predict]] test run at the calibrated mu_r, safe as a folder name"},
      {"predict[].scene", "string", "required", "-", "its scene" + paths},
      {"predict[].measured_deg", "number", "required", "deg", "its measured angle, in (0, 90)"},
      {"predict[].measured_sd_deg", "number", "0", "deg", "its 1-sigma uncertainty"},
      {"predict[].seeds", "array of integers or integer", "the campaign's seeds", "-",
       "its run seeds"},
      {"predict[].overrides", "table", "-", "-", "its dotted scene keys, on the common ones"},
      {"predict[].interval_ends", "boolean", "true", "-",
       "also run it at both ends of the calibrated mu_r's 95% interval"},
      {"predict[].table1_sample", "integer", "-", "-", "the paper's Table 1 sample (reports)"},
      {"predict[].description", "string", "-", "-", "free text"},
  };
}

}  // namespace

const std::vector<SceneKey>& campaign_keys() {
  static const std::vector<SceneKey> keys = build();
  return keys;
}

std::set<std::string> campaign_table_keys(const std::string& table) {
  std::set<std::string> out;
  for (const SceneKey& k : campaign_keys()) {
    const auto dot = k.key.find('.');
    std::string head = dot == std::string::npos ? "" : k.key.substr(0, dot);
    if (head.size() > 2 && head.substr(head.size() - 2) == "[]") head.resize(head.size() - 2);
    if (head == table) out.insert(dot == std::string::npos ? k.key : k.key.substr(dot + 1));
  }
  if (table.empty()) out.insert({"case", "sweep", "calibration", "predict"});
  return out;
}

std::string campaign_keys_markdown() {
  std::string t = "| key | type | default | unit | meaning |\n|---|---|---|---|---|\n";
  for (const SceneKey& k : campaign_keys())
    t += "| `" + k.key + "` | " + k.type + " | " + k.default_text + " | " + k.unit + " | " +
         k.meaning + " |\n";
  return t;
}

}  // namespace reposetwin::experiments
