// Checkpoints are byte-reproducible: one state writes one file, whatever memory the state was
// built in. A checkpoint is compared byte for byte (a campaign's cache, a resumed run's proof), so
// no byte of it may come from uninitialised memory such as a struct's padding.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "sim/checkpoint.hpp"
#include "sim/world.hpp"
#include "sim_test_util.hpp"

namespace reposetwin::sim {
namespace {

constexpr unsigned char kGarbage = 0xA5;

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("reposetwin_ckpt_bytes_" + name)).string();
}

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

std::string checkpoint_bytes(const World& w, const std::string& path) {
  write_checkpoint(w, path);
  return file_bytes(path);
}

/// Leaves `fill` in the stack below the caller and in freed heap blocks of a range of sizes, so
/// that the locals, temporaries and allocations of the next calls are likely to start with it.
[[gnu::noinline]] void dirty_memory(unsigned char fill) {
  volatile unsigned char stack[32 * 1024];
  for (std::size_t k = 0; k < sizeof stack; ++k) stack[k] = fill;
  std::vector<std::unique_ptr<unsigned char[]>> blocks;
  for (std::size_t bytes = 16; bytes <= 64 * 1024; bytes *= 2) {  // below malloc's mmap size
    blocks.emplace_back(new unsigned char[bytes]);
    std::memset(blocks.back().get(), fill, bytes);
  }
}

/// The pour with its plate moving up and its funnel disabled, after 300 steps: every wall's
/// state differs from its default, and the springs and neighbor list are in use.
World moved_pour() {
  World w = testing::funnel_pour(150);
  w.set_wall_velocity(0, Vec3(0.0, 0.0, 0.01));
  w.set_wall_enabled(1, false);
  for (int s = 0; s < 300; ++s) w.step();
  return w;
}

void expect_same_walls(const State& a, const State& b) {
  ASSERT_EQ(a.walls.size(), b.walls.size());
  for (std::size_t k = 0; k < a.walls.size(); ++k) {
    EXPECT_EQ(a.walls[k].offset, b.walls[k].offset) << "wall " << k;
    EXPECT_EQ(a.walls[k].velocity, b.walls[k].velocity) << "wall " << k;
    EXPECT_EQ(a.walls[k].enabled, b.walls[k].enabled) << "wall " << k;
  }
}

TEST(Checkpoint, TheSameStateWritesTheSameBytes) {
  const std::string path = temp_path("a.bin");
  dirty_memory(0);
  const World clean = moved_pour();
  const std::string reference = checkpoint_bytes(clean, path);
  ASSERT_EQ(clean.state().walls.size(), 2u);

  // The same world built again, in memory left full of garbage.
  dirty_memory(kGarbage);
  const World rebuilt = moved_pour();
  ASSERT_EQ(state_hash(rebuilt.state()), state_hash(clean.state()));
  expect_same_walls(rebuilt.state(), clean.state());
  EXPECT_TRUE(checkpoint_bytes(rebuilt, temp_path("b.bin")) == reference)
      << "a rebuilt world wrote another file";

  // The same walls in storage that held garbage before their fields were set: what is left in
  // the bytes between and after the fields must not reach the file.
  World refilled = moved_pour();
  std::vector<WallState> walls(refilled.state().walls.size());
  std::memset(static_cast<void*>(walls.data()), kGarbage, walls.size() * sizeof(WallState));
  for (std::size_t k = 0; k < walls.size(); ++k) {
    walls[k].offset = refilled.state().walls[k].offset;
    walls[k].velocity = refilled.state().walls[k].velocity;
    walls[k].enabled = refilled.state().walls[k].enabled;
  }
  refilled.state().walls.swap(walls);
  expect_same_walls(refilled.state(), clean.state());
  EXPECT_TRUE(checkpoint_bytes(refilled, temp_path("c.bin")) == reference)
      << "walls in dirty storage wrote another file";

  // Read back and written again: the same file.
  World resumed = testing::funnel_pour(0);
  read_checkpoint(resumed, path);
  EXPECT_TRUE(checkpoint_bytes(resumed, temp_path("d.bin")) == reference)
      << "a resumed world wrote another file";

  for (const char* name : {"a.bin", "b.bin", "c.bin", "d.bin"}) std::filesystem::remove(temp_path(name));
}

}  // namespace
}  // namespace reposetwin::sim
