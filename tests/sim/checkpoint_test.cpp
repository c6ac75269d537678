// Checkpoints are byte-reproducible: one state writes one file, whatever memory the state was
// built in. A checkpoint is compared byte for byte (a campaign's cache, a resumed run's proof), so
// no byte of it may come from uninitialised memory such as a struct's padding.
#include "sim/checkpoint.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

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

  for (const char* name : {"a.bin", "b.bin", "c.bin", "d.bin"})
    std::filesystem::remove(temp_path(name));
}

/// Where the walls' array (its length, then one record per wall) starts in a checkpoint of `w`.
std::size_t walls_at(const std::string& bytes, const World& w) {
  const std::uint64_t n = w.state().walls.size();
  std::string key(reinterpret_cast<const char*>(&n), sizeof n);
  key.append(reinterpret_cast<const char*>(w.state().walls[0].offset.data()), sizeof(Vec3));
  const std::size_t at = bytes.find(key);
  EXPECT_NE(at, std::string::npos);
  EXPECT_EQ(bytes.find(key, at + 1), std::string::npos) << "the walls' start is ambiguous";
  return at;
}

void write_file(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// The same bytes as a format-3 file (no checksum): how a file made before the checksum reads,
// and how a byte can be edited here without the checksum refusing the whole file.
std::string as_format3(std::string bytes) {
  bytes[7] = '3';
  bytes.resize(bytes.size() - sizeof(std::uint64_t));
  return bytes;
}

TEST(Checkpoint, WallRecordsKeepTheirLayoutAndIgnoreTheirReservedBytes) {
  const std::string path = temp_path("walls.bin");
  const World w = moved_pour();
  const std::string reference = checkpoint_bytes(w, path);
  const std::size_t at = walls_at(reference, w) + sizeof(std::uint64_t);
  // Each record: offset, velocity, the enabled flag, zeros up to 56 bytes.
  constexpr std::size_t kRecord = 56, kFields = 2 * sizeof(Vec3) + 1;
  std::string garbage = reference;
  for (std::size_t k = 0; k < w.state().walls.size(); ++k) {
    const WallState& ws = w.state().walls[k];
    const std::size_t r = at + k * kRecord;
    EXPECT_EQ(std::memcmp(reference.data() + r, ws.offset.data(), sizeof(Vec3)), 0) << k;
    EXPECT_EQ(std::memcmp(reference.data() + r + sizeof(Vec3), ws.velocity.data(), sizeof(Vec3)), 0)
        << k;
    EXPECT_EQ(reference[r + 2 * sizeof(Vec3)], ws.enabled ? 1 : 0) << k;
    EXPECT_EQ(reference.substr(r + kFields, kRecord - kFields),
              std::string(kRecord - kFields, '\0'));
    garbage.replace(r + kFields, kRecord - kFields, "ed) thr");
  }
  // Files whose reserved bytes hold garbage (written from the struct's memory) read the same.
  write_file(path, as_format3(garbage));
  World resumed = testing::funnel_pour(0);
  read_checkpoint(resumed, path);
  expect_same_walls(resumed.state(), w.state());
  EXPECT_TRUE(checkpoint_bytes(resumed, path) == reference);
  // A flag byte that is no bool is refused, naming the file.
  std::string bad = reference;
  bad[at + 2 * sizeof(Vec3)] = 2;  // the first wall's flag
  write_file(path, as_format3(bad));
  try {
    read_checkpoint(resumed, path);
    ADD_FAILURE() << "a flag of 2 was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("neither 0 nor 1"), std::string::npos) << e.what();
  }
  // In a current file any changed byte, reserved or not, fails the checksum.
  for (const std::string& changed : {garbage, bad}) {
    write_file(path, changed);
    try {
      read_checkpoint(resumed, path);
      ADD_FAILURE() << "a changed file was accepted";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("checksum"), std::string::npos) << e.what();
    }
  }
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace reposetwin::sim
