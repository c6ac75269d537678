// photograph_pile keeps one renderer per thread for the thread's life (photographs.cpp): one
// photograph gives the same measurement whether its renderer is new, reused after another pile,
// or one of two threads' photographing at once; and a child forked after its parent rendered gets an error at once instead of
// the hang llvmpipe would give it (its rasteriser threads are not in the child).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <thread>

#include "../../support/cone_pile.hpp"
#include "experiments/photos/photographs.hpp"

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

struct Reading {
  double theta_deg = 0.0, height_m = 0.0, diameter_m = 0.0;
};

Reading photograph_cone(double height_m = 14e-3) {
  const test_support::Spheres s =
      test_support::make_cone(height_m, 24e-3, 0.0, 0.0, 1.75e-3, 11, 0.3);
  const PileSpheres pile{{s.x.begin(), s.x.end()}, s.r, std::vector<int>(s.r.size(), 0)};
  PhotoSettings settings;
  settings.width_px = 480;
  settings.height_px = 360;
  settings.side_views = 2;
  settings.top_view = false;
  settings.scale_reference = false;
  settings.write_photos = false;
  settings.write_overlays = false;
  const PilePhotos photos = photograph_pile(
      pile, settings, (fs::temp_directory_path() / "reposetwin_renderer_reuse").string());
  if (!photos.summary) throw std::runtime_error("the cone was not measured");
  return {photos.summary->theta_deg.mean, photos.summary->height_m.mean,
          photos.summary->diameter_m.mean};
}

void expect_same(const Reading& a, const Reading& b) {
  EXPECT_EQ(a.theta_deg, b.theta_deg);
  EXPECT_EQ(a.height_m, b.height_m);
  EXPECT_EQ(a.diameter_m, b.diameter_m);
}

TEST(RendererReuse, EveryWayOfGettingARendererGivesTheSameMeasurement) {
  const Reading first = photograph_cone();
  const Reading other = photograph_cone(10e-3);  // the renderer is reused on another pile
  EXPECT_NE(first.theta_deg, other.theta_deg);  // the comparison can fail
  expect_same(photograph_cone(), first);

  // Two threads at once, each with its own new renderer.
  Reading in_thread[2];
  std::thread t0([&] { in_thread[0] = photograph_cone(); });
  std::thread t1([&] { in_thread[1] = photograph_cone(); });
  t0.join();
  t1.join();
  expect_same(in_thread[0], first);
  expect_same(in_thread[1], first);

  // A forked child is refused at once (the alarm kills it, and fails the test, if it hangs).
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::alarm(30);
    try {
      photograph_cone();
    } catch (const std::logic_error& e) {
      ::_exit(std::strstr(e.what(), "forked after its parent rendered") ? 0 : 4);
    } catch (...) {
      ::_exit(5);
    }
    ::_exit(6);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status)) << "the child did not finish (signal " << WTERMSIG(status) << ")";
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

}  // namespace
}  // namespace reposetwin::experiments
