#include "experiments/io/toml_edit.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace reposetwin::experiments {
namespace {

toml::table scene() {
  return toml::parse(R"(
seed = 7
[rolling]
model = "epsd"
mu_r = 0.1
[sample]
mass = 0.2
count = 100
[[walls]]
name = "plate"
friction = 0.3
[[walls]]
name = "funnel"
friction = 0.4
)");
}

std::string error_of(toml::table& doc, const std::string& key, const toml::node& v) {
  try {
    apply_override(doc, key, v, "test.toml, case c1");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(Overrides, SetsANestedFloat) {
  auto doc = scene();
  apply_override(doc, "rolling.mu_r", toml::value<double>(0.125));
  EXPECT_DOUBLE_EQ(doc["rolling"]["mu_r"].value<double>().value(), 0.125);
  EXPECT_EQ(doc["rolling"]["model"].value<std::string>().value(), "epsd");  // sibling untouched
}

TEST(Overrides, IntegerStandsForFloatAndBecomesFloat) {
  auto doc = scene();
  apply_override(doc, "sample.mass", toml::value<std::int64_t>(1));
  ASSERT_TRUE(doc["sample"]["mass"].is_floating_point());
  EXPECT_DOUBLE_EQ(doc["sample"]["mass"].value<double>().value(), 1.0);
}

TEST(Overrides, TypeChangeIsAnErrorNamingTheKey) {
  auto doc = scene();
  const auto e1 = error_of(doc, "sample.count", toml::value<double>(2.5));  // float -> int
  EXPECT_NE(e1.find("sample.count"), std::string::npos) << e1;
  EXPECT_NE(e1.find("test.toml, case c1"), std::string::npos) << e1;
  EXPECT_NE(e1.find("2.5"), std::string::npos) << e1;
  const auto e2 = error_of(doc, "rolling.mu_r", toml::value<std::string>("0.1"));  // string
  EXPECT_NE(e2.find("rolling.mu_r"), std::string::npos) << e2;
  EXPECT_DOUBLE_EQ(doc["rolling"]["mu_r"].value<double>().value(), 0.1);  // unchanged
}

TEST(Overrides, MissingParentIsAnError) {
  auto doc = scene();
  const auto e = error_of(doc, "rolling.spring.k", toml::value<double>(1.0));
  EXPECT_NE(e.find("rolling.spring.k"), std::string::npos) << e;
  EXPECT_NE(e.find("does not exist"), std::string::npos) << e;
  EXPECT_FALSE(error_of(doc, "nosuch.key", toml::value<double>(1.0)).empty());
  // A scalar cannot be a parent.
  EXPECT_FALSE(error_of(doc, "seed.x", toml::value<double>(1.0)).empty());
}

TEST(Overrides, NewLeafUnderAnExistingTableIsAllowed) {
  auto doc = scene();
  apply_override(doc, "rolling.damping", toml::value<double>(0.3));
  EXPECT_DOUBLE_EQ(doc["rolling"]["damping"].value<double>().value(), 0.3);
}

TEST(Overrides, TablesTheSceneFormatHasAreCreatedOthersRefused) {
  auto doc = scene();
  const auto scene_tables = MissingTables::kSceneTables;
  apply_override(doc, "sample.shape.elongation", toml::value<double>(1.5), "c", scene_tables);
  EXPECT_DOUBLE_EQ(doc["sample"]["shape"]["elongation"].value<double>().value(), 1.5);
  EXPECT_DOUBLE_EQ(doc["sample"]["mass"].value<double>().value(), 0.2);  // sibling untouched
  apply_override(doc, "contacts.rock-plate.friction", toml::value<double>(0.4), "c",
                 scene_tables);
  EXPECT_DOUBLE_EQ(doc["contacts"]["rock-plate"]["friction"].value<double>().value(), 0.4);
  // No scene has [rolling.spring] or a [sample.shapes] table (it is an array of tables).
  for (const char* key : {"rolling.spring.k", "sample.shapes.0.elongation"}) {
    std::string e;
    try {
      apply_override(doc, key, toml::value<double>(1.0), "test.toml, case c1", scene_tables);
    } catch (const std::invalid_argument& x) {
      e = x.what();
    }
    EXPECT_NE(e.find(key), std::string::npos) << e;
    EXPECT_NE(e.find("does not exist"), std::string::npos) << e;
    EXPECT_NE(e.find("reposetwin keys"), std::string::npos) << e;
  }
  EXPECT_FALSE(doc["rolling"]["spring"]);
  // --set's rule creates any table and leaves the judgement to the strict parser.
  apply_override(doc, "rolling.spring.k", toml::value<double>(1.0), "--set",
                 MissingTables::kCreate);
  EXPECT_DOUBLE_EQ(doc["rolling"]["spring"]["k"].value<double>().value(), 1.0);
}

TEST(Overrides, ATableValueIsSetWhole) {
  auto doc = scene();
  apply_override(doc, "rolling", toml::table{{"model", "cdt"}});
  EXPECT_EQ(doc["rolling"]["model"].value<std::string>().value(), "cdt");
  EXPECT_FALSE(doc["rolling"]["mu_r"]);  // replaced, not merged
  apply_override(doc, "sample.shape", toml::table{{"kind", "generated"}, {"spheres", 4}});
  EXPECT_EQ(doc["sample"]["shape"]["spheres"].value<std::int64_t>().value(), 4);
  EXPECT_FALSE(error_of(doc, "seed", toml::table{{"a", 1}}).empty());  // an integer there
}

TEST(Overrides, ArrayIndexSegments) {
  auto doc = scene();
  apply_override(doc, "walls.1.friction", toml::value<double>(0.55));
  EXPECT_DOUBLE_EQ(doc["walls"][1]["friction"].value<double>().value(), 0.55);
  EXPECT_DOUBLE_EQ(doc["walls"][0]["friction"].value<double>().value(), 0.3);
  const auto e = error_of(doc, "walls.2.friction", toml::value<double>(0.5));
  EXPECT_NE(e.find("out of range"), std::string::npos) << e;
}

TEST(Overrides, MalformedKeysAreErrors) {
  auto doc = scene();
  for (const char* k : {"", ".a", "a.", "rolling..mu_r"})
    EXPECT_THROW(apply_override(doc, k, toml::value<double>(1.0)), std::invalid_argument) << k;
}

TEST(Overrides, WholeTableBeforeItsMembers) {
  auto doc = scene();
  toml::table ov;
  ov.insert("rolling.mu_r", 0.3);
  ov.insert("rolling", toml::table{{"model", "cdt"}, {"mu_r", 0.2}});
  apply_overrides(doc, ov);
  EXPECT_EQ(doc["rolling"]["model"].value<std::string>().value(), "cdt");
  EXPECT_DOUBLE_EQ(doc["rolling"]["mu_r"].value<double>().value(), 0.3);
}

TEST(Overrides, SplitDottedKey) {
  const auto p = split_dotted_key("a.b.c");
  ASSERT_EQ(p.size(), 3u);
  EXPECT_EQ(p[0], "a");
  EXPECT_EQ(p[2], "c");
}

}  // namespace
}  // namespace reposetwin::experiments
