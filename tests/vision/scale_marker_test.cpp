// Tests of vision/scale_marker: the band bar and the checker card of the render convention.
#include "vision/scale_marker.hpp"

#include <gtest/gtest.h>

#include "tests/vision/synthetic.hpp"

namespace reposetwin::vision {
namespace {

TEST(ScaleBar, GivesTheDrawnScaleAtSeveralScales) {
  for (double mm_per_px : {0.13, 0.25, 0.6}) {
    synthetic::SideScene s;
    s.mm_per_px = mm_per_px;
    s.height_mm = 30.0 * mm_per_px / 0.13;
    s.diameter_mm = 100.0 * mm_per_px / 0.13;
    s.height = 1080;
    s.plate_v = 950.0;  // the whole 100 mm bar in view at the finest scale
    s.bar_offset_mm =
        -(0.5 * s.diameter_mm + 0.5 * (0.5 * s.width * mm_per_px - 0.5 * s.diameter_mm));
    const auto bar = find_scale_bar(synthetic::draw_side(s));
    ASSERT_TRUE(bar.has_value()) << "mm/px " << mm_per_px;
    EXPECT_NEAR(bar->mm_per_px, mm_per_px, 0.003 * mm_per_px) << "mm/px " << mm_per_px;
    EXPECT_GE(bar->black_bands, 3);
    EXPECT_LT(bar->sigma_rel, 0.02);
  }
}

TEST(ScaleBar, SurvivesPhotoConditions) {
  synthetic::SideScene s;
  s.look.noise_sigma = 8.0;
  s.look.blur_sigma_px = 1.5;
  s.look.lighting_gradient = 0.2;
  s.look.backdrop_texture = 12.0;
  const auto bar = find_scale_bar(synthetic::draw_side(s));
  ASSERT_TRUE(bar.has_value());
  EXPECT_NEAR(bar->mm_per_px, s.mm_per_px, 0.005 * s.mm_per_px);
}

TEST(ScaleBar, AbsentBarIsNotInvented) {
  synthetic::SideScene s;
  s.scale_bar = false;
  EXPECT_FALSE(find_scale_bar(synthetic::draw_side(s)).has_value());
}

TEST(CheckerCard, GivesTheDrawnScale) {
  for (double mm_per_px : {0.2, 0.35}) {
    synthetic::TopScene t;
    t.mm_per_px = mm_per_px;
    t.diameter_mm = 120.0;  // clear of the card
    t.look.noise_sigma = 5.0;
    t.look.blur_sigma_px = 1.0;
    const auto card = find_checker_card(synthetic::draw_top(t));
    ASSERT_TRUE(card.has_value()) << "mm/px " << mm_per_px;
    EXPECT_NEAR(card->mm_per_px, mm_per_px, 0.005 * mm_per_px);
    EXPECT_EQ(card->squares, 8);
  }
  synthetic::TopScene none;
  none.checker_card = false;
  EXPECT_FALSE(find_checker_card(synthetic::draw_top(none)).has_value());
}

}  // namespace
}  // namespace reposetwin::vision
