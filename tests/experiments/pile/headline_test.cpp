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
  EXPECT_FALSE(to_json(clogged).contains("headline_angle_deg"));
}

}  // namespace
}  // namespace reposetwin::experiments
