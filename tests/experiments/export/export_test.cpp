// The LIGGGHTS deck carries the scene's physics line by line, its container mesh is the scene's
// frustum, the rolling conventions are the stated ratios, and a dump is read by its column names;
// what cannot be carried or read is an InputError naming the file.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>

#include "../../support/scratch.hpp"
#include "../../support/tiny_scene.hpp"
#include "experiments/export/liggghts_deck.hpp"
#include "experiments/export/particle_dump.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/scene.hpp"
#include "experiments/io/vtk_output.hpp"
#include "sim/particles.hpp"

namespace reposetwin::experiments {
namespace {

SceneConfig tiny(const std::string& extra = "") {
  return parse_scene_text(test_support::kTinyScene + extra, "tiny.toml");
}

bool has(const std::string& text, const std::string& line) {
  return text.find(line) != std::string::npos;
}

TEST(LiggghtsDeck, CarriesTheSoftenedStiffnessTheLawAndTheProcedure) {
  const SceneConfig s = tiny();
  const LiggghtsDeck d = liggghts_deck(s);
  const double e = s.settings.softened_youngs_modulus;
  ASSERT_GT(e, 0.0);
  std::ostringstream young;
  young.precision(10);
  young << "youngsModulus peratomtype " << e << " " << e << " " << e << "\n";
  EXPECT_TRUE(has(d.input, young.str())) << d.input;
  EXPECT_TRUE(has(d.input, "soft_particles yes"));
  EXPECT_TRUE(has(d.input, "pair_style gran model hertz tangential history rolling_friction epsd2"));
  EXPECT_TRUE(has(d.input, "primitive type 3 zplane 0.0"));
  EXPECT_TRUE(has(d.input, "move/mesh mesh cad linear 0.0 0.0 " +
                               std::to_string(s.procedure.lift_speed).substr(0, 4)));
  EXPECT_TRUE(has(d.input, "write_dump all custom final.dump id type x y z radius"));
  // The sample's mass is inserted, and the PSD's mass fractions sum to one.
  EXPECT_TRUE(has(d.input, "particledistribution/discrete/massbased"));
  // Settling stops at the twin's threshold: kinetic energy per grain 1/2 m_mean v^2, that is
  // 1/2 M v^2 in all.
  const double v = s.procedure.settle_speed;
  std::ostringstream stop;
  stop.precision(10);
  stop << "variable ke_stop equal " << 0.5 * s.mass * v * v << "\n";
  EXPECT_TRUE(has(d.input, stop.str())) << d.input;
  EXPECT_TRUE(has(d.input, "if \"${ke_now} < ${ke_stop}\" then \"jump SELF fill_done\""));
  // The notes warn of the install that breaks the twin's build, with the command that avoids it.
  EXPECT_TRUE(has(d.notes, "`sudo apt-get install --no-install-recommends liggghts`")) << d.notes;
  EXPECT_TRUE(has(d.notes, "removes python3-vtk9 and libvtk9-dev")) << d.notes;
  // The notes name every epsd contact whose dashpot epsd2 cannot carry.
  for (const auto& [a, b] : s.contact_pairs)
    if (s.contacts.at({a, b}).rolling_damping > 0)
      EXPECT_TRUE(has(d.notes, "contacts." + a + "-" + b)) << d.notes;
}

// A pair is one [contacts] table: the notes name it once, as the scene writes it, though the
// scene's contact map holds it in both orders.
TEST(LiggghtsDeck, NotCarriedNamesEachPairOnceAsWritten) {
  const SceneConfig s = tiny(R"(
[materials.plate]
density_kg_m3 = 7800.0
youngs_modulus_pa = 200e9
poisson_ratio = 0.3
[contacts.rock-plate]
restitution = 0.4
friction = 0.6
rolling_friction = 0.2
rolling_damping = 0.3
)");
  ASSERT_EQ(s.contacts.count({"plate", "rock"}), 1u);
  const LiggghtsDeck d = liggghts_deck(s);
  EXPECT_FALSE(has(d.notes, "contacts.plate-rock")) << d.notes;
  const std::string line = "- The rolling dashpot of contacts.rock-plate:";
  const auto first = d.notes.find(line);
  ASSERT_NE(first, std::string::npos) << d.notes;
  EXPECT_EQ(d.notes.find(line, first + 1), std::string::npos) << d.notes;
}

// Started from the twin's filled sample, the deck reads it instead of inserting one: the data
// file holds every grain with its diameter, density and position, and a state the deck cannot
// carry (a clump, a grain outside the box, another material) is refused.
TEST(LiggghtsDeck, StartsFromTheTwinsFilledSample) {
  const SceneConfig s = tiny();
  SnapshotParticles filled;
  filled.x = {{0.001, 0.002, 0.003}, {-0.004, 0.0, 0.02}};
  filled.radius = {0.002, 0.0025};
  filled.material = {0, 0};
  LiggghtsDeckSettings set;
  set.initial_state = &filled;
  const LiggghtsDeck d = liggghts_deck(s, set);
  EXPECT_TRUE(has(d.input, "read_data initial.data\n"));
  EXPECT_FALSE(has(d.input, "create_box"));
  EXPECT_FALSE(has(d.input, "insert/pack"));
  EXPECT_FALSE(has(d.input, "particletemplate"));
  EXPECT_TRUE(has(d.input, "move/mesh"));
  EXPECT_TRUE(has(d.initial_data, "2 atoms\n3 atom types\n"));
  std::istringstream data(d.initial_data.substr(d.initial_data.find("Atoms\n\n") + 7));
  int id = 0, type = 0;
  double diameter = 0, density = 0, x = 0, y = 0, z = 0;
  ASSERT_TRUE(data >> id >> type >> diameter >> density >> x >> y >> z);
  EXPECT_EQ(id, 1);
  EXPECT_EQ(type, 1);
  EXPECT_DOUBLE_EQ(diameter, 0.004);
  for (const sim::Material& m : s.materials) {
    if (m.name == s.sample_material) {
      EXPECT_DOUBLE_EQ(density, m.density);
    }
  }
  EXPECT_DOUBLE_EQ(z, 0.003);
  ASSERT_TRUE(data >> id >> type >> diameter >> density >> x >> y >> z);
  EXPECT_EQ(id, 2);
  EXPECT_DOUBLE_EQ(x, -0.004);
  EXPECT_TRUE(has(d.notes, "as the twin filled it: 2 grains"));

  SnapshotParticles clump = filled;
  clump.body = {0, 0};
  set.initial_state = &clump;
  EXPECT_THROW(liggghts_deck(s, set), InputError);
  SnapshotParticles far = filled;
  far.x[1].z() = 5.0;
  set.initial_state = &far;
  try {
    liggghts_deck(s, set);
    ADD_FAILURE() << "a grain outside the box was accepted";
  } catch (const InputError& e) {
    EXPECT_TRUE(has(e.what(), "grain 1")) << e.what();
  }
}

// The mesh is the frustum: every vertex lies on the cone between the rims, every facet's normal
// is a unit vector, and there are two facets per step around.
TEST(LiggghtsDeck, TheContainerMeshIsTheScenesFrustum) {
  const SceneConfig s = tiny();
  LiggghtsDeckSettings set;
  set.facets = 24;
  const LiggghtsDeck d = liggghts_deck(s, set);
  const ContainerConfig& c = s.container;
  std::istringstream in(d.funnel_stl);
  std::string word;
  int facets = 0, vertices = 0;
  while (in >> word) {
    if (word == "normal") {
      double n[3];
      in >> n[0] >> n[1] >> n[2];
      EXPECT_NEAR(std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), 1.0, 1e-9);
      ++facets;
    } else if (word == "vertex") {
      double x, y, z;
      in >> x >> y >> z;
      const double u = (z - c.gap) / c.height;
      EXPECT_GE(u, -1e-9);
      EXPECT_LE(u, 1 + 1e-9);
      const double r = 0.5 * (c.bottom_diameter + u * (c.top_diameter - c.bottom_diameter));
      EXPECT_NEAR(std::hypot(x, y), r, 1e-9);
      ++vertices;
    }
  }
  EXPECT_EQ(facets, 48);
  EXPECT_EQ(vertices, 144);
}

TEST(LiggghtsDeck, RollingConventionsAreTheStatedRatios) {
  const RollingConventions m = rolling_conventions(0.4);
  EXPECT_DOUBLE_EQ(m.liggghts, 0.4);
  EXPECT_DOUBLE_EQ(m.lammps, 0.4);
  EXPECT_DOUBLE_EQ(m.edem, 0.2);  // R = 2 R* for equal spheres
}

TEST(LiggghtsDeck, GrainShapesAreRefusedWithTheReason) {
  try {
    liggghts_deck(tiny("\n[sample.shape]\nkind = \"blocky\"\nelongation = 1.4\n"));
    FAIL() << "a clump scene was exported";
  } catch (const InputError& e) {
    EXPECT_TRUE(has(e.what(), "tiny.toml")) << e.what();
    EXPECT_TRUE(has(e.what(), "sample.shape")) << e.what();
    EXPECT_TRUE(has(e.what(), "not exported")) << e.what();
  }
}

std::string write(const std::string& name, const std::string& text) {
  static const std::filesystem::path dir = test_support::temp_dir("export_test");
  const std::string path = (dir / name).string();
  std::ofstream(path) << text;
  return path;
}

TEST(ParticleDump, ReadsTheLastSnapshotByColumnName) {
  const std::string two =
      "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS ff ff ff\n0 1\n0 1\n0 1\n"
      "ITEM: ATOMS id type x y z radius\n1 1 0.5 0.5 0.5 0.001\n"
      "ITEM: TIMESTEP\n100\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS ff ff ff\n0 1\n0 1\n0 1\n"
      "ITEM: ATOMS radius z id y x\n0.002 0.003 1 0.02 0.01\n0.004 0.005 2 0.04 0.03\n";
  const ParticleDump d = read_particle_dump(write("two.dump", two));
  EXPECT_EQ(d.timestep, 100);
  ASSERT_EQ(d.x.size(), 2u);
  EXPECT_DOUBLE_EQ(d.x[1].x(), 0.03);
  EXPECT_DOUBLE_EQ(d.x[1].y(), 0.04);
  EXPECT_DOUBLE_EQ(d.x[1].z(), 0.005);
  EXPECT_DOUBLE_EQ(d.radius[0], 0.002);
}

// A twin snapshot is read as another engine's dump is: the same grains, in the same order.
TEST(ParticleDump, ReadsATwinSnapshotByItsExtension) {
  const std::filesystem::path dir = test_support::temp_dir("export_read_vtp");
  sim::Particles p;
  p.resize(2);
  p.x[0] = sim::Vec3(0.01, 0.02, 0.003);
  p.x[1] = sim::Vec3(-0.01, 0.0, 0.004);
  p.radius[0] = 0.003;
  p.radius[1] = 0.004;
  for (std::size_t i = 0; i < 2; ++i) {
    p.body[i] = -1;
    p.component[i] = -1;
  }
  const std::string vtp = (dir / "frame.vtp").string();
  write_vtp(vtp, p, FrameInfo{}, nullptr);
  const ParticleDump d = read_particles(vtp);
  ASSERT_EQ(d.x.size(), 2u);
  EXPECT_DOUBLE_EQ(d.x[1].z(), 0.004);
  EXPECT_DOUBLE_EQ(d.radius[0], 0.003);
  EXPECT_THROW(read_particles((dir / "missing.vtp").string()), InputError);
}

TEST(ParticleDump, BadDumpsNameTheFileAndLine) {
  auto error = [](const std::string& text) {
    try {
      read_particle_dump(write("bad.dump", text));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string head = "ITEM: TIMESTEP\n5\nITEM: NUMBER OF ATOMS\n2\n";
  EXPECT_TRUE(has(error(head + "ITEM: ATOMS id x y z\n1 0 0 0\n2 0 0 0\n"), "radius"));
  EXPECT_TRUE(has(error(head + "ITEM: ATOMS x y z radius\n0 0 0 0.1\n"), "ends after 1 of 2"));
  EXPECT_TRUE(has(error(head + "ITEM: ATOMS x y z radius\n0 0 0 0.1\n0 0 nan 0.1\n"),
                  "not finite"));
  EXPECT_TRUE(has(error(head + "ITEM: ATOMS x y z radius\n0 0 0 0.1\n0 0 0 -1\n"),
                  "not positive"));
  EXPECT_TRUE(has(error("nothing here\n"), "no snapshot"));
  EXPECT_TRUE(has(error(head + "ITEM: ATOMS x y z radius\n0 0 0 0.1\n0 0 0 -1\n"), "bad.dump:"));
}

}  // namespace
}  // namespace reposetwin::experiments
