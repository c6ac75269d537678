// Photographs of a clump pile: every component sphere is drawn, and vision reads the rendered
// pile's height close to the height measured from the component spheres themselves.
#include <gtest/gtest.h>

#include <filesystem>

#include "../../support/tiny_scene.hpp"
#include "experiments/io/scene.hpp"
#include "experiments/photos/photographs.hpp"
#include "experiments/photos/pile_images.hpp"
#include "experiments/pile/pile_run.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

TEST(ClumpPhotos, ARodPileIsDrawnByItsComponentsAndMeasuredByVision) {
  const fs::path dir = fs::temp_directory_path() / "reposetwin_clump_photos";
  fs::remove_all(dir);
  RunOptions opt;
  opt.out_dir = (dir / "run").string();
  opt.progress = false;
  const std::string text = std::string(test_support::kTinyScene) + test_support::kTinyRods;
  const std::optional<PileRun> run =
      run_pile_test(parse_scene_text(text, (dir / "rods.toml").string()), opt);
  ASSERT_TRUE(run && run->pile_ok());
  ASSERT_TRUE(run->shape.has_value());
  // The scene handed to the renderer: one sphere per component, of the component's radius.
  const render::Scene scene = centred_pile_scene(run->final_spheres, std::nullopt, nullptr);
  EXPECT_EQ(static_cast<std::int64_t>(scene.positions.size()), run->shape->components_final);
  EXPECT_EQ(scene.radii, run->final_spheres.radius);
  ImageSettings s;
  s.width_px = 640;
  s.height_px = 360;
  s.side_views = 2;
  const nlohmann::json m = render_and_measure_run(opt.out_dir, s);
  // Vision sees a pile. Its height is the apex's, robust even for about 50 grains; the width
  // is not (a few strays widen an image's D by 10-30% at this size), so only H is compared.
  EXPECT_GT(m["theta_deg"].get<double>(), 5.0) << m.dump();
  EXPECT_NEAR(m["height_m"].get<double>(), run->pile.height_m, 0.25 * run->pile.height_m);
}

}  // namespace
}  // namespace reposetwin::experiments
