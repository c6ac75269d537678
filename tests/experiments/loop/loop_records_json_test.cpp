// Every loop record back from its loop.json fields: filled with distinct values (so a swapped or
// dropped field shows), written, read and written again, the JSON and the fields unchanged.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "experiments/io/input_error.hpp"
#include "experiments/io/json_read.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/loop/loop_records.hpp"

namespace reposetwin::experiments {
namespace {

using nlohmann::json;

ResidualRow residual(double x) {
  ResidualRow r{"t" + std::to_string(x), Role::kValidate, x + 0.1, x + 0.2, x + 0.3, x + 0.4,
                x + 0.5,                 x + 0.6,    x + 0.7, {},      x + 0.8,
                x + 0.9,                 x + 1.0};
  return r;
}

RefitSummary refit() {
  return {"lift_speed", 2.5, 3.0, 0.75, 0.21, {{1.0, 0.5, 0.6, 0.2, 1.1}, {3.0, 0.9, 0.75, 0.21, 0.8}},
          "at 5: no pile; "};
}

ChosenEffect chosen() {
  ChosenEffect c;
  c.refit = refit();
  c.kind = "physics";
  c.key = "procedure.lift_speed_m_s";
  c.units = "x declared";
  c.off = 1.0;
  c.probe = 4.0;
  c.value = 2.5;
  c.value_se = 0.3;
  c.t_at_limit = true;
  c.mu_r_se = 0.01;
  return c;
}

CandidateScore score() {
  return {"plate_friction", 0.8, 0.1, 8.0, 0.02, true, 1.2, 1.4, 0.6, 0.7, true, false, false,
          "t = 8 > 2; LOO gain 0.6 < 0.9"};
}

// write(read(write(x))) == write(x) through the file's text: every field loop.json holds comes
// back (a NaN is written as null and read back as NaN).
template <typename T, typename F>
void expect_round_trip(const T& x, F from) {
  const std::string text = to_json(x).dump();
  EXPECT_EQ(to_json(from(json::parse(text))).dump(), text);
}

// A photo pair with both views, one whose twin view is missing (null, with its note), and one
// the lab gave no photo of (null).
TEST(LoopRecordsJson, PhotoPairsRoundTrip) {
  const PhotoView lab{
      "photos/a/lab.jpg", "photos/a/lab.measured.png", "/lab/a.jpg", 0.2, 400, 300, 31.5};
  const PhotoView twin{
      "photos/a/twin.png", "photos/a/twin.measured.png", "/cache/x.png", 0.125, 960, 720, 29.25};
  expect_round_trip(lab, photo_view_from_json);
  const PhotoPair both{"a", lab, twin, 0.15, 1000002, {{"plate_friction", 0.3}, {"cohesion", 2.5}},
                       ""};
  expect_round_trip(both, photo_pair_from_json);
  const PhotoPair one{"b", lab, std::nullopt, 0.3, 7, {}, "no view could be measured"};
  expect_round_trip(one, photo_pair_from_json);
  const PhotoPair twin_alone{"c", std::nullopt, twin, 0.3, 7, {}, ""};  // a typed angle
  expect_round_trip(twin_alone, photo_pair_from_json);
  EXPECT_FALSE(photo_pair_from_json(to_json(twin_alone)).lab);
  EXPECT_TRUE(to_json(one).at("twin").is_null());
  EXPECT_EQ(photo_pair_from_json(to_json(both)).twin->mm_per_px, 0.125);
}

TEST(LoopRecordsJson, SmallRecordsRoundTrip) {
  expect_round_trip(residual(1.0), residual_row_from_json);
  ResidualRow both = residual(2.0);
  both.residual_h_mm = -0.25;
  expect_round_trip(both, residual_row_from_json);
  expect_round_trip(RoleRmse{2.5, 1.5, 3, 2}, role_rmse_from_json);
  expect_round_trip(RoleRmse{2.5, std::nullopt, 3, 0}, role_rmse_from_json);
  EXPECT_FALSE(role_rmse_from_json(to_json(RoleRmse{2.5, std::nullopt, 3, 0})).validate_deg);
  expect_round_trip(UnavailableCandidate{"fines", "the declared d_min is 0"},
                    unavailable_candidate_from_json);
  expect_round_trip(RefitTrialRecord{1.0, 0.5, 0.6, 0.2, 1.1}, refit_trial_record_from_json);
  expect_round_trip(RefitFailed{"cohesion", "at 1e4: clogged; ", 5000.0}, refit_failed_from_json);
  expect_round_trip(SimulationCounts{12, 7, 301.5}, simulation_counts_from_json);
  expect_round_trip(score(), candidate_score_from_json);
  expect_round_trip(NullScore{0.01, 2.0, 1.5, 1.8}, null_score_from_json);
  const CandidateScore s = candidate_score_from_json(to_json(score()));
  EXPECT_EQ(s.why, score().why);
  EXPECT_TRUE(s.mu_shift_at_bound);
  EXPECT_FALSE(s.predictive);
}

TEST(LoopRecordsJson, BaselineAndFingerprintRoundTrip) {
  BaselineRecord b;
  b.fit = {0.21, 0.02, 0.0, 0.0, true, {}, Eigen::Matrix2d::Zero(), {}};
  b.seed_sd_deg = 0.9;
  b.seed_se_deg = 0.6;
  b.residuals = {residual(1.0), residual(2.0)};
  b.rmse = {1.2, 0.8, 1, 1};
  const double nan = std::numeric_limits<double>::quiet_NaN();
  b.curves = {{"m4", {0.1, 0.3}, {25.0, 31.0}, {{24.5, 25.5}, {30.0, nan}}, {{1001, 1002}, {1001, 1003}},
               {0, 1}}};
  expect_round_trip(b, baseline_record_from_json);
  const BaselineRecord back = baseline_record_from_json(to_json(b));
  EXPECT_TRUE(back.fit.at_edge);
  EXPECT_TRUE(std::isnan(back.curves[0].angle_seeds_deg[1][1]));  // NaN is null and back
  EXPECT_EQ(back.curves[0].pour_seeds[1][1], 1003u);

  FingerprintRecord f{"plate_friction", 0.15, 0.3, {}, {0.2, 0.3}, {0.075, 0.15}};
  f.change[Channel::kAngle] = {1.0, -0.5};
  f.change[Channel::kH] = {0.4, 0.1};
  f.change[Channel::kD] = {-2.0, 3.0};
  f.change[Channel::kCrest] = {0.5, -0.25};
  expect_round_trip(f, fingerprint_record_from_json);
  EXPECT_EQ(fingerprint_record_from_json(to_json(f)).change[Channel::kD], f.change[Channel::kD]);
  EXPECT_EQ(fingerprint_record_from_json(to_json(f)).change[Channel::kCrest],
            f.change[Channel::kCrest]);
  EXPECT_EQ(fingerprint_record_from_json(to_json(f)).probes_tried, f.probes_tried);
  // Its surface: a grid point with changes, one whose pours failed.
  FingerprintNode at;
  at.mu_r = 0.1;
  at.change[Channel::kAngle] = {2.0, std::numeric_limits<double>::quiet_NaN()};
  at.change[Channel::kH] = {0.7, 0.2};
  at.change[Channel::kD] = {-1.0, 1.5};
  FingerprintNode failed;
  failed.mu_r = 0.2;
  failed.missing = "a run formed no pile";
  f.surface = {at, failed};
  expect_round_trip(f, fingerprint_record_from_json);
  const FingerprintRecord back_f = fingerprint_record_from_json(to_json(f));
  ASSERT_EQ(back_f.surface.size(), 2u);
  EXPECT_EQ(back_f.surface[0].change[Channel::kH], at.change[Channel::kH]);
  EXPECT_TRUE(std::isnan(back_f.surface[0].change[Channel::kAngle][1]));
  EXPECT_EQ(back_f.surface[1].missing, failed.missing);
  EXPECT_TRUE(back_f.surface[1].change[Channel::kAngle].empty());
}

TEST(LoopRecordsJson, EffectsAndIterationsRoundTrip) {
  expect_round_trip(chosen(), chosen_effect_from_json);
  expect_round_trip(NotConfirmed{refit(), 1.7, "t = 0.2 below 1"}, not_confirmed_from_json);
  const ChosenEffect c = chosen_effect_from_json(to_json(chosen()));
  EXPECT_EQ(c.refit.trials.size(), 2u);
  EXPECT_EQ(c.refit.refit_notes, "at 5: no pile; ");

  IterationRecord it;
  it.iteration = 2;
  it.mu_r = 0.2;
  it.null = {0.01, 2.0, 1.5, 1.8};
  it.candidates = {score()};
  expect_round_trip(it, iteration_record_from_json);  // chosen: null
  it.stopped = "max_effects (1) reached";
  it.not_confirmed = NotConfirmed{refit(), 1.7, "no gain"};
  expect_round_trip(it, iteration_record_from_json);
  IterationRecord failed = it;
  failed.refit_failed = RefitFailed{"cohesion", "every pour clogged", 5000.0};
  expect_round_trip(failed, iteration_record_from_json);
  EXPECT_TRUE(iteration_record_from_json(to_json(failed)).refit_failed.has_value());
  EXPECT_FALSE(iteration_record_from_json(to_json(failed)).chosen.has_value());
  IterationRecord with = it;
  with.chosen = chosen();
  expect_round_trip(with, iteration_record_from_json);
  EXPECT_TRUE(iteration_record_from_json(to_json(with)).chosen.has_value());
  // A declared hypothesis (--refit): the iteration's statement and the effect's flag.
  with.declared = "grain_shape is refitted because it was declared (--refit)";
  with.chosen->declared = true;
  expect_round_trip(with, iteration_record_from_json);
  const IterationRecord back = iteration_record_from_json(to_json(with));
  EXPECT_EQ(back.declared, with.declared);
  EXPECT_TRUE(back.chosen->declared);
  // A named candidate's refit set aside for the next contender's, and the ranked contenders.
  with.declared.reset();
  with.chosen->declared = false;
  with.decision.verdict = TraceVerdict::kNamed;
  with.decision.named = "plate_friction";
  with.decision.contenders = {"plate_friction", "grain_shape"};
  with.set_aside = NotConfirmed{refit(), 2.45, "chi^2 55 over 5 degrees of freedom"};
  expect_round_trip(with, iteration_record_from_json);
  const IterationRecord aside = iteration_record_from_json(to_json(with));
  ASSERT_TRUE(aside.set_aside.has_value());
  EXPECT_EQ(aside.set_aside->reason, with.set_aside->reason);
  EXPECT_EQ(aside.decision.contenders, with.decision.contenders);
  // A loop.json written before declared hypotheses reads as trace-chosen.
  nlohmann::json old = to_json(chosen());
  old.erase("declared");
  EXPECT_FALSE(chosen_effect_from_json(old).declared);
}

TEST(LoopRecordsJson, FinalAndProvenanceRoundTrip) {
  FinalRecord f;
  f.fit = {0.19, 0.015, 0.75, 0.1, false, {}, Eigen::Matrix2d::Zero(), {}};
  f.effects = {chosen()};
  f.residuals = {residual(3.0)};
  f.rmse = {0.7, std::nullopt, 1, 0};
  expect_round_trip(f, final_record_from_json);

  LoopProvenance p;
  p.code_version = "v1-abc";
  p.data = "/lab/measured.csv";
  p.angle_measure = "image";
  p.angle_method = "atan(2H/D) on renders";
  p.lab_angle_source = "photos";
  p.seeds = {1001, 1002};
  p.mu_grid = {0.1, 0.3};
  p.mu_key = "contacts.{sample}-{sample}.rolling_friction";
  p.image = "960x720";
  p.cache = "/cache";
  p.finished = "2026-01-01T00:00:00Z";
  p.max_pours = 3;
  p.scenes = {"/a.toml", "/b.toml"};
  expect_round_trip(p, loop_provenance_from_json);
  p.run = json{{"code_version", "v1-abc"}, {"threads", 1}};
  expect_round_trip(p, loop_provenance_from_json);
}

TEST(LoopRecordsJson, AMissingFieldIsAnError) {
  json j = to_json(chosen());
  j.erase("value_se");
  try {
    chosen_effect_from_json(j);
    ADD_FAILURE() << "read without value_se";
  } catch (const JsonFieldError& e) {
    EXPECT_EQ(e.pointer(), "/value_se");
  }
  j = to_json(chosen());
  j["trials"][1]["t"] = "0.75";
  try {
    chosen_effect_from_json(j);
    ADD_FAILURE() << "read a text as t";
  } catch (const JsonFieldError& e) {
    EXPECT_EQ(e.pointer(), "/trials/1/t");
    EXPECT_EQ(e.problem(), "is string, not a number");
  }
}

json committed_loop(const std::string& folder) {
  return json::parse(
      read_file(std::string(REPOSETWIN_SOURCE_DIR) + "/results/" + folder + "/loop.json"));
}

// A loop.json as the loop writes it, read into the LoopRecord and written again: the same JSON,
// field for field (the committed run of the paper's tests with restitution, made by this
// loop.json's writer), but for the candidate registry, which is the code's, written anew; read
// and written once more, the JSON is unchanged with the registry too.
TEST(LoopRecordsJson, ACommittedLoopJsonRoundTrips) {
  json j = committed_loop("paper_loop_restitution");
  const LoopRecord loop = loop_record_from_json(j, "loop.json");
  EXPECT_FALSE(loop.iterations.empty());
  EXPECT_EQ(loop.tests.size(), loop.final_model.residuals.size());
  json again = to_json(loop);
  EXPECT_EQ(to_json(loop_record_from_json(again, "loop.json")), again);
  j.erase("candidate_registry");
  again.erase("candidate_registry");
  EXPECT_EQ(again, j) << json::diff(j, again).dump(1).substr(0, 2000);
}

// The reader refuses a loop.json with one field missing or of the wrong type, naming the file
// and the field's JSON pointer, at every depth.
TEST(LoopRecordsJson, ALoopJsonMissingOrMistypingAFieldIsRefusedByPointer) {
  const json good = committed_loop("paper_loop_restitution");
  auto refusal = [](const json& j) -> std::string {
    try {
      loop_record_from_json(j, "results/x/loop.json");
    } catch (const InputError& e) {
      return e.what();
    }
    return "read";
  };
  for (const std::string pointer :
       {"/summary/reduction", "/baseline/residuals/2/sigma_deg", "/iterations/0/joint/0/chi2",
        "/tests/0/role", "/final/rmse", "/provenance/finished", "/photo_pairs/0/twin/width_px",
        "/grid/statement", "/iterations/0/decision/verdict"}) {
    json j = good;
    const json::json_pointer p(pointer);
    j[p.parent_pointer()].erase(p.back());
    EXPECT_EQ(refusal(j), "results/x/loop.json: " + pointer + ": missing");
  }
  json j = good;
  j["/tests/1/angle_deg"_json_pointer] = "33.5";
  EXPECT_EQ(refusal(j), "results/x/loop.json: /tests/1/angle_deg: is string, not a number");
  j = good;
  j["/iterations/0/candidates/0/accepted"_json_pointer] = 1;
  EXPECT_EQ(
      refusal(j),
      "results/x/loop.json: /iterations/0/candidates/0/accepted: has the wrong type (number)");
  j = good;
  j["/summary/verdict"_json_pointer] = "maybe";
  EXPECT_NE(refusal(j).find("results/x/loop.json: /summary/verdict: "), std::string::npos)
      << refusal(j);
  j = good;
  j["final"]["residuals"].erase(1);
  EXPECT_NE(refusal(j).find("results/x/loop.json: /final/residuals: has "), std::string::npos)
      << refusal(j);
  EXPECT_EQ(refusal(json::array()), "results/x/loop.json: the document: is array, not an object");
}

// Every loop.json committed under results/ reads, but the first paper loop's (written before
// the design, the grid and the joint trace were recorded), which is refused by name.
TEST(LoopRecordsJson, CommittedLoopJsonFilesRead) {
  for (const char* folder :
       {"paper_loop_image", "paper_loop_image_fines", "paper_loop_restitution",
        "loop_validation/cohesion", "loop_validation/lift", "loop_validation/null",
        "loop_validation/plate", "loop_validation/rolling_size", "loop_validation/shape",
        "loop_validation/shape_long", "loop_validation/shape_long_known_plate",
        "loop_validation/shape_low_grid", "loop_validation/shape_repeats"})
    try {
      loop_record_from_json(committed_loop(folder), folder);
    } catch (const InputError& e) {
      ADD_FAILURE() << e.what();
    }
  EXPECT_THROW(loop_record_from_json(committed_loop("paper_loop"), "paper_loop"), InputError);
}

}  // namespace
}  // namespace reposetwin::experiments
