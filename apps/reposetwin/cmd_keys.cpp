// `reposetwin keys`: every scene key with its type, default, unit and meaning; with --campaign,
// every campaign and calibration file key and the columns of the lab's sheets.
#include <iostream>
#include <memory>

#include "apps/reposetwin/commands.hpp"
#include "experiments/io/campaign_keys.hpp"
#include "experiments/io/psd_file.hpp"
#include "experiments/io/scene_keys.hpp"
#include "experiments/loop/loop_data.hpp"

namespace reposetwin::cli {
namespace {

void print_keys(const std::vector<experiments::SceneKey>& keys) {
  for (const experiments::SceneKey& k : keys)
    std::cout << k.key << "  (" << k.type << ", default " << k.default_text
              << (k.unit == "-" ? "" : ", " + k.unit) << ")\n    " << k.meaning << "\n";
}

// The campaign and calibration keys and the sheets' columns: the key part of
// docs/calibration.md with --markdown.
void print_campaign_keys(bool markdown) {
  if (markdown) {
    std::cout << "### Campaign and calibration file keys\n\n"
              << experiments::campaign_keys_markdown() << "\n### Test sheet columns\n\n"
              << experiments::test_sheet_markdown() << "\n### Sieve sheet\n\n"
              << "A CSV whose header is `" << experiments::kCsvHeader
              << "` (either order), one row a sieve: its opening [mm] and the cumulative "
                 "percent passing by mass; or `sieve_mm,retained_percent` (the percent retained "
                 "on each sieve) or `sieve_mm,cumulative_retained_percent`, converted to percent "
                 "passing (the plan says so). Sieves finest first or coarsest first; `#` lines "
                 "are notes. Or TOML with a `[psd]` table (`reposetwin keys`, sample.psd).\n\n"
                 "### Paths\n\n"
              << experiments::kRelativePathRule << "\n";
    return;
  }
  std::cout << "Campaign and calibration file keys (docs/calibration.md):\n";
  print_keys(experiments::campaign_keys());
  std::cout << "\nTest sheet columns (reposetwin calibrate --tests, reposetwin loop):\n";
  for (const experiments::SheetColumn& c : experiments::test_sheet_columns())
    std::cout << c.column << "\n    " << c.meaning << "\n";
  for (const experiments::ConditionColumn& c : experiments::condition_columns())
    std::cout << c.column << "\n    a condition [" << c.unit << "]: sets the scene's " << c.key
              << "\n";
  std::cout << "set:KEY\n    any other scene key; the value is TOML or a bare word\n"
            << "(* every row needs angle_deg, or H_mm and D_mm, or photo)\n"
            << "\nSieve sheet (calibrate --sieve, sample.psd_file): CSV with the header "
            << experiments::kCsvHeader << ", or TOML with a [psd] table\n"
            << "\nPaths: " << experiments::kRelativePathRule << "\n";
}

}  // namespace

void add_keys_command(CLI::App& app) {
  auto markdown = std::make_shared<bool>(false);
  auto campaign = std::make_shared<bool>(false);
  auto* cmd = app.add_subcommand(
      "keys",
      "List every scene key (type, default, unit, meaning); with --campaign, every campaign and "
      "calibration key and the lab's sheet columns");
  cmd->add_flag("--markdown", *markdown,
                "As Markdown: docs/scene.md, or with --campaign the key part of "
                "docs/calibration.md");
  cmd->add_flag("--campaign", *campaign,
                "The campaign and calibration file keys and the test and sieve sheet columns");
  cmd->callback([markdown, campaign]() {
    if (*campaign) {
      print_campaign_keys(*markdown);
      return;
    }
    if (*markdown) {
      std::cout << experiments::scene_keys_markdown();
      return;
    }
    print_keys(experiments::scene_keys());
    std::cout << "\nCampaign and calibration keys, and the lab's sheets: reposetwin keys "
                 "--campaign\n";
    std::cout << "\nPaths: " << experiments::kRelativePathRule << "\n";
  });
}

}  // namespace reposetwin::cli
