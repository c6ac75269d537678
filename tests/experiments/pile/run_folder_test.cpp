// Run folders (pile/run_folder.hpp): what a folder holds decides whether a run may write there,
// and --force removes a run's own files only. No simulation: the folders are made by hand.
#include "experiments/pile/run_folder.hpp"
#include "experiments/pile/run_state.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "experiments/io/input_error.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

fs::path fresh(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("reposetwin_run_folder_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

void put(const fs::path& p) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << "x";
}

std::string refusal(const fs::path& dir, bool resume, bool force) {
  try {
    check_run_folder(dir.string(), resume, force);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(RunFolder, TheRunsOwnFilesAreKnownByName) {
  for (const char* f :
       {"result.json", "final.vtp", "checkpoint.bin", "checkpoint.bin.tmp",
        "controller.json.tmp.4242", "series.pvd", "scene.resolved.toml", "summary.html",
        "frames/frame_00012.vtp", "frames/container_00000.vtp", "frames/plate.vtp",
        "images/measurement.json", "images/side_az045.png", "images/side_az045_2.measured.png",
        "images/top.json", "images/frame_00004/side_az000.png", "report/index.html",
        "report/angles.gp", "run_state.json"})
    EXPECT_TRUE(is_run_file(f)) << f;
  for (const char* f :
       {"notes.txt", "frames/notes.txt", "images/holiday.jpg", "images/side_az45.png",
        "images/mine/top.png", "data/result.json", "final.vtp.bak", "report/notes.txt",
        "report/sub/index.html"})
    EXPECT_FALSE(is_run_file(f)) << f;
}

TEST(RunFolder, EachStateIsRefusedOrTakenAsItsFlagsSay) {
  const fs::path d = fresh("states");
  EXPECT_EQ(run_folder_state(d / "absent"), RunFolderState::kAbsent);
  EXPECT_EQ(refusal(d / "absent", false, false), "");
  EXPECT_EQ(run_folder_state(d), RunFolderState::kEmpty);

  const fs::path killed = d / "killed";
  put(killed / "scene.resolved.toml");
  put(killed / "checkpoint.bin");
  put(killed / "controller.json");
  EXPECT_EQ(run_folder_state(killed), RunFolderState::kInterrupted);
  const std::string why = refusal(killed, false, false);
  EXPECT_NE(why.find("--resume"), std::string::npos) << why;
  EXPECT_NE(why.find("--force"), std::string::npos) << why;
  EXPECT_EQ(refusal(killed, true, false), "");
  EXPECT_EQ(refusal(killed, false, true), "");

  // A result.json alone is a run stopped between stages: the stage record decides.
  put(killed / "result.json");
  EXPECT_EQ(run_folder_state(killed), RunFolderState::kInterrupted);
  EXPECT_NE(refusal(killed, false, false).find("run_state.json"), std::string::npos);
  record_simulated(killed.string(), false);
  EXPECT_EQ(run_folder_state(killed), RunFolderState::kInterrupted);
  EXPECT_NE(refusal(killed, false, false).find("missing: summarised, reported"),
            std::string::npos)
      << refusal(killed, false, false);
  record_stage(killed.string(), RunStage::kSummarised);
  record_stage(killed.string(), RunStage::kReported);
  EXPECT_EQ(run_folder_state(killed), RunFolderState::kFinished);
  EXPECT_NE(refusal(killed, false, false).find("--force"), std::string::npos);
  EXPECT_NE(refusal(killed, true, false).find("nothing to resume"), std::string::npos);
  EXPECT_EQ(refusal(killed, false, true), "");

  // A person's folder: a summary.html of their own is no run, nor is a notes file beside one.
  const fs::path mine = d / "mine";
  put(mine / "summary.html");
  EXPECT_EQ(run_folder_state(mine), RunFolderState::kForeign);
  put(mine / "notes.txt");
  std::vector<std::string> foreign;
  EXPECT_EQ(run_folder_state(mine, &foreign), RunFolderState::kForeign);
  EXPECT_EQ(foreign, std::vector<std::string>{"notes.txt"});
  EXPECT_NE(refusal(mine, false, false).find("not a run folder"), std::string::npos);
  EXPECT_EQ(refusal(mine, false, true), "");
}

TEST(RunFolder, OutNamingNothingOrAFileIsRefusedSayingSo) {
  const fs::path d = fresh("paths");
  put(d / "a_file");
  EXPECT_NE(refusal("", false, false).find("--out is empty"), std::string::npos);
  EXPECT_NE(refusal(d / "a_file", false, false).find("names a file"), std::string::npos);
  const std::string under = refusal(d / "a_file" / "run", false, false);
  EXPECT_NE(under.find("is a file, not a folder"), std::string::npos) << under;
  EXPECT_FALSE(fs::exists(d / "a_file" / "run"));
}

TEST(RunFolder, ForceRemovesOnlyTheRunsOwnFiles) {
  const fs::path d = fresh("force");
  for (const char* f : {"result.json", "final.vtp", "checkpoint.bin", "summary.html",
                        "frames/frame_00000.vtp", "frames/plate.vtp", "images/top.png",
                        "images/measurement.json", "images/frame_00001/top.png"})
    put(d / f);
  for (const char* f : {"notes.txt", "images/holiday.jpg", "frames/readme.md"}) put(d / f);
  remove_run_files(d);
  for (const char* f : {"notes.txt", "images/holiday.jpg", "frames/readme.md"})
    EXPECT_TRUE(fs::exists(d / f)) << f;
  for (const char* f : {"result.json", "final.vtp", "checkpoint.bin", "summary.html",
                        "frames/frame_00000.vtp", "images/top.png", "images/frame_00001"})
    EXPECT_FALSE(fs::exists(d / f)) << f;
}

}  // namespace
}  // namespace reposetwin::experiments
