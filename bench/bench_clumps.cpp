// bench_clumps: throughput of the DEM engine with rigid clumps beside spheres.
//
// Design note. Two beds are built the same way and timed the same way: N four-sphere clumps
// (tetrahedra: component radius r, centres at 0.9 r from the body's centre, r uniform in
// [0.5, 0.6] mm in six template sizes, random orientations), and 4N spheres with radii drawn from
// the same range, so both have the same number of spheres. Each starts on a lattice inside a
// cylindrical container (radius 30 mm) on a plate (square layers, each shifted by half a spacing
// from the one below, sites jittered by up to 0.02 mm so that no column stands on its own), falls
// and settles for --settle steps under
// --settle-gravity g, then relaxes --relax steps at 1 g with a small velocity damping (as
// bench_sim), and the settled bed is timed for --steps steps on each requested thread count.
// Printed: body-steps/s and component-steps/s for the clumps, particle-steps/s for the spheres,
// the contacts per sphere of each bed, the time per component-step over the time per sphere
// particle-step (the target: within 1.3x), and each phase's time. Every thread count
// computes the identical trajectory; the benchmark checks that the state hashes agree.
//
// With --beds PREFIX the settled beds are read from PREFIX.clumps.ckpt and PREFIX.spheres.ckpt if
// they exist, and written there otherwise, so that builds can be timed on the same start.
//
// Usage: bench_clumps [--quick] [--clumps N] [--steps N] [--threads 1,2] [--settle N]
//                     [--relax N] [--settle-gravity G] [--settle-threads N] [--seed S]
//                     [--beds PREFIX]
#include <omp.h>
#include <time.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <string>
#include <vector>

#include "sim/checkpoint.hpp"
#include "sim/model.hpp"
#include "sim/random.hpp"
#include "sim/world.hpp"

namespace {

using namespace reposetwin::sim;

constexpr double kRadiusMin = 0.5e-3, kRadiusMax = 0.6e-3;  // component / sphere radii [m]
constexpr int kSizes = 6;                                   // clump template sizes
constexpr double kArm = 0.9;                     // component centre distance / radius [-]
constexpr double kContainer = 0.03;              // container radius [m]
constexpr double kRelaxDamping = 0.005;          // velocity damping per relax step [-]

struct Options {
  int clumps = 5000;
  int steps = 1000;
  int settle = 7000;
  int relax = 3000;
  double settle_gravity = 5.0;
  int settle_threads = 2;
  std::vector<int> threads{1, 2};
  std::uint64_t seed = 1;
  std::string beds;
};

Model make_model(double gravity_factor) {
  Model m;
  Material rock;
  rock.youngs_modulus = 46.8e9;
  Material steel = rock;
  steel.name = "steel";
  m.materials = {rock, steel};
  m.settings.softened_youngs_modulus = 46.8e6;
  m.settings.gravity = Vec3(0, 0, -9.81 * gravity_factor);
  m.settings.max_overlap_ratio = 0.15;
  PairParams pair;  // the paper's e 0.79, mu_s 0.466, EPSD mu_r 0.15
  m.set_pair(0, 0, pair);
  m.set_pair(0, 1, pair);
  m.set_pair(1, 1, pair);
  WallSpec plate;
  m.walls.push_back(plate);
  WallSpec can;
  can.name = "container";
  can.kind = WallKind::kShell;
  can.z_top = 0.2;
  can.r_bottom = kContainer;
  can.r_top = kContainer;
  m.walls.push_back(can);
  for (int k = 0; k < kSizes; ++k) {
    const double r = kRadiusMin + (kRadiusMax - kRadiusMin) * (k + 0.5) / kSizes;
    const double a = kArm * r / std::sqrt(3.0);
    m.add_clump_template({"tetra", {a * Vec3(1, 1, 1), a * Vec3(1, -1, -1), a * Vec3(-1, 1, -1),
                                    a * Vec3(-1, -1, 1)},
                          {r, r, r, r}});
  }
  m.finalize(kRadiusMin, kRadiusMax);
  return m;
}

/// A bed of `count` grains on a cubic lattice of spacing `spacing` inside the container.
World make_bed(const Model& model, int count, bool clumps, double spacing, std::uint64_t seed) {
  World w(model);
  Rng rng(seed);
  const int across = static_cast<int>((kContainer - 0.5 * spacing) / spacing);
  int placed = 0;
  for (int layer = 0; placed < count; ++layer) {
    for (int ix = -across; ix <= across && placed < count; ++ix)
      for (int iy = -across; iy <= across && placed < count; ++iy) {
        const double shift = layer % 2 == 0 ? 0.0 : 0.5 * spacing;
        const Vec3 x(spacing * ix + shift + rng.uniform(-0.02e-3, 0.02e-3),
                     spacing * iy + shift + rng.uniform(-0.02e-3, 0.02e-3),
                     0.5 * spacing + spacing * layer);
        if (std::hypot(x.x(), x.y()) > kContainer - 0.5 * spacing) continue;
        if (clumps) {
          const Quat q(rng.normal(0, 1), rng.normal(0, 1), rng.normal(0, 1), rng.normal(0, 1));
          w.add_clump(static_cast<int>(rng.uniform() * kSizes), x, q.normalized(), 0);
        } else {
          w.add_particle(x, rng.uniform(kRadiusMin, kRadiusMax), 0);
        }
        ++placed;
      }
  }
  return w;
}

double touching_per_sphere(const World& w) {
  const Diagnostics d = w.diagnose();
  return static_cast<double>(d.contacts) / static_cast<double>(w.state().particles.size());
}

/// Settles the bed: settle_gravity g, then 1 g with damping (velocities of spheres and bodies).
void settle(World& world, const Options& o, const char* what) {
  const auto t0 = std::chrono::steady_clock::now();
  omp_set_num_threads(o.settle_threads);
  World heavy(make_model(o.settle_gravity));
  heavy.state() = world.state();
  for (int s = 0; s < o.settle; ++s) heavy.step();
  world.state() = heavy.state();
  for (int s = 0; s < o.relax; ++s) {
    world.step();
    Particles& p = world.state().particles;
    for (std::size_t i = 0; i < p.size(); ++i) {
      p.v[i] *= 1.0 - kRelaxDamping;
      p.w[i] *= 1.0 - kRelaxDamping;
    }
    Bodies& b = world.state().bodies;
    for (std::size_t k = 0; k < b.size(); ++k) {
      b.v[k] *= 1.0 - kRelaxDamping;
      b.w[k] *= 1.0 - kRelaxDamping;
      b.l[k] *= 1.0 - kRelaxDamping;
    }
  }
  const Diagnostics d = world.diagnose();
  std::cout << "  " << what << ": settled in "
            << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()
            << " s: KE " << d.kinetic_energy << " J, " << touching_per_sphere(world)
            << " contacts (pairs + walls) per sphere, max overlap " << d.max_overlap_ratio << ", status "
            << status_name(d.status) << "\n";
  if (d.status != Status::kOk) throw std::runtime_error(std::string("settle: ") + d.detail);
}

double process_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

struct Timing {
  double seconds = 0, cpu = 0;
  std::uint64_t hash = 0;
};

Timing timed(const World& settled, int steps, int threads, const char* what) {
  World w = settled;
  omp_set_num_threads(threads);
  w.reset_profile();
  const auto t0 = std::chrono::steady_clock::now();
  const double c0 = process_cpu_seconds();
  for (int s = 0; s < steps; ++s) w.step();
  Timing t;
  t.cpu = process_cpu_seconds() - c0;
  t.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  t.hash = state_hash(w.state());
  const double n = static_cast<double>(w.state().particles.size());
  const double nb = static_cast<double>(w.state().bodies.size());
  std::cout << "  " << what << ", threads " << threads << ": " << steps << " steps in "
            << std::setprecision(4) << t.seconds << " s wall, " << t.cpu << " s CPU; ";
  if (nb > 0) std::cout << nb * steps / t.seconds << " body-steps/s, ";
  std::cout << n * steps / t.seconds << (nb > 0 ? " component-steps/s" : " particle-steps/s")
            << " (" << 1e9 * t.seconds / (n * steps) << " ns each); state hash 0x" << std::hex
            << t.hash << std::dec << "\n";
  const Profile& pr = w.profile();
  std::cout << "    ns per sphere-step: kick_drift " << 1e9 * pr.kick_drift / (n * steps)
            << ", neighbors " << 1e9 * pr.neighbors / (n * steps) << ", pair_forces "
            << 1e9 * pr.pair_forces / (n * steps) << ", gather_walls_kick "
            << 1e9 * pr.gather_walls_kick / (n * steps) << ", bodies "
            << 1e9 * pr.bodies / (n * steps) << "\n";
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_clumps: clumps of four spheres beside spheres (body- and sphere-steps/s)"};
  Options o;
  bool quick = false;
  app.add_flag("--quick", quick, "1,000 clumps, 3,000 + 1,000 settle and 300 timed steps");
  app.add_option("--clumps", o.clumps, "number of clumps (the sphere bed has 4x as many)")
      ->check(CLI::PositiveNumber);
  app.add_option("--steps", o.steps, "timed steps")->check(CLI::PositiveNumber);
  app.add_option("--settle", o.settle, "settle steps under --settle-gravity g");
  app.add_option("--relax", o.relax, "then steps under 1 g before timing");
  app.add_option("--settle-gravity", o.settle_gravity, "gravity factor of the settle [-]");
  app.add_option("--settle-threads", o.settle_threads, "threads of the untimed settle");
  app.add_option("--threads", o.threads, "thread counts to time, e.g. 1,2")->delimiter(',');
  app.add_option("--seed", o.seed, "seed of the sizes and orientations");
  app.add_option("--beds", o.beds, "read or write the settled beds as PREFIX.*.ckpt");
  CLI11_PARSE(app, argc, argv);
  if (quick) {
    if (app.count("--clumps") == 0) o.clumps = 1000;
    if (app.count("--settle") == 0) o.settle = 3000;
    if (app.count("--relax") == 0) o.relax = 1000;
    if (app.count("--steps") == 0) o.steps = 300;
  }
  try {
    const Model model = make_model(1.0);
    double reach = 0.0;
    for (const ClumpTemplate& t : model.clumps) reach = std::max(reach, t.reach);
    std::cout << "bench_clumps: " << o.clumps << " tetrahedral clumps of 4 spheres (reach up to "
              << reach * 1e3 << " mm) and " << 4 * o.clumps << " spheres, r " << kRadiusMin * 1e3
              << "-" << kRadiusMax * 1e3 << " mm; dt " << model.dt << " s\n";
    World clumps = make_bed(model, o.clumps, true, 2.0 * reach + 0.05e-3, o.seed);
    World spheres = make_bed(model, 4 * o.clumps, false, 2.0 * kRadiusMax + 0.05e-3, o.seed);
    for (auto [bed, what] : {std::pair{&clumps, "clumps"}, std::pair{&spheres, "spheres"}}) {
      const std::string file = o.beds + "." + what + ".ckpt";
      if (!o.beds.empty() && std::filesystem::exists(file)) {
        read_checkpoint(*bed, file);
        std::cout << "  " << what << ": read the settled bed from " << file << " ("
                  << touching_per_sphere(*bed) << " contacts (pairs + walls) per sphere)\n";
        continue;
      }
      settle(*bed, o, what);
      if (!o.beds.empty()) write_checkpoint(*bed, file);
    }
    bool same = true;
    std::cout << "RESULT clumps=" << o.clumps << " spheres=" << 4 * o.clumps
              << " steps=" << o.steps << "\n";
    for (int t : o.threads) {
      const Timing c = timed(clumps, o.steps, t, "clumps");
      const Timing s = timed(spheres, o.steps, t, "spheres");
      std::cout << "  threads " << t << ": time per component-step / per sphere particle-step = "
                << std::setprecision(4) << c.seconds / s.seconds << " (CPU " << c.cpu / s.cpu
                << ")\n";
      static std::uint64_t first_c = c.hash, first_s = s.hash;
      same = same && c.hash == first_c && s.hash == first_s;
    }
    std::cout << "final states " << (same ? "identical" : "DIFFER") << " across thread counts\n";
    return same ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "bench_clumps: " << e.what() << "\n";
    return 1;
  }
}
