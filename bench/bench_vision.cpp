// bench_vision: milliseconds per 1920x1080 image for the vision measurements (goal: < 50 ms for a
// side view). Images come from the analytic test generator (tests/vision/synthetic.hpp), drawn
// once before timing. Prints figures; not a test.
#include <chrono>
#include <cstdio>
#include <ctime>
#include <functional>
#include <string>

#include "tests/vision/synthetic.hpp"
#include "vision/measure.hpp"

namespace {

using reposetwin::vision::synthetic::SideScene;
using reposetwin::vision::synthetic::TopScene;
namespace vision = reposetwin::vision;

struct Timing {
  double wall_ms = 0.0;  // elapsed time per call [ms]
  double cpu_ms = 0.0;   // process CPU time per call, all threads [ms]
};

// Wall time depends on what else the (shared) machine runs; CPU time much less so.
Timing time_per_call(const std::function<void()>& f, int reps) {
  f();  // warm-up
  const auto t0 = std::chrono::steady_clock::now();
  const std::clock_t c0 = std::clock();
  for (int i = 0; i < reps; ++i) f();
  const std::clock_t c1 = std::clock();
  const auto t1 = std::chrono::steady_clock::now();
  return {std::chrono::duration<double, std::milli>(t1 - t0).count() / reps,
          1000.0 * static_cast<double>(c1 - c0) / CLOCKS_PER_SEC / reps};
}

}  // namespace

int main() {
  constexpr int kReps = 10;
  SideScene clean;
  clean.width = 1920;
  clean.height = 1080;
  clean.mm_per_px = 0.2;
  clean.plate_v = 800.0;
  clean.bar_offset_mm = -160.0;
  SideScene hard = clean;
  hard.look.noise_sigma = 8.0;
  hard.look.blur_sigma_px = 1.5;
  hard.look.lighting_gradient = 0.2;
  hard.look.backdrop_texture = 12.0;
  hard.look.pile_speckle = 0.08;
  const cv::Mat side_clean = vision::synthetic::draw_side(clean);
  const cv::Mat side_hard = vision::synthetic::draw_side(hard);
  SideScene persp = clean;
  const auto cam = reposetwin::camera::side_view(1.0, 0.4, 0.0, 0.0, 1920, 1080);
  persp.camera = cam;
  const cv::Mat side_persp = vision::synthetic::draw_side(persp);
  TopScene top;
  top.width = 1920;
  top.height = 1080;
  top.mm_per_px = 0.2;
  top.look.noise_sigma = 8.0;
  top.look.pile_speckle = 0.08;
  const cv::Mat top_img = vision::synthetic::draw_top(top);

  vision::ScaleSpec given;
  given.mm_per_px = clean.mm_per_px;
  vision::ScaleSpec with_camera;
  with_camera.camera = cam;

  std::printf("bench_vision: ms per 1920x1080 image (mean of %d, after one warm-up; goal < 50)\n",
              kReps);
  std::printf("  %-52s %9s %9s\n", "", "wall ms", "CPU ms");
  auto row = [&](const char* what, const std::function<void()>& f) {
    const Timing t = time_per_call(f, kReps);
    std::printf("  %-52s %9.2f %9.2f\n", what, t.wall_ms, t.cpu_ms);
  };
  row("side, pixels only (clean)", [&] { vision::measure_side_pixels(side_clean); });
  row("side, pixels only (noise, blur, light, texture)",
      [&] { vision::measure_side_pixels(side_hard); });
  row("side, given mm/px", [&] { vision::measure_side(side_clean, given); });
  row("side, scale bar search + measurement", [&] { vision::measure_side(side_hard); });
  row("side, known camera (perspective corrected)",
      [&] { vision::measure_side(side_persp, with_camera); });
  row("scale bar search alone", [&] { vision::find_scale_bar(side_hard); });
  row("top view, checker card + footprint", [&] { vision::measure_top(top_img); });
  {
    const vision::SideMeasurement m = vision::measure_side(side_hard);
    row("side overlay drawing", [&] { vision::draw_side_overlay(side_hard, m); });
  }
  return 0;
}
