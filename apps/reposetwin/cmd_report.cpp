#include <algorithm>
#include <filesystem>
#include <iostream>
#include <memory>

#include "apps/reposetwin/commands.hpp"
#include "apps/reposetwin/validators.hpp"
#include "experiments/io/files.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/pile/run_folder.hpp"
#include "experiments/pile/run_state.hpp"
#include "experiments/report/folder_results.hpp"
#include "experiments/report/report.hpp"

namespace reposetwin::cli {

namespace {

// What `report` prints: one line for a person, or the summary as JSON for a script.
void print(const nlohmann::json& summary, const std::string& page, bool json) {
  if (json)
    std::cout << summary.dump(2) << "\n";
  else
    std::cout << experiments::report_line(summary, page) << std::endl;
}

}  // namespace

void add_report_command(CLI::App& app) {
  struct Args {
    std::vector<std::string> dirs;
    std::string out;
    experiments::ReportSettings settings;
    bool force = false;
    bool json = false;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "report",
      "Build an HTML report (plots, tables, renders) of a run, campaign or calibration folder; "
      "over several calibration folders (or their parent), the comparison with the paper's "
      "Table 3");
  cmd->add_option("dirs", a->dirs, "Run, campaign or calibration folder(s), or a parent of several")
      ->required();
  cmd->add_option("--out,-o", a->out,
                  "Where the report over several folders goes (OUT/report/index.html; default: "
                  "their common parent folder)");
  cmd->add_option("--lab-photo", a->settings.lab_photo, "A lab photo to measure and show");
  cmd->add_option("--lab-mm-per-px", a->settings.lab_mm_per_px,
                  "The lab photo's scale [mm/px] (default: find the scale bar)")
      ->check(positive_number());
  cmd->add_option("--title", a->settings.title, "Report title");
  cmd->add_option("--paper-data", a->settings.paper_dir,
                  "Folder of the paper's CSVs (default: data/paper found upwards from the "
                  "calibration's campaign file, then from the working folder)");
  cmd->add_flag("--force", a->force, "Rebuild a report that is already there");
  cmd->add_flag("--json", a->json,
                "Print the report's summary as JSON on stdout instead of the one line");
  cmd->callback([a]() {
    namespace fs = std::filesystem;
    std::string out = a->out;
    if (!out.empty()) experiments::check_output_folder(out);
    // A report is a result: an earlier one stays unless asked (checked before anything is read).
    // Over several folders, each folder's own report is rebuilt too.
    std::vector<fs::path> pages;
    for (const auto& d : a->dirs) pages.push_back(experiments::report_page(d));
    if (!out.empty()) pages.push_back(fs::path(out) / "report" / "index.html");
    for (const fs::path& p : pages)
      if (fs::exists(p) && !a->force)
        throw experiments::InputError(p.string() +
                                      ": a report is already there; pass --force to rebuild it");
    // A report writes into each run folder it reads (RUN_DIR/report/): it holds the folder's
    // lock for the whole command, so no run or render changes the stages under it.
    // A report writes into each folder's report/ and reads the runs' files: a link inside a
    // folder that leads outside it is refused, as run and render refuse it.
    for (const auto& d : a->dirs) {
      experiments::report::refuse_part_folder(d);
      experiments::refuse_escaping_links(d);
    }
    std::vector<std::unique_ptr<experiments::RunFolderLock>> locks;
    for (const auto& d : a->dirs)
      if (experiments::report::is_run_dir(d))
        locks.push_back(std::make_unique<experiments::RunFolderLock>(d));
    if (a->dirs.size() == 1 && out.empty()) {
      const nlohmann::json s = experiments::build_report(a->dirs[0], a->settings);
      print(s, experiments::report_page(a->dirs[0]), a->json);
      if (s.contains("incomplete")) set_exit_code(ExitCode::kIncomplete);
      return;
    }
    if (out.empty()) {  // the folders' common parent
      fs::path common = fs::absolute(a->dirs[0]).lexically_normal().parent_path();
      for (const auto& d : a->dirs) {
        const fs::path p = fs::absolute(d).lexically_normal();
        while (!common.empty() &&
               std::mismatch(common.begin(), common.end(), p.begin(), p.end()).first !=
                   common.end())
          common = common.parent_path();
      }
      out = common.string();
      if (fs::exists(fs::path(out) / "report" / "index.html") && !a->force)
        throw experiments::InputError(out + "/report/index.html: a report is already there; pass "
                                      "--force to rebuild it");
    }
    const nlohmann::json s = experiments::build_report(a->dirs, out, a->settings);
    print(s, out + "/report/index.html", a->json);
  });
}

}  // namespace reposetwin::cli
