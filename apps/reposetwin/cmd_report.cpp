#include <iostream>
#include <memory>

#include "apps/reposetwin/commands.hpp"
#include "experiments/report.hpp"

namespace reposetwin::cli {

void add_report_command(CLI::App& app) {
  struct Args {
    std::string dir;
    experiments::ReportSettings settings;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "report", "Build an HTML report (plots, tables, renders) of a run, campaign or calibration");
  cmd->add_option("dir", a->dir, "Run, campaign or calibration folder")->required();
  cmd->add_option("--lab-photo", a->settings.lab_photo, "A lab photo to measure and show");
  cmd->add_option("--lab-mm-per-px", a->settings.lab_mm_per_px,
                  "The lab photo's scale [mm/px] (default: find the scale bar)");
  cmd->add_option("--title", a->settings.title, "Report title");
  cmd->callback([a]() {
    const nlohmann::json s = experiments::build_report(a->dir, a->settings);
    std::cout << s.dump(2) << "\n" << a->dir << "/report/index.html\n";
  });
}

}  // namespace reposetwin::cli
