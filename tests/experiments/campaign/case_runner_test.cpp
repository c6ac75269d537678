// The angle a calibration takes from one run: the image angle, the particle angle, and never an
// angle from a run without a headline (a jam, a time limit, an unsettled pile, a physics stop),
// which a campaign counts by its reason. And a campaign's pile run
// interrupted mid-way (machine lost) continues from its checkpoint to the uninterrupted result.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "experiments/calibration/campaign_target.hpp"
#include "experiments/campaign/case_runner.hpp"
#include "experiments/pile/pile_run.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/io/scene.hpp"

namespace reposetwin::experiments {
namespace {

nlohmann::json run_result(const std::string& reason, const std::string& pile_status) {
  return {{"result",
           {{"stop", {{"reason", reason}, {"detail", "largest overlap 0.2009 exceeds 0.2"}}},
            {"pile",
             {{"status", pile_status}, {"theta_hd_deg", 27.5}, {"slice_angle_mean_deg", 31.75}}},
            {"image", {{"theta_deg", 24.25}, {"flank_deg", 29.5}}},
            {"run_dir", "cases/x/seed_2/run"}}}};
}

TEST(CaseAngle, ImageFirstThenParticles) {
  EXPECT_DOUBLE_EQ(case_angle_deg(run_result("settled", "ok")), 24.25);
  EXPECT_DOUBLE_EQ(case_angle_deg(run_result("settled", "ok"), AngleMeasure::kParticles), 27.5);
  EXPECT_TRUE(case_made_no_pile(run_result("clogged", "no pile")));
  EXPECT_TRUE(case_made_no_pile(run_result("clogged", "no pile")["result"]));
  EXPECT_FALSE(case_made_no_pile(run_result("settled", "ok")));
  EXPECT_EQ(case_outcome(run_result("settled", "ok")["result"]), PileStatus::kPile);
}

// Every run without a headline gives no angle under any measure, and its outcome names why.
TEST(CaseAngle, ARunWithoutAHeadlineHasNoAngleAndCountsByItsReason) {
  const std::pair<const char*, const char*> cases[] = {{"clogged", "jam"},
                                                       {"time limit", "time_limit"},
                                                       {"settle time limit", "not_settled"},
                                                       {"physics: nan", "physics_stop"}};
  for (const auto& [stop, outcome] : cases) {
    const nlohmann::json r = run_result(stop, stop == std::string("clogged") ? "no pile" : "ok");
    EXPECT_EQ(case_outcome_word(r["result"]), outcome) << stop;
    for (AngleMeasure m : {AngleMeasure::kImage, AngleMeasure::kParticles, AngleMeasure::kSlice})
      EXPECT_THROW(case_angle_deg(r, m), std::runtime_error) << stop;
  }
  EXPECT_EQ(case_outcome(run_result("settled", "no flanks")["result"]), PileStatus::kNoPile);
  EXPECT_EQ(case_outcome(run_result("settled", "no pile")["result"]), PileStatus::kNoPile);
  // A case result written for a run that settled carries its headline; one that did not, null.
  CaseResult unsettled;
  unsettled.stop = {StopReason::kSettleTimeLimit, sim::Status::kOk, "still moving", ""};
  unsettled.pile.status = sim::PileStatus::kOk;
  unsettled.pile.theta_hd_deg = 30.0;
  const nlohmann::json j = to_json(unsettled);
  EXPECT_TRUE(j["headline_angle_deg"].is_null());
  EXPECT_EQ(j["no_headline"]["reason"], "not_settled");
}

TEST(CaseAngle, MeasureNamesRoundTripAndAnUnknownNameIsRejected) {
  for (AngleMeasure m : {AngleMeasure::kImage, AngleMeasure::kImageFlank, AngleMeasure::kParticles,
                         AngleMeasure::kSlice})
    EXPECT_EQ(parse_angle_measure(angle_measure_name(m), "here"), m);
  try {
    parse_angle_measure("protractor", "c.toml: key 'calibration.angle'");
    FAIL() << "an unknown angle name was accepted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("c.toml"), std::string::npos) << what;
    EXPECT_NE(what.find("protractor"), std::string::npos) << what;
    EXPECT_NE(what.find("image_flank"), std::string::npos) << what;
  }
}

TEST(CaseAngle, APhysicsFailureHasNoAngle) {
  try {
    case_angle_deg(run_result("physics: overlap", "ok"));
    FAIL() << "a run stopped on overlap gave an angle";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("physics: overlap"), std::string::npos) << what;
    EXPECT_NE(what.find("cases/x/seed_2/run"), std::string::npos) << what;
  }
}

namespace fs = std::filesystem;

// One case of the tiny loop scene, one seed, without photographs.
Campaign tiny_campaign(const fs::path& dir) {
  const std::string scene = std::string(REPOSETWIN_SOURCE_DIR) + "/data/loop/tiny_scene.toml";
  write_file_atomic((dir / "c.toml").string(), "name = \"resume_pile\"\nscene = \"" + scene +
                                                   "\"\nseeds = [5]\n[[case]]\nname = \"mu\"\n"
                                                   "overrides = { \"sample.mass_kg\" = 0.004 }\n");
  return load_campaign((dir / "c.toml").string());
}

RunnerSettings one_worker() {
  RunnerSettings r;
  r.workers = 1;
  r.progress = false;
  r.rank.reset();
  return r;
}

// What a campaign killed mid-run leaves: started.json with the run's inputs and a pile run
// stopped (with its checkpoint) after `steps` steps in the pile service's store (OUT/cache), built
// as pile_case_fn builds it.
void leave_interrupted_run(const fs::path& out, const CaseSpec& spec, std::int64_t steps,
                           const nlohmann::json& stored_spec) {
  const fs::path dir = out / spec.relative_dir();
  fs::create_directories(dir);
  write_json_atomic((dir / "started.json").string(),
                    {{"spec", stored_spec}, {"started", "2026-11-22T00:00:00Z"},
                     {"code_version", "earlier"}});
  SceneDoc doc = build_case_scene(spec);
  doc.set_seed(spec.seed);
  RunOptions opt;
  opt.out_dir = PileService((out / "cache").string()).pile_dir(case_request(spec, {})) + "/run";
  opt.progress = false;
  opt.stop_after_steps = steps;
  ASSERT_FALSE(run_pile_test(doc.config(), opt).has_value());
}

TEST(CampaignPileRun, AnInterruptedRunContinuesFromItsCheckpoint) {
  const fs::path dir = fs::temp_directory_path() / "reposetwin_case_runner_resume";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const Campaign c = tiny_campaign(dir);
  ASSERT_EQ(c.runs.size(), 1u);
  const CaseSpec& spec = c.runs[0];
  CaseRunSettings rs;
  rs.images = false;
  const CaseFn fn = pile_case_fn(rs);
  auto case_json = [&](const fs::path& out) {
    return nlohmann::json::parse(read_file((out / spec.relative_dir() / "result.json").string()));
  };
  auto run_json = [&](const fs::path& out) {  // the pile run the case record points at
    const fs::path run = out / spec.relative_dir() /
                         case_json(out)["result"]["run_dir"].get<std::string>() / "result.json";
    return nlohmann::json::parse(read_file(run.string()));
  };
  auto resumed = [](const nlohmann::json& run) {
    int n = 0;
    for (const auto& e : run["procedure"]["events"]) n += e.value("event", "") == "resumed";
    return n;
  };

  // Reference: uninterrupted.
  const fs::path ref = dir / "ref";
  ASSERT_EQ(run_campaign(c, ref.string(), fn, one_worker()).finished, 1);
  const nlohmann::json a = run_json(ref);
  ASSERT_EQ(a["stop"]["reason"], "settled") << a["stop"].dump();
  EXPECT_EQ(resumed(a), 0);
  EXPECT_FALSE(case_json(ref).contains("earlier_attempts"));

  // Interrupted after 3000 steps, then the campaign again: it continues, bit-identically.
  const fs::path out = dir / "out";
  leave_interrupted_run(out, spec, 3000, to_json(spec));
  const auto s = run_campaign(c, out.string(), fn, one_worker());
  EXPECT_EQ(s.finished, 1);
  EXPECT_EQ(s.ran, 1);
  const nlohmann::json b = run_json(out);
  EXPECT_EQ(resumed(b), 1) << b["procedure"]["events"].dump();
  EXPECT_EQ(b["pile"], a["pile"]);
  EXPECT_EQ(b["performance"]["steps"], a["performance"]["steps"]);
  const nlohmann::json cb = case_json(out);
  ASSERT_TRUE(cb.contains("earlier_attempts")) << cb.dump();
  EXPECT_EQ(cb["earlier_attempts"].size(), 1u);
  EXPECT_EQ(cb["earlier_attempts"][0]["code_version"], "earlier");
  EXPECT_EQ(cb["result"]["pile"], case_json(ref)["result"]["pile"]);

  // A damaged checkpoint is not continued: the run starts again and still ends the same.
  const fs::path broken = dir / "broken";
  leave_interrupted_run(broken, spec, 3000, to_json(spec));
  write_file_atomic(
      PileService((broken / "cache").string()).pile_dir(case_request(spec, {})) + "/run/checkpoint.bin",
      "junk");
  EXPECT_EQ(run_campaign(c, broken.string(), fn, one_worker()).finished, 1);
  EXPECT_EQ(resumed(run_json(broken)), 0);
  EXPECT_EQ(run_json(broken)["pile"], a["pile"]);

  // A case folder whose interrupted attempt was at other inputs (another mass) is cleared; the
  // pour in the store is keyed by what it pours, this case's request, so it is continued.
  const fs::path other = dir / "other";
  nlohmann::json other_spec = to_json(spec);
  other_spec["overrides"]["sample.mass_kg"] = 0.005;
  leave_interrupted_run(other, spec, 3000, other_spec);
  EXPECT_EQ(run_campaign(c, other.string(), fn, one_worker()).finished, 1);
  EXPECT_EQ(resumed(run_json(other)), 1);
  EXPECT_FALSE(case_json(other).contains("earlier_attempts"));
  EXPECT_EQ(run_json(other)["pile"], a["pile"]);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace reposetwin::experiments
