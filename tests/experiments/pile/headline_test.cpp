// The one headline angle: taken from the side photographs' summary, or from the particles and
// saying so; every measure named in the outputs is defined in docs/measures.md.
#include "experiments/pile/headline.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "experiments/campaign/case_runner.hpp"

namespace reposetwin::experiments {
namespace {

TEST(Headline, FromImagesIsTheSideViewsMeanAtan2HD) {
  const nlohmann::json m = {{"side_summary",
                             {{"views", 4},
                              {"H_m", {{"mean", 0.0156}, {"stddev", 0.0001}}},
                              {"D_m", {{"mean", 0.0813}, {"stddev", 0.002}}},
                              {"theta_deg", {{"mean", 20.97}, {"stddev", 0.71}}}}}};
  const Headline h = headline_from_images(m);
  EXPECT_DOUBLE_EQ(h.angle_deg, 20.97);
  EXPECT_DOUBLE_EQ(h.angle_sd_deg, 0.71);
  EXPECT_DOUBLE_EQ(h.height_m, 0.0156);
  EXPECT_DOUBLE_EQ(h.diameter_m, 0.0813);
  EXPECT_EQ(h.views, 4);
  const nlohmann::json j = to_json(h);
  EXPECT_EQ(j["headline_measure"], "image atan(2H/D), side views");
  EXPECT_THROW(headline_from_images(nlohmann::json::object()), std::invalid_argument);
}

TEST(Headline, WithoutImagesItIsTheParticleAngleAndSaysSo) {
  PileMeasure p;
  p.theta_hd_deg = 23.6;
  p.height_m = 0.0158;
  p.base_diameter_m = 0.0725;
  const Headline h = headline_from_particles(p);
  EXPECT_DOUBLE_EQ(h.angle_deg, 23.6);
  EXPECT_FALSE(h.from_images);
  EXPECT_NE(h.measure.find("--no-images"), std::string::npos);
}

// Only a settled, measured pile has a headline; every other end says why, in its own words.
TEST(Headline, NoHeadlineWithoutASettledMeasuredPile) {
  PileMeasure ok;
  ok.status = sim::PileStatus::kOk;
  RunStop settled;
  EXPECT_FALSE(no_headline(settled, ok));
  const RunStop time_limit{StopReason::kTimeLimit, sim::Status::kOk,
                           "procedure.max_time_s = 0.3 s reached while filling", ""};
  const RunStop unsettled{StopReason::kSettleTimeLimit, sim::Status::kOk, "still moving", ""};
  const RunStop jam{StopReason::kClogged, sim::Status::kOk, "12 particles lodged", ""};
  const RunStop nan{StopReason::kPhysics, sim::Status::kNan, "particle 3", ""};
  const struct {
    RunStop stop;
    PileMeasure pile;
    NoHeadlineReason reason;
    const char* word;
    const char* says;
  } cases[] = {
      {time_limit, ok, NoHeadlineReason::kTimeLimit, "time_limit", "while filling"},
      {unsettled, ok, NoHeadlineReason::kNotSettled, "not_settled", "did not settle"},
      {jam, clogged_pile(12, "12 particles lodged"), NoHeadlineReason::kJammed, "jam", "jammed"},
      {nan, unmeasured_pile("nan"), NoHeadlineReason::kPhysicsStop, "physics_stop", "physics: nan"},
      {settled, PileMeasure{}, NoHeadlineReason::kNoPile, "no_pile", "formed no pile"},
  };
  for (const auto& c : cases) {
    const auto n = no_headline(c.stop, c.pile);
    ASSERT_TRUE(n) << c.word;
    EXPECT_EQ(n->reason, c.reason);
    EXPECT_STREQ(no_headline_word(n->reason), c.word);
    EXPECT_NE(n->message.find(c.says), std::string::npos) << n->message;
    EXPECT_FALSE(no_headline_advice(n->reason).empty());
    const nlohmann::json j = to_json(*n);
    EXPECT_TRUE(j.at("headline_angle_deg").is_null());
    EXPECT_EQ(j["no_headline"]["reason"], c.word);
  }
  PileMeasure no_flanks = ok;
  no_flanks.status = sim::PileStatus::kNoFlanks;
  EXPECT_EQ(no_headline(settled, no_flanks)->reason, NoHeadlineReason::kNoPile);
}

TEST(Headline, EveryMeasureIsDefinedInTheDocs) {
  std::ifstream in(std::filesystem::path(REPOSETWIN_SOURCE_DIR) / "docs" / "measures.md");
  std::stringstream s;
  s << in.rdbuf();
  const std::string doc = s.str();
  ASSERT_FALSE(doc.empty());
  for (const MeasureDefinition& d : measure_definitions()) {
    std::string name = d.name;  // "a, b" names two fields
    for (std::size_t start = 0;;) {
      const std::size_t comma = name.find(", ", start);
      const std::string field = name.substr(start, comma - start);
      EXPECT_NE(doc.find("`" + field + "`"), std::string::npos) << field << " missing in docs";
      if (comma == std::string::npos) break;
      start = comma + 2;
    }
    EXPECT_NE(doc.find(d.definition), std::string::npos) << d.name << ": definition differs";
  }
}

TEST(Headline, ACasesResultCarriesItUnderTheSameName) {
  CaseResult r;
  r.pile.status = sim::PileStatus::kOk;
  r.pile.theta_hd_deg = 23.6;
  EXPECT_EQ(to_json(r)["headline_measure"], kHeadlineFromParticles);
  EXPECT_DOUBLE_EQ(to_json(r)["headline_angle_deg"].get<double>(), 23.6);
  r.image = CaseImages{20.97, 0.71, 0.0156, 0.0813, 26.45, "run/images"};
  const nlohmann::json j = to_json(r);
  EXPECT_EQ(j["headline_measure"], kHeadlineFromImages);
  EXPECT_DOUBLE_EQ(j["headline_angle_deg"].get<double>(), 20.97);
  EXPECT_DOUBLE_EQ(j["image"]["theta_deg"].get<double>(), 20.97);  // the old field is kept
  CaseResult clogged;
  clogged.pile = clogged_pile(12, "arched");
  EXPECT_TRUE(to_json(clogged)["headline_angle_deg"].is_null());
  EXPECT_EQ(to_json(clogged)["no_headline"]["reason"], "jam");
}

}  // namespace
}  // namespace reposetwin::experiments
