// The ParaView series read back with VTK's own readers: the particle arrays and material names,
// the plate and the funnel where the run had them, and the optional contact lines.
#include "experiments/io/vtk_output.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>
#include <vtkXMLPolyDataReader.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "../../support/tiny_scene.hpp"
#include "experiments/io/scene.hpp"
#include "experiments/pile/pile_run.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

vtkSmartPointer<vtkPolyData> read_poly(const fs::path& p) {
  EXPECT_TRUE(fs::exists(p)) << p;
  vtkNew<vtkXMLPolyDataReader> reader;
  reader->SetFileName(p.string().c_str());
  reader->Update();
  vtkSmartPointer<vtkPolyData> poly = reader->GetOutput();
  return poly;
}

std::string frame_tag(int k) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%05d", k);
  return buf;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The tiny pile with a frame every 50 ms of simulated time and contact lines, in a folder of the
// test's own (ctest runs the tests of this file side by side, each in its own process).
const fs::path& tiny_run() {
  static const fs::path dir = [] {
    const fs::path d =
        fs::temp_directory_path() /
        (std::string("reposetwin_vtk_series_") +
         ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(d);
    RunOptions opt;
    opt.out_dir = (d / "run").string();
    opt.progress = false;
    const std::string text = std::string(test_support::kTinyScene) +
                             "[output]\nframe_interval_s = 0.05\ncontact_forces = true\n";
    run_pile_test(parse_scene_text(text, (d / "tiny.toml").string()), opt);
    return d / "run";
  }();
  return dir;
}

TEST(VtkSeries, ParticlesCarryDiameterAndMaterialNames) {
  const vtkSmartPointer<vtkPolyData> poly = read_poly(tiny_run() / "frames" / "frame_00000.vtp");
  ASSERT_GT(poly->GetNumberOfPoints(), 10);
  auto* radius = vtkDoubleArray::SafeDownCast(poly->GetPointData()->GetArray("radius"));
  auto* diameter = vtkDoubleArray::SafeDownCast(poly->GetPointData()->GetArray("diameter"));
  ASSERT_TRUE(radius && diameter);
  for (vtkIdType i = 0; i < poly->GetNumberOfPoints(); ++i) {
    EXPECT_DOUBLE_EQ(diameter->GetValue(i), 2.0 * radius->GetValue(i));
    // The tiny scene's sieves: 3 to 4 mm.
    EXPECT_GE(diameter->GetValue(i), 3e-3 - 1e-12);
    EXPECT_LE(diameter->GetValue(i), 4e-3 + 1e-12);
  }
  auto* names =
      vtkStringArray::SafeDownCast(poly->GetFieldData()->GetAbstractArray("material_names"));
  ASSERT_TRUE(names);
  ASSERT_GE(names->GetNumberOfValues(), 1);
  EXPECT_EQ(names->GetValue(0), "rock");
  auto* phase = vtkStringArray::SafeDownCast(poly->GetFieldData()->GetAbstractArray("phase"));
  ASSERT_TRUE(phase);
  EXPECT_EQ(phase->GetValue(0), "fill");
}

TEST(VtkSeries, FunnelFollowsTheLiftAndPlateIsABoard) {
  const fs::path run = tiny_run();
  // Frame 0 (t = 0): the funnel of the tiny scene on the plate, 20 to 50 mm across, 40 mm tall.
  const vtkSmartPointer<vtkPolyData> f0 = read_poly(run / "frames" / "container_00000.vtp");
  double b[6];
  f0->GetBounds(b);
  EXPECT_NEAR(b[1] - b[0], 0.05, 1e-4);  // top rim diameter (96 facets: cos(pi/96) ~ 1)
  EXPECT_NEAR(b[4], 0.0, 1e-9);
  EXPECT_NEAR(b[5], 0.04, 1e-9);
  // Each later funnel file stands at lift_speed (50 mm/s) times its frame's time, read from the
  // particle file of the same step.
  int lifted = 0;
  for (int k = 1; fs::exists(run / "frames" / ("frame_" + frame_tag(k) + ".vtp")); ++k) {
    const std::string tag = frame_tag(k);
    const SnapshotParticles p = read_vtp((run / "frames" / ("frame_" + tag + ".vtp")).string());
    ASSERT_TRUE(p.info.has_value());
    const fs::path shell = run / "frames" / ("container_" + tag + ".vtp");
    if (!p.info->container) {
      EXPECT_FALSE(fs::exists(shell));  // removed after the lift
      continue;
    }
    const vtkSmartPointer<vtkPolyData> f = read_poly(shell);
    f->GetBounds(b);
    EXPECT_NEAR(b[4], p.info->container->z_bottom_m, 1e-9);
    EXPECT_NEAR(b[5] - b[4], 0.04, 1e-9);
    if (b[4] > 1e-4) ++lifted;
  }
  EXPECT_GT(lifted, 0) << "no frame caught the funnel lifted";
  const vtkSmartPointer<vtkPolyData> plate = read_poly(run / "frames" / "plate.vtp");
  plate->GetBounds(b);
  EXPECT_NEAR(b[5], 0.0, 1e-12);  // top face at z = 0
  EXPECT_GT(b[1] - b[0], 0.05);   // wider than the funnel
  EXPECT_EQ(plate->GetNumberOfPolys(), 6);
  // series.pvd names every part of a step: particles (0), plate (1), funnel (2), contacts.
  const std::string pvd = slurp(run / "series.pvd");
  EXPECT_NE(pvd.find("part=\"1\" file=\"frames/plate.vtp\""), std::string::npos);
  EXPECT_NE(pvd.find("part=\"2\" file=\"frames/container_00000.vtp\""), std::string::npos);
  EXPECT_NE(pvd.find("contacts_00000.vtp"), std::string::npos);
}

TEST(VtkSeries, ContactLinesJoinTouchingParticles) {
  const fs::path run = tiny_run();
  // The last frame is the settled pile: its particles touch.
  std::string last;
  for (const auto& e : fs::directory_iterator(run / "frames"))
    if (e.path().filename().string().rfind("contacts_", 0) == 0)
      last = std::max(last, e.path().filename().string());
  ASSERT_FALSE(last.empty());
  const vtkSmartPointer<vtkPolyData> c = read_poly(run / "frames" / last);
  ASSERT_GT(c->GetNumberOfLines(), 5);
  auto* mag = vtkDoubleArray::SafeDownCast(c->GetCellData()->GetArray("force_magnitude"));
  auto* force = vtkDoubleArray::SafeDownCast(c->GetCellData()->GetArray("force"));
  ASSERT_TRUE(mag && force);
  for (vtkIdType k = 0; k < c->GetNumberOfLines(); ++k) {
    double a[3], b[3], f[3];
    c->GetPoint(2 * k, a);
    c->GetPoint(2 * k + 1, b);
    force->GetTuple(k, f);
    EXPECT_NEAR(mag->GetValue(k), std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]), 1e-12);
    EXPECT_GT(mag->GetValue(k), 0.0);
    // Touching: the centres closer than the largest diameter (4 mm).
    const double d = std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                               (a[2] - b[2]) * (a[2] - b[2]));
    EXPECT_LT(d, 4e-3);
  }
}

// Without output.contact_forces the series still ends with the settled pile's contacts (what a
// user opens the final state for), and no earlier frame has any.
TEST(VtkSeries, TheLastFrameHasItsContactsByDefault) {
  const fs::path d = fs::temp_directory_path() / "reposetwin_vtk_series_default_contacts";
  fs::remove_all(d);
  RunOptions opt;
  opt.out_dir = (d / "run").string();
  opt.progress = false;
  const std::string text = std::string(test_support::kTinyScene) + "[output]\nframe_interval_s = 0.05\n";
  run_pile_test(parse_scene_text(text, (d / "tiny.toml").string()), opt);
  std::vector<std::string> frames, contacts;
  for (const auto& e : fs::directory_iterator(d / "run" / "frames")) {
    const std::string name = e.path().filename().string();
    if (name.rfind("frame_", 0) == 0) frames.push_back(name.substr(6));
    if (name.rfind("contacts_", 0) == 0) contacts.push_back(name.substr(9));
  }
  ASSERT_GT(frames.size(), 2u);
  ASSERT_EQ(contacts.size(), 1u);
  EXPECT_EQ(contacts[0], *std::max_element(frames.begin(), frames.end()));
  EXPECT_GT(read_poly(d / "run" / "frames" / ("contacts_" + contacts[0]))->GetNumberOfLines(), 5);
  EXPECT_NE(slurp(d / "run" / "series.pvd").find("contacts_" + contacts[0]), std::string::npos);
}

TEST(PvdSeries, PartsSurviveALoadAndTruncate) {
  const fs::path dir = fs::temp_directory_path() / "reposetwin_pvd_parts";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string path = (dir / "s.pvd").string();
  {
    PvdSeries s(path);
    s.add(0.0, std::vector<std::string>{"a0.vtp", "plate.vtp", "f0.vtp"});
    s.add(0.5, std::vector<std::string>{"a1.vtp", "plate.vtp"});
  }
  PvdSeries s(path);
  s.load();
  s.truncate_after(0.25);
  const std::string text = slurp(path);
  EXPECT_NE(text.find("part=\"2\" file=\"f0.vtp\""), std::string::npos);
  EXPECT_EQ(text.find("a1.vtp"), std::string::npos);
}

}  // namespace
}  // namespace reposetwin::experiments
