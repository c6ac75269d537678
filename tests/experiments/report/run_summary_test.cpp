// The run summary: a tiny pile run photographed from memory, its headline in result.json under
// the one name, and a page whose every link and image is relative and exists.
#include "experiments/report/run_summary.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "../../support/tiny_scene.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/photos/pile_images.hpp"
#include "experiments/pile/pile_run.hpp"
#include "experiments/report/page_check.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

struct TinyRun {
  SceneConfig scene;
  PileRun run;
  fs::path dir;
};

TinyRun tiny_run(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("reposetwin_run_summary_" + name);
  fs::remove_all(dir);
  TinyRun t;
  t.dir = dir / "run";
  t.scene = parse_scene_text(test_support::kTinyScene, (dir / "tiny.toml").string());
  RunOptions opt;
  opt.out_dir = t.dir.string();
  opt.progress = false;
  t.run = *run_pile_test(t.scene, opt);
  return t;
}

TEST(RunSummary, PhotographedRunHasTheImageHeadlineAndAPageWhoseImagesExist) {
  TinyRun t = tiny_run("images");
  ASSERT_TRUE(t.run.pile_ok());
  ImageSettings s;
  s.width_px = 640;
  s.height_px = 360;
  s.side_views = 2;
  RunSummaryInputs in;
  in.run_dir = t.dir.string();
  in.overrides = {"procedure.lift_speed_m_s=0.02"};
  in.images = render_and_measure_run(t.run, in.run_dir, s);
  in.wall_s = 12.0;
  const RunSummary summary = finish_run(t.run, t.scene, in);
  ASSERT_TRUE(summary.headline);
  EXPECT_TRUE(summary.headline->from_images);
  EXPECT_EQ(summary.headline->views, 2);

  // result.json: the headline is the images' atan(2H/D) under its one name; old fields kept.
  const json r = json::parse(read_file((t.dir / "result.json").string()));
  EXPECT_EQ(r["headline_measure"], kHeadlineFromImages);
  EXPECT_DOUBLE_EQ(r["headline_angle_deg"].get<double>(), (*in.images)["theta_deg"].get<double>());
  EXPECT_DOUBLE_EQ(r["image"]["theta_deg"].get<double>(), (*in.images)["theta_deg"].get<double>());
  EXPECT_DOUBLE_EQ(r["pile"]["theta_hd_deg"].get<double>(), t.run.pile.theta_hd_deg);
  EXPECT_NO_THROW(pile_run_from_json(r));

  // The page: relative links only, each to a file that exists; two side overlays and the top.
  const std::string html = read_file(summary.page);
  for (const report::PageProblem& p : report::page_problems(summary.page))
    ADD_FAILURE() << report::to_string(p.kind) << ": " << p.what;
  int images = 0;
  for (const std::string& ref : report::page_references(html))
    images += ref.find(".measured.png") != std::string::npos;
  EXPECT_EQ(images, 3);
  for (const char* name : {"headline_angle_deg", "pile.theta_hd_deg", "pile.slice_angle_mean_deg",
                           "flank_deg", "procedure.lift_speed_m_s=0.02", "Provenance"})
    EXPECT_NE(html.find(name), std::string::npos) << name;

  const std::string line = headline_line(t.run, summary, 12.0);
  EXPECT_NE(line.find("image atan(2H/D), 2 side views"), std::string::npos) << line;
  EXPECT_NE(line.find("report " + summary.page), std::string::npos) << line;
  EXPECT_NE(line.find(std::to_string(t.run.particles.final) + " particles"), std::string::npos);
}

TEST(RunSummary, WithoutPhotographsTheHeadlineIsTheParticleAngleAndSaysSo) {
  TinyRun t = tiny_run("particles");
  RunSummaryInputs in;
  in.run_dir = t.dir.string();
  in.images_note = "--no-images";
  const RunSummary summary = finish_run(t.run, t.scene, in);
  ASSERT_TRUE(summary.headline);
  EXPECT_FALSE(summary.headline->from_images);
  const json r = json::parse(read_file((t.dir / "result.json").string()));
  EXPECT_EQ(r["headline_measure"], kHeadlineFromParticles);
  EXPECT_DOUBLE_EQ(r["headline_angle_deg"].get<double>(), t.run.pile.theta_hd_deg);
  EXPECT_FALSE(r.contains("image"));
  const std::string html = read_file(summary.page);
  EXPECT_NE(html.find("not the lab&apos;s measure"), std::string::npos);
  EXPECT_NE(headline_line(t.run, summary, 1.0).find("particle atan(2H/D): no photographs"),
            std::string::npos);
  EXPECT_TRUE(report::page_problems(summary.page).empty());
}

}  // namespace
}  // namespace reposetwin::experiments
