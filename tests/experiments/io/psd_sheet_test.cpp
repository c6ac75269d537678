// Sieve sheets as CSV: the same reader and rules as the TOML tables, the header's columns named
// in every refusal, and the one rule for relative paths (a path in a file is relative to that
// file, one typed on the command line to the working folder).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "../../support/tiny_scene.hpp"
#include "experiments/campaign/campaign.hpp"
#include "experiments/io/campaign_file.hpp"
#include "experiments/io/psd_file.hpp"
#include "experiments/io/scene.hpp"
#include "experiments/io/scene_overrides.hpp"
#include "experiments/pile/run_plan.hpp"

namespace reposetwin::experiments {
namespace {

namespace fs = std::filesystem;

fs::path dir_of(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("reposetwin_psd_sheet_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::string write(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << text;
  return p.string();
}

// The error a reader throws for `text` as a sheet, or "" when it reads.
std::string refusal(const std::string& text) {
  const std::string path = write(dir_of("bad") / "sheet.csv", text);
  try {
    read_psd_file(path);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(PsdSheet, ACsvSheetReadsAsTheSameTableInToml) {
  const fs::path d = dir_of("same");
  const PsdFile csv = read_psd_file(write(d / "rock.csv",
                                          "\xEF\xBB\xBF# lab sheet 12\n"
                                          "sieve_mm,passing_percent\n"
                                          "0.5,10\n1,30.0\n 2.0 , 60\n4.0,100\r\n"));
  const PsdFile toml = read_psd_file(write(d / "rock.toml",
                                           "[psd]\nsieve_mm = [0.5, 1, 2.0, 4.0]\n"
                                           "passing_percent = [10, 30.0, 60, 100]\n"));
  EXPECT_EQ(csv.spec.table.size, toml.spec.table.size);
  EXPECT_EQ(csv.spec.table.passing, toml.spec.table.passing);
  EXPECT_EQ(csv.name, "rock");
  EXPECT_NE(csv.provenance.find("lab sheet 12"), std::string::npos) << csv.provenance;
  // Columns in the other order read the same.
  const PsdFile swapped = read_psd_file(
      write(d / "swapped.CSV", "passing_percent,sieve_mm\n10,0.5\n30,1\n60,2\n100,4\n"));
  EXPECT_EQ(swapped.spec.table.size, toml.spec.table.size);
  EXPECT_EQ(swapped.spec.table.passing, toml.spec.table.passing);
}

TEST(PsdSheet, OtherHeadersAreRefusedNamingTheColumn) {
  struct Case {
    const char* text;
    std::vector<std::string> says;
  };
  const Case cases[] = {
      {"size_mm,passing_percent\n1,0\n2,100\n", {"sheet.csv:1", "\"size_mm\"", kCsvHeader}},
      {"sieve_mm,passing\n1,0\n2,100\n", {"column 2", "\"passing\"", kCsvHeader}},
      {"sieve_mm,passing_percent,retained\n1,0,5\n2,100,0\n", {"\"retained\""}},
      {"sieve_mm\n1\n2\n", {"lacks \"passing_percent\""}},
      {"sieve_mm,sieve_mm\n1,1\n", {"\"sieve_mm\" is named twice"}},
      {"sieve_mm,passing_percent\n1,0\n2,all\n", {"sheet.csv:3", "passing_percent = \"all\""}},
      {"sieve_mm,passing_percent\n1,0\n2\n", {"sheet.csv:3", "1 fields, the header has 2"}},
      {"sieve_mm,passing_percent\n", {"no sieves"}},
      {"sieve_mm,passing_percent\n2,0\n1,100\n", {"columns sieve_mm / passing_percent"}},
      {"sieve_mm = [1, 2]\n", {"sieve_mm = [1", kCsvHeader}},
  };
  for (const Case& c : cases) {
    const std::string what = refusal(c.text);
    ASSERT_FALSE(what.empty()) << c.text;
    for (const std::string& s : c.says) EXPECT_NE(what.find(s), std::string::npos) << what;
  }
}

// A sheet listed coarsest first (as a lab sheet often starts at the top sieve), or in percent
// retained on each sieve or cumulative, reads as the same table, and its note says how it was read.
TEST(PsdSheet, EitherOrderAndPercentRetainedReadAsTheSameTable) {
  const fs::path d = dir_of("forms");
  const PsdFile passing = read_psd_file(
      write(d / "passing.csv", "sieve_mm,passing_percent\n0.5,10\n1,30\n2,60\n4,100\n"));
  EXPECT_TRUE(passing.note.empty()) << passing.note;
  const PsdFile coarse_first = read_psd_file(
      write(d / "coarse.csv", "sieve_mm,passing_percent\n4,100\n2,60\n1,30\n0.5,10\n"));
  EXPECT_EQ(coarse_first.spec.table.size, passing.spec.table.size);
  EXPECT_EQ(coarse_first.spec.table.passing, passing.spec.table.passing);
  EXPECT_NE(coarse_first.note.find("listed coarsest first"), std::string::npos);
  // Retained on each sieve, top sieve first: 0 on 4 mm, 40 on 2, 30 on 1, 20 on 0.5, 10 in the pan.
  const PsdFile retained = read_psd_file(
      write(d / "retained.csv", "sieve_mm,retained_percent\n4,0\n2,40\n1,30\n0.5,20\n"));
  EXPECT_EQ(retained.spec.table.size, passing.spec.table.size);
  ASSERT_EQ(retained.spec.table.passing.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i)
    EXPECT_NEAR(retained.spec.table.passing[i], passing.spec.table.passing[i], 1e-12) << i;
  EXPECT_NE(retained.note.find("percent retained on each sieve converted"), std::string::npos)
      << retained.note;
  const PsdFile cumulative = read_psd_file(write(
      d / "cumulative.csv", "cumulative_retained_percent,sieve_mm\n90,0.5\n70,1\n40,2\n0,4\n"));
  EXPECT_EQ(cumulative.spec.table.passing, passing.spec.table.passing);
  EXPECT_NE(cumulative.note.find("cumulative percent retained"), std::string::npos);
  // The TOML form may be listed coarsest first too.
  const PsdFile toml = read_psd_file(write(d / "coarse.toml",
                                           "[psd]\nsieve_mm = [4, 2, 1, 0.5]\n"
                                           "passing_percent = [100, 60, 30, 10]\n"));
  EXPECT_EQ(toml.spec.table.passing, passing.spec.table.passing);
  // Percent retained that is not (it sums above 100), and a misspelt column, are refused.
  EXPECT_NE(refusal("sieve_mm,retained_percent\n4,0\n2,70\n1,50\n").find("sums to 120"),
            std::string::npos);
  EXPECT_NE(refusal("sieve_mm,retained_percnt\n4,0\n2,70\n")
                .find("did you mean \"retained_percent\"?"),
            std::string::npos)
      << refusal("sieve_mm,retained_percnt\n4,0\n2,70\n");
}

// A run's plan says how its sieve sheet was read when not as written.
TEST(PsdSheet, ThePlanSaysASheetWasConverted) {
  const fs::path d = dir_of("plan");
  const std::string scene = write(d / "tiny.toml", test_support::kTinyScene);
  const std::string sheet =
      write(d / "retained.csv", "sieve_mm,retained_percent\n4.0,0\n3.5,50\n3.0,50\n");
  const RunPlan plan = plan_run(load_scene(scene, {"sample.psd_file=" + sheet}), 1);
  const std::string text = plan_text(plan);
  EXPECT_NE(text.find("plan: the sieve sheet " + sheet + ": listed coarsest first"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("percent retained on each sieve converted"), std::string::npos) << text;
}

// A scene names its sheet relative to its own folder; the run folder's resolved scene carries the
// sheet as a table, so it loads from anywhere.
TEST(PsdSheet, ASceneReadsItsCsvSheetRelativeToItsOwnFolder) {
  const fs::path d = dir_of("scene");
  // A sheet of the same name beside the working folder must not be the one read.
  write(d / "sheets" / "tiny.csv", "sieve_mm,passing_percent\n3.0,0\n3.9,50\n4.0,100\n");
  std::string text = test_support::kTinyScene;
  const std::string inline_psd =
      "[sample.psd]\nsieve_mm = [3.0, 3.5, 4.0]\npassing_percent = [0.0, 50.0, 100.0]\n";
  text.replace(text.find(inline_psd), inline_psd.size(), "");
  text.replace(text.find("material = \"rock\"\n"), 18,
               "material = \"rock\"\npsd_file = \"sheets/tiny.csv\"\n");
  write(d / "scenes" / "sheets" / "tiny.csv", "sieve_mm,passing_percent\n3.0,0\n3.5,50\n4.0,100\n");
  const std::string scene_path = write(d / "scenes" / "s.toml", text);
  const fs::path cwd = fs::current_path();
  fs::current_path(d);  // not the scene's folder
  const SceneConfig s = load_scene(scene_path);
  fs::current_path(cwd);
  EXPECT_EQ(fs::path(s.psd.source).lexically_normal(),
            (d / "scenes" / "sheets" / "tiny.csv").lexically_normal());
  EXPECT_DOUBLE_EQ(s.psd.spec.table.size[1], 3.5e-3);
  EXPECT_NE(s.resolved_toml.find("passing_percent"), std::string::npos);
  EXPECT_EQ(s.resolved_toml.find("psd_file"), std::string::npos);
  EXPECT_NO_THROW(parse_scene_text(s.resolved_toml, (d / "elsewhere.toml").string()));
}

// --set is typed on the command line: its path is relative to the working folder.
TEST(PsdSheet, ASetPathIsRelativeToTheWorkingFolder) {
  const fs::path d = dir_of("set");
  write(d / "work" / "mine.csv", "sieve_mm,passing_percent\n3.0,0\n3.6,40\n4.0,100\n");
  const std::string scene_path = write(d / "scenes" / "s.toml", test_support::kTinyScene);
  const fs::path cwd = fs::current_path();
  fs::current_path(d / "work");
  SceneConfig s;
  EXPECT_NO_THROW(s = load_scene(scene_path, {"sample.psd_file=mine.csv"}));
  fs::current_path(cwd);
  ASSERT_EQ(s.psd.spec.table.size.size(), 3u);
  EXPECT_DOUBLE_EQ(s.psd.spec.table.size[1], 3.6e-3);
}

// A campaign file's overrides are written in the campaign file: a sheet named there is found
// beside it, not beside the scene.
TEST(PsdSheet, ACampaignOverridePathIsRelativeToTheCampaignFile) {
  const fs::path d = dir_of("campaign");
  std::string text = test_support::kTinyScene;
  const std::string inline_psd =
      "[sample.psd]\nsieve_mm = [3.0, 3.5, 4.0]\npassing_percent = [0.0, 50.0, 100.0]\n";
  text.replace(text.find(inline_psd), inline_psd.size(), "");
  text.replace(text.find("material = \"rock\"\n"), 18,
               "material = \"rock\"\npsd_file = \"base.csv\"\n");
  write(d / "scenes" / "base.csv", "sieve_mm,passing_percent\n3.0,0\n3.5,50\n4.0,100\n");
  write(d / "scenes" / "s.toml", text);
  write(d / "study" / "lab.csv", "sieve_mm,passing_percent\n3.0,0\n3.2,70\n4.0,100\n");
  const std::string campaign =
      write(d / "study" / "c.toml",
            "name = \"sheets\"\nscene = \"../scenes/s.toml\"\nseeds = [1]\n"
            "[[case]]\nname = \"lab\"\noverrides = { \"sample.psd_file\" = \"lab.csv\" }\n");
  const Campaign c = read_campaign_file(campaign);
  ASSERT_EQ(c.runs.size(), 1u);
  const SceneConfig s = build_case_scene(c.runs[0]).config();
  EXPECT_EQ(fs::path(s.psd.source).lexically_normal(),
            (d / "study" / "lab.csv").lexically_normal());
  EXPECT_DOUBLE_EQ(s.psd.spec.table.passing[1], 70.0);
}

}  // namespace
}  // namespace reposetwin::experiments
