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

// A figure page's own faults: an empty image, a script reading an empty data file, a figure
// drawn from another's data (fig8 reads the same numbers as t3 under other names) and a figure
// that is another's image; the figure with its own data passes.
TEST(PageCheck, NamesEmptyAndRepeatedFigures) {
  const fs::path dir = test_support::temp_dir("page_check_figures");
  const auto put = [&](const std::string& name, const std::string& text) {
    write_file_atomic((dir / name).string(), text);
  };
  put("t3.png", "png t3");
  put("t3.gp", "set output 't3.png'\nplot 't3_runs.dat' using 1:2, 't3_fit.dat' with lines\n");
  put("t3_runs.dat", "0.1 30\n0.2 34\n");
  put("t3_fit.dat", "0.1 30\n0.2 34\n");
  put("fig8.png", "png fig8");
  put("fig8.gp", "set output 'fig8.png'\nplot 'fig8_runs.dat' using 1:2, 'fig8_fit.dat' with lines\n");
  put("fig8_runs.dat", "0.1 30\n0.2 34\n");
  put("fig8_fit.dat", "0.1 30\n0.2 34\n");
  put("fig5.png", "png fig5");
  put("fig5.gp", "set output 'fig5.png'\nplot 'fig5_ours.dat', 'fig5_paper.dat'\n");
  put("fig5_ours.dat", "0.1 21 0.5\n");
  put("fig5_paper.dat", "");
  put("fig6.png", "");
  put("fig7.png", "png t3");
  put("fig9.png", "png fig9");
  put("fig9.gp", "set output 'fig9.png'\nplot 'fig9_ours.dat'\n");
  put("fig9_ours.dat", "50 31 0.4\n900 36 0.3\n");
  put("index.html",
      "<img src='t3.png'><img src='fig8.png'><img src='fig5.png'><img src='fig6.png'>"
      "<img src='fig7.png'><img src='fig9.png'><a href='t3.png'>t3 again</a>");
  const std::vector<PageProblem> problems = page_problems(dir / "index.html");
  const auto n = kinds(problems);
  EXPECT_EQ(n.count(PageProblemKind::kEmptyImage) ? n.at(PageProblemKind::kEmptyImage) : 0, 1);
  EXPECT_EQ(n.count(PageProblemKind::kEmptyData) ? n.at(PageProblemKind::kEmptyData) : 0, 1);
  EXPECT_EQ(n.count(PageProblemKind::kSameData) ? n.at(PageProblemKind::kSameData) : 0, 2);
  EXPECT_EQ(problems.size(), 4u);
  for (const PageProblem& p : problems) {
    if (p.kind == PageProblemKind::kEmptyImage) EXPECT_EQ(p.what, "fig6.png");
    if (p.kind == PageProblemKind::kEmptyData) EXPECT_EQ(p.what, "fig5_paper.dat");
    if (p.kind == PageProblemKind::kSameData)
      EXPECT_TRUE(p.what == "fig8.png is drawn from the data of t3.png" ||
                  p.what == "fig7.png shows t3.png")
          << p.what;
  }
}

}  // namespace
}  // namespace reposetwin::experiments::report
