// The paper's index: read strictly, every listed file loads, the planned cost fits the budget,
// and a tiny index over the tiny scene runs end to end and resumes.
#include "experiments/reproduce/paper_index.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include "../../support/tiny_scene.hpp"
#include "experiments/campaign/case_runner.hpp"
#include "experiments/io/provenance.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

struct Scratch {
  explicit Scratch(const std::string& name)
      : path(fs::temp_directory_path() /
             ("reposetwin_paper_index_test_" + std::to_string(::getpid()) + "_" + name)) {
    fs::remove_all(path);
    fs::create_directories(path);
    write_file_atomic((path / "tiny.toml").string(), test_support::kTinyScene);
    write_file_atomic((path / "sweep.toml").string(),
                      "name = \"tiny_sweep\"\nscene = \"tiny.toml\"\nseeds = [1, 2]\n"
                      "[sweep]\nkey = \"contacts.rock-rock.rolling_friction\"\nvalues = [0.3]\n");
    write_file_atomic((path / "cal.toml").string(),
                      "name = \"tiny_cal\"\nscene = \"tiny.toml\"\n[calibration]\n"
                      "key = \"contacts.rock-rock.rolling_friction\"\ntarget_deg = 20.0\n"
                      "mu_r_range = [0.1, 0.5]\nmethod = \"bracket\"\nmax_simulations = 4\n"
                      "angle = \"particles\"\nbootstrap_replicates = 200\n");
  }
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  fs::path write(const std::string& text) const {
    write_file_atomic((path / "index.toml").string(), text);
    return path / "index.toml";
  }
  fs::path path;
};

constexpr const char* kTinyIndex = R"TOML(title = "tiny"
budget_cpu_hours = 1.0
[[item]]
name = "sweep"
paper = "Fig. 6"
kind = "campaign"
file = "sweep.toml"
reductions = "the tiny scene"
x_key = "contacts.rock-rock.rolling_friction"
[item.paper_points]
x = [0.3]
y = [22.0]
source = "a test"
[[item]]
name = "cal"
paper = "Table 3"
kind = "calibration"
file = "cal.toml"
reductions = "the tiny scene"
[[item]]
name = "mu_r_vs_dmax"
paper = "Fig. 7"
kind = "derived"
from = ["cal"]
reductions = "none (drawn from cal)"
)TOML";

std::string index_error(const Scratch& d, const std::string& text) {
  try {
    load_paper_index(d.write(text).string());
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(PaperIndex, ReadsTheTinyIndex) {
  const Scratch d("read");
  const PaperIndex idx = load_paper_index(d.write(kTinyIndex).string());
  ASSERT_EQ(idx.items.size(), 3u);
  EXPECT_EQ(idx.items[0].kind, PaperItemKind::kCampaign);
  EXPECT_EQ(idx.items[1].kind, PaperItemKind::kCalibration);
  EXPECT_EQ(idx.items[2].kind, PaperItemKind::kDerived);
  ASSERT_TRUE(idx.items[0].paper_points);
  EXPECT_DOUBLE_EQ(idx.items[0].paper_points->y[0], 22.0);
  // Campaign: its two runs; calibration: its budget of four pours; derived: nothing.
  EXPECT_EQ(plan_item(idx.items[0]).runs, 2);
  EXPECT_EQ(plan_item(idx.items[1]).runs, 4);
  EXPECT_EQ(plan_item(idx.items[2]).runs, 0);
  const ItemPlan p = plan_item(idx.items[0]);
  ASSERT_EQ(p.groups.size(), 1u);
  EXPECT_GT(p.groups[0].plan.particles, 10);
  EXPECT_DOUBLE_EQ(p.groups[0].softened_e_pa, 5e6);
  EXPECT_NEAR(p.cpu_hours, 2 * p.groups[0].plan.wall_s / 3600.0, 1e-12);
  EXPECT_EQ(code_commit("0.1.0+abc1234-dirty").commit, "abc1234");
  EXPECT_TRUE(code_commit("0.1.0+abc1234-dirty").dirty);
  EXPECT_FALSE(code_commit("0.1.0+abc1234").dirty);
}

TEST(PaperIndex, RefusesBadInputNamingFileKeyAndValue) {
  const Scratch d("bad");
  std::string m = index_error(d, std::string(kTinyIndex) + "budjet = 3\n");
  EXPECT_NE(m.find("budjet"), std::string::npos) << m;
  EXPECT_NE(m.find("index.toml"), std::string::npos) << m;
  std::string t = kTinyIndex;
  t.replace(t.find("file = \"sweep.toml\""), 19, "file = \"sweeps.toml\"");
  m = index_error(d, t);
  EXPECT_NE(m.find("item[0].file"), std::string::npos) << m;
  EXPECT_NE(m.find("sweeps.toml"), std::string::npos) << m;
  t = kTinyIndex;
  t.replace(t.find("kind = \"campaign\""), 17, "kind = \"campain\"");
  m = index_error(d, t);
  EXPECT_NE(m.find("item[0].kind"), std::string::npos) << m;
  EXPECT_NE(m.find("campain"), std::string::npos) << m;
  t = kTinyIndex;
  t.replace(t.find("reductions = \"the tiny scene\""), 29, "reduction = \"the tiny scene\"");
  m = index_error(d, t);
  EXPECT_NE(m.find("reduction"), std::string::npos) << m;
  t = kTinyIndex;
  t.replace(t.find("from = [\"cal\"]"), 14, "from = [\"sweep\"]");
  m = index_error(d, t);
  EXPECT_NE(m.find("item[2].from"), std::string::npos) << m;
  t = kTinyIndex;
  t.replace(t.find("name = \"cal\""), 12, "name = \"sweep\"");
  m = index_error(d, t);
  EXPECT_NE(m.find("another item"), std::string::npos) << m;
  // A listed file that does not parse is refused with its own message behind the index's key.
  write_file_atomic((d.path / "sweep.toml").string(), "name = \"tiny_sweep\"\nscene = 3\n");
  m = index_error(d, kTinyIndex);
  EXPECT_NE(m.find("item[0].file"), std::string::npos) << m;
  EXPECT_NE(m.find("scene"), std::string::npos) << m;
}

// The shipped index covers every item of issue 24, every file loads, and the whole set fits in
// its budget by the run plan's own estimate.
TEST(PaperIndex, TheShippedIndexCoversThePaperWithinItsBudget) {
  const PaperIndex idx =
      load_paper_index(std::string(REPOSETWIN_SOURCE_DIR) + "/experiments/paper/index.toml");
  double total = 0.0;
  std::set<std::string> papers;
  int table3_epsd = 0, table3_cdt = 0;
  for (const PaperItem& item : idx.items) {
    const ItemPlan p = plan_item(item);
    total += p.cpu_hours;
    papers.insert(item.paper);
    if (item.paper.rfind("Table 3", 0) == 0 && item.name.find("epsd") != std::string::npos)
      ++table3_epsd;
    if (item.paper.rfind("Table 3", 0) == 0 && item.name.find("cdt") != std::string::npos)
      ++table3_cdt;
    EXPECT_FALSE(item.reductions.empty()) << item.name;
    EXPECT_TRUE(item.paper_points || !item.trend.empty()) << item.name << ": no paper value";
  }
  EXPECT_EQ(table3_epsd, 4);
  EXPECT_EQ(table3_cdt, 4);
  for (const char* fig : {"Fig. 5", "Fig. 6", "Fig. 7", "Fig. 8", "Fig. 10", "Figs. 11-13",
                          "Figs. 14/15", "Fig. 18"}) {
    bool found = false;
    for (const auto& p : papers) found = found || p.rfind(fig, 0) == 0;
    EXPECT_TRUE(found) << fig;
  }
  EXPECT_LE(total, idx.budget_cpu_hours);
  EXPECT_LE(idx.budget_cpu_hours, 15.0);
}

// A case function counting its runs (threads mode: one process).
CaseFn counting(std::atomic<int>& n) {
  CaseRunSettings s;
  s.images = false;
  const CaseFn base = pile_case_fn(s);
  return [&n, base](const CaseSpec& spec, const std::string& dir) {
    ++n;
    return base(spec, dir);
  };
}

TEST(PaperIndex, ATinyIndexRunsEndToEndAndResumes) {
  const Scratch d("run");
  const PaperIndex idx = load_paper_index(d.write(kTinyIndex).string());
  RunnerSettings rs;
  rs.mode = WorkerMode::kThreads;
  rs.workers = 2;
  rs.progress = false;
  rs.rank.reset();
  rs.outcome_of = case_outcome_word;
  const fs::path out = d.path / "out";
  std::atomic<int> runs{0};
  const json first = run_paper(idx, out.string(), counting(runs), rs);
  EXPECT_GE(runs.load(), 4);
  EXPECT_LE(runs.load(), 6);
  EXPECT_EQ(first["items"][0]["status"], "done") << first["items"][0]["status_detail"];
  const std::string cal_state = first["items"][1]["status"];
  EXPECT_TRUE(cal_state == "done" || cal_state == "cannot reach") << cal_state;
  EXPECT_TRUE(fs::exists(out / "paper.json"));
  for (const char* item : {"sweep", "cal"}) {
    const json prov = json::parse(read_file((out / item / "provenance.json").string()));
    ASSERT_EQ(prov["attempts"].size(), 1u) << item;
    EXPECT_EQ(prov["attempts"][0]["code_version"], code_version());
    EXPECT_EQ(prov["attempts"][0]["dirty"], code_commit(code_version()).dirty);
    EXPECT_FALSE(prov["attempts"][0]["commit"].get<std::string>().empty());
    EXPECT_TRUE(prov["attempts"][0].contains("finished_utc"));
  }
  EXPECT_TRUE(fs::exists(out / "sweep" / "cases" / "contacts.rock-rock.rolling_friction_0.3" /
                         "seed_2" / "result.json") ||
              fs::exists(out / "sweep" / "campaign.json"));
  // Again: every item is finished, nothing runs, and no attempt is added.
  std::atomic<int> again{0};
  run_paper(idx, out.string(), counting(again), rs);
  EXPECT_EQ(again.load(), 0);
  const json prov = json::parse(read_file((out / "sweep" / "provenance.json").string()));
  EXPECT_EQ(prov["attempts"].size(), 1u);
}

// An item reusing a calibration that found no mu_r predicts, when it declares
// if_not_calibrated = "closest_point", at the usable point whose fitted angle is closest to the
// target, and its record says that mu_r is not calibrated; without the key it is skipped.
TEST(PaperIndex, AnUncalibratedSourceIsPredictedAtItsClosestPointOnlyWhenDeclared) {
  const Scratch d("closest");
  const std::string cal_table =
      "[calibration]\nkey = \"contacts.rock-rock.rolling_friction\"\ntarget_deg = 20.0\n"
      "mu_r_range = [0.1, 0.5]\nmethod = \"bracket\"\nmax_simulations = 4\n"
      "angle = \"particles\"\nbootstrap_replicates = 200\n";
  write_file_atomic((d.path / "pred.toml").string(),
                    "name = \"tiny_cal\"\nscene = \"tiny.toml\"\n" + cal_table +
                        "[[predict]]\nname = \"check\"\nscene = \"tiny.toml\"\n"
                        "measured_deg = 21.0\nseeds = 1\ninterval_ends = false\n");
  const std::string index = std::string(kTinyIndex) +
                            "[[item]]\nname = \"pred\"\npaper = \"Fig. 8\"\n"
                            "kind = \"calibration\"\nfile = \"pred.toml\"\n"
                            "calibrated_by = \"cal\"\nreductions = \"the tiny scene\"\n";
  RunnerSettings rs;
  rs.mode = WorkerMode::kThreads;
  rs.workers = 1;
  rs.progress = false;
  rs.rank.reset();
  rs.outcome_of = case_outcome_word;
  const fs::path out = d.path / "out";
  const PaperIndex plain = load_paper_index(d.write(index).string());
  // The source: the tiny calibration cannot reach 20 deg (its lowest mu_r piles steeper).
  PaperRunOptions only;
  only.only = {"cal"};
  std::atomic<int> source_runs{0};
  run_paper(plain, out.string(), counting(source_runs), rs, only);
  const json source = json::parse(read_file((out / "cal" / "calibration.json").string()));
  ASSERT_FALSE(source["mu_r"].is_number()) << source.dump(1);
  ASSERT_GE(source["fit"]["points"].size(), 1u);
  double closest = 0.0, gap = 1e9;
  for (const json& q : source["fit"]["points"])
    if (std::abs(q["fitted_deg"].get<double>() - 20.0) < gap) {
      gap = std::abs(q["fitted_deg"].get<double>() - 20.0);
      closest = q["mu_r"].get<double>();
    }

  only.only = {"pred"};
  std::atomic<int> skipped{0};
  run_paper(plain, out.string(), counting(skipped), rs, only);
  EXPECT_EQ(skipped.load(), 0);
  EXPECT_FALSE(fs::exists(out / "pred" / "calibration.json"));

  std::atomic<int> runs{0};
  const PaperIndex declared =
      load_paper_index(d.write(index + "if_not_calibrated = \"closest_point\"\n").string());
  ASSERT_TRUE(declared.items.back().closest_if_not_calibrated);
  run_paper(declared, out.string(), counting(runs), rs, only);
  ASSERT_EQ(runs.load(), 1) << read_file((out / "pred" / "provenance.json").string());
  const json cal = json::parse(read_file((out / "pred" / "calibration.json").string()));
  EXPECT_DOUBLE_EQ(cal["mu_r"].get<double>(), closest);
  ASSERT_TRUE(cal.contains("not_calibrated"));
  EXPECT_EQ(cal["not_calibrated"]["status"], source["status"]);
  EXPECT_NE(cal["not_calibrated"]["mu_r_basis"].get<std::string>().find("not a calibrated"),
            std::string::npos);
  const json pred = json::parse(read_file((out / "pred" / "predictions.json").string()));
  EXPECT_EQ(pred["predictions"][0]["name"], "check");
  EXPECT_DOUBLE_EQ(pred["predictions"][0]["mu_r"].get<double>(), closest);

  // The key belongs to items that reuse a calibration, and takes two words.
  EXPECT_NE(index_error(d, index + "if_not_calibrated = \"nearest\"\n").find("nearest"),
            std::string::npos);
  const std::string on_sweep = std::string(kTinyIndex).replace(
      std::string(kTinyIndex).find("file = \"sweep.toml\""), 19,
      "file = \"sweep.toml\"\nif_not_calibrated = \"skip\"");
  EXPECT_NE(index_error(d, on_sweep).find("calibrated_by"), std::string::npos);
}

}  // namespace
}  // namespace reposetwin::experiments
