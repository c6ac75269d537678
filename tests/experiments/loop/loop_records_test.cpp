// The loop's records and their loop.json fields: the RMSE by role, an iteration's `chosen`
// field in each of its three forms, and the summary made from the baseline and final records.
#include "experiments/loop/loop_records.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace reposetwin::experiments {
namespace {

ResidualRow row(Role role, double residual) {
  ResidualRow r;
  r.id = role_name(role) + std::to_string(residual);
  r.role = role;
  r.residual_deg = residual;
  return r;
}

// One naming of the traced observables: the joint trace's names map to the channel that
// indexes the model, the noise and the fingerprint's columns, and back; a name the trace never
// gives is an error, not the crest.
TEST(LoopRecords, ChannelsMapByNameToTheFingerprintsColumns) {
  FingerprintRecord f;
  for (Channel c : kAllChannels) f.change[c] = {1.0 + static_cast<double>(c)};
  for (Channel c : kAllChannels) {
    EXPECT_EQ(channel_from_name(channel_name(c)), c);
    EXPECT_EQ(f.change[channel_from_name(channel_name(c))].front(), 1.0 + static_cast<double>(c));
  }
  EXPECT_EQ(channel_from_name("H"), Channel::kH);
  EXPECT_STREQ(channel_unit(Channel::kAngle), "deg");
  EXPECT_STREQ(channel_unit(Channel::kCrest), "mm");
  EXPECT_THROW(channel_from_name("theta"), std::logic_error);
  // loop.json keeps its keys per channel.
  const nlohmann::json j = to_json(f);
  EXPECT_EQ(j["angle_deg"][0], 1.0);
  EXPECT_EQ(j["H_mm"][0], 2.0);
  EXPECT_EQ(j["D_mm"][0], 3.0);
  EXPECT_EQ(j["crest_mm"][0], 4.0);
}

TEST(LoopRecords, RmseByRoleSplitsCalibrationAndValidation) {
  const RoleRmse r =
      rmse_by_role(
      {row(Role::kCalibrate, 3.0), row(Role::kCalibrate, -4.0), row(Role::kValidate, 2.0)});
  EXPECT_DOUBLE_EQ(r.calibrate_deg, std::sqrt(12.5));
  ASSERT_TRUE(r.validate_deg.has_value());
  EXPECT_DOUBLE_EQ(*r.validate_deg, 2.0);
  const nlohmann::json j = to_json(r);
  EXPECT_EQ(j["n_calibrate"], 2);
  EXPECT_EQ(j["n_validate"], 1);
  // Without validation tests the field is null, not 0.
  EXPECT_TRUE(to_json(rmse_by_role({row(Role::kCalibrate, 1.0)}))["validate_deg"].is_null());
}

TEST(LoopRecords, ResidualRowWritesLabHAndDOnlyWhenMeasured) {
  ResidualRow r = row(Role::kCalibrate, 1.0);
  EXPECT_FALSE(to_json(r).contains("residual_H_mm"));
  r.residual_h_mm = 0.5;
  r.residual_d_mm = -2.0;
  const nlohmann::json j = to_json(r);
  EXPECT_EQ(j["residual_H_mm"], 0.5);
  EXPECT_EQ(j["residual_D_mm"], -2.0);
}

TEST(LoopRecords, IterationChosenIsNullARefitFailureOrTheEffect) {
  IterationRecord it;
  it.iteration = 1;
  it.stopped = "max_effects (1) reached";
  nlohmann::json j = to_json(it);
  EXPECT_TRUE(j["chosen"].is_null());
  EXPECT_EQ(j["stopped"], "max_effects (1) reached");
  EXPECT_FALSE(j.contains("not_confirmed"));

  it = {};
  it.refit_failed = RefitFailed{"plate_friction", "at 0.1: no pile; ", 0.1};
  j = to_json(it);
  EXPECT_EQ(j["chosen"]["refit_failed"], "at 0.1: no pile; ");
  EXPECT_EQ(j["chosen"]["linear_estimate"], 0.1);

  it = {};
  it.not_confirmed = NotConfirmed{{"lift_speed", 2.0, 2.0, 0.0, 0.2, {}, ""}, 1.0, "t = 0"};
  j = to_json(it);
  EXPECT_TRUE(j["chosen"].is_null());
  EXPECT_EQ(j["not_confirmed"]["reason"], "t = 0");

  it = {};
  ChosenEffect c;
  c.refit.name = "plate_friction";
  c.refit.trials = {{0.2, 0.6, 0.9, 0.25, 0.8}};
  it.chosen = c;
  j = to_json(it);
  EXPECT_EQ(j["chosen"]["name"], "plate_friction");
  EXPECT_EQ(j["chosen"]["trials"][0]["response_fraction"], 0.6);
}

TEST(LoopRecords, SummaryComparesTheBaselineAndFinalModels) {
  LoopRecord loop;
  loop.baseline.rmse.calibrate_deg = 4.0;
  loop.baseline.seed_se_deg = 0.5;
  loop.rule.loo_margin_factor = 2.0;
  loop.final_model.rmse.calibrate_deg = 1.0;
  loop.final_model.rmse.validate_deg = 1.5;
  ChosenEffect c;
  c.refit.name = "plate_friction";
  loop.final_model.effects = {c};
  loop.summary = summarise(loop);
  EXPECT_EQ(loop.summary.verdict, std::nullopt) << "no iteration, no verdict";
  const nlohmann::json j = to_json(loop);
  EXPECT_EQ(j["summary"]["chosen"], "plate_friction");
  EXPECT_EQ(j["summary"]["effects"], nlohmann::json::array({"plate_friction"}));
  EXPECT_DOUBLE_EQ(j["summary"]["reduction"].get<double>(), 0.75);
  EXPECT_TRUE(j["summary"]["rmse_validate_before_deg"].is_null());
  EXPECT_EQ(j["summary"]["rmse_validate_after_deg"], 1.5);
  EXPECT_DOUBLE_EQ(j["rule"]["loo_margin_deg"].get<double>(), 1.0);
  EXPECT_FALSE(j["candidate_registry"].empty());
  EXPECT_FALSE(j["provenance"].contains("run"));
}

// No effect chosen: the verdict is the last iteration's trace, unless the simulations did not
// bear its refit out, and the statement says so (a trace that named plate_friction is not the
// end of the story when the refit was then not confirmed).
TEST(LoopRecords, SummarySaysWhenTheSimulatedRefitDidNotConfirm) {
  LoopRecord loop;
  IterationRecord it;
  it.decision.verdict = TraceVerdict::kNamed;
  it.decision.statement = "named plate_friction";
  loop.iterations = {it};
  EXPECT_EQ(summarise(loop).verdict, Verdict::kNamed);
  loop.iterations[0].not_confirmed =
      NotConfirmed{{"plate_friction", 0.67, 0.67, 1.6, 0.47, {}, ""}, 1.59, "RMSE 2.55 to 1.59"};
  EXPECT_EQ(summarise(loop).verdict, Verdict::kNotConfirmed);
  EXPECT_EQ(summarise(loop).statement,
            "iteration 0: named plate_friction; plate_friction not confirmed by "
            "the simulated refit: RMSE 2.55 to 1.59");
  loop.iterations[0].not_confirmed.reset();
  loop.iterations[0].refit_failed = RefitFailed{"plate_friction", "at 0.67: no pile; ", 0.67};
  loop.summary = summarise(loop);
  EXPECT_EQ(loop.summary.verdict, Verdict::kRefitFailed);
  // to_json writes the verdict summarise decided, as its word; from_json reads it back.
  const nlohmann::json s = to_json(loop)["summary"];
  EXPECT_EQ(s["verdict"], "refit_failed");
  EXPECT_NE(s["statement"].get<std::string>().find("could not be simulated: at 0.67: no pile"),
            std::string::npos);
  EXPECT_EQ(loop_summary_from_json(s).verdict, Verdict::kRefitFailed);
  EXPECT_EQ(loop_summary_from_json(s).statement, loop.summary.statement);
  // A chosen effect is named, or declared when it was the user's hypothesis; a loop that traced
  // nothing is not_traced whatever its iterations say.
  ChosenEffect c;
  c.refit.name = "plate_friction";
  loop.final_model.effects = {c};
  EXPECT_EQ(summarise(loop).verdict, Verdict::kNamed);
  loop.final_model.effects[0].declared = true;
  EXPECT_EQ(summarise(loop).verdict, Verdict::kDeclared);
  loop.not_traced = "mu_r on the grid's bound";
  EXPECT_EQ(summarise(loop).verdict, Verdict::kNotTraced);
  EXPECT_EQ(summarise(loop).statement, "mu_r on the grid's bound");
}

// Every verdict's word reads back as that verdict, and an unknown word is refused by name.
TEST(LoopRecords, VerdictWordsRoundTrip) {
  for (Verdict v : {Verdict::kNothing, Verdict::kNamed, Verdict::kIndistinguishable,
                    Verdict::kMeasurementSuspected, Verdict::kDeclared, Verdict::kNotConfirmed,
                    Verdict::kRefitFailed, Verdict::kNotTraced})
    EXPECT_EQ(parse_verdict(verdict_name(v)), v);
  EXPECT_STREQ(verdict_name(verdict_of(TraceVerdict::kMeasurementSuspected)),
               "measurement_suspected");
  try {
    (void)parse_verdict("maybe");
    ADD_FAILURE() << "an unknown verdict was read";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("\"maybe\""), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace reposetwin::experiments
