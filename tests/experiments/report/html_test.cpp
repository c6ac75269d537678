// The report's page machinery: values are escaped by the templates, tables and figures render
// their parts, numbers follow the one formatter.
#include "experiments/report/html.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <optional>

#include "experiments/report/format.hpp"
#include "experiments/report/templates.hpp"

namespace reposetwin::experiments::report {
namespace {

// An error message recorded in loop.json names the scene by the path the loop resolved; a
// committed page must not carry the builder's folders (CommittedReports.OpenInAFreshClone).
TEST(ReportHtml, PathsInFreeTextAreShownAsThePageShowsAPath) {
  const std::string why =
      "test t1: /nowhere/built/here/data/scene.toml: sample.psd: d_min = 1.4 mm (see "
      "/nowhere/x.csv), ratio 2/3 and a/b stay";
  EXPECT_EQ(paths_for_page(why),
            "test t1: scene.toml: sample.psd: d_min = 1.4 mm (see x.csv), ratio 2/3 and a/b stay");
  EXPECT_EQ(paths_for_page("no path here"), "no path here");
  EXPECT_EQ(paths_for_page("/a/b.png"), "b.png");
}

TEST(ReportHtml, PageEscapesValuesAndKeepsRenderedSections) {
  const Page page{"a <b> & \"c\"", "Heading <i>", {"<p>section one</p>", "<p>two</p>"}};
  const std::string html = render_page(page);
  EXPECT_NE(html.find("<title>a &lt;b&gt; &amp; &quot;c&quot;</title>"), std::string::npos);
  EXPECT_NE(html.find("<h1>Heading &lt;i&gt;</h1>"), std::string::npos);
  EXPECT_LT(html.find("<p>section one</p>"), html.find("<p>two</p>"));
  EXPECT_NE(html.find("<style>"), std::string::npos);
}

TEST(ReportHtml, TableCellsRenderEveryPartEscaped) {
  Table t;
  t.header = {"name", "value \u00b1 sd"};
  t.caption_html = "<code>kept</code>";
  Cell c("text<");
  c.bold = "prediction";
  c.code = "{\"k\":1}";
  c.small = "small";
  c.note = "note";
  c.links = {{"../a/series.pvd", "pvd"}};
  t.rows.push_back({{"plain", c}, true});
  mustache::data d;
  d.set("t", to_data(t));
  const std::string html = render("{{#t}}{{> table}}{{/t}}", d);
  EXPECT_NE(html.find("<caption><code>kept</code></caption>"), std::string::npos) << html;
  EXPECT_NE(html.find("<th>value \u00b1 sd</th>"), std::string::npos);
  EXPECT_NE(html.find("<tr class='shaded'><td>plain</td>"), std::string::npos) << html;
  EXPECT_NE(html.find("<b>prediction</b> <code>{&quot;k&quot;:1}</code>text&lt; <small>small</small>"
                      "<br><small>note</small><a href='../a/series.pvd'>pvd</a>"),
            std::string::npos)
      << html;
  EXPECT_THROW(render("{{#open}}", d), std::logic_error);
}

TEST(ReportHtml, FiguresAndNumbers) {
  mustache::data d;
  d.set("f", to_data(std::vector<Figure>{{"a.png", "cap & more", 480}, {"b.png", "b", 0}}));
  const std::string html = render("{{#f}}{{> figure}}{{/f}}", d);
  EXPECT_NE(html.find("<img src='a.png' width='480'><figcaption>cap &amp; more"), std::string::npos)
      << html;
  EXPECT_NE(html.find("<img src='b.png'><figcaption>"), std::string::npos) << html;
  EXPECT_EQ(fixed(35.126), "35.13");
  EXPECT_EQ(fixed(0.14444, 3), "0.144");
  EXPECT_EQ(fixed_or_dash(nlohmann::json()), "-");
  EXPECT_EQ(sig3(nlohmann::json(0.123456)), "0.123");
  EXPECT_EQ(sig3(nlohmann::json("x")), "-");
  // A number read back from a result file prints as its JSON does: NaN was null, "-".
  EXPECT_EQ(sig3_or_dash(24.0), sig3(nlohmann::json(24)));
  EXPECT_EQ(sig3_or_dash(0.123456), "0.123");
  EXPECT_EQ(sig3_or_dash(std::numeric_limits<double>::quiet_NaN()), "-");
  EXPECT_EQ(sig3_or_dash(std::optional<double>()), "-");
  EXPECT_EQ(as_printed(nlohmann::json(200.0)), "200");
  EXPECT_EQ(as_printed(nlohmann::json(3.35)), "3.35");
  EXPECT_EQ(mean_sd(35.0, 0.25), "35.00 \u00b1 0.25");
}

}  // namespace
}  // namespace reposetwin::experiments::report
