// bench_clumps: throughput of the DEM engine with rigid clumps beside spheres.
//
// Design note. Two beds are built the same way and timed the same way: N four-sphere clumps
// (tetrahedra: component radius r, centres at 0.9 r from the body's centre, r uniform in
// [0.5, 0.6] mm in six template sizes, random orientations), and 4N spheres with radii drawn from
// the same range, so both have the same number of spheres. Each starts on a lattice inside a
// cylindrical container (radius --container-mm, 30 mm) on a plate: square layers of spacing s (a
// grain's largest reach, twice, plus 0.05 mm), each shifted by half a spacing in x and y from the
// one below and s / sqrt(2) above it, so that a grain's nearest neighbours in the layers below and
// above are s away as in its own layer (a body-centred lattice, as dense as random orientations
// allow without overlaps); sites are jittered by up to 0.02 mm so that no column stands on its
// own. The bed falls and settles for --settle steps under --settle-gravity g, then relaxes
// --relax steps at 1 g with a small velocity damping (as bench_sim), and the settled bed is timed
// for --steps steps on each requested thread count. The settle is the cost of building a bed:
// it grows with the number of grains times the fall, which is the lattice's height, so the
// issue's 50,000 clumps (--issue) stand in a wide container (120 mm) where the lattice is six
// layers deep (12 mm) and collapses under 20 g (its top falls 5 mm in about 1,900 steps; 5,000
// steps), then relaxes 2,000 steps at 1 g: 0.68 contacts per component at the end on a bed of the
// same depth, as on the deeper beds' 0.74-0.80; the result is a flat settled bed rather than a
// cone, every grain resting on its neighbours as in a heap's interior.
// Printed: body-steps/s and component-steps/s for the clumps, particle-steps/s for the spheres,
// the contacts per sphere of each bed, the time per component-step over the time per sphere
// particle-step (the issue's target: within 1.3x), and each phase's time. Every thread count
// computes the identical trajectory; the benchmark checks that the state hashes agree.
//
// With --beds PREFIX the settled beds are read from PREFIX.clumps.ckpt and PREFIX.spheres.ckpt if
// they exist, and written there otherwise, so that builds can be timed on the same start.
// With --write-yade DIR the settled clump bed is also written for Yade (bench/compare_yade.sh):
// DIR/bed.txt (per clump its velocity, angular velocity, mass, principal moments and component
// spheres in world coordinates) and DIR/run.py, a Yade script that builds the same bed, walls
// and Hertz-Mindlin physics and times the same number of steps. --no-spheres skips the sphere
// bed (the Yade comparison needs only the clumps). Each thread count's times are also printed as
// one machine-readable line, "TIMING threads=T clump_seconds=.. clump_cpu_seconds=.. ...".
//
// With --collapse DIR (scripts/verify_yade_clumps.sh, the physics check against Yade) nothing is
// timed: each settled bed is released on the plate, its container removed at t = 0 (a column
// collapse), for --collapse-steps steps on one thread and written as DIR/WHAT/twin.vtp; the same
// bed goes to DIR/WHAT/bed.txt with DIR/WHAT/collapse.py, the Yade script of the same release,
// which writes DIR/WHAT/initial.dump and DIR/WHAT/final.dump (WHAT: clumps, spheres). Yade's
// Mindlin has no rolling resistance, so the check runs with --rolling-friction 0 (no rolling model
// at all in this engine).
//
// Usage: bench_clumps [--quick | --issue] [--clumps N] [--container-mm R] [--steps N]
//                     [--threads 1,2] [--settle N] [--relax N] [--settle-gravity G]
//                     [--settle-threads N] [--seed S] [--beds PREFIX] [--no-spheres]
//                     [--write-yade DIR] [--rolling-friction MU_R]
//                     [--collapse DIR [--collapse-steps N]]
#include <omp.h>
#include <time.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <string>
#include <vector>

#include "experiments/io/vtk_output.hpp"
#include "sim/checkpoint.hpp"
#include "sim/model.hpp"
#include "sim/random.hpp"
#include "sim/world.hpp"

namespace {

using namespace reposetwin::sim;

constexpr double kRadiusMin = 0.5e-3, kRadiusMax = 0.6e-3;  // component / sphere radii [m]
constexpr int kSizes = 6;                                   // clump template sizes
constexpr double kArm = 0.9;                     // component centre distance / radius [-]
constexpr double kRelaxDamping = 0.005;          // velocity damping per relax step [-]

struct Options {
  double container_mm = 30.0;  // container radius [mm]
  int clumps = 5000;
  int steps = 1000;
  int settle = 7000;
  int relax = 3000;
  double settle_gravity = 5.0;
  int settle_threads = 2;
  std::vector<int> threads{1, 2};
  std::uint64_t seed = 1;
  std::string beds;
  bool no_spheres = false;
  std::string yade_dir;
  double rolling_friction = 0.15;  // EPSD mu_r of every pair; 0: no rolling resistance [-]
  std::string collapse_dir;
  int collapse_steps = 60000;
};

/// The contact of every pair: the paper's e 0.79, mu_s 0.466, and EPSD rolling resistance mu_r
/// (0.15 by default), or none at all when mu_r = 0 (the Yade collapse: Mindlin has none).
PairParams bench_pair(double rolling_friction) {
  PairParams pair;
  pair.rolling_friction = rolling_friction;
  if (rolling_friction == 0.0) pair.rolling_model = RollingModel::kNone;
  return pair;
}

Model make_model(double gravity_factor, double container_radius, double rolling_friction) {
  Model m;
  Material rock;
  rock.youngs_modulus = 46.8e9;
  Material steel = rock;
  steel.name = "steel";
  m.materials = {rock, steel};
  m.settings.softened_youngs_modulus = 46.8e6;
  m.settings.gravity = Vec3(0, 0, -9.81 * gravity_factor);
  m.settings.max_overlap_ratio = 0.15;
  const PairParams pair = bench_pair(rolling_friction);
  m.set_pair(0, 0, pair);
  m.set_pair(0, 1, pair);
  m.set_pair(1, 1, pair);
  WallSpec plate;
  m.walls.push_back(plate);
  WallSpec can;
  can.name = "container";
  can.kind = WallKind::kShell;
  can.z_top = 0.2;
  can.r_bottom = container_radius;
  can.r_top = container_radius;
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

/// A bed of `count` grains on a body-centred lattice of spacing `spacing` inside the container
/// (design note).
World make_bed(const Model& model, int count, bool clumps, double spacing, std::uint64_t seed) {
  World w(model);
  Rng rng(seed);
  const double radius = model.walls[1].r_bottom;
  const double rise = spacing / std::sqrt(2.0) + 0.03e-3;  // layer to layer [m]
  const int across = static_cast<int>((radius - 0.5 * spacing) / spacing);
  int placed = 0;
  for (int layer = 0; placed < count; ++layer) {
    for (int ix = -across; ix <= across && placed < count; ++ix)
      for (int iy = -across; iy <= across && placed < count; ++iy) {
        const double shift = layer % 2 == 0 ? 0.0 : 0.5 * spacing;
        const Vec3 x(spacing * ix + shift + rng.uniform(-0.02e-3, 0.02e-3),
                     spacing * iy + shift + rng.uniform(-0.02e-3, 0.02e-3),
                     0.5 * spacing + rise * layer);
        if (std::hypot(x.x(), x.y()) > radius - 0.5 * spacing) continue;
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

/// The highest sphere surface of the bed [m].
double bed_top(const World& w) {
  const Particles& p = w.state().particles;
  double top = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) top = std::max(top, p.x[i].z() + p.radius[i]);
  return top;
}

double touching_per_sphere(const World& w) {
  const Diagnostics d = w.diagnose();
  return static_cast<double>(d.contacts) / static_cast<double>(w.state().particles.size());
}

/// Settles the bed: settle_gravity g, then 1 g with damping (velocities of spheres and bodies).
void settle(World& world, const Options& o, const char* what) {
  const auto t0 = std::chrono::steady_clock::now();
  omp_set_num_threads(o.settle_threads);
  World heavy(make_model(o.settle_gravity, 1e-3 * o.container_mm, o.rolling_friction));
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
            << " contacts (pairs + walls) per sphere, top " << 1e3 * bed_top(world)
            << " mm, max overlap " << d.max_overlap_ratio << ", status "
            << status_name(d.status) << std::endl;  // kept if a long run is cut off later
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

/// A settled bed as text for Yade: one line per grain (a clump, or a free sphere as a grain of
/// one): velocity, angular velocity, mass, principal moments, the number of spheres n, then n
/// times the sphere's centre and radius (world frame, SI).
void write_bed(const World& w, const std::string& path, const char* option) {
  const Particles& p = w.state().particles;
  const Bodies& b = w.state().bodies;
  std::vector<std::vector<std::size_t>> members(b.size());
  for (std::size_t i = 0; i < p.size(); ++i)
    if (p.body[i] >= 0) members[static_cast<std::size_t>(p.body[i])].push_back(i);
  std::ofstream f(path);
  f << std::setprecision(17);
  f << "# bench_clumps settled bed: " << b.size() << " clumps, " << p.size()
    << " spheres. Per line: vx vy vz wx wy wz mass I1 I2 I3 n, then n times x y z r (world "
       "frame, SI)\n";
  const auto sphere = [&](std::size_t i) {
    f << " " << p.x[i].x() << " " << p.x[i].y() << " " << p.x[i].z() << " " << p.radius[i];
  };
  for (std::size_t k = 0; k < b.size(); ++k) {
    f << b.v[k].x() << " " << b.v[k].y() << " " << b.v[k].z() << " " << b.w[k].x() << " "
      << b.w[k].y() << " " << b.w[k].z() << " " << b.mass[k] << " " << b.inertia[k].x() << " "
      << b.inertia[k].y() << " " << b.inertia[k].z() << " " << members[k].size();
    for (std::size_t i : members[k]) sphere(i);
    f << "\n";
  }
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.body[i] >= 0) continue;
    f << p.v[i].x() << " " << p.v[i].y() << " " << p.v[i].z() << " " << p.w[i].x() << " "
      << p.w[i].y() << " " << p.w[i].z() << " " << p.mass[i] << " " << p.inertia[i] << " "
      << p.inertia[i] << " " << p.inertia[i] << " 1";
    sphere(i);
    f << "\n";
  }
  if (!f) throw std::runtime_error(std::string(option) + ": cannot write " + path);
}

// The bed reader both Yade scripts share (write_bed's bed.txt: per body its velocity, angular
// velocity, mass, principal moments, component count and each component's centre and radius):
// read_bed(path, material, members_carry_clump_mass) builds every body and returns the counts of
// clumps and spheres. A body of one component is a plain sphere.
constexpr const char* kYadeReadBed = R"PY(def read_bed(path, material, members_carry_clump_mass):
    clumps = spheres = 0
    with open(path) as bed:
        for line in bed:
            if line.startswith('#'):
                continue
            v = [float(t) for t in line.split()]
            n = int(v[10])
            balls = [sphere((v[11 + 4 * i], v[12 + 4 * i], v[13 + 4 * i]), v[14 + 4 * i],
                            material=material) for i in range(n)]
            if n == 1:
                O.bodies.append(balls[0])
                s = balls[0].state
            else:
                cid, ids = O.bodies.appendClumped(balls)
                s = O.bodies[cid].state
                if members_carry_clump_mass:
                    for i in ids:
                        O.bodies[i].state.mass = v[6]
                clumps += 1
            # Mass and principal moments of the union of the spheres, as the twin's (Yade's
            # default sums the members' own, counting overlaps twice); a tetrahedral clump's
            # inertia is isotropic up to the integration error, so the principal frame Yade
            # chose does not matter.
            s.mass = v[6]
            s.inertia = Vector3(v[7], v[8], v[9])
            s.vel = Vector3(v[0], v[1], v[2])
            s.angVel = Vector3(v[3], v[4], v[5])
            spheres += n
    return clumps, spheres
)PY";

/// The column collapse (design note): the settled bed `bed` written for Yade (DIR/bed.txt and
/// DIR/collapse.py, which removes the container and runs --collapse-steps steps), then the same
/// run in this engine on one thread, its final state written as DIR/twin.vtp (write_vtp, which
/// `reposetwin measure-particles` reads).
void collapse(const World& bed, const Options& o, const std::string& dir, const char* what) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  write_bed(bed, (fs::path(dir) / "bed.txt").string(), "--collapse");
  const Model& m = bed.model();
  const Material& rock = m.materials[0];
  const PairParams pair = bench_pair(o.rolling_friction);
  {
    std::ofstream f(fs::path(dir) / "collapse.py");
    f << std::setprecision(17);
    f << "# Yade script written by bench_clumps --collapse: its settled bed (bed.txt) released\n"
         "# on the plate (the container removed at t = 0), Hertz-Mindlin as the twin's (README of\n"
         "# results/studies/clump_yade_check lists what differs); writes final.dump (x y z\n"
         "# radius of every sphere). Run in this folder: yade -j1 -n -x collapse.py\n"
         "import math, os, time\n"
         "E, NU, DENSITY, E_REST, MU_S, MU_S_PLATE = "
      << m.youngs_modulus_used(0) << ", " << rock.poisson_ratio << ", " << rock.density << ", "
      << pair.restitution << ", " << pair.friction << ", " << pair.friction
      << "\nDT, SKIN, STEPS = " << m.dt << ", " << bed.state().neighbors.skin << ", "
      << o.collapse_steps << "\n"
      << kYadeReadBed
      << R"PY(here = os.getcwd()  # run in its folder: Yade's __file__ names the yade binary
rock = O.materials.append(FrictMat(young=E, poisson=NU, density=DENSITY,
                                   frictionAngle=math.atan(MU_S), label='rock'))
# Yade's wall contact takes the wall as a sphere of the grain's radius (R* = r/2, the twin's
# plate R* = r). A plate of E_w = (1 + sqrt 2) E gives Yade's Ip2 the twin's E* sqrt(R*), hence
# the twin's Hertz spring; its tangential spring then also equals the twin's 8 G* sqrt(R* delta)
# (both checked on one contact against the closed forms).
plate_mat = O.materials.append(FrictMat(young=(1 + math.sqrt(2)) * E, poisson=NU,
                                        density=DENSITY, frictionAngle=math.atan(MU_S_PLATE),
                                        label='plate'))
O.bodies.append(wall((0, 0, 0), axis=2, sense=1, material=plate_mat))
# The twin's damping (EDEM, Tsuji): c = 2 sqrt(5/6) |beta| sqrt(S m*) with S = 2 E* sqrt(R* delta)
# normal and 8 G* sqrt(R* delta) tangential, beta = ln e / sqrt(ln^2 e + pi^2). Yade's Law2 damps
# with 2 beta_n sqrt(k_n m*) and 2 beta_s sqrt(k_s m*), k_n = 3/2 kno sqrt(delta) = S_n and
# k_s = S_t, so beta_n = beta_s = sqrt(5/6) |beta| gives the same dashpots. (Its en = e would
# give beta_n 0.0719 at e 0.79, 5% above the twin's 0.0683.)
LOG_E = math.log(E_REST)
BETA = math.sqrt(5.0 / 6.0) * -LOG_E / math.sqrt(LOG_E ** 2 + math.pi ** 2)
# The twin's contact damping uses m* of the bodies (a component carries its clump's mass);
# Yade's Law2 reads the member's own state.mass, which nothing else uses once the clump is
# built, so the members are given the clump's mass.
clumps, spheres = read_bed(os.path.join(here, 'bed.txt'), rock, members_carry_clump_mass=True)
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()], verletDist=SKIN),
    InteractionLoop(
        [Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()],
        [Ip2_FrictMat_FrictMat_MindlinPhys(betan=BETA, betas=BETA)],
        [Law2_ScGeom_MindlinPhys_Mindlin()]),
    NewtonIntegrator(damping=0.0, gravity=(0, 0, -9.81)),
]
O.dt = DT
def dump(name):  # every sphere as a LAMMPS-style dump "x y z radius", written atomically
    rows = ['%.17g %.17g %.17g %.17g' % (b.state.pos[0], b.state.pos[1], b.state.pos[2],
                                         b.shape.radius)
            for b in O.bodies if isinstance(b.shape, Sphere)]
    with open(os.path.join(here, name + '.tmp'), 'w') as f:
        f.write('ITEM: TIMESTEP\n%d\nITEM: NUMBER OF ATOMS\n%d\nITEM: ATOMS x y z radius\n'
                % (O.iter, len(rows)))
        f.write('\n'.join(rows) + '\n')
    os.replace(os.path.join(here, name + '.tmp'), os.path.join(here, name))
dump('initial.dump')  # Yade's bed as built, to check it against bed.txt
t0, c0 = time.perf_counter(), time.process_time()
O.run(STEPS, True)
seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
dump('final.dump')
ke = sum(0.5 * b.state.mass * b.state.vel.squaredNorm() for b in O.bodies
         if b.isClump or (isinstance(b.shape, Sphere) and not b.isClumpMember))
print('YADE_COLLAPSE clumps=%d spheres=%d steps=%d seconds=%.6g cpu_seconds=%.6g ke_end=%.6g'
      % (clumps, spheres, O.iter, seconds, cpu, ke))
)PY";
    if (!f) throw std::runtime_error("--collapse: cannot write " + dir + "/collapse.py");
  }
  World w = bed;
  w.set_wall_enabled(1, false);
  omp_set_num_threads(1);
  const auto t0 = std::chrono::steady_clock::now();
  const double c0 = process_cpu_seconds();
  for (int s = 0; s < o.collapse_steps; ++s) w.step();
  const double cpu = process_cpu_seconds() - c0;
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  namespace ex = reposetwin::experiments;
  ex::FrameInfo info;
  info.time_s = w.state().time;
  info.phase = "done";
  ex::write_vtp((fs::path(dir) / "twin.vtp").string(), w.state().particles, info,
                &w.state().bodies);
  const Diagnostics d = w.diagnose();
  std::cout << std::setprecision(6) << "COLLAPSE bed=" << what
            << " bodies=" << w.state().bodies.size() << " spheres=" << w.state().particles.size()
            << " steps=" << o.collapse_steps << " seconds=" << wall << " cpu_seconds=" << cpu
            << " ke_end=" << d.kinetic_energy << " status=" << status_name(d.status) << std::endl;
  if (d.status != Status::kOk) throw std::runtime_error(std::string("collapse: ") + d.detail);
}

/// The settled clump bed as Yade input (design note): bed.txt and run.py in `dir`.
void write_yade(const World& w, const Options& o, const std::string& dir) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  write_bed(w, (fs::path(dir) / "bed.txt").string(), "--write-yade");
  const Model& m = w.model();
  const Material& rock = m.materials[0];
  const PairParams pair = bench_pair(o.rolling_friction);  // every pair of make_model
  std::ofstream f(fs::path(dir) / "run.py");
  f << std::setprecision(17);
  f << "# Yade script written by bench_clumps: its settled clump bed (bed.txt), the same walls,\n"
       "# Hertz-Mindlin contact, E, nu, e, mu_s and dt; times the same number of steps.\n"
       "# Run in this folder: yade -j1 -n -x run.py (bench/compare_yade.sh). Not modelled\n"
       "# here: rolling resistance (bench/README.md lists the differences).\n"
       "import math, os, time\n"
       "from yade import geom\n"
       "E, NU, DENSITY, E_REST, MU_S = "
    << m.youngs_modulus_used(0) << ", " << rock.poisson_ratio << ", " << rock.density << ", "
    << pair.restitution << ", " << pair.friction << "\n"
    << "DT, SKIN, STEPS, CONTAINER_R, CONTAINER_TOP = " << m.dt << ", " << w.state().neighbors.skin
    << ", " << o.steps << ", " << m.walls[1].r_bottom << ", " << m.walls[1].z_top << "\n"
    << kYadeReadBed
    << R"PY(here = os.getcwd()  # run in its folder: Yade's __file__ names the yade binary
mat = O.materials.append(FrictMat(young=E, poisson=NU, density=DENSITY,
                                  frictionAngle=math.atan(MU_S), label='rock'))
# The plate z = 0 and the cylindrical container (side only), as bench_clumps' two walls.
O.bodies.append(wall((0, 0, 0), axis=2, sense=1, material=mat))
O.bodies.append(geom.facetCylinder((0, 0, 0.5 * CONTAINER_TOP), CONTAINER_R, CONTAINER_TOP,
                                   segmentsNumber=128, wallMask=4, material=mat))
clumps, _ = read_bed(os.path.join(here, 'bed.txt'), mat, members_carry_clump_mass=False)
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Facet_Aabb(), Bo1_Wall_Aabb()],
                          verletDist=SKIN),
    InteractionLoop(
        [Ig2_Sphere_Sphere_ScGeom(), Ig2_Facet_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()],
        [Ip2_FrictMat_FrictMat_MindlinPhys(en=E_REST, es=E_REST)],
        [Law2_ScGeom_MindlinPhys_Mindlin()]),
    NewtonIntegrator(damping=0.0, gravity=(0, 0, -9.81)),
]
O.dt = DT
O.run(1, True)  # the collider's first sort and the contacts' creation, untimed
ke0 = sum(0.5 * b.state.mass * b.state.vel.squaredNorm() for b in O.bodies if b.isClump)
t0, c0 = time.perf_counter(), time.process_time()
O.run(STEPS, True)
seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
ke1 = sum(0.5 * b.state.mass * b.state.vel.squaredNorm() for b in O.bodies if b.isClump)
spheres = sum(1 for b in O.bodies if b.isClumpMember)
print('YADE clumps=%d spheres=%d steps=%d seconds=%.6g cpu_seconds=%.6g interactions=%d '
      'ke_start=%.6g ke_end=%.6g' % (clumps, spheres, STEPS, seconds, cpu,
                                     O.interactions.countReal(), ke0, ke1))
)PY";
  if (!f) throw std::runtime_error("--write-yade: cannot write " + dir + "/run.py");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_clumps: clumps of four spheres beside spheres (body- and sphere-steps/s)"};
  Options o;
  bool quick = false, issue = false;
  app.add_flag("--quick", quick, "1,000 clumps, 3,000 + 1,000 settle and 300 timed steps");
  app.add_flag("--issue", issue,
               "the issue's bed: 50,000 clumps in a 120 mm container, settled 5,000 steps at 20 g "
               "+ 2,000 at 1 g, 300 timed steps");
  app.add_option("--container-mm", o.container_mm, "container radius [mm]")
      ->check(CLI::PositiveNumber);
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
  app.add_flag("--no-spheres", o.no_spheres, "time the clump bed only");
  app.add_option("--write-yade", o.yade_dir, "also write the settled clump bed for Yade here");
  app.add_option("--rolling-friction", o.rolling_friction,
                 "EPSD mu_r of every pair (0: no rolling resistance, as Yade's Mindlin)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--collapse", o.collapse_dir,
                 "release each settled bed on the plate (container removed) here and in a Yade "
                 "script; DIR/clumps and DIR/spheres (scripts/verify_yade_clumps.sh)");
  app.add_option("--collapse-steps", o.collapse_steps, "steps of the collapse")
      ->check(CLI::PositiveNumber);
  CLI11_PARSE(app, argc, argv);
  const auto preset = [&](int clumps, double container_mm, int settle, int relax, int steps) {
    if (app.count("--clumps") == 0) o.clumps = clumps;
    if (app.count("--container-mm") == 0) o.container_mm = container_mm;
    if (app.count("--settle") == 0) o.settle = settle;
    if (app.count("--relax") == 0) o.relax = relax;
    if (app.count("--steps") == 0) o.steps = steps;
  };
  if (quick) preset(1000, 30.0, 3000, 1000, 300);
  if (issue) {
    preset(50000, 120.0, 5000, 2000, 300);
    if (app.count("--settle-gravity") == 0) o.settle_gravity = 20.0;
  }
  try {
    const Model model = make_model(1.0, 1e-3 * o.container_mm, o.rolling_friction);
    double reach = 0.0;
    for (const ClumpTemplate& t : model.clumps) reach = std::max(reach, t.reach);
    std::cout << "bench_clumps: " << o.clumps << " tetrahedral clumps of 4 spheres (reach up to "
              << reach * 1e3 << " mm) and " << 4 * o.clumps << " spheres, r " << kRadiusMin * 1e3
              << "-" << kRadiusMax * 1e3 << " mm, in a container of radius " << o.container_mm
              << " mm; dt " << model.dt << " s\n";
    World clumps = make_bed(model, o.clumps, true, 2.0 * reach + 0.05e-3, o.seed);
    World spheres = make_bed(model, o.no_spheres ? 0 : 4 * o.clumps, false,
                             2.0 * kRadiusMax + 0.05e-3, o.seed);
    std::vector<std::pair<World*, const char*>> beds{{&clumps, "clumps"}};
    if (!o.no_spheres) beds.emplace_back(&spheres, "spheres");
    for (auto [bed, what] : beds)
      std::cout << "  " << what << ": lattice of " << bed->state().particles.size()
                << " spheres, top " << 1e3 * bed_top(*bed) << " mm\n";
    for (auto [bed, what] : beds) {
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
    if (!o.collapse_dir.empty()) {
      for (auto [bed, what] : beds)
        collapse(*bed, o, (std::filesystem::path(o.collapse_dir) / what).string(), what);
      return 0;  // a physics check, not a timing
    }
    if (!o.yade_dir.empty()) {
      write_yade(clumps, o, o.yade_dir);
      std::cout << "wrote " << o.yade_dir << "/bed.txt and " << o.yade_dir << "/run.py\n";
    }
    bool same = true;
    std::cout << "RESULT clumps=" << o.clumps << " spheres=" << (o.no_spheres ? 0 : 4 * o.clumps)
              << " components=" << clumps.state().particles.size() << " steps=" << o.steps
              << "\n";
    for (int t : o.threads) {
      const Timing c = timed(clumps, o.steps, t, "clumps");
      static std::uint64_t first_c = c.hash;
      same = same && c.hash == first_c;
      if (o.no_spheres) {
        std::cout << std::setprecision(6) << "TIMING threads=" << t
                  << " clump_seconds=" << c.seconds << " clump_cpu_seconds=" << c.cpu << "\n";
        continue;
      }
      const Timing s = timed(spheres, o.steps, t, "spheres");
      std::cout << std::setprecision(6) << "TIMING threads=" << t << " clump_seconds=" << c.seconds
                << " clump_cpu_seconds=" << c.cpu << " sphere_seconds=" << s.seconds
                << " sphere_cpu_seconds=" << s.cpu << "\n";
      std::cout << "  threads " << t << ": time per component-step / per sphere particle-step = "
                << std::setprecision(4) << c.seconds / s.seconds << " (CPU " << c.cpu / s.cpu
                << ")\n";
      static std::uint64_t first_s = s.hash;
      same = same && s.hash == first_s;
    }
    std::cout << "final states " << (same ? "identical" : "DIFFER") << " across thread counts\n";
    return same ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "bench_clumps: " << e.what() << "\n";
    return 1;
  }
}
