// The pile service: one pour, photographed and measured, asked for as a typed request and
// answered from one content-addressed store.
//
// Design note. Every simulated pile of experiments/ (a campaign's case, a calibration's point, a
// prediction, the loop's baseline, fingerprints and refits) is the same thing: a scene file with
// overrides and a seed, poured, then perhaps photographed with some settings. A PileRequest says
// exactly that and nothing else; how it is run (threads, progress, frame series) is not part of
// it. The store keeps each answer under a key that is the SHA-256 (OpenSSL's libcrypto, a
// Debian package) of the scene the request pours in its canonical form (the scene file with the
// overrides applied and the seed set, read strictly and written back: SceneConfig::resolved_toml)
// and the engine's source hash (engine_version()), never of the file's path or the overrides'
// text: one scene at two paths is one pile, and an edited scene file is a new one; a photograph
// under the
// SHA-256 of its pile's key, the photo settings' JSON and the imaging source hash
// (imaging_version()). No field is listed by hand for the key: a field added to a record enters
// its to_json and so changes the key by itself, and a changed engine or renderer computes afresh
// beside the old entries. So a calibration's piles are a loop's piles when both ask the same
// question of the same store, and a killed caller resumes where it stopped (a pile from its
// checkpoint).
//
// Layout: STORE/piles/<key>/run/ (the pile run: result.json, final.vtp, checkpoint) beside
// STORE/piles/<key>/request.json, and STORE/photos/<key>/ (the photographs, measurement.json,
// result.json). An entry is finished exactly when its result.json exists (written atomically,
// last). Each entry is computed under an exclusive lock on its folder, so two processes asking
// for the same pile at once compute it once: the second waits and reads it.
//
// run() answers many requests on a local pool (pile runs in forked processes, photographs on
// threads, each keeping its renderer); run_one() answers one in this process (a campaign's
// worker, which is already a forked process of its own pool). OpenMP and OSMesa do not survive a
// fork: call run() before this process has used either.
#pragma once

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "experiments/io/overrides.hpp"
#include "experiments/photos/photographs.hpp"
#include "experiments/pile/pile_record.hpp"

namespace reposetwin::experiments {

/// How a pour ended, as the callers count it.
enum class PileStatus {
  kPile,         // a settled pile, measured
  kJam,          // grains arched in the outlet: no pile
  kNoPile,       // no measurable pile on the plate
  kNotSettled,   // the last settling ended still moving
  kTimeLimit,    // procedure.max_time_s stopped the run first
  kPhysicsStop,  // the engine stopped the run (NaN, runaway overlap, an escaped particle)
  kUnmeasured,   // a pile formed, but no photograph of it could be measured
  kCount
};

/// The status's word in files and counts ("pile", "jam", "no_pile", "not_settled",
/// "time_limit", "physics_stop", "photographs").
const char* pile_status_word(PileStatus s);

/// The status of a finished pile run (before its photographs).
PileStatus pile_status_of(const RunStop& stop, const PileMeasure& pile);

/// The SHA-256 of `text` as 64 lower-case hex digits.
std::string sha256_hex(std::string_view text);

/// Which finished pile runs are photographed.
enum class PhotographWhen {
  kHeadline,  // a pile with a headline only (settled, not jammed): a campaign's case
  kFormed,    // every pile the run measured on the plate, settled or not: the loop judges a
              // pour by whether its photographs can be measured
};

/// How a pile is photographed: the one photo pipeline's settings (photos/photographs.hpp),
/// where its camera axis is centred, and which runs are photographed.
struct PhotoRequest {
  PhotoSettings settings;
  // True: centred on the footprint centre the pile run measured (a campaign's photos); false:
  // on the footprint the photo pipeline measures from the spheres (the loop's).
  bool centre_on_run_footprint = false;
  PhotographWhen when = PhotographWhen::kHeadline;
};
nlohmann::json to_json(const PhotoRequest& p);

/// One pour: a scene file with overrides (applied in order) and a seed, optionally photographed.
struct PileRequest {
  std::string scene_path;            // the scene file (absolute)
  std::vector<Override> overrides;   // applied to the scene in this order
  std::uint64_t seed = 1;            // [scene] seed
  std::optional<PhotoRequest> photo;  // absent: the pile is not photographed
};
/// The request as asked (the scene path, the overrides in order, the seed), the SHA-256 of the
/// scene it pours (resolved, as pile_key takes it) and the photo request: the store's record of
/// an entry (request.json). Throws as pile_key does.
nlohmann::json to_json(const PileRequest& r);

/// The store key of the request's pile run: SHA-256 of the resolved scene (the file with the
/// overrides applied in order and the seed set, read strictly and written back), the seed and
/// the engine version. Throws std::runtime_error for an unreadable scene file and InputError
/// naming it for a scene the overrides break.
std::string pile_key(const PileRequest& r);
/// The store key of its photograph: SHA-256 of the pile key, the photo request's JSON and the
/// imaging version. Throws std::invalid_argument for a request without a photo.
std::string photo_key(const PileRequest& r);

/// What the photographs measured: the side views' mean (and spread of the angle).
struct PhotoMeasure {
  double theta_deg = 0.0;     // vision atan(2H/D) [deg]
  double theta_sd_deg = 0.0;  // its spread over the side views [deg]
  double height_m = 0.0;      // H [m]
  double diameter_m = 0.0;    // D [m]
  double flank_deg = 0.0;     // flank-line angle [deg]
  double crest_width_m = 0.0;  // crest width [m]
};

/// A photograph's outcome.
struct PhotoOutcome {
  std::optional<PhotoMeasure> measured;  // absent: no side view could be measured
  std::string error;                     // why not (the first view's error)
  nlohmann::json side_views = nlohmann::json::array();  // every view as vision measured it
  std::string dir;                       // the photographs' folder (absolute)
};

/// One request's answer.
struct PileOutcome {
  PileStatus status = PileStatus::kPile;
  RunStop stop;
  PileMeasure pile;
  ParticleCounts particles;
  RunPerformance performance;
  RunProvenance provenance;
  double psd_fines_fraction = 0.0;   // PSD mass below d_min, not simulated [-]
  std::optional<ShapeRecord> shape;  // a clump sample's shapes as run
  std::string run_dir;               // the pile run's folder (absolute)
  std::optional<PhotoOutcome> photo;  // when asked for and the run is one photo.when takes
};

/// Whether a finished run with this status and pile is photographed under `when`.
bool photographed(PhotographWhen when, PileStatus status, const PileMeasure& pile);

/// How the service runs what it has to: settings of this process, not of the answer.
struct PileServiceSettings {
  int workers = 2;            // concurrent pile runs in run() [-]
  int threads = 1;            // OpenMP threads per pile run [-]
  bool frames = false;        // write the scene's frame series (else the final state only)
  bool progress = false;      // a line on stderr per computed entry
};

/// The store (see the design note).
class PileService {
 public:
  explicit PileService(std::string dir, PileServiceSettings settings = {});
  /// Answers every request (in order), computing only what the store lacks. Throws
  /// std::runtime_error naming every request that failed.
  std::vector<PileOutcome> run(const std::vector<PileRequest>& requests);
  /// Answers one request in this process. Throws what the pile run or the photographs throw.
  PileOutcome run_one(const PileRequest& request);
  /// Pile runs and photographs this object computed (did not find finished).
  int simulations_started() const { return started_sims_; }
  int photos_started() const { return started_photos_; }
  const std::string& dir() const { return dir_; }
  /// The folders of a request's entries.
  std::string pile_dir(const PileRequest& r) const;
  std::string photo_dir(const PileRequest& r) const;

 private:
  void pour_missing(const std::vector<PileRequest>& requests,
                    std::map<std::size_t, std::string>& errors);
  void photograph_missing(const std::vector<PileRequest>& requests,
                          std::map<std::size_t, std::string>& errors);
  PileOutcome finished_run(const PileRequest& r) const;
  std::string errors_dir() const;

  std::string dir_;
  PileServiceSettings settings_;
  int started_sims_ = 0;
  int started_photos_ = 0;
};

}  // namespace reposetwin::experiments
