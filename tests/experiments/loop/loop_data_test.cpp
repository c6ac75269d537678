// The loop's measured-data CSV: a good file is read into tests with their overrides, and every
// kind of bad input gives an error naming the file, the line and the column.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>

#include "experiments/loop/loop.hpp"
#include "experiments/loop/loop_data.hpp"
#include "experiments/loop/loop_effects.hpp"
#include "experiments/loop/loop_records.hpp"
#include "experiments/loop/loop_sim.hpp"
#include "experiments/io/csv.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/report/loop_report.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

const std::string kScene = std::string(REPOSETWIN_SOURCE_DIR) + "/data/loop/tiny_scene.toml";

// Writes `body` (after a header) as a CSV in a fresh folder and returns its path.
std::string write_csv(const std::string& name, const std::string& text) {
  const fs::path dir = fs::temp_directory_path() / "reposetwin_loop_data_test";
  fs::create_directories(dir);
  const fs::path p = dir / (name + ".csv");
  write_file_atomic(p.string(), text);
  return p.string();
}

// The error message of reading `text`, or "" if it reads.
std::string error_of(const std::string& name, const std::string& text) {
  try {
    (void)read_lab_csv(write_csv(name, text));
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(LoopData, AGoodFileBecomesTestsWithOverrides) {
  const std::string csv = write_csv(
      "good",
      "# comment line\n"
      "id,role,scene,mass_g,W_mm,lift_speed_m_s,set:contacts.rock-plate.friction,H_mm,D_mm,"
      "angle_deg,repeats\n"
      "a,calibrate," + kScene + ",6,20,0.05,0.3,10,40,,2\n"
      "b,validate," + kScene + ",4,25,,,,,27.5,\n");
  const LabData d = read_lab_csv(csv);
  ASSERT_EQ(d.tests.size(), 2u);
  const LabTest& a = d.tests[0];
  EXPECT_EQ(a.id, "a");
  EXPECT_EQ(a.line, 3);
  EXPECT_EQ(a.repeats, 2);
  // The angle from H and D: atan(2H/D).
  EXPECT_NEAR(a.angle_deg, std::atan(0.5) * 180.0 / M_PI, 1e-12);
  EXPECT_NEAR(a.conditions.at("mass_g"), 6.0, 1e-12);
  // The condition columns became scene keys in SI units.
  EXPECT_NEAR(scene_value(a, "sample.mass_kg"), 0.006, 1e-15);
  EXPECT_NEAR(scene_value(a, "container.bottom_diameter_m"), 0.020, 1e-15);
  EXPECT_NEAR(scene_value(a, "contacts.rock-plate.friction"), 0.3, 1e-15);
  EXPECT_NEAR(scene_value(d.tests[1], "contacts.{sample}-{plate}.friction"), 0.5, 1e-15);
  EXPECT_NEAR(d.tests[1].angle_deg, 27.5, 1e-12);
  EXPECT_FALSE(d.tests[1].height_mm.has_value());
}

// Text conditions (a plate material, a set: column holding a word) are kept by column for the
// page's category plots, apart from the numeric ones; a set: column holding a number stays a
// number, and one that only starts with a number is text.
TEST(LoopData, TextConditionsAreKeptApartFromNumbers) {
  const LabData d = read_lab_csv(
      write_csv("text",
                "id,role,scene,plate,set:scene.name,set:contacts.rock-plate.friction,angle_deg\n"
                "a,calibrate," +
                    kScene +
                    ",plate,tiny_a,0.3,30\n"
                    "b,calibrate," +
                    kScene + ",,\"2b\",0.4,31\n"));
  const LabTest& a = d.tests.at(0);
  EXPECT_EQ(a.text_conditions.at("plate"), "plate");
  EXPECT_EQ(a.text_conditions.at("set:scene.name"), "tiny_a");
  EXPECT_EQ(a.conditions.count("set:scene.name"), 0u);
  EXPECT_NEAR(a.conditions.at("set:contacts.rock-plate.friction"), 0.3, 1e-15);
  EXPECT_EQ(a.text_conditions.count("set:contacts.rock-plate.friction"), 0u);
  const LabTest& b = d.tests.at(1);
  EXPECT_EQ(b.text_conditions.count("plate"), 0u);
  EXPECT_EQ(b.text_conditions.at("set:scene.name"), "2b");
  EXPECT_EQ(b.conditions.count("set:scene.name"), 0u);
  EXPECT_EQ(to_json(a).at("text_conditions").at("plate"), "plate");
  EXPECT_FALSE(to_json(b).at("text_conditions").contains("plate"));
}

// A calibrated parameter may be several scene keys set together (rock-rock and rock-plate rolling
// friction, as the Table 3 calibrations do); each takes the same mu_r, and a key the test's scene
// does not have is an error naming the key and the test.
TEST(LoopData, TheCalibratedParameterMaySetSeveralKeys) {
  const LabData d = read_lab_csv(
      write_csv("mukey", "id,role,scene,angle_deg\nt1,calibrate," + kScene + ",30\n"));
  const LabTest& t = d.tests.at(0);
  const std::string both =
      "contacts.{sample}-{sample}.rolling_friction,contacts.{sample}-{plate}.rolling_friction";
  const SimRequest r = make_request(t, both, 0.37, 5, {}, ImageVariant{});
  std::map<std::string, std::string> set(r.extra.begin(), r.extra.end());
  ASSERT_EQ(set.size(), 2u);
  EXPECT_EQ(std::stod(set.at("contacts.rock-rock.rolling_friction")), 0.37);
  EXPECT_EQ(std::stod(set.at("contacts.rock-plate.rolling_friction")), 0.37);
  EXPECT_NO_THROW(check_mu_key(t, both));
  // One key alone sets only that key.
  EXPECT_EQ(make_request(t, "contacts.{sample}-{sample}.rolling_friction", 0.2, 5, {},
                         ImageVariant{})
                .extra.size(),
            1u);
  try {
    check_mu_key(t, "contacts.{sample}-{sample}.rolling_friction,contacts.rock-rock.rolling_fric");
    ADD_FAILURE() << "a misspelt key was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("contacts.rock-rock.rolling_fric"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("t1"), std::string::npos) << e.what();
  }
  EXPECT_THROW(check_mu_key(t, ","), std::invalid_argument);
}

// The loop on the tiny scene, quickly: two grid points, two seeds, the particles' angle, one
// small photo a pile (for the page), two pours at most, no page unless a test asks.
LoopSettings tiny_settings() {
  LoopSettings s;
  s.mu_grid = {0.1, 0.3};
  s.seeds = {1, 2};
  s.angle = AngleMeasure::kParticles;
  s.image.width_px = 640;
  s.image.height_px = 480;
  s.image.side_views = 1;
  s.progress = false;
  s.html = false;
  s.max_pours = 2;
  return s;
}

// A twin run that forms no pile (the outlet clogs) has no angle: the pour is repeated with a new
// seed, and when every pour jams the loop stops with an error naming the test and the grid point
// instead of averaging a 0 deg "angle" into the test's curve.
TEST(LoopData, ATwinRunWithoutAPileStopsTheLoop) {
  const std::string csv = write_csv(
      "clogging", "id,role,scene,W_mm,mass_g,angle_deg\n"
                  "a,calibrate," + kScene + ",20,6,25\n"
                  "b,calibrate," + kScene + ",20,8,26\n"
                  "narrow,calibrate," + kScene + ",5,6,27\n");
  const fs::path out = fs::temp_directory_path() / "reposetwin_loop_clog_test";
  fs::remove_all(out);
  const LoopSettings s = tiny_settings();
  try {
    (void)run_loop(read_lab_csv(csv), out.string(), s);
    ADD_FAILURE() << "the loop ran on a test whose twin clogs";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("test narrow formed no pile"), std::string::npos) << what;
    EXPECT_NE(what.find("mu_r 0.1"), std::string::npos) << what;
    EXPECT_NE(what.find("in 2 pour(s)"), std::string::npos) << what;
    // The last pour named is the repeat, with its own seed.
    EXPECT_NE(what.find("seed " + std::to_string(1 + kRepourSeedStride)), std::string::npos)
        << what;
  }
  EXPECT_FALSE(fs::exists(out / "loop.json"));
}

// mu_r's declared range is checked before anything runs: a grid that leaves it is refused,
// naming the range and its reason.
TEST(LoopData, AGridOutsideTheDeclaredMuRangeIsRefusedBeforeAnyRun) {
  const std::string csv = write_csv(
      "prior", "id,role,scene,mass_g,angle_deg\n"
               "a,calibrate," + kScene + ",6,25\n");
  const fs::path out = fs::temp_directory_path() / "reposetwin_loop_prior_test";
  fs::remove_all(out);
  LoopSettings s = tiny_settings();
  s.mu_grid = {0.1, 0.5};
  s.mu_prior = {0.02, 0.4, "rock in our convention"};
  try {
    (void)run_loop(read_lab_csv(csv), out.string(), s);
    ADD_FAILURE() << "the loop ran a grid beyond its declared mu_r range";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("--mu-range 0.02-0.4 (rock in our convention)"), std::string::npos)
        << what;
  }
  EXPECT_FALSE(fs::exists(out / "loop.json"));
}

using nlohmann::json;

// A value loop.json holds as null (NaN once written), or NaN in the returned object.
bool missing(const json& v) { return v.is_null() || std::isnan(v.get<double>()); }

const json& row_of(const json& rows, const std::string& id) {
  for (const json& r : rows)
    if (r["id"] == id) return r;
  throw std::runtime_error("no residual row " + id);
}

// A held-out test whose twin pours all jam is a prediction ("no pile"), not an error: the loop
// fits mu_r on the calibration tests, traces the tests that have a prediction, refits, and
// reports the jammed one as "no pile predicted" in loop.json and on the page, leaving it out of
// every RMSE and saying so.
TEST(LoopHeldOut, AHeldOutTestWhoseTwinJamsIsPredictedNoPileAndTheRefitGoesOn) {
  const fs::path dir = fs::temp_directory_path() / "reposetwin_loop_held_out_test";
  fs::remove_all(dir);
  // Four calibration tests that pour, and one held out through a 5 mm outlet that the 3-4 mm
  // spheres arch over on every pour (the same outlet stops the loop as a calibration test).
  const LabData data = read_lab_csv(write_csv(
      "held_out", "id,role,scene,W_mm,mass_g,angle_deg\n"
                  "a,calibrate," + kScene + ",20,5,25\n"
                  "b,calibrate," + kScene + ",20,6,26\n"
                  "c,calibrate," + kScene + ",20,7,25.5\n"
                  "d,calibrate," + kScene + ",20,8,26.5\n"
                  "narrow,validate," + kScene + ",5,6,27\n"));
  LoopSettings s = tiny_settings();
  s.at_bound = GridBound::kTrace;
  s.candidates = {"plate_friction", "lift_speed"};
  // Declared, so its trial is simulated whatever the trace says (here: that it cannot tell the
  // two apart).
  s.refit = "lift_speed";
  s.max_effects = 1;
  // The first trial is what this test is about; the follow-ups (LoopRefit.*) would pour three
  // more surfaces, one of them stepping back from a lift so fast that test b forms no pile.
  s.refit_follow_ups = 0;
  s.probe_scalings = 1;  // the lift's fingerprint stands out at twice its probe
  s.html = true;
  s.page = write_loop_html;
  s.cache_dir = (dir / "cache").string();
  const fs::path out = dir / "loop";
  json loop;
  ASSERT_NO_THROW(loop = run_loop(data, out.string(), s));

  // The baseline predicts no pile for it, with where its pours jammed, and no number.
  const json& before = row_of(loop["baseline"]["residuals"], "narrow");
  ASSERT_TRUE(before.contains("no_pile")) << before.dump();
  const std::string why = before["no_pile"];
  EXPECT_NE(why.find("no pile predicted"), std::string::npos) << why;
  EXPECT_NE(why.find("in 2 pour(s) at mu_r 0.1 seed 1"), std::string::npos) << why;
  EXPECT_TRUE(missing(before["predicted_deg"]));
  EXPECT_TRUE(missing(before["residual_deg"]));
  EXPECT_FALSE(row_of(loop["baseline"]["residuals"], "a").contains("no_pile"));
  // Left out of every RMSE, and counted.
  EXPECT_EQ(loop["baseline"]["rmse"]["n_no_pile"], 1);
  EXPECT_EQ(loop["baseline"]["rmse"]["n_calibrate"], 4);
  EXPECT_EQ(loop["baseline"]["rmse"]["n_validate"], 0);
  EXPECT_TRUE(loop["baseline"]["rmse"]["validate_deg"].is_null());
  EXPECT_TRUE(std::isfinite(loop["summary"]["rmse_all_before_deg"].get<double>()));
  // Its fingerprint is not simulated (NaN), and the trace names it as left out.
  ASSERT_EQ(loop["fingerprints"].size(), 2u) << loop["unavailable_candidates"].dump();
  for (const json& f : loop["fingerprints"]) {
    EXPECT_TRUE(missing(f["angle_deg"][4])) << f.dump();
    EXPECT_TRUE(std::isfinite(f["angle_deg"][0].get<double>())) << f.dump();
  }
  ASSERT_FALSE(loop["iterations"].empty());
  const json& it0 = loop["iterations"][0];
  ASSERT_EQ(it0["tests_left_out"].size(), 1u) << it0.dump();
  EXPECT_EQ(it0["tests_left_out"][0].get<std::string>().rfind("narrow: no pile predicted", 0), 0u);
  EXPECT_EQ(it0["candidates"].size(), 2u) << "four tests with a prediction are traced";
  // The two move these piles alike: the trace names neither, and the lab's hypothesis decides.
  EXPECT_EQ(it0["decision"]["verdict"], "indistinguishable") << it0["decision"].dump();

  // The declared lift speed is refitted by simulation although the trace names nothing, with
  // the trace's verdict on record, and although the held-out test jams at the trial's value
  // too: the trial records it instead of stepping back.
  EXPECT_NE(it0.value("declared", "").find("not because the trace names it"), std::string::npos)
      << it0.dump(1);
  const std::string verdict = loop["summary"]["verdict"];
  EXPECT_TRUE(verdict == "declared" || verdict == "not_confirmed") << loop["summary"].dump();
  const json refit = it0.contains("not_confirmed") ? it0["not_confirmed"] : it0["chosen"];
  ASSERT_TRUE(refit.is_object()) << it0.dump();
  ASSERT_FALSE(refit.contains("refit_failed")) << refit.dump();
  ASSERT_FALSE(refit["trials"].empty());
  EXPECT_EQ(refit["trials"][0]["no_pile"], json::array({"narrow"})) << refit.dump();
  EXPECT_EQ(refit["refit_notes"], "") << "no step back";
  const json& after = row_of(loop["final"]["residuals"], "narrow");
  EXPECT_TRUE(after.contains("no_pile"));
  EXPECT_EQ(loop["summary"]["no_pile_predicted"], json::array({"narrow"}));
  EXPECT_NE(loop["summary"]["statement"].get<std::string>().find("no pile predicted for narrow"),
            std::string::npos)
      << loop["summary"].dump();
  // No twin photo of a pile that was not formed; the pair says why.
  const json& pair = loop["photo_pairs"][4];
  EXPECT_EQ(pair["id"], "narrow");
  EXPECT_TRUE(pair["twin"].is_null());
  EXPECT_EQ(pair["note"].get<std::string>().rfind("no pile predicted", 0), 0u) << pair.dump();

  // The records read back (the report reads loop.json).
  const ResidualRow r = residual_row_from_json(after);
  EXPECT_FALSE(r.no_pile.empty());
  EXPECT_TRUE(std::isnan(r.predicted_deg));
  EXPECT_EQ(role_rmse_from_json(loop["final"]["rmse"]).n_no_pile, 1u);

  // The page says "no pile" where a number would be, and why.
  const std::string html = read_file((out / "index.html").string());
  EXPECT_NE(html.find("<td class='l'>no pile</td>"), std::string::npos);
  EXPECT_NE(html.find("After, no pile predicted: the twin&apos;s pours of test narrow"),
            std::string::npos);
  EXPECT_NE(html.find("no pile predicted (held out)"), std::string::npos) << "the trials' column";
  EXPECT_NE(html.find("held-out tests the twin forms no pile for"), std::string::npos);
  EXPECT_EQ(html.find(">nan<"), std::string::npos);
  EXPECT_EQ(html.find("-nan"), std::string::npos);

  // Without test d, three tests have a prediction: too few to judge a candidate by leave-one-out
  // (the design's own bound is 4), so the iteration says so and traces nothing (the piles come
  // from the cache).
  LabData three = data;
  three.tests.erase(three.tests.begin() + 3);
  LoopSettings plain = s;
  plain.refit.clear();
  const json few = run_loop(three, (dir / "few").string(), plain);
  ASSERT_EQ(few["iterations"].size(), 1u) << few["iterations"].dump(1);
  const json& only = few["iterations"][0];
  EXPECT_TRUE(only["candidates"].empty()) << only.dump(1);
  EXPECT_EQ(only["decision"]["statement"].get<std::string>().rfind(
                "nothing traced: 3 test(s) have a prediction", 0),
            0u)
      << only["decision"].dump();
  EXPECT_EQ(only["tests_left_out"].size(), 1u);
  EXPECT_EQ(few["summary"]["verdict"], "nothing");
  EXPECT_EQ(few["summary"]["no_pile_predicted"], json::array({"narrow"}));
  // The page's "None:" gives that reason, not "no candidate beat the seed noise".
  const std::string page = read_file((dir / "few" / "index.html").string());
  EXPECT_NE(page.find("None: nothing traced: 3 test(s) have a prediction"), std::string::npos);
}

// A scatter of small spheres on the plate (what a jammed outlet lets through) is too low for any
// side view to find the pile's toes: photograph_pile returns the error, which the cache turns
// into a pour without a pile (repeated, and named in the loop's error), not an exception that
// would stop the whole batch.
TEST(LoopData, APileNoViewCanMeasureIsReportedNotThrown) {
  std::vector<Eigen::Vector3d> x;
  for (int k = 0; k < 40; ++k) {
    const double a = 0.157 * k, r = 0.02 * std::sqrt((k + 0.5) / 40.0);
    x.emplace_back(r * std::cos(a), r * std::sin(a), 0.2e-3);
  }
  ImageVariant v;
  v.width_px = 320;
  v.height_px = 240;
  v.side_views = 2;
  const nlohmann::json got =
      photograph_pile(x, std::vector<double>(x.size(), 0.2e-3), std::vector<int>(x.size(), 0), v,
                      (fs::temp_directory_path() / "rt_tiny").string());
  ASSERT_TRUE(got.contains("error")) << got.dump();
  EXPECT_NE(got["error"].get<std::string>().find("no side view of the pile could be measured"),
            std::string::npos);
  EXPECT_FALSE(got.contains("angle_deg"));
  EXPECT_EQ(got["views"].size(), 2u);
}

// A pile's store key takes in the engine version (a hash of the engine's sources: another engine
// must not reuse piles an older one made, and a commit that leaves it alone finds them; the
// hash itself is checked by experiments.engine_hash_follows_its_sources); the same inputs give
// the same key, so a killed loop resumes.
TEST(LoopData, CachedPileRunsAreKeyedByEngineVersion) {
  EXPECT_EQ(engine_version().rfind("engine-", 0), 0u) << engine_version();
  EXPECT_EQ(engine_version().size(), 7u + 16u) << engine_version();
  EXPECT_EQ(imaging_version().rfind("imaging-", 0), 0u) << imaging_version();
  // The pile service's keys (campaign/pile_service.hpp) take the engine version in; the
  // request's own fields are checked by PileStore.KeysFollowTheRequestRecord.
  const std::string scene = std::string(REPOSETWIN_SOURCE_DIR) + "/data/loop/tiny_scene.toml";
  const PileRequest r{scene, {{"sample.mass_kg", "0.005"}}, 1, std::nullopt};
  EXPECT_EQ(pile_key(r), pile_key(r));
  EXPECT_EQ(pile_key(r).size(), 64u);
}

// The CSV's quoting is RFC 4180's (io/csv over libcsv): a quoted field keeps its commas and
// doubled quotes, CRLF line ends and a spreadsheet's byte-order mark read as plain LF text, and
// a stray or unterminated quote is an error naming the file and the line.
TEST(LoopData, QuotingLineEndsAndByteOrderMark) {
  const std::string head = "id,role,scene,mass_kg,W_mm,angle_deg,note\n";
  const std::string good = head + "t1,calibrate," + kScene + ",0.006,20,30,\"a, \"\"b\"\"\"\n" +
                           "t2,validate,\"" + kScene + "\",0.004,20,28,plain\n";
  const LabData plain = read_lab_csv(write_csv("quoted", good));
  ASSERT_EQ(plain.tests.size(), 2u);
  EXPECT_EQ(plain.tests[1].scene_path, fs::path(kScene).lexically_normal().string());
  EXPECT_EQ(plain.tests[1].line, 3);
  std::string crlf;
  for (char c : good) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  const LabData dos = read_lab_csv(write_csv("crlf", "\xEF\xBB\xBF" + crlf));
  ASSERT_EQ(dos.tests.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(dos.tests[k].id, plain.tests[k].id);
    EXPECT_EQ(dos.tests[k].overrides, plain.tests[k].overrides);
    EXPECT_EQ(dos.tests[k].angle_deg, plain.tests[k].angle_deg);
  }
  // A line of spaces is blank, as an empty line is.
  EXPECT_EQ(read_lab_csv(write_csv("spaces", head + "   \n" + good.substr(head.size()))).tests.size(),
            2u);
  std::string e = error_of("unterminated", head + "t1,calibrate," + kScene + ",0.006,20,30,\"open\n");
  EXPECT_NE(e.find("unterminated.csv:2"), std::string::npos) << e;
  e = error_of("stray", head + "t1,calibrate," + kScene + ",0.006,20,30,a\"b\n");
  EXPECT_NE(e.find("stray.csv:2"), std::string::npos) << e;
  // A quoted comma does not split a field: this row has five fields, not six.
  e = error_of("count", head + "t1,calibrate," + kScene + ",0.006,\"20,30\"\n");
  EXPECT_NE(e.find("line 2: 5 fields for 7 columns"), std::string::npos) << e;
}

TEST(LoopData, BadInputNamesTheLineAndColumn) {
  const std::string head = "id,role,scene,mass_kg,W_mm,angle_deg\n";
  auto row = [&](const std::string& rest) { return head + "t1,calibrate," + kScene + "," + rest + "\n"; };
  std::string e = error_of("missing", "id,role,mass_kg,angle_deg\nt1,calibrate,0.006,30\n");
  EXPECT_NE(e.find("required column \"scene\""), std::string::npos) << e;
  e = error_of("nonnumber", row("heavy,20,30"));
  EXPECT_NE(e.find("line 2 (test t1), column mass_kg"), std::string::npos) << e;
  EXPECT_NE(e.find("\"heavy\" is not a number"), std::string::npos) << e;
  e = error_of("angle", row("0.006,20,95"));
  EXPECT_NE(e.find("column angle_deg"), std::string::npos) << e;
  EXPECT_NE(e.find("outside (0, 90)"), std::string::npos) << e;
  e = error_of("noangle", head + "t1,calibrate," + kScene + ",0.006,20,\n");
  EXPECT_NE(e.find("no measured value"), std::string::npos) << e;
  e = error_of("unknown", "id,role,scene,angel_deg\nt1,calibrate," + kScene + ",30\n");
  EXPECT_NE(e.find("unknown column \"angel_deg\""), std::string::npos) << e;
  e = error_of("role", head + "t1,fit," + kScene + ",0.006,20,30\n");
  EXPECT_NE(e.find("column role"), std::string::npos) << e;
  e = error_of("dup", row("0.006,20,30") + "t1,calibrate," + kScene + ",0.006,20,31\n");
  EXPECT_NE(e.find("appears twice"), std::string::npos) << e;
  e = error_of("fields", head + "t1,calibrate," + kScene + ",0.006\n");
  EXPECT_NE(e.find("4 fields for 6 columns"), std::string::npos) << e;
  e = error_of("noscene", head + "t1,calibrate,nowhere.toml,0.006,20,30\n");
  EXPECT_NE(e.find("column scene"), std::string::npos) << e;
}

// The crest width is an optional column: read where given (0, a sharp cone, included), absent
// on a row left empty, and a bad value refused naming the file, line, test, column and value.
TEST(LoopData, AnOptionalCrestColumnIsReadAndBadValuesRefused) {
  const std::string head = "id,role,scene,angle_deg,crest_mm\n";
  const std::string path =
      write_csv("crest", head + "a,calibrate," + kScene + ",30,7.25\n" + "b,validate," + kScene +
                             ",31,\n" + "c,validate," + kScene + ",32,0\n");
  const LabData d = read_lab_csv(path);
  ASSERT_EQ(d.tests.size(), 3u);
  ASSERT_TRUE(d.tests[0].crest_mm.has_value());
  EXPECT_DOUBLE_EQ(*d.tests[0].crest_mm, 7.25);
  EXPECT_FALSE(d.tests[1].crest_mm.has_value());
  EXPECT_DOUBLE_EQ(d.tests[2].crest_mm.value_or(-1.0), 0.0);
  EXPECT_DOUBLE_EQ(to_json(d.tests[0]).at("crest_mm").get<double>(), 7.25);
  EXPECT_EQ(to_json(d.tests[0]).at("crest_source"), "typed");
  EXPECT_FALSE(to_json(d.tests[1]).contains("crest_source"));
  EXPECT_FALSE(to_json(d.tests[1]).contains("crest_mm"));
  // Without the column, no test has a crest.
  const LabData none = read_lab_csv(
      write_csv("nocrest", "id,role,scene,angle_deg\na,calibrate," + kScene + ",30\n"));
  EXPECT_FALSE(none.tests[0].crest_mm.has_value());
  std::string e = error_of("crestneg", head + "a,calibrate," + kScene + ",30,-2.5\n");
  EXPECT_NE(e.find("crestneg.csv line 2 (test a), column crest_mm: -2.5 must not be negative"),
            std::string::npos)
      << e;
  e = error_of("crestword", head + "a,calibrate," + kScene + ",30,wide\n");
  EXPECT_NE(e.find("crestword.csv line 2 (test a), column crest_mm: \"wide\" is not a number"),
            std::string::npos)
      << e;
}

// Two columns that set one scene key are refused, naming both, before any row is read: with
// mass_kg and mass_g (or a set:KEY beside the named column for KEY) one would silently win on
// every row. Columns that set different keys stay accepted.
TEST(LoopData, TwoColumnsSettingOneSceneKeyAreRefused) {
  std::string e = error_of("bothmass", "id,role,scene,mass_kg,mass_g,angle_deg\n"
                                       "t1,calibrate," + kScene + ",0.006,7,30\n");
  EXPECT_NE(e.find("bothmass.csv line 1: columns mass_kg and mass_g both set the scene key "
                   "sample.mass_kg"),
            std::string::npos)
      << e;
  e = error_of("setmass", "id,role,scene,set:sample.mass_kg,mass_kg,angle_deg\n"
                          "t1,calibrate," + kScene + ",0.007,0.006,30\n");
  EXPECT_NE(e.find("columns set:sample.mass_kg and mass_kg both set the scene key sample.mass_kg"),
            std::string::npos)
      << e;
  e = error_of("setplate", "id,role,scene,plate,set:plate.material,angle_deg\n"
                           "t1,calibrate," + kScene + ",plate,plate,30\n");
  EXPECT_NE(e.find("columns plate and set:plate.material"), std::string::npos) << e;
  // The refusal holds whichever rows are filled: a column left empty on every row still names
  // the key twice in the header.
  e = error_of("emptymass", "id,role,scene,mass_kg,mass_g,angle_deg\n"
                            "t1,calibrate," + kScene + ",0.006,,30\n");
  EXPECT_NE(e.find("columns mass_kg and mass_g"), std::string::npos) << e;
  EXPECT_EQ(error_of("onemass", "id,role,scene,mass_g,set:contacts.rock-plate.friction,angle_deg\n"
                                "t1,calibrate," + kScene + ",6,0.3,30\n"),
            "");
}

TEST(LoopData, ATestTheEngineCannotBuildNamesItsColumn) {
  // A scene key that does not exist and a plate material that does not exist.
  std::string e = error_of("badkey", "id,role,scene,set:contacts.rock-plate.fricton,angle_deg\n"
                                     "t1,calibrate," + kScene + ",0.3,30\n");
  EXPECT_NE(e.find("column set:contacts.rock-plate.fricton"), std::string::npos) << e;
  EXPECT_NE(e.find("cannot build"), std::string::npos) << e;
  e = error_of("badplate", "id,role,scene,plate,angle_deg\nt1,calibrate," + kScene + ",glass,30\n");
  EXPECT_NE(e.find("line 2 (test t1), column plate"), std::string::npos) << e;
  e = error_of("badmass", "id,role,scene,mass_kg,angle_deg\nt1,calibrate," + kScene + ",-1,30\n");
  EXPECT_NE(e.find("column mass_kg"), std::string::npos) << e;
}

TEST(LoopData, PhotosWithoutAUsableScaleAreRejected) {
  // An image with no pile, no sidecar and no scale marker; then one that does not exist.
  const fs::path dir = fs::temp_directory_path() / "reposetwin_loop_data_test";
  fs::create_directories(dir);
  {
    std::ofstream f(dir / "blank.pgm", std::ios::binary);
    f << "P5\n64 48\n255\n" << std::string(64 * 48, char(200));
  }
  std::string e = error_of("photo", "id,role,scene,photo\nt1,calibrate," + kScene + ",blank.pgm\n");
  EXPECT_NE(e.find("line 2 (test t1), column photo"), std::string::npos) << e;
  EXPECT_NE(e.find("photo_camera sidecar JSON or mm_per_px"), std::string::npos) << e;
  e = error_of("nophoto", "id,role,scene,photo\nt1,calibrate," + kScene + ",missing.png\n");
  EXPECT_NE(e.find("column photo: \"" + (dir / "missing.png").string() + "\" does not exist"),
            std::string::npos)
      << e;
  e = error_of("badscale",
               "id,role,scene,photo,mm_per_px\nt1,calibrate," + kScene + ",blank.pgm,-2\n");
  EXPECT_NE(e.find("column mm_per_px"), std::string::npos) << e;
}

// The loop's rows are split by the one CSV reader (io/csv.hpp): the same quote rules.
TEST(LoopData, CsvFieldsFollowQuotes) {
  const auto f = parse_csv("h1,h2,h3,h4\na,\"b,c\",\"d\"\"e\",\n", "x").rows.at(0).fields;
  ASSERT_EQ(f.size(), 4u);
  EXPECT_EQ(f[1], "b,c");
  EXPECT_EQ(f[2], "d\"e");
  EXPECT_EQ(f[3], "");
  EXPECT_THROW(parse_csv("h1,h2\na,\"b", "x"), std::invalid_argument);
}

}  // namespace
}  // namespace reposetwin::experiments
