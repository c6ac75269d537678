// bench_render: time to render a pile of 100,000 spheres at 1920 x 1080 (goal: under 1 s on
// a 2-core machine), side and top views, and the resulting images per second; then the side
// view without occlusion culling and with lens distortion, to show what each costs.
// Usage: bench_render [N_SPHERES] [OUTPUT_STEM]  (with OUTPUT_STEM, also writes the two views).
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <string>

#include "render/output.hpp"
#include "render/renderer.hpp"
#include "render/scene.hpp"

namespace {

using reposetwin::render::Scene;

// A 30-degree cone of randomly placed (overlapping) spheres, 1.0 to 1.5 mm in radius, with the
// packing density of a real pile of that many grains; fixed seed.
Scene cone_pile(int n) {
  Scene s;
  std::uint64_t x = 12345;
  auto next = [&x]() {
    x = x * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(x >> 11) * 0x1.0p-53;
  };
  const double pi = 3.14159265358979323846;
  const double r_mean = 1.25e-3;
  const double grain_volume = n * 4.0 / 3.0 * pi * r_mean * r_mean * r_mean / 0.6;
  const double tan_slope = std::tan(30.0 * pi / 180.0);
  const double radius = std::cbrt(3.0 * grain_volume / (pi * tan_slope));
  const double height = radius * tan_slope;
  while (static_cast<int>(s.positions.size()) < n) {
    const double px = radius * (2.0 * next() - 1.0);
    const double py = radius * (2.0 * next() - 1.0);
    const double pz = height * next();
    const double rho = std::hypot(px, py);
    if (rho > radius || pz > height * (1.0 - rho / radius)) continue;
    const double r = 1.0e-3 + 0.5e-3 * next();
    s.positions.emplace_back(px, py, pz + r);
    s.radii.push_back(r);
    s.material_ids.push_back(s.positions.size() % 2 == 0 ? 0 : 1);
  }
  return s;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  namespace render = reposetwin::render;
  const int n = argc > 1 ? std::atoi(argv[1]) : 100000;
  if (n <= 0) {
    std::cerr << "bench_render: N_SPHERES must be positive, got " << argv[1] << "\n";
    return 2;
  }
  const Scene scene = cone_pile(n);
  const auto side = render::lab_side_camera(scene);
  const auto top = render::lab_top_camera(scene);
  auto side_lens = side;  // a mild barrel distortion: adds the warp
  side_lens.intrinsics.k1 = -0.05;
  render::RenderOptions side_opts, top_opts, side_all;
  top_opts.view = render::View::kTop;
  side_all.occlusion_culling = false;  // every sphere drawn: the cost culling saves

  auto t0 = std::chrono::steady_clock::now();
  render::Renderer renderer;
  const double setup = seconds_since(t0);
  std::cout << "bench_render: " << renderer.gl_description() << "\n";
  std::cout << "  context + shaders: " << setup * 1e3 << " ms\n";
  std::cout << "  pile: " << n << " spheres, radius " << render::pile_extent(scene).radius_m
            << " m, images " << side.intrinsics.width_px << " x " << side.intrinsics.height_px
            << "\n";

  for (const auto& [name, cam, opts] :
       {std::tuple{"side", side, side_opts}, std::tuple{"top", top, top_opts},
        std::tuple{"side_no_culling", side, side_all},
        std::tuple{"side_k1", side_lens, side_opts}}) {
    t0 = std::chrono::steady_clock::now();
    const cv::Mat first = renderer.render(scene, cam, opts);
    const double first_s = seconds_since(t0);
    const int repeats = 3;
    t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < repeats; ++i) renderer.render(scene, cam, opts);
    const double each = seconds_since(t0) / repeats;
    std::cout << "  " << name << " view: first " << first_s * 1e3 << " ms, then " << each * 1e3
              << " ms per image (" << 1.0 / each << " images/s)"
              << (each < 1.0 ? "  [goal < 1 s: met]" : "  [goal < 1 s: NOT met]") << "\n";
    const render::RenderProfile& p = renderer.last_profile();
    std::cout << "    last image: prepare " << p.prepare_s * 1e3 << " ms, draw " << p.draw_s * 1e3
              << " ms, read back " << p.readback_s * 1e3 << " ms, warp " << p.warp_s * 1e3
              << " ms; " << p.spheres_drawn << " spheres drawn\n";
    if (argc > 2) {
      const std::string stem = std::string(argv[2]) + "_" + name;
      render::write_render(stem, first,
                           render::make_sidecar(scene, cam, opts, {{"source", "bench_render"}}));
      std::cout << "  wrote " << stem << ".png and .json\n";
    }
  }
  return 0;
}
