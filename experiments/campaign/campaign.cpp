#include "experiments/campaign/campaign.hpp"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "experiments/io/format.hpp"
#include "experiments/io/hash.hpp"
#include "experiments/io/overrides.hpp"
#include "experiments/io/provenance.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
namespace {

constexpr const char* kResultFile = "result.json";
constexpr const char* kErrorFile = "error.json";
constexpr const char* kStartedFile = "started.json";
constexpr const char* kManifestFile = "campaign.json";
constexpr const char* kBatchFile = "batch.json";

std::string hostname() {
  char buf[256] = {};
  if (gethostname(buf, sizeof buf - 1) != 0) return "unknown";
  return buf;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::optional<nlohmann::json> read_json(const fs::path& p) {
  std::error_code ec;
  if (!fs::is_regular_file(p, ec)) return std::nullopt;
  try {
    return read_json_file(p.string());
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

// Whether a stored spec describes the same inputs as `spec` (the scene's path may have moved).
bool same_inputs(const nlohmann::json& stored, const CaseSpec& spec) {
  const auto now = to_json(spec);
  for (const char* k : {"case", "seed", "scene_fnv1a", "overrides"})
    if (!stored.contains(k) || stored[k] != now[k]) return false;
  return true;
}

// The started.json of an interrupted attempt at this run in `dir`, when the folder may be handed
// back to the case function to continue: same inputs, not failed (a failure is retried clean),
// and not forced.
std::optional<nlohmann::json> interrupted_attempt(const fs::path& dir, const CaseSpec& spec,
                                                  bool force) {
  std::error_code ec;
  if (force || fs::exists(dir / kErrorFile, ec) || fs::exists(dir / kResultFile, ec))
    return std::nullopt;
  auto started = read_json(dir / kStartedFile);
  if (!started || !started->contains("spec") || !same_inputs((*started)["spec"], spec))
    return std::nullopt;
  return started;
}

// Removes the temporaries of the runner's own atomic writes (write_file_atomic names them
// "<file>.tmp.<pid>") that a kill mid-write left in `dir`: they are not the case's output, and a
// case handed its folder back must find only what it (and started.json) left there.
void remove_runner_temporaries(const fs::path& dir) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    for (const char* f : {kStartedFile, kResultFile, kErrorFile})
      if (name.rfind(std::string(f) + ".tmp.", 0) == 0) fs::remove(e.path(), ec);
  }
}

// Runs one run in its folder and records result.json or error.json. Never throws. An interrupted
// attempt with the same inputs keeps its folder, so the case function can continue its work
// (a pile run resumes from its checkpoint); result.json then records the earlier attempt(s).
bool execute_run(const CaseSpec& spec, const fs::path& out_dir, const CaseFn& case_fn,
                 const std::string& job, bool force) {
  const fs::path dir = out_dir / spec.relative_dir();
  const std::string started = utc_now();
  const auto t0 = std::chrono::steady_clock::now();
  nlohmann::json meta = {{"spec", to_json(spec)}, {"job", job},
                         {"host", hostname()},    {"pid", ::getpid()},
                         {"started", started},    {"code_version", code_version()}};
  try {
    std::error_code ec;
    if (auto earlier = interrupted_attempt(dir, spec, force)) {
      nlohmann::json attempts = earlier->value("earlier_attempts", nlohmann::json::array());
      earlier->erase("earlier_attempts");
      earlier->erase("spec");
      attempts.push_back(*earlier);
      meta["earlier_attempts"] = attempts;
      remove_runner_temporaries(dir);
    } else {
      fs::remove_all(dir, ec);  // a failed, forced or changed run restarts clean
      if (ec)
        throw std::runtime_error(dir.string() + ": cannot clean the run folder: " + ec.message());
    }
    fs::create_directories(dir);
    write_json_atomic((dir / kStartedFile).string(), meta);
    nlohmann::json result = case_fn(spec, dir.string());
    meta["finished"] = utc_now();
    meta["wall_time_s"] = seconds_since(t0);
    meta["result"] = std::move(result);
    write_json_atomic((dir / kResultFile).string(), meta);
    return true;
  } catch (const std::exception& e) {
    meta["error"] = e.what();
  } catch (...) {
    meta["error"] = "unknown exception";
  }
  meta["finished"] = utc_now();
  meta["wall_time_s"] = seconds_since(t0);
  try {
    write_json_atomic((dir / kErrorFile).string(), meta);
  } catch (...) {
  }
  return false;
}

// Whether the run in `dir` finished after its worker ended. A worker that could not start, or
// died without writing either file (a crash, a kill), gets an error.json saying so.
bool record_worker_end(const CaseSpec& spec, const fs::path& out_dir, const std::string& job,
                       const JobExit& exit) {
  const fs::path dir = out_dir / spec.relative_dir();
  std::error_code ec;
  if (!exit.started) {
    fs::create_directories(dir, ec);
    write_json_atomic((dir / kErrorFile).string(),
                      {{"spec", to_json(spec)}, {"job", job}, {"error", "fork failed"}});
    return false;
  }
  const bool has_result = fs::is_regular_file(dir / kResultFile, ec);
  if (!has_result && !fs::is_regular_file(dir / kErrorFile, ec)) {
    const std::string why =
        "worker ended without a result" + (exit.how.empty() ? "" : " (" + exit.how + ")");
    fs::create_directories(dir, ec);
    write_json_atomic((dir / kErrorFile).string(),
                      {{"spec", to_json(spec)}, {"job", job}, {"error", why}});
  }
  return has_result;
}

// Status of one run as the manifest records it. Under MPI, rank 0 accepts only files of this job
// (or finished results of earlier jobs when not forcing).
struct RunStatus {
  std::string status;  // "finished", "failed", "pending"
  std::string error;
  double wall_time_s = 0.0;
};

RunStatus run_status(const fs::path& out_dir, const CaseSpec& spec, const std::string& job,
                     bool require_job_result, bool require_job_error) {
  const fs::path dir = out_dir / spec.relative_dir();
  std::error_code ec;
  if (fs::is_regular_file(dir / kResultFile, ec)) {
    auto j = read_json(dir / kResultFile);
    if (j && (!require_job_result || j->value("job", std::string()) == job))
      return {"finished", "", j->value("wall_time_s", 0.0)};
  }
  if (fs::is_regular_file(dir / kErrorFile, ec)) {
    auto j = read_json(dir / kErrorFile);
    if (j && (!require_job_error || j->value("job", std::string()) == job))
      return {"failed", j->value("error", std::string("unknown error")),
              j->value("wall_time_s", 0.0)};
  }
  return {"pending", "", 0.0};
}

using OutcomeFn = std::function<std::string(const nlohmann::json&)>;

nlohmann::json build_manifest(const Campaign& c, const fs::path& out_dir,
                              const std::vector<RunStatus>& st, const OutcomeFn& outcome_of) {
  nlohmann::json runs = nlohmann::json::array();
  int finished = 0, failed = 0, pending = 0, piles = 0;
  std::map<std::string, int> without_pile;
  for (std::size_t i = 0; i < c.runs.size(); ++i) {
    const auto& s = c.runs[i];
    nlohmann::json r = {{"case", s.case_name},
                        {"seed", s.seed},
                        {"dir", s.relative_dir()},
                        {"status", st[i].status}};
    if (st[i].status == "finished") {
      ++finished;
      r["wall_time_s"] = st[i].wall_time_s;
      if (outcome_of) {
        const auto res = read_json(out_dir / s.relative_dir() / kResultFile);
        std::string outcome = "unreadable result";
        if (res && res->contains("result")) {
          try {
            outcome = outcome_of((*res)["result"]);
          } catch (const std::exception& e) {
            outcome = std::string("unreadable result (") + e.what() + ")";
          }
        }
        r["outcome"] = outcome;
        if (outcome == "pile") {
          ++piles;
        } else {
          ++without_pile[outcome];
        }
      }
    } else if (st[i].status == "failed") {
      ++failed;
      r["error"] = st[i].error;
    } else {
      ++pending;
    }
    runs.push_back(r);
  }
  nlohmann::json counts = {
      {"total", c.runs.size()}, {"finished", finished}, {"failed", failed}, {"pending", pending}};
  if (outcome_of) {  // a result is a run that formed a pile; the others by reason
    counts["piles"] = piles;
    counts["without_pile"] = without_pile;
  }
  return {{"campaign", c.name},
          {"file", c.file},
          {"scene", c.scene_path},
          {"description", c.description},
          {"paper", c.paper},
          {"out_dir", fs::absolute(out_dir).string()},
          {"code_version", code_version()},
          {"updated", utc_now()},
          {"counts", counts},
          {"runs", runs}};
}

std::vector<RunStatus> scan(const Campaign& c, const fs::path& out_dir) {
  std::vector<RunStatus> st;
  for (const auto& s : c.runs) st.push_back(run_status(out_dir, s, "", false, false));
  return st;
}

// The absolute output folder, created; refuses runs whose indices are not their positions and a
// folder that holds another campaign.
fs::path prepare_out_dir(const Campaign& campaign, const std::string& out_dir_str) {
  for (std::size_t k = 0; k < campaign.runs.size(); ++k)
    if (campaign.runs[k].index != k)
      throw std::invalid_argument("run_campaign: run " + campaign.runs[k].id() + " has index " +
                                  std::to_string(campaign.runs[k].index) + ", expected " +
                                  std::to_string(k));
  const fs::path out_dir = fs::absolute(fs::path(out_dir_str)).lexically_normal();
  fs::create_directories(out_dir);
  for (const char* name : {kManifestFile, kBatchFile}) {
    if (auto m = read_json(out_dir / name)) {
      const std::string other = m->value("campaign", std::string());
      if (other != campaign.name)
        throw std::runtime_error(out_dir.string() + " holds campaign '" + other + "', not '" +
                                 campaign.name + "': use another output folder");
    }
  }
  return out_dir;
}

// The runs this process does (this rank's share, without the finished ones unless forcing);
// `skipped` counts the finished ones. Refuses to mix finished results made from other inputs.
std::vector<std::size_t> runs_to_do(const Campaign& campaign, const fs::path& out_dir,
                                    const std::optional<RankInfo>& mpi_rank, bool force,
                                    int& skipped) {
  std::vector<std::size_t> todo;
  for (const auto& s : campaign.runs) {
    if (mpi_rank &&
        static_cast<int>(s.index % static_cast<std::size_t>(mpi_rank->size)) != mpi_rank->rank)
      continue;
    const fs::path dir = out_dir / s.relative_dir();
    if (auto r = read_json(dir / kResultFile); r && !force) {
      if (!same_inputs(r->value("spec", nlohmann::json::object()), s))
        throw std::runtime_error((dir / kResultFile).string() + ": finished result of " + s.id() +
                                 " was made from different inputs than " + campaign.file +
                                 " now gives; use --force to redo it or another output folder");
      ++skipped;
      continue;
    }
    todo.push_back(s.index);
  }
  return todo;
}

// Waits for every other rank's runs: a result of this job (or an earlier finished one when not
// forcing), or an error of this job. Without a job id, files newer than this rank's start.
void wait_for_other_ranks(const Campaign& campaign, const fs::path& out_dir, const RankInfo& rank,
                          const RunnerSettings& settings, std::vector<RunStatus>& status,
                          const std::function<void(const std::string&)>& say) {
  const auto wait_start = std::chrono::steady_clock::now();
  const auto file_start = fs::file_time_type::clock::now() - std::chrono::seconds(2);
  const bool have_job = !rank.job.empty();
  for (;;) {
    int pending = 0;
    for (const auto& s : campaign.runs) {
      const fs::path dir = out_dir / s.relative_dir();
      RunStatus st = run_status(out_dir, s, rank.job, settings.force && have_job, have_job);
      if (!have_job && st.status != "pending") {
        std::error_code ec;
        const fs::path f = dir / (st.status == "finished" ? kResultFile : kErrorFile);
        const bool fresh = fs::last_write_time(f, ec) >= file_start;
        if (!fresh && (st.status == "failed" || settings.force)) st = {"pending", "", 0.0};
      }
      status[s.index] = st;
      if (st.status == "pending") ++pending;
    }
    if (pending == 0) return;
    if (settings.wait_timeout_s > 0.0 && seconds_since(wait_start) > settings.wait_timeout_s) {
      say("gave up waiting for " + std::to_string(pending) + " run(s) of other ranks");
      return;
    }
    std::this_thread::sleep_for(std::chrono::duration<double>(settings.poll_interval_s));
  }
}

// The runner behind run_campaign and run_batch. `manifest_name` is the summary file rank 0 writes;
// with `every_rank_waits` all MPI ranks (not only rank 0) wait for every run to end, so each can
// continue with the results (the calibration driver runs the same steps on every rank).
CampaignSummary run_impl(const Campaign& campaign, const std::string& out_dir_str,
                         const CaseFn& case_fn, const RunnerSettings& settings,
                         const std::string& manifest_name, bool every_rank_waits) {
  if (!case_fn) throw std::invalid_argument("run_campaign: no case function");
  const fs::path out_dir = prepare_out_dir(campaign, out_dir_str);
  const bool mpi = settings.rank.has_value() && settings.rank->size > 1;
  const RankInfo rank = settings.rank.value_or(RankInfo{});
  const bool writes_manifest = !mpi || rank.rank == 0;
  std::optional<FolderLock> lock;
  if (!mpi) lock.emplace(out_dir.string(), ".campaign.lock", "another campaign process");
  const std::string tag =
      "[campaign " + campaign.name +
      (mpi ? " rank " + std::to_string(rank.rank) + "/" + std::to_string(rank.size)
           : std::string()) +
      "] ";
  auto say = [&](const std::string& line) {
    if (settings.progress) std::cerr << tag << line << std::endl;
  };

  CampaignSummary summary;
  summary.total = static_cast<int>(campaign.runs.size());
  const std::vector<std::size_t> todo = runs_to_do(
      campaign, out_dir, mpi ? settings.rank : std::nullopt, settings.force, summary.skipped);
  say(std::to_string(todo.size()) + " run(s) to do, " + std::to_string(summary.skipped) +
      " already finished, " + std::to_string(summary.total) + " in the campaign");

  std::vector<RunStatus> status = scan(campaign, out_dir);
  auto write_manifest = [&] {
    summary.manifest = build_manifest(campaign, out_dir, status, settings.outcome_of);
    if (writes_manifest) write_json_atomic((out_dir / manifest_name).string(), summary.manifest);
  };
  if (!mpi) write_manifest();

  const auto t0 = std::chrono::steady_clock::now();
  auto job = [&](std::size_t k) {
    return execute_run(campaign.runs[todo[k]], out_dir, case_fn, rank.job, settings.force);
  };
  auto on_done = [&](std::size_t k, const JobExit& exit) {
    const std::size_t i = todo[k];
    const bool ok = record_worker_end(campaign.runs[i], out_dir, rank.job, exit);
    ++summary.ran;
    status[i] = run_status(out_dir, campaign.runs[i], "", false, false);
    std::ostringstream os;
    os << campaign.runs[i].id() << (ok ? " finished" : " FAILED: " + status[i].error) << " ("
       << summary.ran << "/" << todo.size() << " done, " << static_cast<int>(seconds_since(t0))
       << " s)";
    say(os.str());
    if (!mpi) write_manifest();
  };
  run_jobs(todo.size(), mpi ? 1 : settings.workers, settings.mode, job, on_done);

  if (mpi && (rank.rank == 0 || every_rank_waits))
    wait_for_other_ranks(campaign, out_dir, rank, settings, status, say);
  if (writes_manifest) {
    write_manifest();
  } else {
    summary.manifest =
        build_manifest(campaign, out_dir, scan(campaign, out_dir), settings.outcome_of);
  }
  const auto& counts = summary.manifest["counts"];
  summary.finished = counts["finished"].get<int>();
  summary.failed = counts["failed"].get<int>();
  if (counts.contains("piles")) {
    summary.piles = counts["piles"].get<int>();
    summary.without_pile = counts["without_pile"].get<std::map<std::string, int>>();
  }
  if (!writes_manifest) {
    say("this rank's " + std::to_string(summary.ran) + " run(s) done; rank 0 writes the manifest");
  } else {
    // A finished run without an angle (jammed, not settled, ...) is a failure to the user,
    // named by its reason.
    std::string without;
    for (const auto& [reason, n] : summary.without_pile)
      without += (without.empty() ? "" : ", ") + std::to_string(n) + " " + reason;
    say(std::to_string(summary.finished) + " finished" +
        (without.empty() ? std::string() : " (without an angle: " + without + ")") + ", " +
        std::to_string(summary.failed) + " failed, " +
        std::to_string(counts["pending"].get<int>()) + " pending of " +
        std::to_string(summary.total));
  }
  return summary;
}

// The name of a calibration or prediction run: "<prefix>_<leaf of calibration.key>_<mu_r>".
std::string mu_r_run_name(const Campaign& campaign, const std::string& prefix, double mu_r) {
  const auto parts =
      split_dotted_key(campaign.calibration->key, campaign.file + ": key 'calibration.key'");
  return sanitize_name(prefix + "_" + parts.back() + "_" + shortest_text(mu_r));
}

// A run of `scene_path` with `overrides`, checked now rather than when it runs: the name is safe
// as a folder name and every override applies to the scene (`origin` names the run in messages).
CaseSpec checked_run(const Campaign& campaign, const std::string& name, std::uint64_t seed,
                     const std::string& scene_path, std::vector<Override> overrides,
                     const std::string& origin) {
  if (!is_safe_name(name))
    throw std::invalid_argument(campaign.file + ": run name \"" + name +
                                "\" is not filesystem-safe");
  CaseSpec s;
  s.case_name = name;
  s.seed = seed;
  s.scene_path = scene_path;
  s.scene_hash = fnv1a_hex(read_file(scene_path));
  s.overrides = std::move(overrides);
  (void)SceneDoc(scene_path, s.overrides, origin);
  return s;
}

}  // namespace

SceneDoc build_case_scene(const CaseSpec& spec) {
  return SceneDoc(spec.scene_path, spec.overrides,
                  "case " + spec.case_name + " (scene " + spec.scene_path + ")");
}

nlohmann::json to_json(const CaseSpec& spec) {
  return {{"case", spec.case_name},
          {"seed", spec.seed},
          {"scene", spec.scene_path},
          {"scene_fnv1a", spec.scene_hash},
          {"overrides", overrides_to_json(spec.overrides)}};
}

nlohmann::json campaign_manifest(const Campaign& campaign, const std::string& out_dir,
                                 const OutcomeFn& outcome_of) {
  return build_manifest(campaign, out_dir, scan(campaign, out_dir), outcome_of);
}

CampaignSummary run_campaign(const Campaign& campaign, const std::string& out_dir,
                             const CaseFn& case_fn, const RunnerSettings& settings) {
  return run_impl(campaign, out_dir, case_fn, settings, kManifestFile, false);
}

std::optional<nlohmann::json> read_run_result(const std::string& out_dir, const CaseSpec& spec) {
  return read_json(fs::path(out_dir) / spec.relative_dir() / kResultFile);
}

CaseSpec make_run(const Campaign& campaign, const std::string& case_name,
                  const std::vector<Override>& overrides, std::uint64_t seed) {
  std::vector<Override> all = campaign.overrides;
  for (const Override& o : overrides) set_override(all, o);
  return checked_run(campaign, case_name, seed, campaign.scene_path, std::move(all),
                     campaign.file + ", run " + case_name);
}

CaseSpec calibration_run(const Campaign& campaign, double mu_r, std::uint64_t seed) {
  if (!campaign.calibration)
    throw std::invalid_argument(campaign.file + ": no [calibration] table");
  std::vector<Override> ov;
  set_override(ov, number_override(campaign.calibration->key, mu_r));
  for (const auto& k : campaign.calibration->keys) set_override(ov, number_override(k, mu_r));
  return make_run(campaign, mu_r_run_name(campaign, "calib", mu_r), ov, seed);
}

CaseSpec prediction_run(const Campaign& campaign, const PredictionCase& p, double mu_r,
                        std::uint64_t seed) {
  if (!campaign.calibration)
    throw std::invalid_argument(campaign.file + ": no [calibration] table");
  if (!std::isfinite(mu_r) || mu_r < 0.0)
    throw std::invalid_argument(campaign.file + ", prediction " + p.name +
                                ": mu_r = " + std::to_string(mu_r) + " must be finite and >= 0");
  const std::string name = mu_r_run_name(campaign, "predict_" + p.name, mu_r);
  std::vector<Override> overrides = p.overrides;
  for (const auto& k : campaign.calibration->keys) set_override(overrides, number_override(k, mu_r));
  return checked_run(campaign, name, seed, p.scene_path, std::move(overrides),
                     campaign.file + ", prediction run " + name);
}

std::vector<nlohmann::json> run_batch(const Campaign& campaign, const std::vector<CaseSpec>& runs,
                                      const std::string& out_dir, const CaseFn& case_fn,
                                      const RunnerSettings& settings) {
  Campaign batch = campaign;
  batch.runs = runs;
  std::set<std::string> ids;
  for (std::size_t k = 0; k < batch.runs.size(); ++k) {
    batch.runs[k].index = k;
    if (!ids.insert(batch.runs[k].id()).second)
      throw std::invalid_argument("run_batch: run " + batch.runs[k].id() + " appears twice");
  }
  run_impl(batch, out_dir, case_fn, settings, kBatchFile, true);
  std::vector<nlohmann::json> results;
  std::string failures;
  for (const auto& s : batch.runs) {
    const fs::path dir = fs::path(out_dir) / s.relative_dir();
    if (auto j = read_json(dir / kResultFile)) {
      results.push_back((*j)["result"]);
      continue;
    }
    const auto e = read_json(dir / kErrorFile);
    failures += (failures.empty() ? "" : "; ") + s.id() + ": " +
                (e ? e->value("error", std::string("unknown error")) : std::string("no result"));
  }
  if (!failures.empty()) throw std::runtime_error("run_batch: run(s) failed: " + failures);
  return results;
}

BatchPlan plan_campaign(const Campaign& campaign, int workers) {
  std::vector<BatchPlan::Part> parts;
  std::map<std::string, std::size_t> part_of;  // case name -> its part
  for (const CaseSpec& run : campaign.runs) {
    const auto [it, first] = part_of.emplace(run.case_name, parts.size());
    if (first)
      parts.push_back({"runs of case " + run.case_name,
                       plan_run(build_case_scene(run).config(), 1), 0});
    ++parts[it->second].runs;
  }
  return plan_batch(std::move(parts), workers);
}

}  // namespace reposetwin::experiments
