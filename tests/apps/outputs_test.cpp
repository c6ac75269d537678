// One file layer (issue 52): the outputs that used to destroy what they pointed at, and the
// reads that used to hang, each run as a user would type it. Every case is refused before
// anything is measured or simulated, with exit 2 and a message naming the file and the reason,
// and the file pointed at is unchanged. Each command takes a fraction of a second.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <string>
#include <vector>

#include "tests/apps/cli_support.hpp"

namespace reposetwin::test_support {
namespace {

const fs::path kSource = REPOSETWIN_SOURCE_DIR;

void expect_refused(const CliResult& r, const std::vector<std::string>& words) {
  EXPECT_EQ(r.code, 2) << r.out;
  for (const std::string& w : words)
    EXPECT_NE(r.out.find(w), std::string::npos) << w << "\n" << r.out;
  EXPECT_EQ(r.out.find("filesystem error"), std::string::npos) << r.out;
}

bool names_a_fifo(const fs::path& p) {
  struct stat st {};
  return ::lstat(p.c_str(), &st) == 0 && S_ISFIFO(st.st_mode);
}

TEST(Outputs, MeasureNeverWritesItsOverlayOverItsInputPhoto) {
  const fs::path d = fresh_dir("out_is_input");
  write_text(d / "in.png", "the lab's photo");
  for (const fs::path& overlay : {d / "in.png", d / "." / "in.png"}) {
    const CliResult r = run_cli_argv({"measure", (d / "in.png").string(), "--overlay",
                                      overlay.string(), "--mm-per-px", "0.1", "--force"},
                                     d);
    expect_refused(r, {overlay.string(), "is the input"});
  }
  EXPECT_EQ(read_text(d / "in.png"), "the lab's photo");
  fs::remove_all(d);
}

TEST(Outputs, TwoOverlaysAtOnePathAreRefused) {
  const fs::path d = fresh_dir("two_overlays");
  write_text(d / "side.png", "x");
  write_text(d / "top.png", "x");
  const CliResult r = run_cli_argv({"measure", "side.png", "--top", "top.png", "--overlay", "o.png",
                                    "--top-overlay", "./o.png", "--mm-per-px", "0.1"},
                                   d);
  expect_refused(r, {"--top-overlay ./o.png", "is also --overlay o.png"});
  EXPECT_FALSE(fs::exists(d / "o.png"));
  fs::remove_all(d);
}

TEST(Outputs, AUsersFileNamedLikeAnOverlayIsKeptWithoutForce) {
  const fs::path d = fresh_dir("users_overlay");
  write_text(d / "side.png", "x");
  write_text(d / "side.measured.png", "my own annotated photo");
  const CliResult r = run_cli_argv({"measure", "side.png", "--mm-per-px", "0.1"}, d);
  expect_refused(r, {"side.measured.png", "already there", "--force"});
  EXPECT_EQ(read_text(d / "side.measured.png"), "my own annotated photo");
  fs::remove_all(d);
}

TEST(Outputs, AFifoAsAnOverlayOrTheTruthStaysAFifo) {
  const fs::path d = fresh_dir("fifo_outputs");
  write_text(d / "side.png", "x");
  write_text(d / "design.toml", "x");
  ASSERT_EQ(::mkfifo((d / "pipe").c_str(), 0600), 0);
  CliResult r = run_cli_argv(
      {"measure", "side.png", "--overlay", "pipe", "--mm-per-px", "0.1", "--force"}, d, 20);
  expect_refused(r, {"--overlay pipe", "FIFO", "replaces only a regular file"});
  r = run_cli_argv({"loop-synth", "design.toml", "--truth", "pipe", "--out", "dataset", "--force"},
                   d, 20);
  expect_refused(r, {"--truth pipe", "FIFO"});
  EXPECT_TRUE(names_a_fifo(d / "pipe"));
  EXPECT_FALSE(fs::exists(d / "dataset"));
  fs::remove_all(d);
}

TEST(Outputs, ARunWhoseImagesLinkOutsideIsRefusedByRenderAndRun) {
  const fs::path d = fresh_dir("images_link");
  fs::create_directories(d / "run");
  write_text(d / "photos" / "side_az000.png", "someone's photo");
  write_text(d / "run" / "result.json", "{}");
  fs::create_directory_symlink(d / "photos", d / "run" / "images");
  const CliResult render = run_cli_argv({"render", "run", "--force"}, d);
  expect_refused(render, {"run/images: is a symbolic link leading outside run", "photos"});
  const CliResult run = run_cli_argv({"run", "--out", "run", "--force"}, d);
  expect_refused(run, {"run/images: is a symbolic link leading outside run"});
  EXPECT_EQ(read_text(d / "photos" / "side_az000.png"), "someone's photo");
  fs::remove_all(d);
}

TEST(Outputs, LoopIntoAUsersFolderKeepsTheirIndexHtml) {
  const fs::path d = fresh_dir("loop_dot");
  write_text(d / "index.html", "<p>my page</p>");
  write_text(d / "data.csv", "x");
  const CliResult r = run_cli_argv({"loop", "data.csv", "-o", "."}, d);
  expect_refused(r, {"index.html", "already there", "--force"});
  EXPECT_EQ(read_text(d / "index.html"), "<p>my page</p>");
  fs::remove_all(d);
}

TEST(Outputs, ExportIntoAUsersFolderKeepsTheirReadme) {
  const fs::path d = fresh_dir("export_dot");
  write_text(d / "README.md", "# my project");
  const std::string scene = (kSource / "data" / "scenes" / "quick.toml").string();
  const CliResult r = run_cli_argv({"export", scene, "--out", "."}, d);
  expect_refused(r, {"README.md", "already there", "--force"});
  EXPECT_EQ(read_text(d / "README.md"), "# my project");
  EXPECT_FALSE(fs::exists(d / "in.pile"));
  // Into a folder of its own, then again with --force: the deck replaces only its own files.
  ASSERT_EQ(run_cli_argv({"export", scene, "--out", "deck"}, d).code, 0);
  EXPECT_EQ(run_cli_argv({"export", scene, "--out", "deck", "--force"}, d).code, 0);
  fs::remove_all(d);
}

TEST(Outputs, AFifoOrDevZeroAsADumpIsRefusedNotWaitedOn) {
  const fs::path d = fresh_dir("dump_fifo");
  ASSERT_EQ(::mkfifo((d / "dump").c_str(), 0600), 0);
  const std::string scene = (kSource / "data" / "scenes" / "quick.toml").string();
  CliResult r = run_cli_argv({"measure-particles", "dump", "--scene", scene}, d, 20);
  expect_refused(r, {"dump: is a FIFO"});
  r = run_cli_argv({"measure-particles", "/dev/zero", "--scene", scene}, d, 20);
  expect_refused(r, {"/dev/zero: is a character device"});
  fs::remove_all(d);
}

TEST(Outputs, AFifoAsTheReportsLabPhotoIsRefusedNotWaitedOn) {
  const fs::path d = fresh_dir("lab_photo_fifo");
  const fs::path from = kSource / "results" / "table1_s1_calibration";
  fs::create_directories(d / "cal");
  for (const char* f : {"calibration.json", "predictions.json"})
    fs::copy_file(from / f, d / "cal" / f);
  ASSERT_EQ(::mkfifo((d / "lab.png").c_str(), 0600), 0);
  const CliResult r = run_cli_argv({"report", "cal", "--lab-photo", "lab.png"}, d, 20);
  expect_refused(r, {"--lab-photo lab.png", "not a regular file"});
  fs::remove_all(d);
}

TEST(Outputs, AFifoAsTheSieveSheetIsRefusedNotWaitedOn) {
  const fs::path d = fresh_dir("psd_fifo");
  ASSERT_EQ(::mkfifo((d / "sieve.toml").c_str(), 0600), 0);
  const CliResult r =
      run_cli_argv({"run", (kSource / "data" / "scenes" / "quick.toml").string(), "--set",
                    "sample.psd_file=" + (d / "sieve.toml").string(), "--out", "run"},
                   d, 20);
  expect_refused(r, {"sieve.toml: is a FIFO"});
  EXPECT_FALSE(fs::exists(d / "run" / "result.json"));
  fs::remove_all(d);
}

}  // namespace
}  // namespace reposetwin::test_support
