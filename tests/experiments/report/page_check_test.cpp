// The page checker on pages made here with each fault once, and on a clean page: it names every
// fault by its kind and passes what a reader can open anywhere.
#include "experiments/report/page_check.hpp"

#include <gtest/gtest.h>

#include <map>

#include "../../support/scratch.hpp"
#include "experiments/io/provenance.hpp"

namespace reposetwin::experiments::report {
namespace {
namespace fs = std::filesystem;

std::map<PageProblemKind, int> kinds(const std::vector<PageProblem>& problems) {
  std::map<PageProblemKind, int> n;
  for (const PageProblem& p : problems) ++n[p.kind];
  return n;
}

TEST(PageCheck, NamesEachFaultOfABrokenPage) {
  const fs::path dir = test_support::temp_dir("page_check_broken");
  fs::create_directories(dir / "plots");
  write_file_atomic((dir / "here.png").string(), "png");
  write_file_atomic((dir / "plots" / "a.gp").string(),
                    "set output 'a.png'\nplot '/work/runs/x/a.dat' using 1:2\n");
  write_file_atomic((dir / "index.html").string(),
                    "<html><body><img src='here.png'><img src=\"gone.png\">"
                    "<a href='/work/runs/x/series.pvd'>pvd</a><a href='file:///tmp/a.html'>a</a>"
                    "<a href='#top'>top</a><a href='https://example.org/x'>x</a>"
                    "<a href='../missing/index.html#s'>s</a>"
                    "<p>Built from <code>/work/runs/i6/dmin</code>.</p>"
                    "<pre>{\n  \"mu_r\": 0.3\n}</pre><pre>plain text</pre></body></html>");
  const std::vector<PageProblem> problems = page_problems(dir / "index.html");
  const auto n = kinds(problems);
  EXPECT_EQ(n.count(PageProblemKind::kMissingFile) ? n.at(PageProblemKind::kMissingFile) : 0, 2);
  EXPECT_EQ(n.count(PageProblemKind::kAbsoluteLink) ? n.at(PageProblemKind::kAbsoluteLink) : 0, 2);
  EXPECT_EQ(n.count(PageProblemKind::kRawJson) ? n.at(PageProblemKind::kRawJson) : 0, 1);
  EXPECT_EQ(n.count(PageProblemKind::kAbsolutePath) ? n.at(PageProblemKind::kAbsolutePath) : 0, 1);
  EXPECT_EQ(n.count(PageProblemKind::kAbsoluteScript) ? n.at(PageProblemKind::kAbsoluteScript) : 0,
            1);
  EXPECT_EQ(problems.size(), 7u);
  for (const PageProblem& p : problems)
    if (p.kind == PageProblemKind::kMissingFile)
      EXPECT_TRUE(p.what == "gone.png" || p.what == "../missing/index.html#s") << p.what;
}

TEST(PageCheck, PassesAPageThatOpensAnywhere) {
  const fs::path dir = test_support::temp_dir("page_check_clean");
  fs::create_directories(dir / "images");
  write_file_atomic((dir / "images" / "a&b.png").string(), "png");
  write_file_atomic((dir / "result.json").string(), "{}");
  write_file_atomic((dir / "plot.gp").string(), "set output 'plot.png'\nplot 'plot.dat'\n");
  write_file_atomic((dir / "index.html").string(),
                    "<html><body><img src='images/a&amp;b.png'><a href='result.json'>r</a>"
                    "<a href='#x'>x</a><p>H = 12 mm / 2, 0.5 m/s, mu_r 0.399</p></body></html>");
  const std::vector<PageProblem> problems = page_problems(dir / "index.html");
  for (const PageProblem& p : problems) ADD_FAILURE() << to_string(p.kind) << ": " << p.what;
  EXPECT_EQ(page_references("<img src='a.png'><a HREF=\"b.html\">").size(), 2u);
}

}  // namespace
}  // namespace reposetwin::experiments::report
