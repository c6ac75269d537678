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
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <thread>

#include "../../vision/synthetic.hpp"
#include "experiments/io/provenance.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

constexpr const char* kScene = R"(
seed = 1
[rolling]
model = "epsd"
mu_r = 0.1
[sample]
mass = 0.2
[contacts.rock-rock]
rolling_friction = 0.15
)";

// A fresh folder holding scene.toml.
fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() /
                     ("reposetwin_campaign_test_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  write_file_atomic((d / "scene.toml").string(), kScene);
  return d;
}

fs::path write_campaign(const fs::path& dir, const std::string& text,
                        const std::string& file = "campaign.toml") {
  write_file_atomic((dir / file).string(), text);
  return dir / file;
}

std::string load_error(const fs::path& file) {
  try {
    load_campaign(file.string());
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

// A fresh folder removed at the end of the test (forked children _exit and leave it alone).
struct ScratchDir {
  explicit ScratchDir(const std::string& name) : path(fresh_dir(name)) {}
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  fs::path path;
};

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

const char* kCasesCampaign = R"(
name = "cases_demo"
description = "two cases"
paper = "Fig. 8"
scene = "scene.toml"
seeds = [1, 2]
overrides = { "sample.mass" = 0.9 }
[[case]]
name = "low"
overrides = { "rolling.mu_r" = 0.05 }
[[case]]
name = "high"
overrides = { rolling.mu_r = 0.2, "sample.mass" = 1 }
)";

TEST(Campaign, ParsesCasesCrossedWithSeeds) {
  const ScratchDir scratch("parse_cases");
  const fs::path& dir = scratch.path;
  const auto c = load_campaign(write_campaign(dir, kCasesCampaign).string());
  EXPECT_EQ(c.name, "cases_demo");
  EXPECT_EQ(c.paper, "Fig. 8");
  EXPECT_EQ(c.scene_path, fs::absolute(dir / "scene.toml").lexically_normal().string());
  ASSERT_EQ(c.runs.size(), 4u);
  EXPECT_EQ(c.runs[0].id(), "low/seed_1");
  EXPECT_EQ(c.runs[3].id(), "high/seed_2");
  EXPECT_EQ(c.runs[3].index, 3u);
  // Common overrides apply to every case; a case's own override wins; unquoted dotted keys work.
  const auto low = build_case_scene(c.runs[0]);
  EXPECT_DOUBLE_EQ(low.number("rolling.mu_r").value(), 0.05);
  EXPECT_DOUBLE_EQ(low.number("sample.mass").value(), 0.9);
  const auto high = build_case_scene(c.runs[2]);
  EXPECT_DOUBLE_EQ(high.number("rolling.mu_r").value(), 0.2);
  EXPECT_DOUBLE_EQ(high.number("sample.mass").value(), 1.0);
  EXPECT_FALSE(c.calibration.has_value());
}

TEST(Campaign, ParsesSweepAndCalibration) {
  const ScratchDir scratch("parse_sweep");
  const fs::path& dir = scratch.path;
  fs::create_directories(dir / "campaigns");
  const auto file = write_campaign(dir / "campaigns", R"(
name = "mu_sweep"
scene = "../scene.toml"
seeds = 3
[sweep]
key = "rolling.mu_r"
values = [0.05, 0.1, 0.15]
[calibration]
target_deg = 33.47
target_sd_deg = 0.3
mu_r_range = [0.02, 0.4]
seeds_per_point = 2
max_simulations = 20
angle = "image_flank"
)");
  const auto c = load_campaign(file.string());
  ASSERT_EQ(c.runs.size(), 9u);
  EXPECT_EQ(c.runs[0].case_name, "mu_r_0.05");
  EXPECT_EQ(c.runs[8].id(), "mu_r_0.15/seed_3");
  EXPECT_DOUBLE_EQ(build_case_scene(c.runs[4]).number("rolling.mu_r").value(), 0.1);
  ASSERT_TRUE(c.calibration.has_value());
  EXPECT_EQ(c.calibration->key, "contacts.rock-rock.rolling_friction");  // the scene format's
  EXPECT_DOUBLE_EQ(c.calibration->target.angle_deg, 33.47);
  EXPECT_DOUBLE_EQ(c.calibration->target.sd_deg, 0.3);
  EXPECT_DOUBLE_EQ(c.calibration->settings.mu_r_lo, 0.02);
  EXPECT_DOUBLE_EQ(c.calibration->settings.mu_r_hi, 0.4);
  EXPECT_EQ(c.calibration->settings.seeds_per_point, 2);
  EXPECT_EQ(c.calibration->settings.max_simulations, 20);
  EXPECT_EQ(c.calibration->angle, AngleMeasure::kImageFlank);
}

// The lab's photos as the calibration target, measured as the renders are: atan(2H/D) for the
// image angle, the flank angle for image_flank. Two cones drawn from their geometry (60 mm high,
// 200 mm wide: flanks atan(0.6) = 30.96 deg), one with its apex rounded by a 30 mm arc tangent to
// the flanks (its top 60 - 30 (1/cos 30.96 - 1) = 55.0 mm high: atan(2H/D) 28.81 deg, flanks
// unchanged); the truth is the geometry, not the code.
TEST(Campaign, CalibrationTargetFromLabPhotos) {
  const ScratchDir scratch("target_photos");
  const fs::path& dir = scratch.path;
  fs::create_directories(dir / "lab");
  vision::synthetic::SideScene cone;
  cone.look.noise_sigma = 2.0;
  cv::imwrite((dir / "lab" / "sharp.png").string(), vision::synthetic::draw_side(cone));
  cone.apex_radius_mm = 30.0;
  cv::imwrite((dir / "lab" / "rounded.png").string(), vision::synthetic::draw_side(cone));
  const double flank = std::atan(0.6) * 180.0 / M_PI;
  const double rounded_h = 60.0 - 30.0 * (1.0 / std::cos(std::atan(0.6)) - 1.0);
  const double theta = 0.5 * (flank + std::atan(2.0 * rounded_h / 200.0) * 180.0 / M_PI);
  auto campaign = [&](const std::string& calibration_keys) {
    return write_campaign(dir, "name = \"photo_target\"\nscene = \"scene.toml\"\nseeds = 1\n"
                               "[calibration]\nmu_r_range = [0.05, 0.5]\n" +
                                   calibration_keys);
  };
  const std::string photos =
      "target_photos = [\"lab/sharp.png\", \"lab/rounded.png\"]\ntarget_mm_per_px = 0.25\n";

  Campaign c = load_campaign(campaign(photos).string());
  ASSERT_TRUE(c.calibration.has_value());
  EXPECT_NEAR(c.calibration->target.angle_deg, theta, 0.3);
  EXPECT_GT(c.calibration->target.sd_deg, 0.5);  // the two photos differ by 2.2 deg
  EXPECT_LT(c.calibration->target.sd_deg, 2.0);
  EXPECT_EQ(c.calibration->target_photos["views"].size(), 2u);
  EXPECT_EQ(c.calibration->target_photos["photos"][0], (dir / "lab" / "sharp.png").string());

  c = load_campaign(campaign(photos + "angle = \"image_flank\"\ntarget_sd_deg = 0.4\n").string());
  EXPECT_NEAR(c.calibration->target.angle_deg, flank, 0.3);
  EXPECT_DOUBLE_EQ(c.calibration->target.sd_deg, 0.4);  // given: it replaces the measurement's

  // Bad input names the key and the value.
  std::string e = load_error(campaign(photos + "target_deg = 30.0\n"));
  EXPECT_NE(e.find("calibration.target_photos"), std::string::npos) << e;
  EXPECT_NE(e.find("either target_deg or target_photos"), std::string::npos) << e;
  e = load_error(campaign("target_photos = \"lab/missing.png\"\ntarget_mm_per_px = 0.25\n"));
  EXPECT_NE(e.find("calibration.target_photos"), std::string::npos) << e;
  EXPECT_NE(e.find("missing.png"), std::string::npos) << e;
  e = load_error(campaign("target_photos = \"lab/sharp.png\"\ntarget_mm_per_px = -1\n"));
  EXPECT_NE(e.find("calibration.target_mm_per_px"), std::string::npos) << e;
  e = load_error(campaign("target_deg = 30.0\ntarget_mm_per_px = 0.25\n"));
  EXPECT_NE(e.find("only with target_photos"), std::string::npos) << e;
  e = load_error(campaign("target_photos = []\n"));
  EXPECT_NE(e.find("needs at least one photo"), std::string::npos) << e;
  // A photo with no scale source (no marker drawn, none declared) says how to give one.
  cone.scale_bar = false;
  cv::imwrite((dir / "lab" / "no_scale.png").string(), vision::synthetic::draw_side(cone));
  e = load_error(campaign("target_photos = \"lab/no_scale.png\"\n"));
  EXPECT_NE(e.find("calibration.target_photos"), std::string::npos) << e;
  EXPECT_NE(e.find("target_mm_per_px"), std::string::npos) << e;
}

TEST(Campaign, MissingSceneIsAClearError) {
  const ScratchDir scratch("missing_scene");
  const fs::path& dir = scratch.path;
  const auto e = load_error(write_campaign(dir, R"(
name = "x"
scene = "no_such_scene.toml"
seeds = [1]
[[case]]
name = "a"
)"));
  EXPECT_NE(e.find("campaign.toml"), std::string::npos) << e;
  EXPECT_NE(e.find("'scene'"), std::string::npos) << e;
  EXPECT_NE(e.find("no_such_scene.toml"), std::string::npos) << e;
  const auto e2 = load_error(write_campaign(dir, R"(
name = "x"
scene = "scene.toml"
seeds = [1]
[[case]]
name = "a"
scene = "other.toml"
)"));
  EXPECT_NE(e2.find("case[0].scene"), std::string::npos) << e2;
  EXPECT_NE(e2.find("other.toml"), std::string::npos) << e2;
  EXPECT_NE(load_error(dir / "nothing.toml").find("nothing.toml"), std::string::npos);
}

TEST(Campaign, BadKeysAndValuesAreRejected) {
  const ScratchDir scratch("bad_keys");
  const fs::path& dir = scratch.path;
  const std::string head = "name = \"x\"\nscene = \"scene.toml\"\nseeds = [1, 2]\n";
  struct Bad {
    std::string text, must_contain;
  };
  const std::vector<Bad> cases = {
      {head + "colour = 3\n[[case]]\nname = \"a\"\n", "colour"},
      {head + "[[case]]\nname = \"a\"\nmu = 0.1\n", "case[0].mu"},
      {head + "[[case]]\nname = \"a/b\"\n", "a/b"},
      {head + "[[case]]\nname = \"a\"\n[[case]]\nname = \"a\"\n", "not unique"},
      {head + "[[case]]\nname = \"a\"\noverrides = { \"rolling.spring.k\" = 1.0 }\n",
       "rolling.spring.k"},
      {head + "[[case]]\nname = \"a\"\noverrides = { \"rolling.mu_r\" = \"0.1\" }\n",
       "rolling.mu_r"},
      {head + "[[case]]\nname = \"a\"\n[sweep]\nkey = \"rolling.mu_r\"\nvalues = [0.1]\n",
       "not both"},
      {head + "[sweep]\nkey = \"rolling.mu_r\"\nvalues = [0.1, 0.10]\n", "not unique"},
      {head + "[sweep]\nkey = \"rolling.mu_r\"\nvalues = []\n", "sweep.values"},
      {head + "[sweep]\nkey = \"rolling.mu_r\"\nvalues = [0.1]\nstep = 2\n", "sweep.step"},
      {"name = \"x\"\nscene = \"scene.toml\"\n[[case]]\nname = \"a\"\n", "seeds"},
      {"name = \"x\"\nscene = \"scene.toml\"\nseeds = [1, 1]\n[[case]]\nname = \"a\"\n",
       "repeated"},
      {"name = \"x y\"\nscene = \"scene.toml\"\nseeds = [1]\n[[case]]\nname = \"a\"\n", "x y"},
      {"scene = \"scene.toml\"\nseeds = [1]\n[[case]]\nname = \"a\"\n", "'name'"},
      {head, "no [[case]]"},
      {head + "[calibration]\ntarget_deg = 95\nmu_r_range = [0.0, 0.3]\n", "95"},
      {head + "[calibration]\ntarget_deg = 30\nmu_r_range = [0.3, 0.1]\n", "mu_r_range"},
      {head + "[calibration]\ntarget_deg = 30\nmu_r_range = [0.0, 0.3]\nkey = \"nope.mu\"\n",
       "nope.mu"},
      {head + "[calibration]\ntarget_deg = 30\nmu_r_range = [0.0, 0.3]\nspeed = 1\n",
       "calibration.speed"},
      {head + "[calibration]\ntarget_deg = 30\nmu_r_range = [0.0, 0.3]\nangle = \"flank\"\n",
       "calibration.angle' = \"flank\""},
      {head + "[[case]\nname = \"a\"\n", "campaign.toml:"},
  };
  for (const auto& b : cases) {
    const auto e = load_error(write_campaign(dir, b.text));
    EXPECT_NE(e.find(b.must_contain), std::string::npos) << "text:\n" << b.text << "\nerror: " << e;
    EXPECT_NE(e.find("campaign.toml"), std::string::npos) << e;
  }
}

TEST(Campaign, SafeNames) {
  EXPECT_TRUE(is_safe_name("mu_r_0.15"));
  EXPECT_TRUE(is_safe_name("W-40mm"));
  for (const char* n : {"", ".", "..", ".hidden", "a/b", "a b", "a\\b", "-x"})
    EXPECT_FALSE(is_safe_name(n)) << n;
  EXPECT_FALSE(is_safe_name(std::string(101, 'a')));
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
  for (int i = 0; i < 1000 && count_results() < 2; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  std::this_thread::sleep_for(std::chrono::milliseconds(40));  // the next runs are mid-way
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
  EXPECT_EQ(s2.failed, 0);
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
