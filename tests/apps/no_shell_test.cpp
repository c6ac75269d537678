// No shell, anywhere (issue 52): every command that draws a plot (report on a calibration,
// report rebuilding a loop's page, paper --page) on folders whose names hold single quotes,
// `;`, `$()`, backquotes, spaces, a newline and non-ASCII. The plots exist, and no sentinel that
// an injected command would create does. Inputs are committed records (no simulation): a
// calibration's result files, a loop.json, one paper item's results (each command 0.2-0.6 s).
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "tests/apps/cli_support.hpp"

namespace reposetwin::test_support {
namespace {

const fs::path kSource = REPOSETWIN_SOURCE_DIR;

// Two folder names: every shell metacharacter in one, the characters that are only awkward in the
// other. Each injection would create a file named pwned_* in the folder the command runs in or in
// the parent of the run folder.
const std::vector<std::string> kHostileNames = {
    "O'Brien lab; touch pwned_semi; x' $(touch pwned_subst) `touch pwned_tick` '",
    "new\nline \u00c5ngstr\u00f6m \u6f22\u5b57 & | > pwned_redirect"};

// The folder for one test, with the hostile sub-folders made by the caller.
fs::path root_for(const std::string& test) { return fresh_dir("no_shell_" + test); }

void expect_no_injection(const fs::path& root, const fs::path& dir) {
  for (const fs::path& where : {root, dir, dir.parent_path()})
    for (const char* s : {"pwned_semi", "pwned_subst", "pwned_tick", "pwned_redirect"})
      EXPECT_FALSE(fs::exists(where / s)) << where / s << ": an injected command ran";
}

// The PNGs under `dir` that are not empty.
int plots_in(const fs::path& dir) {
  int n = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.path().extension() == ".png" && e.file_size() > 0) ++n;
  return n;
}

TEST(NoShell, ReportOnACalibrationDrawsItsPlotsInAHostileFolder) {
  const fs::path root = root_for("report");
  const fs::path from = kSource / "results" / "table1_s1_calibration";
  for (const std::string& name : kHostileNames) {
    const fs::path dir = root / name;
    fs::create_directories(dir);
    for (const char* f : {"calibration.json", "predictions.json"}) fs::copy_file(from / f, dir / f);
    fs::copy(from / "cases", dir / "cases", fs::copy_options::recursive);
    const CliResult r = run_cli_argv({"report", dir.string()}, root);
    EXPECT_EQ(r.code, 0) << r.out;
    EXPECT_TRUE(fs::file_size(dir / "report" / "calibration.png") > 0) << r.out;
    EXPECT_EQ(r.out.find("sh: "), std::string::npos) << r.out;
    expect_no_injection(root, dir);
  }
  fs::remove_all(root);
}

TEST(NoShell, ALoopsPageIsRebuiltWithItsPlotsInAHostileFolder) {
  const fs::path root = root_for("loop_page");
  for (const std::string& name : kHostileNames) {
    const fs::path dir = root / name;
    fs::create_directories(dir);
    fs::copy_file(kSource / "results" / "paper_loop_image" / "loop.json", dir / "loop.json");
    const CliResult r = run_cli_argv({"report", dir.string()}, root);
    EXPECT_EQ(r.code, 0) << r.out;
    EXPECT_TRUE(fs::exists(dir / "index.html")) << r.out;
    EXPECT_GE(plots_in(dir / "plots"), 1) << r.out;
    expect_no_injection(root, dir);
  }
  fs::remove_all(root);
}

TEST(NoShell, ThePaperPageDrawsItsPlotsInAHostileFolder) {
  const fs::path root = root_for("paper_page");
  for (const std::string& name : kHostileNames) {
    const fs::path dir = root / name;
    fs::create_directories(dir);
    fs::copy(kSource / "results" / "paper" / "fig8_s2", dir / "fig8_s2",
             fs::copy_options::recursive);
    const CliResult r =
        run_cli_argv({"paper", (kSource / "experiments" / "paper" / "index.toml").string(), "--out",
                      dir.string(), "--page"},
                     root);
    EXPECT_EQ(r.code, 0) << r.out;
    EXPECT_TRUE(fs::file_size(dir / "paper_page" / "fig8_s2.png") > 0) << r.out;
    expect_no_injection(root, dir);
  }
  fs::remove_all(root);
}

}  // namespace
}  // namespace reposetwin::test_support
