// Issue 41's hostile-user cases as one table, run through the built `reposetwin`: each row is a
// command on the tiny scene (or an image and its sidecar), the exit code it must end with, the
// words its message must hold (the key as the user wrote it, the value) and the words it must not
// (a key it once blamed wrongly). Every row is refused before anything runs, so nothing is
// simulated and the table takes seconds. The cases a table cannot hold (a FIFO, a corrupted
// checkpoint, a rerun into a folder) follow it as tests of their own.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "tests/apps/cli_support.hpp"
#include "tests/support/tiny_scene.hpp"

namespace {
namespace fs = std::filesystem;
using reposetwin::test_support::CliResult;
using reposetwin::test_support::fresh_dir;
using reposetwin::test_support::quoted;
using reposetwin::test_support::run_cli;
using reposetwin::test_support::write_text;

struct Case {
  std::string item;              // the issue's item and case, for the failure message
  std::string scene_from, scene_to;  // a replacement in the tiny scene ("" : none)
  std::string args;              // after `run SCENE --out OUT --no-images`
  int code;                      // the exit code
  std::vector<std::string> must;      // in the message
  std::vector<std::string> must_not;  // not in it
};

// `reposetwin run` cases: the tiny scene, edited or given --set values.
const std::vector<Case> kRunCases = {
    // 1. Unbounded plans.
    {"1 E=1e200 by --set", "", "", "--set numerics.softened_youngs_modulus_pa=1e200", 2,
     {"numerics.softened_youngs_modulus_pa", "1e+200", "--set"}, {"steps"}},
    {"1 E=1e300 in the scene", "softened_youngs_modulus_pa = 5e6",
     "softened_youngs_modulus_pa = 1e300", "", 2,
     {"numerics.softened_youngs_modulus_pa", "1e+300"}, {}},
    {"1 E=inf", "", "", "--set numerics.softened_youngs_modulus_pa=inf", 2,
     {"numerics.softened_youngs_modulus_pa", "inf", "finite"}, {"finalised"}},
    // 2. Non-finite and out-of-range values.
    {"2 E=nan", "", "", "--set numerics.softened_youngs_modulus_pa=nan", 2,
     {"numerics.softened_youngs_modulus_pa", "nan"}, {}},
    {"2 time_step nan", "", "", "--set numerics.time_step_s=nan", 2,
     {"numerics.time_step_s", "nan"}, {}},
    {"2 fill_settle_max -1", "", "", "--set procedure.fill_settle_max_s=-1.0", 2,
     {"procedure.fill_settle_max_s", "-1"}, {}},
    {"2 settle_speed inf", "", "", "--set procedure.settle_speed_m_s=inf", 2,
     {"procedure.settle_speed_m_s", "inf"}, {}},
    {"2 final_settle_max inf", "", "", "--set procedure.final_settle_max_s=inf", 2,
     {"procedure.final_settle_max_s", "inf"}, {}},
    {"2 frame_interval nan", "", "", "--set output.frame_interval_s=nan", 2,
     {"output.frame_interval_s", "nan"}, {}},
    {"2 progress_interval -1", "", "", "--set output.progress_interval_s=-1.0", 2,
     {"output.progress_interval_s", "-1"}, {}},
    {"2 progress_interval nan", "", "", "--set output.progress_interval_s=nan", 2,
     {"output.progress_interval_s", "nan"}, {}},
    {"2 checkpoint_interval inf", "", "", "--set output.checkpoint_interval_s=inf", 2,
     {"output.checkpoint_interval_s", "inf"}, {}},
    {"2 youngs_modulus inf", "", "", "--set materials.rock.youngs_modulus_pa=inf", 2,
     {"materials.rock.youngs_modulus_pa", "inf"}, {}},
    {"2 friction inf", "", "", "--set contacts.rock-rock.friction=inf", 2,
     {"contacts.rock-rock.friction", "inf"}, {}},
    {"2 NUL in scene.name", "name = \"tiny\"", "name = \"ti\\u0000ny\"", "", 2,
     {"scene.name", "control character"}, {}},
    {"2 frame_interval 1e-9", "", "", "--set output.frame_interval_s=1e-9", 2,
     {"output.frame_interval_s", "1e-09", "frames"}, {}},
    // 5 is a test of its own (an unused material changes nothing; nothing is refused).
    // 8. Messages that blamed the wrong key.
    {"8 density inf", "", "", "--set materials.rock.density_kg_m3=inf", 2,
     {"materials.rock.density_kg_m3", "inf"}, {"mass_kg"}},
    {"8 density 1e300", "", "", "--set materials.rock.density_kg_m3=1e300", 2,
     {"materials.rock.density_kg_m3", "1e+300"}, {"mass_kg"}},
    {"8 density 1e-300", "", "", "--set materials.rock.density_kg_m3=1e-300", 2,
     {"materials.rock.density_kg_m3", "1e-300"}, {"mass_kg"}},
    {"8 container height inf", "", "", "--set container.height_m=inf", 2,
     {"container.height_m", "inf"}, {"escape_distance"}},
    {"8 top diameter inf", "", "", "--set container.top_diameter_m=inf", 2,
     {"container.top_diameter_m", "inf"}, {"runaway"}},
    {"8 lattice gap 1e6", "", "", "--set procedure.lattice_gap=1e6", 2,
     {"procedure.lattice_gap", "1e+06"}, {"runaway"}},
    {"8 time step above the stability limit", "", "", "--set numerics.time_step_s=0.01", 2,
     {"numerics.time_step_s", "0.01", "stability"}, {"settings."}},
    {"8 two --set of one key", "", "",
     "--set contacts.rock-rock.friction=0.4 --set contacts.rock-rock.friction=-1.0", 2,
     {"contacts.rock-rock.friction", "--set contacts.rock-rock.friction=-1.0"},
     {"friction=0.4)"}},
    {"8 flank band values", "", "", "--set measure.flank_low=0.9 --set measure.flank_high=0.1", 2,
     {"measure.flank_low", "0.9", "flank_high", "0.1"}, {}},
    // Second pass (scene fuzz, hostile pass 2026-12-06): the key as the user writes it.
    // A table listed coarsest first is read in reverse (psd_file.hpp); one in neither order is
    // refused.
    {"P2 sieve table out of order", "", "", "--set sample.psd.sieve_mm=[2.0,4.0,3.0]", 2,
     {"sample.psd.sieve_mm", "--set sample.psd.sieve_mm=[2.0,4.0,3.0]", "not larger"},
     {"[sample.psd]."}},
    {"P2 passing above 100", "", "", "--set sample.psd.passing_percent=[0.0,150.0,100.0]", 2,
     {"sample.psd.passing_percent", "150"}, {"[sample.psd]."}},
    {"P2 psd d_max 0", "", "", "--set sample.psd.d_max_mm=0.0", 2,
     {"sample.psd.d_max_mm", "0.0", "--set"}, {"[sample.psd]."}},
    {"P2 empty psd_file", "", "", "--set sample.psd_file=", 2,
     {"sample.psd_file", "empty"}, {"filesystem", "absolute"}},
    {"P2 psd_file name too long", "", "", "--set sample.psd_file=" + std::string(5000, 'x'), 2,
     {"sample.psd_file", "does not exist"}, {"filesystem error"}},
    {"P2 size exponent without a reference diameter", "", "",
     "--set contacts.rock-rock.rolling_size_exponent=-1.0", 2,
     {"contacts.rock-rock.rolling_size_exponent", "-1", "rolling_reference_diameter_m"}, {}},
    {"P2 --resume with --force", "", "", "--resume --force", 108, {"--resume", "--force"}, {}},
    // 9 (output folders) follows the table.
};

// The tiny scene with `from` replaced by `to`, as DIR/NAME.toml.
fs::path scene_file(const fs::path& dir, const Case& c) {
  std::string text = reposetwin::test_support::kTinyScene;
  if (!c.scene_from.empty()) {
    const std::size_t at = text.find(c.scene_from);
    EXPECT_NE(at, std::string::npos) << c.scene_from;
    if (at != std::string::npos) text.replace(at, c.scene_from.size(), c.scene_to);
  }
  const fs::path p = dir / "scene.toml";
  write_text(p, text);
  return p;
}

void expect_message(const CliResult& r, const std::vector<std::string>& must,
                    const std::vector<std::string>& must_not) {
  for (const std::string& m : must)
    EXPECT_NE(r.out.find(m), std::string::npos) << "no \"" << m << "\" in: " << r.out;
  for (const std::string& m : must_not)
    EXPECT_EQ(r.out.find(m), std::string::npos) << "\"" << m << "\" in: " << r.out;
}

TEST(BadInputTable, EveryRunCaseIsRefusedNamingItsKey) {
  const fs::path dir = fresh_dir("table_run");
  for (const Case& c : kRunCases) {
    SCOPED_TRACE(c.item);
    const fs::path scene = scene_file(dir, c);
    const fs::path out = dir / "run";
    const CliResult r =
        run_cli("run " + quoted(scene) + " --out " + quoted(out) + " --no-images " + c.args);
    EXPECT_EQ(r.code, c.code) << r.out;
    expect_message(r, c.must, c.must_not);
    EXPECT_FALSE(fs::exists(out)) << "a refused run wrote " << out;
  }
}

// `reposetwin measure` on a side image with a sidecar of its camera: the sidecar is complete or
// refused, missing fields named.
struct SidecarCase {
  std::string item;
  std::string from, to;  // a replacement in the complete sidecar
  std::string args;      // extra arguments (after the image and --camera)
  std::vector<std::string> must;
};

const std::string kSidecar = R"({"view": "side",
 "camera": {"projection": "perspective",
  "intrinsics": {"width_px": 64, "height_px": 48, "focal_length_mm": 50.0,
                 "sensor_width_mm": 36.0, "k1": 0.0},
  "extrinsics": {"position": [0, -1, 0.05], "look_at": [0, 0, 0.05], "up": [0, 0, 1]}}})";

const std::vector<SidecarCase> kSidecarCases = {
    {"6 no focal_length_mm", "\"focal_length_mm\": 50.0,", "", "",
     {"cam.json", "intrinsics.focal_length_mm", "missing"}},
    {"6 no intrinsics",
     R"("intrinsics": {"width_px": 64, "height_px": 48, "focal_length_mm": 50.0,
                 "sensor_width_mm": 36.0, "k1": 0.0},)",
     "", "", {"cam.json", "intrinsics", "missing"}},
    {"6 k1 1e6", "\"k1\": 0.0", "\"k1\": 1e6", "", {"cam.json", "k1", "1e+06"}},
    {"6 unknown field", "{\"view\"", "{\"lens_notes\": 1, \"view\"", "",
     {"cam.json", "lens_notes", "not a sidecar field"}},
    {"6 view top on a side image", "\"view\": \"side\"", "\"view\": \"top\"", "",
     {"cam.json", "view", "top", "side image"}},
    {"6 two side images, one --camera", "", "", "--side SIDE2",
     {"--camera", "1 sidecar", "2 side images"}},
    {"8 flank band values", "", "", "--flank-band 0.9,0.1", {"--flank-band", "0.9", "0.1"}},
};

TEST(BadInputTable, EverySidecarCaseIsRefusedNamingItsField) {
  const fs::path dir = fresh_dir("table_sidecar");
  const fs::path image = dir / "side.png", image2 = dir / "side2.png";
  ASSERT_TRUE(cv::imwrite(image.string(), cv::Mat(48, 64, CV_8UC1, cv::Scalar(255))));
  ASSERT_TRUE(cv::imwrite(image2.string(), cv::Mat(48, 64, CV_8UC1, cv::Scalar(255))));
  for (const SidecarCase& c : kSidecarCases) {
    SCOPED_TRACE(c.item);
    std::string text = kSidecar;
    if (!c.from.empty()) {
      const std::size_t at = text.find(c.from);
      ASSERT_NE(at, std::string::npos) << c.from;
      text.replace(at, c.from.size(), c.to);
    }
    write_text(dir / "cam.json", text);
    std::string args = c.args;
    if (const std::size_t at = args.find("SIDE2"); at != std::string::npos)
      args.replace(at, 5, quoted(image2));
    const CliResult r = run_cli("measure " + quoted(image) + " --no-overlay --camera " +
                                quoted(dir / "cam.json") + " " + args);
    EXPECT_EQ(r.code, 2) << r.out;
    expect_message(r, c.must, {});
  }
}

// 7, second pass (loop CSV fuzz): a sheet's row refused naming the line and the column that is
// wrong, in words a person reads.
struct SheetCase {
  std::string item;
  std::string from, to;  // a replacement in the sheet
  std::vector<std::string> must, must_not;
};

const std::string kSheet =
    "id,role,scene,mass_kg,H_mm,D_mm,angle_deg\n"
    "a,calibrate,scene.toml,0.006,8.1,31.0,\n"
    "b,validate,scene.toml,0.006,,,30.9\n";

const std::vector<SheetCase> kSheetCases = {
    {"P2 a folder as the scene", "a,calibrate,scene.toml", "a,calibrate,adir",
     {"line 2", "column scene", "adir", "not a scene file"}, {"column mass_kg"}},
    {"P2 H and D giving 90 deg", "8.1,31.0", "1e300,31.0",
     {"line 2", "H_mm", "D_mm", "1e300", "outside (0, 90)"}, {"column angle_deg"}},
    {"P2 D without H", "8.1,31.0", ",31.0",
     {"line 2", "column H_mm", "D_mm = 31.0", "needs both"}, {}},
    {"P2 an unclosed quote", "b,validate", "b,\"validate", {"sheet.csv:3", "never closed"},
     {"strict checking"}},
    {"P2 a quote inside a field", "b,validate", "b,vali\"date",
     {"sheet.csv:3", "a quote where CSV allows none"}, {"strict checking"}},
};

TEST(BadInputTable, EverySheetCaseIsRefusedNamingItsLineAndColumn) {
  const fs::path dir = fresh_dir("table_sheet");
  write_text(dir / "scene.toml", reposetwin::test_support::kTinyScene);
  fs::create_directories(dir / "adir");
  for (const SheetCase& c : kSheetCases) {
    SCOPED_TRACE(c.item);
    std::string text = kSheet;
    const std::size_t at = text.find(c.from);
    ASSERT_NE(at, std::string::npos) << c.from;
    text.replace(at, c.from.size(), c.to);
    write_text(dir / "sheet.csv", text);
    const CliResult r =
        run_cli("loop " + quoted(dir / "sheet.csv") + " --out " + quoted(dir / "loop"));
    EXPECT_EQ(r.code, 2) << r.out;
    expect_message(r, c.must, c.must_not);
    EXPECT_FALSE(fs::exists(dir / "loop" / "loop.json"));
  }
}

// Second pass (hostile pass 2026-12-06): other commands' options and outputs, refused before
// anything runs. In `args`, SCENE is the tiny scene, CAMP a campaign of it, SHEET a loop sheet
// of it, FIFO a named pipe, AFILE a plain file and DIR the test's folder.
struct CommandCase {
  std::string item;
  std::string args;
  int code;
  std::vector<std::string> must, must_not;
};

const std::vector<CommandCase> kCommandCases = {
    {"P2 campaign --workers 0", "campaign CAMP --out DIR/c --workers 0", 105, {"--workers", "0"},
     {}},
    {"P2 campaign --views 0", "campaign CAMP --out DIR/c --views 0", 105, {"--views", "0"}, {}},
    {"P2 campaign --out at a file", "campaign CAMP --out AFILE", 2,
     {"a_file", "names a file"}, {"filesystem error"}},
    {"P2 loop --out at a file", "loop SHEET --out AFILE", 2, {"a_file", "names a file"},
     {"filesystem error"}},
    {"P2 loop sheet a FIFO", "loop FIFO --out DIR/l", 2, {"fifo.csv", "not a regular file"}, {}},
    {"P2 loop --mu-grid nan", "loop SHEET --out DIR/l --mu-grid 0.1,nan", 2,
     {"--mu-grid", "nan", "is not a number"}, {"grid_extensions"}},
    {"P2 loop --mu-grid negative", "loop SHEET --out DIR/l --mu-grid -0.1,0.2", 2,
     {"--mu-grid -0.1,0.2", "increasing"}, {}},
    {"P2 loop --candidates unknown", "loop SHEET --out DIR/l --candidates warp_drive", 2,
     {"--candidates", "warp_drive"}, {}},
    {"P2 loop --width 0", "loop SHEET --out DIR/l --width 0", 105, {"--width"}, {}},
    {"P2 loop --min-t nan", "loop SHEET --out DIR/l --min-t nan", 105, {"--min-t", "nan"}, {}},
    {"P2 export --seed -1", "export SCENE --out DIR/e --seed -1", 105, {"--seed"}, {}},
    {"P2 a folder as the campaign", "campaign DIR --out DIR/c", 2,
     {"is a directory, not a file"}, {"not found"}},
    // Inputs that would bias a result (issue 52, part 4): each class refused by its one check
    // (io/numbers.hpp, io/files.hpp's refuse_repeated_contents, pile/headline.hpp's rule).
    {"B loop --seeds repeated", "loop SHEET --out DIR/l --seeds 1,2,1", 2,
     {"--seeds 1,2,1", "seed 1 is given twice"}, {}},
    {"B loop --seeds not an integer", "loop SHEET --out DIR/l --seeds 1,2.0", 2,
     {"--seeds 1,2.0", "\"2.0\" is not a seed"}, {}},
    {"B loop --seeds out of range", "loop SHEET --out DIR/l --seeds 9223372036854775808", 2,
     {"--seeds", "\"9223372036854775808\" is not a seed"}, {}},
    {"B loop --mu-grid hex", "loop SHEET --out DIR/l --mu-grid 0.1,0x1", 2,
     {"--mu-grid 0.1,0x1", "\"0x1\"", "a plain decimal is expected"}, {}},
    {"B timestep --seeds repeated", "timestep SCENE --out DIR/t --seeds 3,3", 2,
     {"--seeds 3,3", "seed 3 is given twice"}, {}},
    {"B timestep --tolerance nan", "timestep SCENE --out DIR/t --tolerance nan", 105,
     {"--tolerance", "nan"}, {}},
    {"B timestep --fractions 0", "timestep SCENE --out DIR/t --fractions 0.1,0", 2,
     {"--fractions = 0", "finite number > 0"}, {}},
    {"B measure --mm-per-px hex", "measure AFILE --mm-per-px 0x10", 105,
     {"--mm-per-px", "0x10", "a plain decimal is expected"}, {}},
    {"B measure one photo twice", "measure AFILE --side COPY --mm-per-px 0.1", 2,
     {"is the same image as", "copy_of_a_file"}, {}},
    {"B report --lab-mm-per-px nan", "report DIR --lab-mm-per-px nan", 105,
     {"--lab-mm-per-px", "nan"}, {}},
    {"B measure-particles one grain", "measure-particles DUMP1 --scene SCENE", 7,
     {"no angle", "formed no measurable pile"}, {"particle atan(2H/D)"}},
    {"B measure-particles inf in a dump", "measure-particles DUMPINF --scene SCENE", 2,
     {"\"inf\"", "not finite or not a plain decimal"}, {}},
    // Every command that simulates prints its plan and refuses it above the limits without
    // --yes (issue 52, part 5): the tiny scene's piles against a limit of one particle.
    {"P5 campaign plan above the limit", "campaign CAMP --out DIR/pc --max-particles 1", 6,
     {"runs of case a", "refused", "--yes"}, {}},
    {"P5 timestep plan above the limit", "timestep SCENE --out DIR/pt --max-particles 1", 6,
     {"runs of case dt_fraction", "refused", "--yes"}, {}},
    {"P5 loop plan above the limit", "loop SHEET --out DIR/pl --max-particles 1", 6,
     {"baseline piles of test", "refused", "--yes"}, {}},
};

TEST(BadInputTable, EveryCommandCaseIsRefusedNamingItsOption) {
  const fs::path dir = fresh_dir("table_command");
  write_text(dir / "scene.toml", reposetwin::test_support::kTinyScene);
  write_text(dir / "camp.toml",
             "name = \"t\"\nscene = \"scene.toml\"\nseeds = [1]\n[[case]]\nname = \"a\"\n"
             "overrides = { \"contacts.rock-rock.rolling_friction\" = 0.1 }\n");
  write_text(dir / "sheet.csv", kSheet);
  write_text(dir / "a_file", "x");
  write_text(dir / "copy_of_a_file", "x");
  const std::string dump_head =
      "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS pp pp pp\n-1 1\n-1 1\n"
      "0 1\nITEM: ATOMS x y z radius\n";
  write_text(dir / "one_grain.dump", dump_head + "0 0 0.002 0.002\n");
  write_text(dir / "inf.dump", dump_head + "0 inf 0.002 0.002\n");
  ASSERT_EQ(::mkfifo((dir / "fifo.csv").c_str(), 0644), 0);
  // Longer names first: a name that is the start of another is replaced after it.
  const std::vector<std::pair<std::string, fs::path>> names = {
      {"SCENE", dir / "scene.toml"},    {"CAMP", dir / "camp.toml"},
      {"SHEET", dir / "sheet.csv"},     {"FIFO", dir / "fifo.csv"},
      {"AFILE", dir / "a_file"},        {"COPY", dir / "copy_of_a_file"},
      {"DUMPINF", dir / "inf.dump"},    {"DUMP1", dir / "one_grain.dump"},
      {"DIR", dir}};
  for (const CommandCase& c : kCommandCases) {
    SCOPED_TRACE(c.item);
    std::string args = c.args;
    for (const auto& [name, path] : names)
      for (std::size_t at; (at = args.find(name)) != std::string::npos;)
        args.replace(at, name.size(), quoted(path));
    const CliResult r = run_cli(args);
    EXPECT_EQ(r.code, c.code) << r.out;
    expect_message(r, c.must, c.must_not);
  }
  // The paper's whole index (about 15 CPU-hours) on two workers is above the hour a plan may
  // take unconfirmed.
  const CliResult paper =
      run_cli("paper " +
              quoted(fs::path(REPOSETWIN_SOURCE_DIR) / "experiments" / "paper" / "index.toml") +
              " --out " + quoted(dir / "pp"));
  EXPECT_EQ(paper.code, 6) << paper.out;
  expect_message(paper, {"plan: ", "CPU-hours", "refused", "--max-hours", "--yes"}, {});
  // A refused plan writes nothing.
  for (const char* out : {"pc", "pt", "pl", "pp"}) EXPECT_FALSE(fs::exists(dir / out)) << out;
}

// A study whose run gives no angle did not get what it asked for: timestep exits 4, as a
// campaign does (it exited 0 before). One tiny pile that cannot settle in 0.02 s.
TEST(BadInputTable, ATimestepStudyWithAFailedRunExitsNonZero) {
  const fs::path dir = fresh_dir("table_timestep_failed");
  std::string scene = reposetwin::test_support::kTinyScene;
  const std::string at = "settle_speed_m_s = 0.01\n";
  scene.replace(scene.find(at), at.size(), at + "final_settle_max_s = 0.02\n");
  write_text(dir / "scene.toml", scene);
  const CliResult r = run_cli("timestep " + quoted(dir / "scene.toml") + " --out " +
                              quoted(dir / "t") + " --fractions 0.3 --workers 1");
  EXPECT_EQ(r.code, 4) << r.out;
  expect_message(r, {"1 of 1 runs failed or gave no angle"}, {});
}

// 6, second pass (sidecar fuzz): a principal point off the image, and JSON errors in words.
TEST(BadInputTable, ASidecarPrincipalPointOffTheImageIsRefused) {
  const fs::path dir = fresh_dir("table_sidecar_p2");
  const fs::path image = dir / "side.png";
  ASSERT_TRUE(cv::imwrite(image.string(), cv::Mat(48, 64, CV_8UC1, cv::Scalar(255))));
  std::string text = kSidecar;
  const std::string k1 = "\"k1\": 0.0";
  text.replace(text.find(k1), k1.size(), k1 + ", \"cx_px\": 1e300");
  write_text(dir / "cam.json", text);
  CliResult r = run_cli("measure " + quoted(image) + " --no-overlay --camera " +
                        quoted(dir / "cam.json"));
  EXPECT_EQ(r.code, 2) << r.out;
  expect_message(r, {"cam.json", "intrinsics.cx_px", "1e+300", "within one image size"}, {});
  write_text(dir / "cam.json", "{\"camera\": ");
  r = run_cli("measure " + quoted(image) + " --no-overlay --camera " + quoted(dir / "cam.json"));
  EXPECT_EQ(r.code, 2) << r.out;
  expect_message(r, {"cam.json", "not valid JSON"}, {"json.exception"});
}

// 1. Files that never end or never open: refused by kind, at once, naming the file.
TEST(BadInputTable, AFifoOrADeviceAsTheSceneIsRefusedAtOnce) {
  const fs::path dir = fresh_dir("table_fifo");
  const fs::path fifo = dir / "scene.toml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  for (const std::string& scene : {fifo.string(), std::string("/dev/zero")}) {
    SCOPED_TRACE(scene);
    const CliResult r = run_cli("run " + quoted(fs::path(scene)) + " --out " +
                                quoted(dir / "run") + " --no-images");
    EXPECT_EQ(r.code, 2) << r.out;
    expect_message(r, {scene, "not a regular file"}, {"bad_alloc"});
    EXPECT_FALSE(fs::exists(dir / "run"));
  }
}

// 1. Render views are bounded before anything is rendered.
TEST(BadInputTable, TooManyRenderViewsAreRefused) {
  const fs::path dir = fresh_dir("table_views");
  const CliResult r = run_cli("render " + quoted(dir) + " --views 100000");
  EXPECT_NE(r.code, 0) << r.out;
  expect_message(r, {"--views", "100000"}, {});
}

// 9. Output folders: a file, a folder under a file, a folder that is not a run, a killed run's
// folder. Each is refused before the run writes anything, saying what to pass.
TEST(BadInputTable, OutputFoldersAreCheckedBeforeTheRun) {
  const fs::path dir = fresh_dir("table_out");
  const fs::path scene = dir / "scene.toml";
  write_text(scene, reposetwin::test_support::kTinyScene);
  const auto run = [&](const fs::path& out, const std::string& extra) {
    return run_cli("run " + quoted(scene) + " --out " + quoted(out) + " --no-images " + extra);
  };
  CliResult r = run_cli("run " + quoted(scene) + " --out '' --no-images");
  EXPECT_EQ(r.code, 2) << r.out;
  expect_message(r, {"--out is empty"}, {"filesystem"});
  write_text(dir / "a_file", "x");
  r = run(dir / "a_file", "");
  EXPECT_EQ(r.code, 2) << r.out;
  expect_message(r, {"a_file", "names a file"}, {"lock file"});
  r = run(dir / "a_file" / "run", "");
  EXPECT_EQ(r.code, 2) << r.out;
  expect_message(r, {"a_file", "is a file, not a folder"}, {"lock file"});

  // A folder of the user's own: refused, and nothing in it touched.
  const fs::path mine = dir / "mine";
  write_text(mine / "summary.html", "my page");
  write_text(mine / "notes.txt", "my notes");
  r = run(mine, "");
  EXPECT_EQ(r.code, 2) << r.out;
  expect_message(r, {"mine", "not a run folder", "--force"}, {});
  EXPECT_EQ(reposetwin::test_support::read_text(mine / "summary.html"), "my page");
  EXPECT_FALSE(fs::exists(mine / ".run.lock"));

  // A killed run's folder (its checkpoint and controller, no result): --resume or --force.
  const fs::path killed = dir / "killed";
  write_text(killed / "scene.resolved.toml", "");
  write_text(killed / "checkpoint.bin", "");
  write_text(killed / "controller.json", "{}");
  r = run(killed, "");
  EXPECT_EQ(r.code, 2) << r.out;
  expect_message(r, {"killed", "interrupted", "--resume", "--force"}, {});
  EXPECT_TRUE(fs::exists(killed / "checkpoint.bin"));
}

// A snapshot of another scene (issue 52, part 4): a twin's frames/filled.vtp records the scene
// it is of, and `export --initial-state` refuses it for another; a tiny run makes one (a second).
TEST(BadInputTable, AnotherScenesSnapshotIsRefusedAsTheInitialState) {
  const fs::path dir = fresh_dir("table_snapshot");
  write_text(dir / "scene.toml", reposetwin::test_support::kTinyScene);
  const CliResult made = run_cli("run " + quoted(dir / "scene.toml") + " --out " +
                                 quoted(dir / "run") +
                                 " --no-images --quiet --set output.frame_interval_s=0.05");
  ASSERT_EQ(made.code, 0) << made.out;
  const fs::path filled = dir / "run" / "frames" / "filled.vtp";
  ASSERT_TRUE(fs::exists(filled));
  const std::string deck = "export " + quoted(dir / "scene.toml") + " --initial-state " +
                           quoted(filled) + " --set output.frame_interval_s=0.05 --out ";
  const CliResult same = run_cli(deck + quoted(dir / "same"));
  EXPECT_EQ(same.code, 0) << same.out;
  const CliResult other =
      run_cli(deck + quoted(dir / "other") + " --set sample.mass_kg=0.008");
  EXPECT_EQ(other.code, 2) << other.out;
  expect_message(other, {"filled.vtp", "--initial-state", "another scene"}, {});
  EXPECT_FALSE(fs::exists(dir / "other" / "in.pile"));
}

}  // namespace
