// A run folder's stage record (pile/run_state.hpp): the transitions it allows, the record read
// back only as written (any damage, edit or unknown word refused), written atomically, rewound
// with the files of the stages above, the lock refusing a second writer, and the test hook that
// kills the process right after a stage is recorded. No simulation: folders are made by hand.
#include "experiments/pile/run_state.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "experiments/io/files.hpp"
#include "experiments/io/provenance.hpp"
#include "tests/support/scratch.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

void put(const fs::path& p, const std::string& text = "x") {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

TEST(RunState, EveryStageHasItsWordAndBack) {
  for (std::size_t i = 0; i < kRunStageNames.size(); ++i) {
    const auto s = static_cast<RunStage>(i);
    EXPECT_EQ(run_stage_from(run_stage_name(s)), s);
  }
  EXPECT_FALSE(run_stage_from("finished"));
  EXPECT_FALSE(run_stage_from(""));
  EXPECT_THROW(run_stage_name(RunStage::kCount), std::logic_error);
}

TEST(RunState, TransitionsGoOneStageOnOrSkipPhotographsOnlyWithoutThem) {
  using S = RunStage;
  struct Row {
    S from, to;
    bool photographs, allowed;
  };
  const std::vector<Row> rows = {
      {S::kSimulated, S::kPhotographed, true, true},
      {S::kPhotographed, S::kMeasured, true, true},
      {S::kMeasured, S::kSummarised, true, true},
      {S::kSummarised, S::kReported, true, true},
      {S::kSimulated, S::kSummarised, false, true},  // --no-images, or no pile
      {S::kSimulated, S::kSummarised, true, false},  // photographs skipped
      {S::kSimulated, S::kMeasured, true, false},    // measured without photographs
      {S::kSimulated, S::kPhotographed, false, false},
      {S::kPhotographed, S::kSummarised, true, false},
      {S::kSummarised, S::kMeasured, true, false},  // backwards: only by rewinding
      {S::kReported, S::kReported, true, false},
      {S::kReported, S::kCount, true, false},
      {S::kMeasured, S::kMeasured, true, false},
  };
  for (const Row& r : rows)
    EXPECT_EQ(run_stage_follows(r.from, r.to, r.photographs), r.allowed)
        << run_stage_name(r.from) << " -> " << static_cast<int>(r.to) << " photographs "
        << r.photographs;

  RunState s;
  EXPECT_EQ(s.missing(), "photographed, measured, summarised, reported");
  s.photographs = false;
  EXPECT_EQ(s.next(), RunStage::kSummarised);
  EXPECT_EQ(s.missing(), "summarised, reported");
  s.stage = RunStage::kReported;
  EXPECT_TRUE(s.complete());
  EXPECT_FALSE(s.next());
  EXPECT_EQ(s.missing(), "");
}

TEST(RunState, RecordReadsBackAsWrittenAndIsReplacedAtomically) {
  const fs::path d = test_support::temp_dir("run_state_atomic");
  EXPECT_FALSE(read_run_state(d.string()));
  record_simulated(d.string(), true);
  for (RunStage s : {RunStage::kPhotographed, RunStage::kMeasured, RunStage::kSummarised}) {
    record_stage(d.string(), s);
    EXPECT_EQ(read_run_state(d.string())->stage, s);
  }
  record_note(d.string(), "a note");
  EXPECT_EQ(read_run_state(d.string())->note, "a note");
  record_stage(d.string(), RunStage::kReported);
  const RunState s = *read_run_state(d.string());
  EXPECT_TRUE(s.complete());
  EXPECT_TRUE(s.photographs);
  EXPECT_EQ(s.note, "");  // a stage reached clears the reason it was missing
  // Only the record is left: no temporary of an atomic write beside it.
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(d)) names.push_back(e.path().filename().string());
  EXPECT_EQ(names, std::vector<std::string>{kRunStateFile});
  // A stage out of order is a bug of the caller, refused without touching the record.
  EXPECT_THROW(record_stage(d.string(), RunStage::kMeasured), std::logic_error);
  EXPECT_TRUE(read_run_state(d.string())->complete());
  const fs::path none = test_support::temp_dir("run_state_none");
  EXPECT_THROW(record_stage(none.string(), RunStage::kPhotographed), std::logic_error);
}

TEST(RunState, DamagedEditedOrUnknownRecordsAreRefusedNamingTheFileAndWhy) {
  RunState ok;
  ok.stage = RunStage::kMeasured;
  const std::string good = run_state_text(ok);
  EXPECT_EQ(run_state_from_text(good, "r").stage, RunStage::kMeasured);
  nlohmann::json j = nlohmann::json::parse(good);
  const auto edited = [&](const char* key, const nlohmann::json& v) {
    nlohmann::json e = j;
    if (v.is_discarded())
      e.erase(key);
    else
      e[key] = v;
    return e.dump();
  };
  const nlohmann::json drop = nlohmann::json(nlohmann::json::value_t::discarded);
  struct Case {
    std::string text, why;
  };
  const std::vector<Case> cases = {
      {good.substr(0, good.size() / 2), "not valid JSON"},
      {"", "not valid JSON"},
      {"[]", "not a run-state record"},
      {edited("stage", "reported"), "checksum does not match"},  // a hand edit
      {edited("stage", "finished"), "not a stage of a run"},
      {edited("stage", 3), "not a word"},
      {edited("format", "other"), "format is"},
      {edited("version", 2), "version is 2"},
      {edited("photographs", "yes"), "photographs is"},
      {edited("note", 1), "note is"},
      {edited("extra", 1), "unknown field \"extra\""},
      {edited("checksum_fnv1a", drop), "lacks the field \"checksum_fnv1a\""},
      {edited("stage", drop), "lacks the field \"stage\""},
  };
  for (const Case& c : cases) {
    try {
      run_state_from_text(c.text, "RUN/run_state.json");
      ADD_FAILURE() << "accepted: " << c.text;
    } catch (const RunStateError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind("RUN/run_state.json: ", 0), 0u) << what;
      EXPECT_NE(what.find(c.why), std::string::npos) << what;
      EXPECT_NE(what.find("--force"), std::string::npos) << what;
    }
  }
  // In a folder: a record that is a folder, or cut short, is refused too, not read as absent.
  const fs::path d = test_support::temp_dir("run_state_damaged");
  put(d / kRunStateFile, good.substr(0, 10));
  EXPECT_THROW(read_run_state(d.string()), RunStateError);
  fs::remove(d / kRunStateFile);
  fs::create_directories(d / kRunStateFile);
  EXPECT_THROW(read_run_state(d.string()), RunStateError);
}

TEST(RunState, RewindLowersTheRecordFirstAndRemovesWhatTheStagesAboveMade) {
  const fs::path d = test_support::temp_dir("run_state_rewind");
  for (const char* f :
       {"result.json", "final.vtp", "summary.html", "images/measurement.json",
        "images/side_az000.png", "images/side_az045_2.measured.png", "images/top.json",
        "images/frame_00004/side_az000.png", "images/holiday.jpg"})
    put(d / f);
  record_simulated(d.string(), true);
  for (RunStage s :
       {RunStage::kPhotographed, RunStage::kMeasured, RunStage::kSummarised, RunStage::kReported})
    record_stage(d.string(), s);
  rewind_run_state(d.string(), RunStage::kMeasured, true);
  EXPECT_EQ(read_run_state(d.string())->stage, RunStage::kMeasured);
  EXPECT_FALSE(fs::exists(d / "summary.html"));
  EXPECT_TRUE(fs::exists(d / "images/measurement.json"));
  rewind_run_state(d.string(), RunStage::kSimulated, false);
  const RunState s = *read_run_state(d.string());
  EXPECT_EQ(s.stage, RunStage::kSimulated);
  EXPECT_FALSE(s.photographs);
  for (const char* gone : {"images/measurement.json", "images/side_az000.png",
                           "images/side_az045_2.measured.png", "images/top.json"})
    EXPECT_FALSE(fs::exists(d / gone)) << gone;
  // The simulation's files, a frame's photographs and a person's own file stay.
  for (const char* kept :
       {"result.json", "final.vtp", "images/frame_00004/side_az000.png", "images/holiday.jpg"})
    EXPECT_TRUE(fs::exists(d / kept)) << kept;
  EXPECT_THROW(rewind_run_state(d.string(), RunStage::kMeasured, true), std::logic_error);
}

TEST(RunState, ASecondWriterIsRefusedWhileTheLockIsHeld) {
  const fs::path d = test_support::temp_dir("run_state_lock");
  {
    const RunFolderLock first(d.string());
    try {
      const RunFolderLock second(d.string());
      ADD_FAILURE() << "a second lock on one run folder was granted";
    } catch (const FolderBusy& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(d.string()), std::string::npos) << what;
      EXPECT_NE(what.find("another reposetwin command"), std::string::npos) << what;
    }
  }
  EXPECT_NO_THROW(RunFolderLock again(d.string()));  // released with its holder
}

TEST(RunState, TheTestHookKillsRightAfterItsStageIsOnDisk) {
  const fs::path d = test_support::temp_dir("run_state_hook");
  record_simulated(d.string(), true);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    setenv("REPOSETWIN_TEST_KILL_AFTER_STAGE", "photographed", 1);
    record_stage(d.string(), RunStage::kPhotographed);
    _exit(0);  // not reached
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(WTERMSIG(status), SIGKILL);
  EXPECT_EQ(read_run_state(d.string())->stage, RunStage::kPhotographed);
}

}  // namespace
}  // namespace reposetwin::experiments
