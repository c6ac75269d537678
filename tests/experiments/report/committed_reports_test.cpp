// The reports committed under results/ open in a fresh clone: every page's links and images are
// relative and present, no page pastes a result file or names a path of the machine that built
// it, and their plot scripts name files by name only (report/page_check.hpp).
#include <gtest/gtest.h>

#include <filesystem>

#include "experiments/report/page_check.hpp"

namespace reposetwin::experiments::report {
namespace {
namespace fs = std::filesystem;

TEST(CommittedReports, OpenInAFreshClone) {
  const fs::path results = fs::path(REPOSETWIN_SOURCE_DIR) / "results";
  ASSERT_TRUE(fs::is_directory(results)) << results;
  int pages = 0;
  for (const auto& e : fs::recursive_directory_iterator(results)) {
    if (e.path().extension() != ".html") continue;
    ++pages;
    for (const PageProblem& p : page_problems(e.path()))
      ADD_FAILURE() << fs::relative(p.where, results).string() << ": " << to_string(p.kind)
                    << ": " << p.what;
  }
  EXPECT_GE(pages, 8);  // the calibrations, the studies, the loop and the Table 3 comparison
}

}  // namespace
}  // namespace reposetwin::experiments::report
