// Bad inputs as a user or a script meets them: each case of issue 22's hostile-user list run
// through the built `reposetwin`. Each is refused before anything runs, with a non-zero exit, a
// message naming the file and the key as written (and the value or the limit), and nothing
// written into, or removed from, the output folder. All are refusals, so the file runs in
// seconds.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <initializer_list>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <utility>
#include <vector>

#include "tests/apps/cli_support.hpp"
#include "tests/support/tiny_scene.hpp"

namespace {
namespace fs = std::filesystem;
using reposetwin::test_support::CliResult;
using reposetwin::test_support::fresh_dir;
using reposetwin::test_support::quoted;
using reposetwin::test_support::read_text;
using reposetwin::test_support::run_cli;
using reposetwin::test_support::write_text;

// The tiny scene with `from` replaced by `to` (once; `from` must be in it), written as
// DIR/NAME.toml.
fs::path tiny_scene_with(const fs::path& dir, const std::string& name, const std::string& from,
                         const std::string& to) {
  std::string text = reposetwin::test_support::kTinyScene;
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  const fs::path p = dir / (name + ".toml");
  write_text(p, text);
  return p;
}

// Every file under `dir`, relative, sorted: what a refused command must leave as it was.
std::vector<std::string> listing(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    out.push_back(fs::relative(e.path(), dir).string());
  std::sort(out.begin(), out.end());
  return out;
}

void expect_mentions(const CliResult& r, std::initializer_list<std::string> parts) {
  for (const std::string& p : parts)
    EXPECT_NE(r.out.find(p), std::string::npos) << "no \"" << p << "\" in: " << r.out;
}

// `reposetwin run SCENE --out DIR/run EXTRA`: refused with `code`, the message holding each of
// `parts`, and no run folder made.
CliResult expect_run_refused(const fs::path& scene, const std::string& extra, int code,
                             std::initializer_list<std::string> parts) {
  const fs::path out = scene.parent_path() / "run";
  const CliResult r = run_cli("run " + quoted(scene) + " --out " + quoted(out) + " --no-images " +
                              extra);
  EXPECT_EQ(r.code, code) << r.out;
  expect_mentions(r, parts);
  EXPECT_FALSE(fs::exists(out)) << "a refused run wrote " << out;
  return r;
}

// A scene with one value changed: refused at parse time (exit 2), naming the file and the key.
void expect_scene_refused(const std::string& name, const std::string& from, const std::string& to,
                          std::initializer_list<std::string> parts) {
  const fs::path dir = fresh_dir("bad_" + name);
  const fs::path scene = tiny_scene_with(dir, name, from, to);
  SCOPED_TRACE(name);
  const CliResult r = expect_run_refused(scene, "", 2, parts);
  expect_mentions(r, {name + ".toml"});
}

TEST(BadInput, GravityHugeViaSetIsRefusedAtParseTime) {
  const fs::path dir = fresh_dir("bad_gravity");
  const fs::path scene = tiny_scene_with(dir, "g", "[scene]", "[scene]");
  const CliResult r = expect_run_refused(scene, "--set numerics.gravity_m_s2=1e30", 2,
                                         {"g.toml", "numerics.gravity_m_s2", "1e+30", "100"});
  const CliResult n = expect_run_refused(scene, "--set numerics.gravity_m_s2=nan", 2,
                                         {"g.toml", "numerics.gravity_m_s2", "nan"});
  (void)r, (void)n;
}

TEST(BadInput, SampleSizesMustBePositive) {
  expect_scene_refused("dmin_neg", "[sample]\n", "[sample]\nd_min_mm = -1\n",
                       {"sample.d_min_mm", "-1", "positive"});
  expect_scene_refused("dmin_zero", "[sample]\n", "[sample]\nd_min_mm = 0\n",
                       {"sample.d_min_mm", "= 0", "positive"});
  expect_scene_refused("dmax_neg", "[sample]\n", "[sample]\nd_max_mm = -4\n",
                       {"sample.d_max_mm", "-4", "positive"});
}

TEST(BadInput, MassBelowOneGrainIsRefused) {
  expect_scene_refused("mass", "mass_kg = 0.006", "mass_kg = 1e-9",
                       {"sample.mass_kg", "1e-09", "at least 10"});
}

TEST(BadInput, NegativeThreadsIsARangeError) {
  const fs::path dir = fresh_dir("bad_threads");
  const fs::path scene = tiny_scene_with(dir, "t", "[scene]", "[scene]");
  expect_run_refused(scene, "--threads -1", 105, {"--threads", "-1", "0 to 4096"});
}

TEST(BadInput, LiftSpeedAboveTheLimitIsRefused) {
  expect_scene_refused("lift", "lift_speed_m_s = 0.05", "lift_speed_m_s = 1e6",
                       {"procedure.lift_speed_m_s", "1e+06", "(0, 1]"});
}

TEST(BadInput, MeasureSectorsZeroIsRefusedAtParseTime) {
  expect_scene_refused("sectors", "[numerics]\n", "[measure]\nsectors = 0\n[numerics]\n",
                       {"measure.sectors", "= 0", "at least 4"});
}

TEST(BadInput, NegativeOverlapToleranceIsRefusedAtParseTime) {
  expect_scene_refused("overlap", "[numerics]\n", "[numerics]\ninitial_overlap_tolerance = -1\n",
                       {"numerics.initial_overlap_tolerance", "-1", "negative"});
}

TEST(BadInput, RayleighFractionNamesTheSceneKeyAndTheLimit) {
  const fs::path dir = fresh_dir("bad_rayleigh");
  const fs::path scene =
      tiny_scene_with(dir, "rayleigh", "rayleigh_fraction = 0.3", "rayleigh_fraction = 0.8");
  const CliResult r =
      expect_run_refused(scene, "", 2, {"rayleigh.toml", "numerics.rayleigh_fraction", "0.8", "0.5"});
  EXPECT_EQ(r.out.find("settings."), std::string::npos) << r.out;
}

TEST(BadInput, MisspeltTableIsNamed) {
  const fs::path dir = fresh_dir("bad_sampel");
  const fs::path scene = tiny_scene_with(dir, "sampel", "[sample]\n", "[sampel]\n");
  const CliResult r = expect_run_refused(scene, "", 2, {"sampel.toml", "sampel", "sample"});
  EXPECT_EQ(r.out.find("is required"), std::string::npos)
      << "the misspelt table is the error, not the missing one: " << r.out;
}

TEST(BadInput, DirectoryAsTheSceneIsNamedADirectory) {
  const fs::path dir = fresh_dir("bad_dir");
  fs::create_directories(dir / "scene_dir");
  const CliResult r = expect_run_refused(dir / "scene_dir", "", 2, {"scene_dir", "directory"});
  EXPECT_EQ(r.out.find("is required"), std::string::npos) << r.out;
}

TEST(BadInput, MaxRayleighFractionIsNotASceneKey) {
  expect_scene_refused("maxray", "[numerics]\n", "[numerics]\nmax_rayleigh_fraction = 0.9\n",
                       {"numerics.max_rayleigh_fraction", "not a known key"});
}

TEST(BadInput, ForceWithABadInputLeavesTheOldResult) {
  const fs::path dir = fresh_dir("bad_force");
  const fs::path scene =
      tiny_scene_with(dir, "force", "rayleigh_fraction = 0.3", "rayleigh_fraction = 0.8");
  const fs::path out = dir / "run";
  write_text(out / "result.json", "{\"old\": true}\n");
  const std::vector<std::string> before = listing(out);
  const CliResult r =
      run_cli("run " + quoted(scene) + " --out " + quoted(out) + " --no-images --force");
  EXPECT_EQ(r.code, 2) << r.out;
  expect_mentions(r, {"force.toml", "numerics.rayleigh_fraction"});
  EXPECT_EQ(read_text(out / "result.json"), "{\"old\": true}\n");
  EXPECT_EQ(listing(out), before);
}

// A measured-data CSV saved by a spreadsheet starts with a UTF-8 byte-order mark; its header
// must read as "id", so the file gets as far as its first row (whose scene is missing, which
// stops it before any simulation). Disabled while the measured-data reader splits lines itself:
// it passes once that reader reads through io/csv, which strips the mark (branch s12-io).
TEST(BadInput, CsvWithAByteOrderMarkIsRead) {
  const fs::path dir = fresh_dir("bad_bom");
  write_text(dir / "lab.csv", "\xEF\xBB\xBFid,role,scene,angle_deg\nt1,calibrate,missing.toml,30\n");
  const fs::path out = dir / "loop";
  const CliResult r = run_cli("loop " + quoted(dir / "lab.csv") + " --out " + quoted(out));
  EXPECT_EQ(r.code, 2) << r.out;
  expect_mentions(r, {"lab.csv", "line 2", "missing.toml"});
  EXPECT_EQ(r.out.find("unknown column"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(out)) << r.out;
}

// A declared hypothesis must be one of the candidates the loop fingerprints, with room for its
// refit: refused, naming the option and the value, before any pile is poured.
TEST(BadInput, LoopRefitOfACandidateNotTracedIsRefused) {
  const fs::path dir = fresh_dir("bad_refit");
  const fs::path scene = tiny_scene_with(dir, "refit", "[scene]", "[scene]");
  write_text(dir / "lab.csv", "id,role,scene,angle_deg\nt1,calibrate," + scene.filename().string() +
                                  ",30\nt2,calibrate," + scene.filename().string() + ",31\n");
  const fs::path out = dir / "loop";
  const std::string cmd = "loop " + quoted(dir / "lab.csv") + " --out " + quoted(out);
  CliResult r = run_cli(cmd + " --refit grain_shape");
  EXPECT_EQ(r.code, 2) << r.out;
  expect_mentions(r, {"--refit grain_shape", "opt-in", "--candidates"});
  r = run_cli(cmd + " --candidates plate_friction,cohesion --refit grain_shape");
  EXPECT_EQ(r.code, 2) << r.out;
  expect_mentions(r, {"--refit grain_shape", "--candidates names others"});
  r = run_cli(cmd + " --candidates grain_shape --refit grain_shape --max-effects 0");
  EXPECT_EQ(r.code, 2) << r.out;
  expect_mentions(r, {"--refit grain_shape", "--max-effects 0"});
  r = run_cli(cmd + " --refit rounder_grains");
  EXPECT_EQ(r.code, 2) << r.out;
  expect_mentions(r, {"--refit", "rounder_grains", "grain_shape"});
  EXPECT_FALSE(fs::exists(out / "loop.json"));
  EXPECT_FALSE(fs::exists(out / "cache" / "cases")) << "a refused loop poured a pile";
}

// The hidden settings of a synthetic dataset must not be written where the loop reads the data:
// loop-synth --truth inside --out is refused before any pile is poured.
TEST(BadInput, LoopSynthTruthInsideTheDatasetIsRefused) {
  const fs::path dir = fresh_dir("bad_synth_truth");
  write_text(dir / "design.toml", "scene = \"" + std::string(REPOSETWIN_SOURCE_DIR) +
                                      "/data/loop/tiny_scene.toml\"\nmu_r = 0.2\nseeds = [7001]\n"
                                      "[[test]]\nid = \"t1\"\nmass_kg = 0.025\n");
  const fs::path out = dir / "data";
  const CliResult r = run_cli("loop-synth " + quoted(dir / "design.toml") + " --out " +
                              quoted(out) + " --truth " + quoted(out / "sub" / ".." / "t.json"));
  EXPECT_EQ(r.code, 2) << r.out;
  expect_mentions(r, {"--truth", "t.json", "inside the dataset's folder"});
  EXPECT_FALSE(fs::exists(out / "measured.csv"));
  EXPECT_FALSE(fs::exists(out / "t.json"));
}

TEST(BadInput, ThinImageIsRefusedNamingTheFile) {
  const fs::path dir = fresh_dir("bad_thin");
  ASSERT_TRUE(cv::imwrite((dir / "thin.png").string(), cv::Mat(20000, 1, CV_8UC1, cv::Scalar(255))));
  const std::vector<std::string> before = listing(dir);
  const CliResult r = run_cli("measure " + quoted(dir / "thin.png") + " --mm-per-px 0.1");
  EXPECT_EQ(r.code, 2) << r.out;
  expect_mentions(r, {"thin.png", "1 x 20000", "16 pixels"});
  EXPECT_EQ(listing(dir), before) << "a refused image wrote an overlay";
}

// A sidecar's pixel count of 10^12 does not fit an int: it must be named as too large, not
// wrapped to a negative number.
TEST(BadInput, SidecarWidthTooLargeIsNamed) {
  const fs::path dir = fresh_dir("bad_sidecar");
  ASSERT_TRUE(cv::imwrite((dir / "side.png").string(), cv::Mat(48, 64, CV_8UC1, cv::Scalar(255))));
  const std::string camera =
      R"({"camera": {"projection": "orthographic", "intrinsics": {"width_px": WIDTH,
      "height_px": 48, "ortho_width_m": 0.1}, "extrinsics": {"position": [0, -1, 0.05],
      "look_at": [0, 0, 0.05], "up": [0, 0, 1]}}})";
  for (const std::string width : {"1000000000000", "1e12"}) {
    SCOPED_TRACE(width);
    std::string text = camera;
    text.replace(text.find("WIDTH"), 5, width);
    write_text(dir / "cam.json", text);
    const std::vector<std::string> before = listing(dir);
    const CliResult r = run_cli("measure " + quoted(dir / "side.png") + " --camera " +
                                quoted(dir / "cam.json"));
    EXPECT_EQ(r.code, 2) << r.out;
    expect_mentions(r, {"cam.json", "width_px", "1000000000000"});
    EXPECT_EQ(r.out.find("got -"), std::string::npos) << r.out;
    EXPECT_EQ(listing(dir), before);
  }
}

}  // namespace

// A campaign over shape keys whose case sets a value the shape reader refuses: the campaign
// command reads every case's scene before running any, so nothing runs and no output is made.
TEST(BadInput, ACampaignCaseWithARefusedShapeValueRunsNothing) {
  const fs::path dir = fresh_dir("bad_shape_campaign");
  write_text(dir / "scene.toml", std::string(reposetwin::test_support::kTinyScene) +
                                     reposetwin::test_support::kTinyRods);
  write_text(dir / "shapes.toml",
             "name = \"shapes\"\nscene = \"scene.toml\"\nseeds = [1]\n"
             "[[case]]\nname = \"fine\"\noverrides = { \"sample.shape.elongation\" = 2.0 }\n"
             "[[case]]\nname = \"squat\"\noverrides = { \"sample.shape.elongation\" = 0.5 }\n");
  const fs::path out = dir / "out";
  const CliResult r = run_cli("campaign " + quoted(dir / "shapes.toml") + " --out " +
                              quoted(out) + " --no-images --workers 1");
  EXPECT_EQ(r.code, 2) << r.out;
  expect_mentions(r, {"shapes.toml", "case squat", "sample.shape.elongation", "0.5"});
  EXPECT_FALSE(fs::exists(out)) << "a refused campaign wrote " << out;
}

// A calibration file whose runs would read a refused shape value, in the common overrides (the
// calibration runs) or in a [[predict]] test only: calibrate reads every scene it can run before
// running any, exits 2 naming the file, the run, the key and the value, and makes no output.
TEST(BadInput, ACalibrationWithARefusedShapeValueRunsNothing) {
  const fs::path dir = fresh_dir("bad_shape_calibration");
  write_text(dir / "scene.toml", reposetwin::test_support::kTinyScene);
  const std::string head = "name = \"cal\"\nscene = \"scene.toml\"\n";
  const std::string calibration =
      "[calibration]\ntarget_deg = 25.0\nmu_r_range = [0.1, 0.4]\nseeds_per_point = 1\n";
  const std::string squat =
      "sample.shape = { kind = \"generated\", elongation = 0.5, spheres = 4 }";
  struct Bad {
    std::string text, run;
  };
  const Bad files[] = {
      {head + "overrides = { " + squat + " }\n" + calibration, "calibration"},
      {head + calibration + "[[predict]]\nname = \"rods\"\nscene = \"scene.toml\"\n"
                            "measured_deg = 30.0\noverrides = { " + squat + " }\n",
       "prediction rods"},
  };
  for (const Bad& b : files) {
    write_text(dir / "cal.toml", b.text);
    const fs::path out = dir / "out";
    const CliResult r =
        run_cli("calibrate " + quoted(dir / "cal.toml") + " --out " + quoted(out) + " --workers 1");
    SCOPED_TRACE(b.run);
    EXPECT_EQ(r.code, 2) << r.out;
    expect_mentions(r, {"cal.toml", b.run, "sample.shape.elongation", "0.5"});
    EXPECT_FALSE(fs::exists(out)) << "a refused calibration wrote " << out;
  }
}

namespace {

// A disk that fills up mid-run, made by a file-size limit (`ulimit -f`, a write past it fails
// with EFBIG as one on a full disk fails with ENOSPC; root cannot fill a real disk in a test):
// the run stops with a non-zero exit and a message naming a file it could not write, and leaves
// no truncated final.vtp behind (writes are atomic: the whole file or none).
TEST(BadInput, AFullDiskStopsTheRunNamingTheFile) {
  const fs::path dir = fresh_dir("disk_full");
  const fs::path scene = dir / "tiny.toml";
  write_text(scene, reposetwin::test_support::kTinyScene);
  const fs::path out = dir / "run", log = dir / "log.txt";
  const std::string cmd = "ulimit -f 4; '" + std::string(REPOSETWIN_BIN) + "' run " +
                          quoted(scene) + " --out " + quoted(out) +
                          " --no-images --yes --quiet </dev/null >" + quoted(log) +
                          " 2>&1";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status)) << "killed by a signal: " << read_text(log);
  EXPECT_NE(WEXITSTATUS(status), 0) << read_text(log);
  const std::string text = read_text(log);
  EXPECT_NE(text.find(out.string()), std::string::npos) << text;
  EXPECT_FALSE(fs::exists(out / "final.vtp"));
  for (const auto& e : fs::recursive_directory_iterator(out))
    EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos)
        << "a temporary file was left: " << e.path();
}

}  // namespace
