#include "experiments/campaign/pile_service.hpp"

#include <openssl/evp.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>

#include "experiments/campaign/pool.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/scene_overrides.hpp"
#include "experiments/io/vtk_output.hpp"
#include "experiments/photos/pile_images.hpp"
#include "experiments/pile/headline.hpp"
#include "experiments/pile/pile_run.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;

const char* pile_status_word(PileStatus s) {
  switch (s) {
    case PileStatus::kPile: return "pile";
    case PileStatus::kJam: return "jam";
    case PileStatus::kNoPile: return "no_pile";
    case PileStatus::kNotSettled: return "not_settled";
    case PileStatus::kTimeLimit: return "time_limit";
    case PileStatus::kPhysicsStop: return "physics_stop";
    case PileStatus::kUnmeasured: return "photographs";
    case PileStatus::kCount: break;
  }
  throw std::logic_error("pile_status_word: not a status");
}

PileStatus pile_status_of(const RunStop& stop, const PileMeasure& pile) {
  const auto none = no_headline(stop, pile);
  if (!none) return PileStatus::kPile;
  switch (none->reason) {
    case NoHeadlineReason::kTimeLimit: return PileStatus::kTimeLimit;
    case NoHeadlineReason::kNotSettled: return PileStatus::kNotSettled;
    case NoHeadlineReason::kJammed: return PileStatus::kJam;
    case NoHeadlineReason::kNoPile: return PileStatus::kNoPile;
    case NoHeadlineReason::kPhysicsStop: return PileStatus::kPhysicsStop;
    case NoHeadlineReason::kPhotographs: return PileStatus::kUnmeasured;
    case NoHeadlineReason::kCount: break;
  }
  throw std::logic_error("pile_status_of: unknown reason");
}

std::string sha256_hex(std::string_view text) {
  unsigned char md[EVP_MAX_MD_SIZE];
  unsigned int n = 0;
  if (EVP_Digest(text.data(), text.size(), md, &n, EVP_sha256(), nullptr) != 1)
    throw std::runtime_error("sha256: OpenSSL EVP_Digest failed");
  std::string out;
  char buf[3];
  for (unsigned int i = 0; i < n; ++i) {
    std::snprintf(buf, sizeof buf, "%02x", md[i]);
    out += buf;
  }
  return out;
}

json to_json(const PhotoRequest& p) {
  return {{"settings", to_json(p.settings)},
          {"centre_on_run_footprint", p.centre_on_run_footprint},
          {"when", p.when == PhotographWhen::kHeadline ? "headline" : "formed"}};
}

bool photographed(PhotographWhen when, PileStatus status, const PileMeasure& pile) {
  switch (when) {
    case PhotographWhen::kHeadline: return status == PileStatus::kPile;
    case PhotographWhen::kFormed: return pile.status == sim::PileStatus::kOk;
  }
  throw std::logic_error("photographed: unknown PhotographWhen");
}

namespace {

// The request's scene as it is poured, in one canonical text: the scene file with the
// overrides applied in order and the seed set, read strictly and written back
// (SceneConfig::resolved_toml: keys sorted, every value in one spelling, a sieve-table file
// copied in, every contact's defaults written out). The key is made from this, not from the
// file's path or the overrides' text, so one scene at two paths (a loop's copy of the lab's
// scene beside its CSV) is one pile, overrides that end in the same scene are one pile whatever
// their order or spelling, and an edited scene file (or sieve file) is never served a stale pile.
// The frame series is not part of it (final_frame_only is a setting of the run, not the pile).
// Throws InputError naming the scene file for a scene the overrides break.
std::string resolved_scene(const PileRequest& r) {
  SceneDoc doc(r.scene_path, r.overrides, "pile request (scene " + r.scene_path + ")");
  doc.set_seed(r.seed);
  return doc.config().resolved_toml;
}

json pile_json(const PileRequest& r) {
  json ov = json::array();
  for (const Override& o : r.overrides) ov.push_back({o.key, o.value});
  return {{"scene", r.scene_path}, {"overrides", ov}, {"seed", r.seed}};
}

// Waits for an entry's lock: another process computing the same entry finishes it, and this
// one then reads it.
std::unique_ptr<FolderLock> lock_entry(const std::string& dir, const std::string& what) {
  for (int attempt = 0;; ++attempt) {
    try {
      return std::make_unique<FolderLock>(dir, ".lock", what);
    } catch (const FolderBusy&) {
      if (attempt > 7200) throw;
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
    }
  }
}

PileOutcome outcome_of(const PileRun& run, const std::string& run_dir) {
  PileOutcome o;
  o.status = pile_status_of(run.stop, run.pile);
  o.stop = run.stop;
  o.pile = run.pile;
  o.particles = run.particles;
  o.performance = run.performance;
  o.provenance = run.provenance;
  o.psd_fines_fraction = run.psd.fines_fraction_not_simulated;
  o.shape = run.shape;
  o.run_dir = run_dir;
  return o;
}

PhotoOutcome photo_outcome_of(const json& m, const std::string& dir) {
  PhotoOutcome p;
  p.dir = dir;
  p.side_views = m.value("side_views", json::array());
  if (m.contains("theta_deg")) {
    p.measured = PhotoMeasure{m.at("theta_deg"),  m.at("theta_sd_deg"), m.at("height_m"),
                              m.at("diameter_m"), m.at("flank_deg"),    m.at("crest_width_m")};
  } else {
    p.error = "no side view of the pile could be measured";
    if (!p.side_views.empty() && p.side_views[0].contains("error"))
      p.error += ": " + p.side_views[0].at("error").get<std::string>();
  }
  return p;
}

// The request's scene as the pile run reads it.
SceneConfig request_scene(const PileRequest& r, bool frames) {
  SceneDoc doc(r.scene_path, r.overrides, "pile request (scene " + r.scene_path + ")");
  doc.set_seed(r.seed);
  if (!frames) doc.final_frame_only();
  return doc.config();
}

}  // namespace

json to_json(const PileRequest& r) {
  json j = pile_json(r);
  j["scene_resolved_sha256"] = sha256_hex(resolved_scene(r));
  j["photo"] = r.photo ? to_json(*r.photo) : json(nullptr);
  return j;
}

std::string pile_key(const PileRequest& r) {
  const json keyed = {{"scene_resolved", resolved_scene(r)}, {"seed", r.seed}};
  return sha256_hex(keyed.dump() + "\nengine " + engine_version());
}

std::string photo_key(const PileRequest& r) {
  if (!r.photo) throw std::invalid_argument("photo_key: the request asks for no photograph");
  return sha256_hex(pile_key(r) + "\n" + to_json(*r.photo).dump() + "\nimaging " +
                    imaging_version());
}

PileService::PileService(std::string dir, PileServiceSettings settings)
    : dir_(fs::absolute(dir).lexically_normal().string()), settings_(settings) {
  fs::create_directories(dir_);
}

std::string PileService::pile_dir(const PileRequest& r) const {
  return (fs::path(dir_) / "piles" / pile_key(r)).string();
}

std::string PileService::photo_dir(const PileRequest& r) const {
  return (fs::path(dir_) / "photos" / photo_key(r)).string();
}

namespace {

// The pile stage: the finished run of the request, from the store or run now (its final
// spheres then in memory). `started` is set when it had to run.
PileRun pile_stage(const PileRequest& r, const std::string& entry, const PileServiceSettings& s,
                   bool& started) {
  const fs::path run_dir = fs::path(entry) / "run";
  const fs::path done = run_dir / "result.json";
  started = false;
  if (fs::exists(done)) return pile_run_from_json(read_json_file(done.string()));
  const auto lock = lock_entry(entry, "another process pouring the same pile");
  if (fs::exists(done)) return pile_run_from_json(read_json_file(done.string()));
  started = true;
  write_json_atomic((fs::path(entry) / "request.json").string(), to_json(r));
  RunOptions opt;
  opt.out_dir = run_dir.string();
  opt.progress = false;
  opt.threads = s.threads;
  opt.extra_provenance = {{"pile_request", pile_json(r)}};
  const std::optional<PileRun> run = run_pile_test_or_continue(request_scene(r, s.frames), opt);
  if (!run) throw std::logic_error(opt.out_dir + ": a pile request has no stop limit, yet stopped");
  return *run;
}

// The photo stage: the photographs of a finished pile run, from the store or taken now (from
// the spheres in memory, or the run's final.vtp).
PhotoOutcome photo_stage(const PileRequest& r, const PileRun& run, const std::string& run_dir,
                         const std::string& entry, bool& started) {
  const fs::path done = fs::path(entry) / "result.json";
  started = false;
  if (fs::exists(done)) return photo_outcome_of(read_json_file(done.string()), entry);
  const auto lock = lock_entry(entry, "another process photographing the same pile");
  if (fs::exists(done)) return photo_outcome_of(read_json_file(done.string()), entry);
  started = true;
  PileSpheres spheres = run.final_spheres;
  if (spheres.x.empty()) {
    SnapshotParticles p = read_vtp((fs::path(run_dir) / "final.vtp").string());
    spheres = PileSpheres{std::move(p.x), std::move(p.radius), std::move(p.material),
                          std::move(p.body)};
  }
  json prov = to_json(run.provenance);
  prov["run_dir"] = run_dir;
  prov["snapshot"] = "final.vtp";
  std::optional<Eigen::Vector2d> centre;
  if (r.photo->centre_on_run_footprint)
    centre = Eigen::Vector2d(run.pile.centre_x_m, run.pile.centre_y_m);
  const json m = render_and_measure(spheres, entry, r.photo->settings, prov, centre);
  write_json_atomic(done.string(), m);
  return photo_outcome_of(m, entry);
}

}  // namespace

PileOutcome PileService::run_one(const PileRequest& r) {
  bool started = false;
  const std::string entry = pile_dir(r);
  const PileRun run = pile_stage(r, entry, settings_, started);
  started_sims_ += started;
  PileOutcome o = outcome_of(run, (fs::path(entry) / "run").string());
  if (!r.photo || !photographed(r.photo->when, o.status, o.pile)) return o;
  o.photo = photo_stage(r, run, o.run_dir, photo_dir(r), started);
  started_photos_ += started;
  if (!o.photo->measured && o.status == PileStatus::kPile) o.status = PileStatus::kUnmeasured;
  return o;
}

namespace {

// Runs `jobs` (indices into the requests) on the pool; a job that fails leaves its message in
// `errors`. `done`, when given, is told of each job that ended, in this process.
void pool_jobs(const std::vector<std::size_t>& jobs, int workers, WorkerMode mode,
               const std::function<void(std::size_t)>& job, const std::string& error_dir,
               std::map<std::size_t, std::string>& errors,
               const std::function<void(std::size_t, bool)>& done = {}) {
  std::mutex m;
  for (std::size_t i : jobs) fs::remove(fs::path(error_dir) / ("error_" + std::to_string(i)));
  run_jobs(
      jobs.size(), workers, mode,
      [&](std::size_t k) {
        try {
          job(jobs[k]);
          return true;
        } catch (const std::exception& e) {
          // A forked worker reports through a file; a thread through memory as well.
          write_file_atomic((fs::path(error_dir) / ("error_" + std::to_string(jobs[k]))).string(),
                            e.what());
          return false;
        }
      },
      [&](std::size_t k, const JobExit& exit) {
        std::lock_guard<std::mutex> g(m);
        if (done) done(jobs[k], exit.ok);
        if (exit.ok) return;
        const fs::path f = fs::path(error_dir) / ("error_" + std::to_string(jobs[k]));
        errors[jobs[k]] = fs::exists(f) ? read_file(f.string()) : "worker ended: " + exit.how;
      });
}

}  // namespace

// The stages of run(): the piles the store lacks, then their photographs, then every answer.
std::vector<PileOutcome> PileService::run(const std::vector<PileRequest>& requests) {
  std::map<std::size_t, std::string> errors;  // request -> what failed
  pour_missing(requests, errors);
  photograph_missing(requests, errors);
  if (!errors.empty()) {
    std::string msg = "pile service: " + std::to_string(errors.size()) + " request(s) failed:";
    for (const auto& [i, e] : errors)
      msg += "\n  " + requests[i].scene_path + " seed " + std::to_string(requests[i].seed) +
             ": " + e;
    throw std::runtime_error(msg);
  }
  std::vector<PileOutcome> out;
  out.reserve(requests.size());
  const int sims = started_sims_, shots = started_photos_;
  for (const PileRequest& r : requests) out.push_back(run_one(r));  // all in the store now
  started_sims_ = sims;
  started_photos_ = shots;
  return out;
}

// The pile runs the store lacks, one per key, in forked workers (each with its own OpenMP).
void PileService::pour_missing(const std::vector<PileRequest>& requests,
                               std::map<std::size_t, std::string>& errors) {
  std::set<std::string> seen;
  std::vector<std::size_t> piles;
  for (std::size_t i = 0; i < requests.size(); ++i) {
    const std::string entry = pile_dir(requests[i]);
    if (seen.insert(entry).second && !fs::exists(fs::path(entry) / "run" / "result.json"))
      piles.push_back(i);
  }
  const std::size_t before = errors.size();
  const PileServiceSettings s = settings_;
  pool_jobs(
      piles, settings_.workers, WorkerMode::kProcesses,
      [&](std::size_t i) {
        bool started = false;
        pile_stage(requests[i], pile_dir(requests[i]), s, started);
      },
      errors_dir(), errors, [&, ended = std::size_t{0}](std::size_t i, bool ok) mutable {
        if (!s.progress) return;
        const PileRequest& r = requests[i];
        std::fprintf(stderr, "[piles] %zu/%zu %s: %s seed %llu (store key %.12s)\n", ++ended,
                     piles.size(), ok ? "poured" : "failed",
                     fs::path(r.scene_path).filename().string().c_str(),
                     static_cast<unsigned long long>(r.seed), pile_key(r).c_str());
      });
  started_sims_ += static_cast<int>(piles.size() - (errors.size() - before));
}

// The photographs the store lacks of the piles that formed, on threads (each keeps its renderer
// from job to job; a forked job would build a GL context and compile the shaders again).
void PileService::photograph_missing(const std::vector<PileRequest>& requests,
                                     std::map<std::size_t, std::string>& errors) {
  std::set<std::string> failed_piles, seen;
  for (const auto& [i, e] : errors) failed_piles.insert(pile_dir(requests[i]));
  std::vector<std::size_t> photos;
  for (std::size_t i = 0; i < requests.size(); ++i) {
    if (!requests[i].photo || failed_piles.count(pile_dir(requests[i]))) continue;
    const std::string entry = photo_dir(requests[i]);
    if (!seen.insert(entry).second || fs::exists(fs::path(entry) / "result.json")) continue;
    const PileOutcome pile = finished_run(requests[i]);
    if (photographed(requests[i].photo->when, pile.status, pile.pile)) photos.push_back(i);
  }
  const std::size_t before = errors.size();
  pool_jobs(
      photos, settings_.workers, WorkerMode::kThreads,
      [&](std::size_t i) {
        const PileOutcome pile = finished_run(requests[i]);
        const PileRun run =
            pile_run_from_json(read_json_file((fs::path(pile.run_dir) / "result.json").string()));
        bool started = false;
        photo_stage(requests[i], run, pile.run_dir, photo_dir(requests[i]), started);
      },
      errors_dir(), errors);
  started_photos_ += static_cast<int>(photos.size() - (errors.size() - before));
}

// A finished pile run of the store, without its photographs.
PileOutcome PileService::finished_run(const PileRequest& r) const {
  const fs::path run_dir = fs::path(pile_dir(r)) / "run";
  return outcome_of(pile_run_from_json(read_json_file((run_dir / "result.json").string())),
                    run_dir.string());
}

std::string PileService::errors_dir() const {
  const fs::path d = fs::path(dir_) / "errors";
  fs::create_directories(d);
  return d.string();
}

}  // namespace reposetwin::experiments
