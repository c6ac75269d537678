// Whole-world behaviour: determinism (pinned hash, thread counts), checkpoint resume, a bed
// lifted by its plate, the funnel shell, and status reports.
#include <gtest/gtest.h>
#include <omp.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>

#include "sim/checkpoint.hpp"
#include "sim/random.hpp"
#include "sim/world.hpp"
#include "sim_test_util.hpp"

namespace reposetwin::sim {
namespace {

World small_pour(int n = 400, int parallel_min = 2000) {
  return testing::funnel_pour(n, parallel_min);
}

/// The pour at 20 g for `steps` steps on `threads` threads: its state hash and, at the end,
/// the number of touching pairs and wall contacts.
std::pair<std::uint64_t, std::size_t> run_pour(int threads, int steps) {
  omp_set_num_threads(threads);
  // Every phase threaded, even this small; 20 g so that the spheres land, pile and slide on
  // each other within the run (the pair kernel's sticking, slipping and rolling all take part).
  World w = testing::funnel_pour(400, /*parallel_min=*/0, -20.0 * 9.81);
  for (int s = 0; s < steps; ++s) w.step();
  return {state_hash(w.state()), w.diagnose().contacts};
}

TEST(Determinism, PinnedHashAndThreadCountsAgree) {
  const auto [h1, contacts] = run_pour(1, 3000);
  EXPECT_GT(contacts, 400u) << "the pour must have settled into contact";
  EXPECT_EQ(h1, run_pour(2, 3000).first) << "1 and 2 threads must give bit-identical states";
  EXPECT_EQ(h1, run_pour(1, 3000).first) << "the same run twice must agree";
  // Pinned: an accidental change of physics or ordering changes this value. Update it only
  // with a deliberate physics change, and say so in the commit.
  EXPECT_EQ(h1, 0x795f6cf48368b581ull) << std::hex << "state hash 0x" << h1;
}

TEST(Checkpoint, ResumesBitIdentically) {
  World a = small_pour();
  for (int s = 0; s < 1500; ++s) a.step();
  const std::string path =
      (std::filesystem::temp_directory_path() / "reposetwin_ckpt_test.bin").string();
  write_checkpoint(a, path);
  for (int s = 0; s < 1500; ++s) a.step();
  World b = small_pour(0);
  read_checkpoint(b, path);
  for (int s = 0; s < 1500; ++s) b.step();
  EXPECT_EQ(state_hash(a.state()), state_hash(b.state()));
  EXPECT_EQ(a.state().step, b.state().step);
  // Checkpoints of spheres only in the older formats are read too: format 2 (the particles'
  // core fields, no clump fields and no bodies) and format 1 (format 2, then each pair's overlap
  // ratio, dropped on reading). Both are made here from a current file by cutting off its closing
  // checksum (which leaves format 3) and cutting out its clump section: the particles' clump
  // fields, the empty body arrays and the next body id.
  for (const char format : {'2', '1'}) {
    World c = small_pour();
    for (int s = 0; s < 1500; ++s) c.step();
    write_checkpoint(c, path);
    std::string bytes;
    {
      std::ifstream in(path, std::ios::binary);
      bytes.assign(std::istreambuf_iterator<char>(in), {});
    }
    // A current file (format 4) without its closing checksum is a format-3 file.
    ASSERT_EQ(bytes.substr(0, 8), "RTWCKPT4");
    bytes.resize(bytes.size() - sizeof(std::uint64_t));
    const std::size_t n = c.state().particles.size();
    std::size_t core = 0, clump = 0;
#define CORE_BYTES(type, name, doc) core += sizeof(std::uint64_t) + n * sizeof(type);
#define CLUMP_BYTES(type, name, doc) clump += sizeof(std::uint64_t) + n * sizeof(type);
#define BODY_BYTES(type, name, doc) clump += sizeof(std::uint64_t);
    REPOSETWIN_PARTICLE_CORE_FIELDS(CORE_BYTES)
    REPOSETWIN_PARTICLE_CLUMP_FIELDS(CLUMP_BYTES)
    REPOSETWIN_BODY_FIELDS(BODY_BYTES)
#undef CORE_BYTES
#undef CLUMP_BYTES
#undef BODY_BYTES
    clump += sizeof(std::int64_t);  // next_body_id
    const std::size_t header = 8 + sizeof(double) + sizeof(std::uint64_t);
    bytes.erase(header + core, clump);
    bytes[7] = format;
    if (format == '1') {
      const std::uint64_t np = c.state().neighbors.pairs();
      bytes.append(reinterpret_cast<const char*>(&np), sizeof np);
      bytes.append(np * sizeof(double), '\0');
    }
    {
      std::ofstream out(path, std::ios::binary | std::ios::trunc);
      out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    }
    World d = small_pour(0);
    read_checkpoint(d, path);
    EXPECT_EQ(state_hash(d.state()), state_hash(c.state())) << "format " << format;
    for (int s = 0; s < 500; ++s) {
      c.step();
      d.step();
    }
    EXPECT_EQ(state_hash(d.state()), state_hash(c.state())) << "format " << format;
  }
  // A corrupt file is refused with a message naming it.
  { std::FILE* f = std::fopen(path.c_str(), "wb"); std::fputs("garbage", f); std::fclose(f); }
  try {
    read_checkpoint(b, path);
    ADD_FAILURE() << "a corrupt checkpoint was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
  }
  std::filesystem::remove(path);
}

TEST(Walls, BedOnALiftedPlateMovesWithIt) {
  PairParams pair;
  Model m = testing::make_model(pair);
  m.walls.push_back(testing::plate());
  m.finalize(1e-3, 1e-3);
  World w(m);
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) w.add_particle(Vec3(2.1e-3 * i, 2.1e-3 * j, 1e-3), 1e-3, 0);
  for (int s = 0; s < 4000; ++s) w.step();  // settle
  const double v_lift = 0.01;
  w.set_wall_velocity(0, Vec3(0, 0, v_lift));
  for (int s = 0; s < 2000; ++s) w.step();  // reach steady lifting
  double z0 = 0;
  for (const Vec3& x : w.state().particles.x) z0 += x.z();
  const double t0 = w.state().time;
  for (int s = 0; s < 6000; ++s) w.step();
  double z1 = 0, vz = 0;
  for (std::size_t i = 0; i < w.state().particles.size(); ++i) {
    z1 += w.state().particles.x[i].z();
    vz += w.state().particles.v[i].z();
  }
  const double n = static_cast<double>(w.state().particles.size());
  const double dt = w.state().time - t0;
  EXPECT_NEAR((z1 - z0) / n / dt, v_lift, 0.01 * v_lift);
  EXPECT_NEAR(vz / n, v_lift, 0.02 * v_lift);
  EXPECT_NEAR(w.state().walls[0].offset.z(), v_lift * (w.state().time - (t0 - 2000 * m.dt)),
              1e-9);
}

TEST(Walls, ShellHoldsParticlesAndLiftsClear) {
  World w = small_pour();
  for (int s = 0; s < 6000; ++s) w.step();
  // Inside the funnel (r_bottom 5 mm), nothing below the plate, nothing through the shell.
  const Diagnostics d = w.diagnose();
  EXPECT_EQ(d.status, Status::kOk) << d.detail;
  for (const Vec3& x : w.state().particles.x) {
    EXPECT_GT(x.z(), 0.0);
    const double rho = std::hypot(x.x(), x.y());
    EXPECT_LT(rho, 0.005 + (0.015 - 0.005) * x.z() / 0.03 + 1e-4);
  }
}

TEST(Diagnostics, ReportsTheLargestOverlapAndTheContacts) {
  // Three spheres of radii 1, 0.8 and 0.5 mm in a row, no walls: overlaps 0.05 mm (ratio 0.0625
  // of the smaller, 0.8 mm) and 0.02 mm (0.04 of 0.5 mm); the first and the third apart.
  Model m = testing::make_model(PairParams{}, 46.8e6, Vec3::Zero());
  m.finalize(0.5e-3, 1e-3);
  World w(m);
  w.add_particle(Vec3(0, 0, 0), 1e-3, 0);
  w.add_particle(Vec3(1.75e-3, 0, 0), 0.8e-3, 0);
  w.add_particle(Vec3(1.75e-3 + 1.28e-3, 0, 0), 0.5e-3, 0);
  w.refresh_forces();
  Diagnostics d = w.diagnose();
  EXPECT_EQ(d.contacts, 2u);
  EXPECT_NEAR(d.max_overlap_ratio, 0.05 / 0.8, 1e-9);
  EXPECT_EQ(d.status, Status::kOk);
  // Pushed to an overlap of a quarter of the smaller radius: the run is stopped.
  Particles& p = w.state().particles;  // (sorted by cell at the list's build)
  std::size_t b = 0, c = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.radius[i] == 0.8e-3) b = i;
    if (p.radius[i] == 0.5e-3) c = i;
  }
  p.x[c] = p.x[b] + Vec3(1.3e-3 - 0.125e-3, 0, 0);
  d = w.diagnose();
  EXPECT_NEAR(d.max_overlap_ratio, 0.25, 1e-9);
  EXPECT_EQ(d.status, Status::kOverlap);
}

TEST(Diagnostics, ReportsNanAndEscape) {
  World w = small_pour(50);
  w.step();
  w.state().particles.v[3] = Vec3(std::nan(""), 0, 0);
  EXPECT_EQ(w.diagnose().status, Status::kNan);
  w.state().particles.v[3] = Vec3::Zero();
  w.state().particles.x[5] = Vec3(5, 0, 0);
  const Diagnostics d = w.diagnose();
  EXPECT_EQ(d.status, Status::kEscaped);
  EXPECT_NE(d.detail.find("farther"), std::string::npos);
}

// A state broken between two diagnose() calls is seen in the step that breaks it: the runner
// then stops at once instead of stepping on for up to a check interval.
TEST(Diagnostics, ANonFiniteStepIsSeenInThatStep) {
  World w = small_pour(50);
  for (int s = 0; s < 200; ++s) w.step();
  EXPECT_FALSE(w.nonfinite_seen()) << "a healthy pour is never flagged";
  w.state().particles.v[7] = Vec3(0, 0, std::numeric_limits<double>::infinity());
  w.step();
  EXPECT_TRUE(w.nonfinite_seen());
  EXPECT_EQ(w.diagnose().status, Status::kNan);

  World nan_world = small_pour(50);
  for (int s = 0; s < 5; ++s) nan_world.step();
  nan_world.state().particles.force[2] = Vec3(std::nan(""), 0, 0);  // a NaN force from a kernel
  nan_world.step();
  EXPECT_TRUE(nan_world.nonfinite_seen());
}

TEST(World, RemovingParticlesKeepsTheRestConsistent) {
  World w = small_pour();
  for (int s = 0; s < 2000; ++s) w.step();
  std::vector<char> drop(w.state().particles.size(), 0);
  for (std::size_t i = 0; i < drop.size(); i += 3) drop[i] = 1;
  const std::size_t before = drop.size();
  const std::size_t removed = w.remove_particles(drop);
  EXPECT_EQ(w.state().particles.size(), before - removed);
  for (int s = 0; s < 500; ++s) w.step();
  EXPECT_EQ(w.diagnose().status, Status::kOk);
}

TEST(World, EachContactTakesItsMaterialPairsConstants) {
  // Two approaching spheres, materials a and b of different stiffness and pair restitution:
  // the force on the larger one is the scalar kernel's with the constants of the pair (a, b),
  // whether the two materials differ or the world holds one material other than 0 (the pair
  // loop's shortcut for a heap of one material).
  PairParams soft;
  soft.restitution = 0.3;
  Model m = testing::make_model(soft, 46.8e6, Vec3::Zero());
  m.materials[1].youngs_modulus = 4.0 * m.materials[0].youngs_modulus;
  PairParams mixed = soft;
  mixed.restitution = 0.6;
  m.set_pair(0, 1, mixed);
  PairParams stiff = soft;
  stiff.restitution = 0.9;
  m.set_pair(1, 1, stiff);
  m.finalize(1e-3, 1.2e-3);
  for (const auto& [ma, mb] : {std::pair{0, 1}, std::pair{1, 1}, std::pair{0, 0}}) {
    World w(m);
    w.add_particle(Vec3(0, 0, 0), 1.2e-3, ma);
    w.add_particle(Vec3(2.19e-3, 0, 0), 1.0e-3, mb);
    w.state().particles.v[1] = Vec3(-0.05, 0.01, 0.0);  // approaching, and sliding
    // Twice: a first touch, then a live pair (the loop treats them apart).
    w.refresh_forces();
    w.refresh_forces();
    const Particles& p = w.state().particles;
    const std::size_t a = p.radius[0] > p.radius[1] ? 0 : 1, b = 1 - a;  // the larger first
    ASSERT_EQ(p.material[a], ma);
    const ContactConstants& c = m.table.c(ma, mb);
    ContactHistory h;
    hertz_mindlin(c, pair_input(p, c, a, b), m.dt, h);
    const ContactOutput o = hertz_mindlin(c, pair_input(p, c, a, b), m.dt, h);
    EXPECT_EQ(p.force[a], o.force) << "materials " << ma << ", " << mb;
    EXPECT_EQ(p.force[b], -o.force) << "materials " << ma << ", " << mb;
    // and not what the constants of the first material alone would give
    const ContactConstants& c00 = m.table.c(0, 0);
    ContactHistory h00;
    hertz_mindlin(c00, pair_input(p, c00, a, b), m.dt, h00);
    const ContactOutput o00 = hertz_mindlin(c00, pair_input(p, c00, a, b), m.dt, h00);
    if (ma != 0 || mb != 0) {
      EXPECT_GT((p.force[a] - o00.force).norm(), 0.05 * o00.force.norm())
          << "materials " << ma << ", " << mb;
    }
  }
}

}  // namespace
}  // namespace reposetwin::sim
