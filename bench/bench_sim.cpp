// bench_sim: throughput of the DEM engine on the standard scene of issue 2 ("Speed").
//
// Design note. The standard scene is a heap of polydisperse spheres (d uniform in 1-2 mm) resting
// on a plate, Hertz-Mindlin with rolling resistance, 50,000 spheres. Pouring a heap of 50k
// spheres takes far longer than the measurement itself, so the heap is constructed: the spheres
// stand in the columns of a body-centred cubic lattice (lattice constant a = 2.03 mm > d_max,
// small horizontal jitter) inside a 30-degree cone, placed half-layer by half-layer, and each
// one is lowered until it rests, within a 1 um gap, on the plate or on the spheres below it. In
// that lattice only the sphere below in the same column and the four in the nearest columns of
// the other sublattice are closer than a horizontally, so checking those guarantees no overlap.
// Each sphere then touches one support only, so the start is loose (solid fraction about 0.47)
// and must collapse: an untimed settle runs 5,000 steps at 5 g (the collapse goes sqrt(5) times
// faster), moves the whole state (springs included) into a world with 1 g, and relaxes 3,000
// steps with a small velocity damping so the springs loaded at 5 g unload without throwing the
// heap apart. The 50k heap ends with about 3.3 touching pairs per sphere and a kinetic energy of
// a few 1e-7 J (printed). The same settled state is then timed for N steps on each requested
// thread count (the engine is deterministic, so every thread count computes the identical
// trajectory; the benchmark checks that the state hashes agree). Each timed run prints wall and
// process CPU time: on a shared machine the CPU time of a one-thread run is the figure that other
// jobs' load does not inflate.
//
// With --write-liggghts DIR the settled heap is written as a LIGGGHTS data file (positions,
// diameters, density, velocities, angular velocities) and the matching input script, so that
// LIGGGHTS 3.8 runs the identical scene with the same physics, dt, skin and number of steps
// (bench/compare_liggghts.sh drives both). Contact histories cannot be carried over, so
// LIGGGHTS starts from zero tangential and rolling springs.
//
// Usage: bench_sim [--quick] [--particles N] [--steps N] [--threads 1,2] [--rolling epsd|cdt]
//                  [--rolling-damping ETA] [--settle N] [--relax N] [--settle-gravity G]
//                  [--settle-threads N] [--write-liggghts DIR] [--seed S] [--heap FILE]
//                  [--isa auto|scalar|sse2|avx|avx512vl]
#include <omp.h>
#include <time.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "sim/checkpoint.hpp"
#include "sim/model.hpp"
#include "sim/random.hpp"
#include "sim/world.hpp"

namespace {

using reposetwin::sim::Material;
using reposetwin::sim::Model;
using reposetwin::sim::PairParams;
using reposetwin::sim::Profile;
using reposetwin::sim::RollingModel;
using reposetwin::sim::Vec3;
using reposetwin::sim::WallKind;
using reposetwin::sim::WallSpec;
using reposetwin::sim::World;

constexpr double kDensity = 2760.0;              // [kg/m^3]
constexpr double kRealYoungs = 46.8e9;           // the rock's E [Pa]
constexpr double kSoftYoungs = 46.8e6;           // softened E used by the run [Pa]
constexpr double kPoisson = 0.19;                // [-]
constexpr double kRestitution = 0.79;            // [-]
constexpr double kFriction = 0.466;              // mu_s [-]
constexpr double kRollingFriction = 0.15;        // mu_r [-]
constexpr double kDiameterMin = 1.0e-3;          // [m]
constexpr double kDiameterMax = 2.0e-3;          // [m]
constexpr double kLattice = 2.03e-3;             // BCC lattice constant, > d_max [m] (design note)
constexpr double kJitter = 0.01e-3;              // largest horizontal shift of a lattice site [m]
constexpr double kGap = 1.0e-6;                  // clearance left above the supporting spheres [m]
constexpr double kRelaxDamping = 0.005;          // velocity damping per relax step [-]
constexpr double kExpectedSolidFraction = 0.55;  // of the constructed heap, to size the cone [-]
constexpr double kHeapAngleDeg = 30.0;           // slope of the constructed cone [deg]

struct Options {
  int particles = 50000;
  int settle = 5000;            // steps under settle_gravity g
  int relax = 3000;             // then steps under 1 g before timing
  double settle_gravity = 5.0;  // gravity factor of the settle (collapses the lattice faster)
  int settle_threads = 1;       // threads of the (untimed) settle; 1 suits a shared machine
  int steps = 2000;
  std::vector<int> threads{1, 2};
  std::string rolling = "epsd";
  double rolling_damping = 0.0;  // LIGGGHTS epsd2 has no rolling dashpot
  std::string liggghts_dir;
  std::string heap_file;  // settled heap checkpoint: read if it exists, else written after settling
  std::uint64_t seed = 2024;
  std::string isa = "auto";  // pair kernel instruction set: auto (the fastest) or a name
};

/// The model of the standard scene: one rock material (index 0) and the plate (index 1) with
/// the same elastic properties; every pair gets the paper's defaults.
Model make_model(const Options& o, double gravity_factor) {
  Model m;
  Material rock;
  rock.name = "rock";
  rock.density = kDensity;
  rock.youngs_modulus = kRealYoungs;
  rock.poisson_ratio = kPoisson;
  Material plate = rock;
  plate.name = "plate";
  m.materials = {rock, plate};
  PairParams p;
  p.restitution = kRestitution;
  p.friction = kFriction;
  p.rolling_friction = kRollingFriction;
  if (o.rolling == "epsd") {
    p.rolling_model = RollingModel::kEpsd;
  } else if (o.rolling == "cdt") {
    p.rolling_model = RollingModel::kCdt;
  } else {
    throw std::invalid_argument("--rolling: unknown model '" + o.rolling +
                                "' (expected epsd or cdt)");
  }
  p.rolling_damping = o.rolling_damping;
  m.set_pair(0, 0, p);
  m.set_pair(0, 1, p);
  m.set_pair(1, 1, p);
  m.settings.softened_youngs_modulus = kSoftYoungs;
  m.settings.gravity = Vec3(0.0, 0.0, -9.81 * gravity_factor);
  WallSpec w;
  w.name = "plate";
  w.kind = WallKind::kPlane;
  w.material = 1;
  w.point = Vec3(0, 0, 0);
  w.normal = Vec3(0, 0, 1);
  m.walls.push_back(w);
  m.finalize(0.5 * kDiameterMin, 0.5 * kDiameterMax);
  return m;
}

/// Places `n` spheres without overlap in a cone of kHeapAngleDeg on the plate z = 0, each
/// resting (within kGap) on the spheres below it (design note).
void build_heap(World& world, int n, std::uint64_t seed) {
  const double tan_slope = std::tan(kHeapAngleDeg * std::numbers::pi / 180.0);
  const double mean_volume =  // E[pi d^3 / 6] for d uniform in [d_min, d_max] [m^3]
      std::numbers::pi / 6.0 * (std::pow(kDiameterMax, 4) - std::pow(kDiameterMin, 4)) /
      (4.0 * (kDiameterMax - kDiameterMin));
  reposetwin::sim::Rng rng(seed);
  // A cone that holds about 10% more spheres than asked for at the expected solid fraction.
  double radius = std::cbrt(3.0 * 1.1 * n * mean_volume / kExpectedSolidFraction /
                            (std::numbers::pi * tan_slope));
  for (int attempt = 0; attempt < 20; ++attempt, radius *= 1.05) {
    const double height = radius * tan_slope;
    const int nxy = static_cast<int>(std::ceil(radius / kLattice)) + 1;
    const int side = 2 * nxy + 1;
    // Columns of both sublattices; each keeps the spheres placed in it, lowest first.
    struct Placed {
      Vec3 x;
      double r;
    };
    std::vector<std::vector<Placed>> columns(2 * side * side);
    auto column = [&](int sub, int i, int j) -> std::vector<Placed>* {
      if (i < -nxy || i > nxy || j < -nxy || j > nxy) return nullptr;
      return &columns[(sub * side + (j + nxy)) * side + (i + nxy)];
    };
    std::vector<char> closed(columns.size(), 0);
    struct Candidate {
      Vec3 x;
      double r, level;
    };
    std::vector<Candidate> placed;
    bool growing = true;
    for (int layer = 0; growing; ++layer) {  // half-layers: sublattice layer % 2
      growing = false;
      const int sub = layer % 2;
      const double h = 0.5 * kLattice * sub;
      for (int j = -nxy; j <= nxy; ++j)
        for (int i = -nxy; i <= nxy; ++i) {
          std::vector<Placed>* own = column(sub, i, j);
          const std::size_t id = own - columns.data();
          if (closed[id]) continue;
          const double d = rng.uniform(kDiameterMin, kDiameterMax);
          const double r = 0.5 * d;
          Vec3 x(i * kLattice + h + rng.uniform(-kJitter, kJitter),
                 j * kLattice + h + rng.uniform(-kJitter, kJitter), r + kGap);
          // Rest on the highest of: the plate, the spheres below in this column, and those in
          // the four nearest columns of the other sublattice (all others are at least a lattice
          // constant, more than d_max, away horizontally).
          auto rest_on = [&](const std::vector<Placed>* c) {
            if (c == nullptr) return;
            const std::size_t m = c->size();
            for (std::size_t q = m > 3 ? m - 3 : 0; q < m; ++q) {
              const Placed& b = (*c)[q];
              const double reach = r + b.r + kGap;
              const double dxy2 =
                  (x.x() - b.x.x()) * (x.x() - b.x.x()) + (x.y() - b.x.y()) * (x.y() - b.x.y());
              if (dxy2 < reach * reach)
                x.z() = std::max(x.z(), b.x.z() + std::sqrt(reach * reach - dxy2));
            }
          };
          rest_on(own);
          const int o = 1 - sub;  // other sublattice: its columns at (i - o .. i + 1 - o)
          for (int dj = 0; dj < 2; ++dj)
            for (int di = 0; di < 2; ++di) rest_on(column(o, i - o + di, j - o + dj));
          const double level = x.z() / height + std::hypot(x.x(), x.y()) / radius;
          if (level > 1.0) {
            closed[id] = 1;
            continue;
          }
          own->push_back({x, r});
          placed.push_back({x, r, level});
          growing = true;
        }
    }
    if (static_cast<int>(placed.size()) < n) continue;  // cone too small: widen it
    // Keep the n innermost spheres (a slightly smaller cone), in a fixed order.
    std::stable_sort(placed.begin(), placed.end(),
                     [](const Candidate& a, const Candidate& b) { return a.level < b.level; });
    for (int k = 0; k < n; ++k) world.add_particle(placed[k].x, placed[k].r, 0);
    return;
  }
  throw std::logic_error("build_heap: could not fit the spheres in a cone");
}

/// Touching particle pairs (from the last force phase) and wall contacts.
struct ContactCount {
  std::size_t pairs = 0, walls = 0;
};

ContactCount count_contacts(const World& w) {
  ContactCount c;
  for (std::uint8_t live : w.state().pair_live) c.pairs += live;
  const auto& p = w.state().particles;
  for (std::size_t i = 0; i < p.size(); ++i) c.walls += p.x[i].z() < p.radius[i] ? 1 : 0;
  return c;
}

/// Writes the heap as a LIGGGHTS data file and the input script that runs `steps` steps of the
/// same physics (bench/compare_liggghts.sh runs it).
void write_liggghts(const World& w, const Options& o, const std::string& dir) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  const auto& p = w.state().particles;
  const Model& m = w.model();
  Vec3 lo = p.x[0], hi = p.x[0];
  for (std::size_t i = 1; i < p.size(); ++i) {
    lo = lo.cwiseMin(p.x[i]);
    hi = hi.cwiseMax(p.x[i]);
  }
  const double margin = 0.01;  // [m] room for spheres rolling off the heap's toe
  {
    std::ofstream f(fs::path(dir) / "heap.data");
    f << std::setprecision(17);
    f << "LIGGGHTS data file written by bench_sim: " << p.size()
      << " spheres settled in a heap on the plate z = 0\n\n";
    f << p.size() << " atoms\n2 atom types\n\n";
    f << lo.x() - margin << " " << hi.x() + margin << " xlo xhi\n";
    f << lo.y() - margin << " " << hi.y() + margin << " ylo yhi\n";
    f << -0.001 << " " << hi.z() + margin << " zlo zhi\n\n";
    // atom_style granular: atom-ID atom-type diameter density x y z
    f << "Atoms\n\n";
    for (std::size_t i = 0; i < p.size(); ++i)
      f << i + 1 << " 1 " << 2.0 * p.radius[i] << " " << kDensity << " " << p.x[i].x() << " "
        << p.x[i].y() << " " << p.x[i].z() << "\n";
    // Velocities of a granular atom: atom-ID vx vy vz wx wy wz
    f << "\nVelocities\n\n";
    for (std::size_t i = 0; i < p.size(); ++i)
      f << i + 1 << " " << p.v[i].x() << " " << p.v[i].y() << " " << p.v[i].z() << " " << p.w[i].x()
        << " " << p.w[i].y() << " " << p.w[i].z() << "\n";
    if (!f) throw std::runtime_error("--write-liggghts: cannot write " + dir + "/heap.data");
  }
  {
    const char* model = o.rolling == "cdt" ? "cdt" : "epsd2";
    std::ofstream f(fs::path(dir) / "in.heap");
    f << std::setprecision(17);
    f << "# LIGGGHTS 3.8 input written by bench_sim: the settled heap of bench_sim, same physics,\n"
         "# dt, skin and steps. Run: liggghts -in in.heap (or mpirun -np 2 liggghts -in in.heap).\n"
         "atom_style granular\n"
         "atom_modify map array\n"
         "boundary f f f\n"
         "communicate single vel yes\n"
         "units si\n"
         "newton off\n"  // LIGGGHTS: pair gran with shear history requires newton pair off
         "processors * * 1\n"
         "read_data heap.data\n"
      << "neighbor " << w.state().neighbors.skin << " bin\n"
      << "neigh_modify delay 0\n"
      << "fix m1 all property/global youngsModulus peratomtype " << kSoftYoungs << " "
      << kSoftYoungs << "\n"
      << "fix m2 all property/global poissonsRatio peratomtype " << kPoisson << " " << kPoisson
      << "\n"
      << "fix m3 all property/global coefficientRestitution peratomtypepair 2 " << kRestitution
      << " " << kRestitution << " " << kRestitution << " " << kRestitution << "\n"
      << "fix m4 all property/global coefficientFriction peratomtypepair 2 " << kFriction << " "
      << kFriction << " " << kFriction << " " << kFriction << "\n"
      << "fix m5 all property/global coefficientRollingFriction peratomtypepair 2 "
      << kRollingFriction << " " << kRollingFriction << " " << kRollingFriction << " "
      << kRollingFriction << "\n"
      << "pair_style gran model hertz tangential history rolling_friction " << model << "\n"
      << "pair_coeff * *\n"
      << "timestep " << m.dt << "\n"
      << "fix gravi all gravity 9.81 vector 0.0 0.0 -1.0\n"
      << "fix plate all wall/gran model hertz tangential history rolling_friction " << model
      << " primitive type 2 zplane 0.0\n"
      << "fix integr all nve/sphere\n"
      << "thermo_style custom step atoms ke\n"
      << "thermo 1000\n"
      << "thermo_modify lost ignore norm no\n"
      << "run " << o.steps << "\n";
    if (!f) throw std::runtime_error("--write-liggghts: cannot write " + dir + "/in.heap");
  }
}

void print_profile(const Profile& pr, double particle_steps) {
  const double total = pr.total();
  auto row = [&](const char* name, double s) {
    std::cout << "    " << std::left << std::setw(17) << name << std::right << std::fixed
              << std::setprecision(3) << std::setw(9) << s << " s  " << std::setprecision(1)
              << std::setw(5) << (total > 0 ? 100.0 * s / total : 0.0) << " %  "
              << std::setprecision(3) << std::setw(7) << 1e9 * s / particle_steps
              << " ns/particle-step\n";
  };
  row("kick_drift", pr.kick_drift);
  row("move_walls", pr.move_walls);
  row("neighbors", pr.neighbors);
  row("pair_forces", pr.pair_forces);
  row("gather_walls_kick", pr.gather_walls_kick);
  std::cout << std::defaultfloat;
}

/// CPU seconds used by the whole process so far (all threads). On a shared machine the CPU time
/// of a one-thread run measures the work without the time spent waiting for a core.
double process_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

struct RunResult {
  int threads = 0;
  double seconds = 0.0;      // wall clock [s]
  double cpu_seconds = 0.0;  // process CPU time, all threads [s]
  double particle_steps_per_s = 0.0;
  double contacts_per_s = 0.0;
  std::uint64_t hash = 0;
};

/// Times `steps` steps of a copy of the settled world on `threads` threads.
RunResult timed_run(const World& settled, int steps, int threads, const std::string& isa) {
  World w = settled;
  omp_set_num_threads(threads);
  if (isa != "auto") {
    for (reposetwin::sim::PairIsa k :
         {reposetwin::sim::PairIsa::kScalar, reposetwin::sim::PairIsa::kSse2,
          reposetwin::sim::PairIsa::kAvx, reposetwin::sim::PairIsa::kAvx512Vl})
      if (isa == reposetwin::sim::pair_isa_name(k)) w.set_pair_isa(k);
  }
  w.reset_profile();
  const std::int64_t builds0 = w.state().neighbors.builds;
  const std::size_t n = w.state().particles.size();
  // Contacts are counted every `every` steps, outside the timed region.
  const int every = std::max(1, steps / 20);
  double seconds = 0.0, cpu = 0.0, contact_sum = 0.0, pair_sum = 0.0, wall_sum = 0.0;
  int samples = 0;
  for (int done = 0; done < steps;) {
    const int chunk = std::min(every, steps - done);
    const auto t0 = std::chrono::steady_clock::now();
    const double c0 = process_cpu_seconds();
    for (int s = 0; s < chunk; ++s) w.step();
    cpu += process_cpu_seconds() - c0;
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    done += chunk;
    const ContactCount c = count_contacts(w);
    pair_sum += c.pairs;
    wall_sum += c.walls;
    contact_sum += c.pairs + c.walls;
    ++samples;
  }
  RunResult r;
  r.threads = threads;
  r.seconds = seconds;
  r.cpu_seconds = cpu;
  r.particle_steps_per_s = static_cast<double>(n) * steps / seconds;
  r.contacts_per_s = contact_sum / samples * steps / seconds;
  r.hash = reposetwin::sim::state_hash(w.state());
  const auto diag = w.diagnose();
  std::cout << "  threads " << threads << ": " << steps << " steps in " << std::setprecision(4)
            << seconds << " s wall, " << cpu << " s CPU; " << std::setprecision(4)
            << r.particle_steps_per_s << " particle-steps/s (" << r.particle_steps_per_s / threads
            << " per core); " << r.contacts_per_s << " contacts/s; contacts per step "
            << std::setprecision(6) << pair_sum / samples << " pairs + " << wall_sum / samples
            << " plate; " << w.state().neighbors.builds - builds0 << " neighbor rebuilds; "
            << w.state().neighbors.pairs() << " listed pairs; KE " << std::setprecision(4)
            << diag.kinetic_energy << " J; status " << reposetwin::sim::status_name(diag.status)
            << "; state hash 0x" << std::hex << r.hash << std::dec << "\n";
  print_profile(w.profile(), static_cast<double>(n) * steps);
  return r;
}

std::string load_average() {
  std::ifstream f("/proc/loadavg");
  std::string a, b, c;
  f >> a >> b >> c;
  return f ? a + " " + b + " " + c : "unknown";
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  bool quick = false;
  CLI::App app{"bench_sim: DEM throughput on the standard heap (issue 2, Speed)"};
  app.add_flag("--quick", quick, "5,000 particles, 2,000 + 2,000 settle and 500 timed steps");
  app.add_option("--particles", o.particles, "number of spheres")->check(CLI::PositiveNumber);
  app.add_option("--settle", o.settle, "settle steps under --settle-gravity g")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--relax", o.relax, "then steps under 1 g before timing")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--settle-threads", o.settle_threads, "threads of the untimed settle")
      ->check(CLI::PositiveNumber);
  app.add_option("--settle-gravity", o.settle_gravity, "gravity factor of the settle [-]")
      ->check(CLI::PositiveNumber);
  app.add_option("--steps", o.steps, "timed steps")->check(CLI::PositiveNumber);
  app.add_option("--threads", o.threads, "thread counts to time, e.g. 1,2")
      ->delimiter(',')
      ->check(CLI::PositiveNumber);
  app.add_option("--rolling", o.rolling, "rolling model: epsd (LIGGGHTS epsd2) or cdt")
      ->check(CLI::IsMember({"epsd", "cdt"}));
  app.add_option("--rolling-damping", o.rolling_damping,
                 "EPSD rolling damping ratio eta_r (0 = LIGGGHTS epsd2)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--write-liggghts", o.liggghts_dir,
                 "write the settled heap and the matching LIGGGHTS input to this folder");
  app.add_option("--seed", o.seed, "seed of the sizes and jitter");
  app.add_option("--isa", o.isa,
                 "instruction set of the pair kernel: auto (the fastest this CPU has), scalar, "
                 "sse2, avx or avx512vl (all give the same bits)")
      ->check(CLI::IsMember({"auto", "scalar", "sse2", "avx", "avx512vl"}));
  app.add_option("--heap", o.heap_file,
                 "checkpoint of the settled heap: read instead of settling if the file exists, "
                 "else written after the settle (the same start for several builds; one file "
                 "per --particles, --seed and --rolling)");
  CLI11_PARSE(app, argc, argv);
  if (quick) {
    if (app.count("--particles") == 0) o.particles = 5000;
    if (app.count("--settle") == 0) o.settle = 2000;
    if (app.count("--relax") == 0) o.relax = 2000;
    if (app.count("--steps") == 0) o.steps = 500;
  }

  try {
    const Model model = make_model(o, 1.0);
    World world(model);
    // A settled heap read from --heap replaces the constructed one: construct only otherwise.
    const bool reuse = !o.heap_file.empty() && std::filesystem::exists(o.heap_file);
    if (!reuse) build_heap(world, o.particles, o.seed);
    std::cout << "bench_sim: " << o.particles << " spheres, d " << kDiameterMin * 1e3 << "-"
              << kDiameterMax * 1e3 << " mm, E " << kSoftYoungs << " Pa (softened), rolling "
              << o.rolling << " mu_r " << kRollingFriction << " eta_r " << o.rolling_damping
              << "; dt " << model.dt << " s (" << model.settings.rayleigh_fraction << " T_R), skin "
              << world.state().neighbors.skin << " m; pair kernel "
              << (o.isa == "auto" ? reposetwin::sim::pair_isa_name(world.pair_isa()) : o.isa)
              << "\n";
    const char* wait_policy = std::getenv("OMP_WAIT_POLICY");
    std::cout << "load average before: " << load_average()
              << "; OMP_WAIT_POLICY=" << (wait_policy ? wait_policy : "(unset)") << "\n";

    // Settle (not timed) on settle_threads threads: first under settle_gravity g,
    // which collapses the loose lattice sqrt(settle_gravity) times faster, then under 1 g in a
    // world with the true model, to which the whole state (contact springs included) moves.
    omp_set_num_threads(o.settle_threads);
    const auto t0 = std::chrono::steady_clock::now();
    auto report = [&](const World& w, const char* phase) {
      const auto d = w.diagnose();
      const ContactCount c = count_contacts(w);
      std::cout << "  " << phase << " step " << w.state().step << ": KE " << d.kinetic_energy
                << " J, max overlap " << d.max_overlap_ratio << " of r, " << c.pairs
                << " touching pairs (" << 2.0 * c.pairs / o.particles << " per sphere), " << c.walls
                << " on the plate, status " << reposetwin::sim::status_name(d.status) << "\n";
      if (d.status != reposetwin::sim::Status::kOk)
        throw std::runtime_error(std::string("settle failed: ") + d.detail);
    };
    const int report_every = std::max(1, (o.settle + o.relax) / 8);
    if (reuse) {
      reposetwin::sim::read_checkpoint(world, o.heap_file);
      std::cout << "read the settled heap from " << o.heap_file << " (no settle)\n";
      if (world.state().particles.size() != static_cast<std::size_t>(o.particles))
        throw std::runtime_error(o.heap_file + ": holds " +
                                 std::to_string(world.state().particles.size()) +
                                 " spheres, not --particles " + std::to_string(o.particles));
    } else if (o.settle > 0) {
      Model heavy_model = make_model(o, o.settle_gravity);
      // The collapse of the lattice under settle_gravity g may overlap more than the 1 g heap.
      heavy_model.settings.max_overlap_ratio = 0.15;
      World heavy(heavy_model);
      heavy.state() = world.state();
      for (int s = 0; s < o.settle; ++s) {
        heavy.step();
        if ((s + 1) % report_every == 0 || s + 1 == o.settle) report(heavy, "settle");
      }
      world.state() = heavy.state();
    }
    // The relax damps every velocity by a factor (1 - kRelaxDamping) per step, so the springs
    // loaded under settle_gravity unload without throwing the heap apart.
    for (int s = 0; s < (reuse ? 0 : o.relax); ++s) {
      world.step();
      auto& p = world.state().particles;
      for (std::size_t i = 0; i < p.size(); ++i) {
        p.v[i] *= 1.0 - kRelaxDamping;
        p.w[i] *= 1.0 - kRelaxDamping;
      }
      if ((s + 1) % report_every == 0 || s + 1 == o.relax) report(world, "relax");
    }
    const double settle_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const auto diag = world.diagnose();
    const ContactCount c = count_contacts(world);
    std::cout << "settled " << o.settle << " steps at " << o.settle_gravity << " g + " << o.relax
              << " at 1 g (" << (o.settle + o.relax) * model.dt << " s simulated) in " << settle_s
              << " s: KE " << diag.kinetic_energy << " J, " << c.pairs << " touching pairs ("
              << 2.0 * c.pairs / o.particles << " per sphere)\n";
    if (diag.status != reposetwin::sim::Status::kOk)
      throw std::runtime_error("settle failed: " + diag.detail);
    if (!o.heap_file.empty() && !reuse) {
      reposetwin::sim::write_checkpoint(world, o.heap_file);
      std::cout << "wrote the settled heap to " << o.heap_file << "\n";
    }
    if (!o.liggghts_dir.empty()) {
      write_liggghts(world, o, o.liggghts_dir);
      std::cout << "wrote " << o.liggghts_dir << "/heap.data and " << o.liggghts_dir
                << "/in.heap\n";
    }

    std::vector<RunResult> results;
    for (int t : o.threads) results.push_back(timed_run(world, o.steps, t, o.isa));
    bool same = true;
    for (const RunResult& r : results) same = same && r.hash == results.front().hash;
    std::cout << "final states " << (same ? "identical" : "DIFFER") << " across thread counts\n";
    std::cout << "load average after: " << load_average() << "\n";

    std::cout << "RESULT particles=" << o.particles << " steps=" << o.steps
              << " rolling=" << o.rolling << std::setprecision(4);
    for (const RunResult& r : results) {
      std::cout << " particle_steps_per_s_" << r.threads << "t=" << r.particle_steps_per_s
                << " per_core_" << r.threads << "t=" << r.particle_steps_per_s / r.threads
                << " contacts_per_s_" << r.threads << "t=" << r.contacts_per_s << " seconds_"
                << r.threads << "t=" << r.seconds << " cpu_seconds_" << r.threads
                << "t=" << r.cpu_seconds;
    }
    std::cout << "\n";
    return same ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "bench_sim: " << e.what() << "\n";
    return 1;
  }
}
