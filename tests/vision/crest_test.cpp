// The crest (flat top) against closed forms: truncated cones drawn analytically
// (tests/vision/synthetic.hpp) whose top width is known, and a sharp cone, whose crest is 0.
// And the flat heap: grains lying apart on the plate are refused with numbers, a layer of
// grains touching one another reads as the low heap it is.
#include "vision/crest.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "tests/vision/synthetic.hpp"
#include "vision/measure.hpp"

namespace reposetwin::vision {
namespace {

using synthetic::SideScene;

double theta_of(double h, double d) { return std::atan(2.0 * h / d) * 180.0 / std::numbers::pi; }

SideMeasurement measure_ortho(const SideScene& s) {
  ScaleSpec spec;
  spec.mm_per_px = s.mm_per_px;
  return measure_side(synthetic::draw_side(s), spec, {}, "crest.png");
}

// A sharp cone's silhouette at depth d below its apex is d (cot + cot) wide, all of it the
// flanks': crest 0. The apex reads about half a pixel low (side_view.hpp), which leaves up to
// half a pixel times the two cotangents (1.7 px at 30 deg); tolerance 2.5 px.
TEST(Crest, SharpConeHasNone) {
  for (double h : {40.0, 60.0, 90.0}) {
    SideScene s;
    s.height_mm = h;
    s.diameter_mm = 200.0;
    const SideMeasurement m = measure_ortho(s);
    EXPECT_NEAR(m.crest.raw_width_px, 0.0, 2.5) << "H = " << h;
    EXPECT_LT(m.crest_width_m, 2.5 * s.mm_per_px * 1e-3) << "H = " << h;
  }
}

// A grain standing on the apex is narrower than the edge window, so the silhouette has no edge
// row within the crest's depth (5% of H) of the apex: the crest is read from the highest rows
// each side has, as for a top that deep. A 100 px tall cone of 45 deg flanks on a plate at row
// 200, its edges from 30 px below the apex down: each end carried up its flank to the apex
// height meets the axis, crest 0 within a pixel (it threw "no silhouette row" before: an exit 2
// for a pile that was there; the LIGGGHTS pours seen from 5 deg above).
TEST(Crest, AGrainOnTheApexReadsFromTheHighestRows) {
  SideProfile p;
  p.plate.a = 200.0;
  p.height_px = 100.0;
  p.apex = {500.0, 100.0};
  const double s = std::sqrt(0.5);
  p.left.direction = {s, -s};
  p.left.angle_deg = 45.0;
  p.right.direction = {-s, -s};
  p.right.angle_deg = 45.0;
  for (double v = 130.0; v <= 195.0; v += 1.0) {
    const double half = v - 100.0;  // 45 deg flanks through the apex
    p.left_edge.emplace_back(500.0 - half, v);
    p.right_edge.emplace_back(500.0 + half, v);
  }
  p.left.point = p.left_edge.front();
  p.right.point = p.right_edge.front();
  Crest c;
  ASSERT_NO_THROW(c = measure_crest(p, {}, "grain.png"));
  EXPECT_NEAR(c.raw_width_px, 0.0, 1.0);
  // Edges that stop below half of H: no crest is read, and the error names the photo.
  SideProfile low = p;
  low.left_edge.assign(p.left_edge.begin() + 30, p.left_edge.end());
  low.right_edge.assign(p.right_edge.begin() + 30, p.right_edge.end());
  EXPECT_THROW(
      {
        try {
          measure_crest(low, {}, "grain.png");
        } catch (const std::runtime_error& e) {
          EXPECT_NE(std::string(e.what()).find("grain.png"), std::string::npos);
          throw;
        }
      },
      std::runtime_error);
}

// A truncated cone of top width w: its silhouette is w + d (cot + cot) wide at any depth d within
// the straight flanks, so the crest is w. The edges are sub-pixel (coverage), the crest's two
// ends each carried up the fitted flank over d (5% of H, 12-18 px here): within 2 px. Its H, D
// and flank angle are those of the frustum: atan(2H/D) is not the flank angle atan(H / (R - w/2)).
TEST(Crest, TruncatedConeGivesItsTopWidth) {
  for (double w : {20.0, 40.0, 80.0}) {
    for (double h : {50.0, 70.0}) {
      SideScene s;
      s.height_mm = h;
      s.diameter_mm = 220.0;
      s.top_width_mm = w;
      const SideMeasurement m = measure_ortho(s);
      const std::string at = "w " + std::to_string(w) + " H " + std::to_string(h);
      EXPECT_NEAR(1e3 * m.crest_width_m, w, 2.0 * s.mm_per_px) << at;
      EXPECT_NEAR(m.theta_deg, theta_of(h, 220.0), 0.3) << at;
      const double flank = std::atan(h / (110.0 - 0.5 * w)) * 180.0 / std::numbers::pi;
      EXPECT_NEAR(0.5 * (m.flank_left_deg + m.flank_right_deg), flank, 0.5) << at;
      EXPECT_GT(m.sigma_crest_width_m, 0.0) << at;
    }
  }
}

// Through a perspective camera level with the plate the frustum's top rim is seen from below:
// its near point is the silhouette's top, its sides (the crest's ends, at the axis' depth L) a
// few pixels lower, and the crest's ends are carried up the flanks to the rim's sides, not to the
// apex height. H is read at the rim's near point mapped to the axis plane: h L / (L - w/2)
// (61.5 mm for 60 at L = 0.8 m), the known bias of a flat top seen from below, within 0.3 mm.
// The crest within 1 mm (3 px at 0.31 mm/px).
TEST(Crest, PerspectiveCameraGivesItsTopWidth) {
  const camera::Camera cam = camera::side_view(0.8, 0.4, 0.0, 30.0, 1280, 720);
  SideScene s;
  s.camera = cam;
  s.height_mm = 60.0;
  s.diameter_mm = 200.0;
  s.top_width_mm = 40.0;
  const SideMeasurement m = measure_side_camera(synthetic::draw_side(s), cam, {}, "frustum.png");
  EXPECT_NEAR(1e3 * m.crest_width_m, 40.0, 1.0);
  EXPECT_NEAR(1e3 * m.height_m, 60.0 * 0.8 / (0.8 - 0.020), 0.3);
  EXPECT_NEAR(1e3 * m.diameter_m, 200.0, 1.0);
  s.top_width_mm = 0.0;
  const SideMeasurement sharp = measure_side_camera(synthetic::draw_side(s), cam, {}, "cone.png");
  EXPECT_LT(1e3 * sharp.crest_width_m, 1.0);
}

// The crest is a typed field of the measurement and of its JSON, and of the views' summary.
TEST(Crest, InTheRecordAndTheSummary) {
  SideScene s;
  s.top_width_mm = 40.0;
  const SideMeasurement m = measure_ortho(s);
  const nlohmann::json j = to_json(m);
  EXPECT_DOUBLE_EQ(j.at("crest_width_m").get<double>(), m.crest_width_m);
  EXPECT_TRUE(j.at("pixels").at("crest").contains("rule"));
  const SideSummary sum = combine_sides({m, m});
  EXPECT_DOUBLE_EQ(sum.crest_width_m.mean, m.crest_width_m);
  EXPECT_TRUE(to_json(sum).contains("crest_width_m"));
  CrestSettings bad;
  bad.depth_fraction = 0.7;
  EXPECT_THROW(measure_crest(m.pixels, bad, "crest.png"), std::invalid_argument);
}

// Grains (3.5 mm disks) lying on the plate in pairs, 12 mm apart: the largest dark blob is a pair,
// and measured as a pile a pair of touching disks reads atan(2 d / 2 d) = 45 deg. It is one of
// many such blobs: refused, with the numbers.
TEST(FlatHeap, ScatteredGrainsAreRefused) {
  SideScene s;
  s.mm_per_px = 0.05;
  s.height_mm = 0.01;  // no cone: the pile is the grains
  s.diameter_mm = 0.01;
  s.stray_diameter_mm = 3.5;
  s.monolayer_mm = 40.0;
  s.monolayer_pitch_mm = 6.0;
  s.scale_bar = false;
  ScaleSpec spec;
  spec.mm_per_px = s.mm_per_px;
  try {
    const SideMeasurement m = measure_side(synthetic::draw_side(s), spec, {}, "grains.png");
    FAIL() << "measured as a pile: theta " << m.theta_deg << " deg";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("no heap"), std::string::npos) << what;
    EXPECT_NE(what.find("blobs of similar size"), std::string::npos) << what;
  }
}

// A layer of grains touching one another (disks 3.5 mm, 3 mm apart, 80 mm long): one blob one
// grain tall; it reads as the flat heap it is, atan(2 x 3.5 / 80) = 5 deg give or take the end
// grains, with a crest most of its width.
TEST(FlatHeap, TouchingMonolayerReadsFlat) {
  SideScene s;
  s.mm_per_px = 0.1;
  s.height_mm = 0.01;
  s.diameter_mm = 0.01;
  s.stray_diameter_mm = 3.5;
  s.monolayer_mm = 40.0;
  s.monolayer_pitch_mm = 3.0;
  s.scale_bar = false;
  ScaleSpec spec;
  spec.mm_per_px = s.mm_per_px;
  const SideMeasurement m = measure_side(synthetic::draw_side(s), spec, {}, "layer.png");
  const double reach = 2.0 * synthetic::monolayer_reach_mm(s);
  EXPECT_LT(m.theta_deg, 7.0);
  EXPECT_NEAR(1e3 * m.diameter_m, reach, 0.1 * reach);
  EXPECT_GT(m.crest_width_m, 0.5 * m.diameter_m);
}

}  // namespace
}  // namespace reposetwin::vision
