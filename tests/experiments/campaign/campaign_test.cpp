#include "experiments/calibration/calibration.hpp"
#include "experiments/calibration/campaign_target.hpp"
#include "experiments/campaign/campaign.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <stdexcept>
#include <thread>

#include "experiments/io/provenance.hpp"
#include "campaign_fixtures.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;
using namespace campaign_fixtures;

// Counts starts of each run in a log file (one line per start; O_APPEND keeps lines whole across
// processes).
void log_start(const fs::path& log, const CaseSpec& s) {
  std::ofstream(log, std::ios::app) << s.id() << "\n";
}
std::map<std::string, int> read_log(const fs::path& log) {
  std::map<std::string, int> n;
  std::ifstream in(log);
  for (std::string line; std::getline(in, line);) ++n[line];
  return n;
}

// A cheap deterministic case: reads the run's scene (overrides applied), sleeps, and returns a
// value computed from mu_r, mass and the seed. Its folder must hold only the runner's
// started.json, or also the partial.out of its own interrupted attempt (which it continues);
// anything else fails it.
CaseFn fake_case(const fs::path& log, int sleep_ms) {
  return [log, sleep_ms](const CaseSpec& s, const std::string& dir) {
    log_start(log, s);
    const auto entries = std::distance(fs::directory_iterator(dir), {});
    const bool started = fs::exists(fs::path(dir) / "started.json");
    const bool continued = started && entries == 2 && fs::exists(fs::path(dir) / "partial.out");
    if (!(started && entries == 1) && !continued)
      throw std::runtime_error("run folder not clean: " + dir);
    std::ofstream(fs::path(dir) / "partial.out") << "partial output\n";
    std::this_thread::sleep_for(std::chrono::milliseconds(sleep_ms));
    const SceneDoc scene = build_case_scene(s);
    const double mu = scene.number("rolling.mu_r").value();
    const double mass = scene.number("sample.mass").value();
    if (mu < 0.0) throw std::runtime_error("negative mu_r");
    return nlohmann::json{{"mu_r", mu}, {"mass", mass}, {"value", 1000.0 * mu + mass + s.seed}};
  };
}

nlohmann::json result_of(const fs::path& out, const CaseSpec& s) {
  return nlohmann::json::parse(read_file((out / s.relative_dir() / "result.json").string()));
}

// Waits until no process holds the campaign folder's lock (the killed campaign's workers die
// with it, asynchronously).
void wait_unlocked(const fs::path& out) {
  const std::string p = (out / ".campaign.lock").string();
  for (int i = 0; i < 500; ++i) {
    const int fd = ::open(p.c_str(), O_RDWR | O_CREAT, 0644);
    const bool free = fd >= 0 && ::flock(fd, LOCK_EX | LOCK_NB) == 0;
    if (fd >= 0) ::close(fd);
    if (free) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  FAIL() << "campaign lock still held";
}

RunnerSettings quiet(WorkerMode mode = WorkerMode::kProcesses) {
  RunnerSettings r;
  r.mode = mode;
  r.progress = false;
  r.rank.reset();
  return r;
}

const char* kRunCampaign = R"(
name = "resume_demo"
scene = "scene.toml"
seeds = [1, 2, 3]
[sweep]
key = "rolling.mu_r"
values = [0.05, 0.1, 0.15, 0.2]
)";

TEST(Campaign, KilledCampaignResumesToTheSameResults) {
  const ScratchDir scratch("resume");
  const fs::path& dir = scratch.path;
  const auto c = load_campaign(write_campaign(dir, kRunCampaign).string());
  ASSERT_EQ(c.runs.size(), 12u);

  // Reference: an uninterrupted run.
  const fs::path ref = dir / "ref";
  const auto s_ref = run_campaign(c, ref.string(), fake_case(dir / "ref.log", 5), quiet());
  EXPECT_EQ(s_ref.finished, 12);
  EXPECT_EQ(s_ref.ran, 12);

  // Interrupted: a child runs the campaign; SIGKILL once two results exist.
  const fs::path out = dir / "out";
  const fs::path log = dir / "out.log";
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    try {
      run_campaign(c, out.string(), fake_case(log, 100), quiet());
    } catch (...) {
    }
    ::_exit(0);
  }
  auto count_results = [&] {
    int n = 0;
    for (const auto& s : c.runs) n += fs::exists(out / s.relative_dir() / "result.json");
    return n;
  };
  // A run is mid-way once its case has written partial output and not yet its result.
  auto mid_way = [&] {
    for (const auto& s : c.runs)
      if (fs::exists(out / s.relative_dir() / "partial.out") &&
          !fs::exists(out / s.relative_dir() / "result.json"))
        return true;
    return false;
  };
  // Poll rather than sleep a fixed time: on a loaded machine a fixed delay can miss the window.
  for (int i = 0; i < 5000 && !(count_results() >= 2 && mid_way()); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  ::kill(child, SIGKILL);
  int st = 0;
  ::waitpid(child, &st, 0);
  ASSERT_TRUE(WIFSIGNALED(st));
  wait_unlocked(out);

  std::map<std::string, fs::file_time_type> mtime_before;
  std::map<std::string, std::string> text_before;
  for (const auto& s : c.runs) {
    const fs::path f = out / s.relative_dir() / "result.json";
    if (fs::exists(f)) {
      mtime_before[s.id()] = fs::last_write_time(f);
      text_before[s.id()] = read_file(f.string());
    }
  }
  ASSERT_GE(mtime_before.size(), 2u);
  ASSERT_LT(mtime_before.size(), 12u) << "the kill came too late to test resuming";
  std::set<std::string> partial;  // started but unfinished runs (most with partial output)
  int with_output = 0;
  for (const auto& s : c.runs)
    if (fs::exists(out / s.relative_dir() / "started.json") &&
        !fs::exists(out / s.relative_dir() / "result.json")) {
      partial.insert(s.id());
      with_output += fs::exists(out / s.relative_dir() / "partial.out");
    }
  ASSERT_GE(with_output, 1) << "the kill did not interrupt a run";
  ASSERT_GE(partial.size(), 1u) << "the kill did not interrupt a run";
  const auto starts_before = read_log(log);

  // Resume.
  const auto s2 = run_campaign(c, out.string(), fake_case(log, 5), quiet());
  EXPECT_EQ(s2.finished, 12);
  EXPECT_EQ(s2.failed, 0) << s2.manifest["runs"].dump();
  EXPECT_EQ(s2.skipped, static_cast<int>(mtime_before.size()));
  EXPECT_EQ(s2.ran, 12 - static_cast<int>(mtime_before.size()));
  const auto starts_after = read_log(log);
  for (const auto& s : c.runs) {
    EXPECT_EQ(result_of(out, s)["result"], result_of(ref, s)["result"]) << s.id();
    const auto stored = read_run_result(out.string(), s);
    ASSERT_TRUE(stored.has_value());
    // The value is computed from the run's inputs, independently of the runner.
    const double mu = 0.05 * static_cast<double>(s.index / 3 + 1);
    EXPECT_NEAR((*stored)["result"]["value"].get<double>(), 1000.0 * mu + 0.2 + s.seed, 1e-9);
    if (mtime_before.count(s.id())) {
      // Finished before the kill: not redone, not rewritten.
      EXPECT_EQ(starts_after.at(s.id()), 1) << s.id();
      EXPECT_EQ(fs::last_write_time(out / s.relative_dir() / "result.json"), mtime_before[s.id()]);
      EXPECT_EQ(read_file((out / s.relative_dir() / "result.json").string()), text_before[s.id()]);
    } else {
      const int before = starts_before.count(s.id()) ? starts_before.at(s.id()) : 0;
      EXPECT_EQ(starts_after.at(s.id()), before + 1) << s.id();
      // An interrupted run was handed back to the case to continue, and says so.
      EXPECT_EQ(result_of(out, s).contains("earlier_attempts"), partial.count(s.id()) == 1)
          << s.id();
    }
  }
  const auto manifest = nlohmann::json::parse(read_file((out / "campaign.json").string()));
  EXPECT_EQ(manifest["campaign"], "resume_demo");
  EXPECT_EQ(manifest["counts"]["finished"], 12);
  EXPECT_EQ(manifest["runs"].size(), 12u);

  // A third call does nothing; --force redoes everything.
  const auto s3 = run_campaign(c, out.string(), fake_case(log, 1), quiet());
  EXPECT_EQ(s3.ran, 0);
  EXPECT_EQ(s3.skipped, 12);
  auto forced = quiet(WorkerMode::kThreads);
  forced.force = true;
  const auto s4 = run_campaign(c, out.string(), fake_case(log, 1), forced);
  EXPECT_EQ(s4.ran, 12);
  EXPECT_EQ(s4.finished, 12);
}

// A kill while the runner wrote result.json (or started.json) leaves its temporary beside the
// interrupted run's output; the resumed run continues from that output, not from a failure.
TEST(Campaign, ResumeIgnoresTemporaryOfAWriteKilledMidWay) {
  const ScratchDir scratch("killed_write");
  const fs::path& dir = scratch.path;
  const auto c = load_campaign(write_campaign(dir, kRunCampaign).string());
  const fs::path out = dir / "out";
  const CaseSpec& s = c.runs[2];
  const fs::path run = out / s.relative_dir();
  fs::create_directories(run);
  write_json_atomic((run / "started.json").string(),
                    {{"spec", to_json(s)}, {"job", ""}, {"pid", 99999}});
  std::ofstream(run / "partial.out") << "partial output\n";
  std::ofstream(run / "result.json.tmp.99999") << "{\"spec\": ";  // cut off by the kill
  const auto sum = run_campaign(c, out.string(), fake_case(dir / "log", 1), quiet());
  EXPECT_EQ(sum.failed, 0) << sum.manifest["runs"].dump();
  EXPECT_EQ(sum.finished, 12);
  EXPECT_TRUE(result_of(out, s).contains("earlier_attempts"));
  EXPECT_FALSE(fs::exists(run / "result.json.tmp.99999"));
}

TEST(Campaign, FailingAndCrashingCasesAreRecordedAndOthersFinish) {
  const ScratchDir scratch("failing");
  const fs::path& dir = scratch.path;
  const auto c = load_campaign(write_campaign(dir, R"(
name = "failing"
scene = "scene.toml"
seeds = [1, 2]
[[case]]
name = "good"
[[case]]
name = "bad"
overrides = { "rolling.mu_r" = -1.0 }
[[case]]
name = "crash"
overrides = { "rolling.mu_r" = 0.3 }
)")
                                   .string());
  auto base = fake_case(dir / "log", 1);
  CaseFn fn = [&](const CaseSpec& s, const std::string& d) {
    if (s.case_name == "crash") std::raise(SIGKILL);  // a worker that dies outright
    return base(s, d);
  };
  const auto s = run_campaign(c, (dir / "out").string(), fn, quiet());
  EXPECT_EQ(s.finished, 2);
  EXPECT_EQ(s.failed, 4);
  const auto m = nlohmann::json::parse(read_file((dir / "out/campaign.json").string()));
  for (const auto& r : m["runs"]) {
    if (r["case"] == "good") {
      EXPECT_EQ(r["status"], "finished");
    } else {
      EXPECT_EQ(r["status"], "failed");
      const std::string err = r["error"];
      if (r["case"] == "bad") {
        EXPECT_NE(err.find("negative mu_r"), std::string::npos) << err;
      }
      if (r["case"] == "crash") {
        EXPECT_NE(err.find("signal 9"), std::string::npos) << err;
      }
    }
  }
  // Threads: an exception is recorded the same way.
  CaseFn no_crash = [&](const CaseSpec& sp, const std::string& d) {
    if (sp.case_name == "crash") throw std::runtime_error("crash case skipped in threads");
    return base(sp, d);
  };
  const auto t =
      run_campaign(c, (dir / "out_threads").string(), no_crash, quiet(WorkerMode::kThreads));
  EXPECT_EQ(t.finished, 2);
  EXPECT_EQ(t.failed, 4);
}

TEST(Campaign, ResumeRefusesChangedInputsAndAnotherCampaign) {
  const ScratchDir scratch("changed");
  const fs::path& dir = scratch.path;
  auto c = load_campaign(write_campaign(dir, kCasesCampaign).string());
  const fs::path out = dir / "out";
  run_campaign(c, out.string(), fake_case(dir / "log", 1), quiet(WorkerMode::kThreads));
  auto edited = c;
  set_override(edited.runs[1].overrides, number_override("rolling.mu_r", 0.07));
  try {
    run_campaign(edited, out.string(), fake_case(dir / "log", 1), quiet());
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("low/seed_2"), std::string::npos) << e.what();
  }
  auto other = c;
  other.name = "another";
  EXPECT_THROW(run_campaign(other, out.string(), fake_case(dir / "log", 1), quiet()),
               std::runtime_error);
}

TEST(Campaign, MpiRanksSplitTheRunsAndRankZeroWritesTheManifest) {
  const ScratchDir scratch("mpi");
  const fs::path& dir = scratch.path;
  const auto c = load_campaign(write_campaign(dir, kRunCampaign).string());
  const fs::path out = dir / "out";
  const fs::path log = dir / "log";
  std::vector<pid_t> ranks;
  for (int r = 0; r < 2; ++r) {
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      auto s = quiet();
      s.rank = RankInfo{r, 2, "job-1"};
      s.poll_interval_s = 0.01;
      s.wait_timeout_s = 20.0;
      int code = 1;
      try {
        const auto sum = run_campaign(c, out.string(), fake_case(log, 2), s);
        code = (r == 0 && sum.finished != 12) ? 2 : 0;
      } catch (...) {
      }
      ::_exit(code);
    }
    ranks.push_back(pid);
  }
  for (pid_t p : ranks) {
    int st = 0;
    ::waitpid(p, &st, 0);
    EXPECT_TRUE(WIFEXITED(st) && WEXITSTATUS(st) == 0);
  }
  const auto starts = read_log(log);
  for (const auto& s : c.runs) {
    EXPECT_EQ(starts.at(s.id()), 1) << s.id();
    EXPECT_EQ(result_of(out, s)["job"], "job-1");
  }
  const auto m = nlohmann::json::parse(read_file((out / "campaign.json").string()));
  EXPECT_EQ(m["counts"]["finished"], 12);
}

TEST(Campaign, DetectsOpenMpiEnvironment) {
  ::setenv("OMPI_COMM_WORLD_RANK", "1", 1);
  ::setenv("OMPI_COMM_WORLD_SIZE", "4", 1);
  ::setenv("PMIX_NAMESPACE", "prterun-x-1@1", 1);
  const auto r = detect_mpi_rank();
  ::unsetenv("OMPI_COMM_WORLD_RANK");
  ::unsetenv("OMPI_COMM_WORLD_SIZE");
  ::unsetenv("PMIX_NAMESPACE");
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->rank, 1);
  EXPECT_EQ(r->size, 4);
  EXPECT_EQ(r->job, "prterun-x-1@1");
  EXPECT_FALSE(detect_mpi_rank().has_value());
}

TEST(Campaign, CalibrationRunsThroughBatchesAndResumesWithoutRedoing) {
  const ScratchDir scratch("calib");
  const fs::path& dir = scratch.path;
  const auto c = load_campaign(write_campaign(dir, R"(
name = "calib_demo"
scene = "scene.toml"
overrides = { "sample.mass" = 0.9 }
[calibration]
key = "rolling.mu_r"
target_deg = 35.0
mu_r_range = [0.0, 0.3]
seeds_per_point = 2
tolerance_deg = 0.3
max_simulations = 20
)")
                                   .string());
  ASSERT_TRUE(c.runs.empty());
  ASSERT_TRUE(c.calibration.has_value());
  const fs::path out = dir / "out";
  const fs::path log = dir / "log";
  // The "simulation": angle = 20 + 100 mu_r plus a small deterministic seed effect.
  CaseFn sim = [log](const CaseSpec& s, const std::string&) {
    log_start(log, s);
    const SceneDoc scene = build_case_scene(s);
    const double mu = scene.number("rolling.mu_r").value();
    EXPECT_DOUBLE_EQ(scene.number("sample.mass").value(), 0.9);  // common override
    return nlohmann::json{{"angle_deg", 20.0 + 100.0 * mu + (s.seed % 2 ? 0.1 : -0.1)}};
  };
  auto calibrate_in = [&](const fs::path& where) {
    SimulateBatchFn batch = [&](const std::vector<std::pair<double, std::uint64_t>>& points) {
      std::vector<CaseSpec> runs;
      for (const auto& [mu, seed] : points) runs.push_back(calibration_run(c, mu, seed));
      std::vector<double> angles;
      for (const auto& r : run_batch(c, runs, where.string(), sim, quiet()))
        angles.push_back(r["angle_deg"].get<double>());
      return angles;
    };
    return calibrate_batch(batch, c.calibration->target, c.calibration->settings);
  };
  const auto first = calibrate_in(out);
  ASSERT_TRUE(first.mu_r.has_value()) << first.message;
  EXPECT_NEAR(*first.mu_r, 0.15, 1e-9);  // seed effects cancel in each point's mean
  const auto runs_first = read_log(log);
  int total = 0;
  for (const auto& [id, n] : runs_first) {
    EXPECT_EQ(n, 1) << id;
    EXPECT_EQ(id.rfind("calib_mu_r_", 0), 0u) << id;
    total += n;
  }
  EXPECT_EQ(total, first.simulations);
  // Again in the same folder: every simulation is reused, none is run again.
  const auto second = calibrate_in(out);
  EXPECT_EQ(read_log(log), runs_first);
  EXPECT_EQ(*second.mu_r, *first.mu_r);
  EXPECT_EQ(second.simulations, first.simulations);

  // A bad override in an extra run names the campaign and the run.
  const std::vector<Override> bad = {{"rolling.spring.k", "1.0"}};
  try {
    make_run(c, "extra", bad, 1);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("extra"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("rolling.spring.k"), std::string::npos) << e.what();
  }
  // A failing run in a batch is an error naming it.
  CaseFn failing = [](const CaseSpec&, const std::string&) -> nlohmann::json {
    throw std::runtime_error("engine blew up");
  };
  try {
    run_batch(c, {calibration_run(c, 0.2, 1)}, (dir / "out2").string(), failing, quiet());
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("calib_mu_r_0.2/seed_1"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("engine blew up"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace reposetwin::experiments
