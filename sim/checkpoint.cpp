#include "sim/checkpoint.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <type_traits>
#include <vector>

namespace reposetwin::sim {
namespace {

// Format 4 ends with a checksum of every byte before it; format 3 added the clumps (the particles'
// clump fields and the bodies). Formats 1 to 3 (1 and 2 spheres only; 1 with per-pair overlaps,
// now derived by World::diagnose) are still read, without a checksum to verify.
constexpr char kMagic[8] = {'R', 'T', 'W', 'C', 'K', 'P', 'T', '4'};
constexpr char kMagicFormat3[8] = {'R', 'T', 'W', 'C', 'K', 'P', 'T', '3'};
constexpr char kMagicFormat2[8] = {'R', 'T', 'W', 'C', 'K', 'P', 'T', '2'};
constexpr char kMagicFormat1[8] = {'R', 'T', 'W', 'C', 'K', 'P', 'T', '1'};

// Values are written as their bytes in memory, so only types without padding may be: a padding
// byte holds whatever the memory held before (a temporary's stack, a reused heap block, the file
// a state was read from), and the same state would write different files. Arithmetic types and
// Eigen's fixed double vectors are packed (long double is not: 10 bytes of 16); a struct is listed
// here with its size checked against its members'. A struct with padding (WallState) is written
// field by field.
template <class T>
constexpr bool kPacked = std::is_arithmetic_v<T> && !std::is_same_v<T, long double>;
template <>
constexpr bool kPacked<Vec3> = sizeof(Vec3) == 3 * sizeof(double);
template <>
constexpr bool kPacked<Quat> = sizeof(Quat) == 4 * sizeof(double);
template <>
constexpr bool kPacked<ContactHistory> = kPacked<Vec3> &&
                                         sizeof(ContactHistory) == 2 * sizeof(Vec3);
template <class T, std::size_t N>
constexpr bool kPacked<std::array<T, N>> = kPacked<T> && sizeof(std::array<T, N>) == N * sizeof(T);

// Each wall's record: offset, velocity, enabled, then zero bytes up to 56, the size of WallState
// in memory on x86-64, which every format's files have (the record is read the same way).
constexpr std::size_t kWallRecordBytes = 56;
constexpr std::size_t kWallReserved = kWallRecordBytes - 2 * sizeof(Vec3) - sizeof(bool);

// FNV-1a (64 bit) of a file's bytes, fed as they pass: a flipped or zeroed byte anywhere (a bad
// disk block, a partial copy, a hand edit) changes it, so a damaged checkpoint is refused rather
// than resumed into a different result. It guards against accidents, not against forgery.
class Checksum {
 public:
  void add(const char* data, std::size_t n) {
    for (std::size_t k = 0; k < n; ++k) {
      h_ ^= static_cast<unsigned char>(data[k]);
      h_ *= 0x100000001b3ULL;
    }
  }
  std::uint64_t value() const { return h_; }

 private:
  std::uint64_t h_ = 0xcbf29ce484222325ULL;
};

class Writer {
 public:
  explicit Writer(std::ofstream& out) : out_(out) {}
  template <class T>
  void pod(const T& v) {
    static_assert(kPacked<T>, "a type with padding bytes: write its fields");
    bytes(reinterpret_cast<const char*>(&v), sizeof(T));
  }
  template <class T, class A>
  void vec(const std::vector<T, A>& v) {
    static_assert(kPacked<T>, "a type with padding bytes: write its fields");
    count(v);
    bytes(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
  }
  void bytes(const char* data, std::size_t n) {
    sum_.add(data, n);
    out_.write(data, static_cast<std::streamsize>(n));
  }
  /// The checksum of every byte written so far, appended (not itself summed).
  void checksum() {
    const std::uint64_t h = sum_.value();
    out_.write(reinterpret_cast<const char*>(&h), sizeof h);
  }
  template <class T, class A>
  void count(const std::vector<T, A>& v) {
    pod<std::uint64_t>(v.size());
  }
  /// Zero bytes where the format keeps room.
  void reserved(std::size_t n) {
    const std::array<char, 64> zeros{};
    for (std::size_t k = 0; k < n; k += zeros.size())
      bytes(zeros.data(), std::min(zeros.size(), n - k));
  }

 private:
  std::ofstream& out_;
  Checksum sum_;
};

class Reader {
 public:
  Reader(std::ifstream& in, const std::string& path) : in_(in), path_(path) {}
  template <class T>
  void pod(T& v) {
    if constexpr (std::is_same_v<T, bool>) {  // a byte other than 0 or 1 is no bool
      std::uint8_t byte = 0;
      pod(byte);
      if (byte > 1) fail("has a flag that is neither 0 nor 1");
      v = byte == 1;
    } else {
      bytes(reinterpret_cast<char*>(&v), sizeof(T));
    }
  }
  template <class T, class A>
  void vec(std::vector<T, A>& v) {
    count(v);
    bytes(reinterpret_cast<char*>(v.data()), v.size() * sizeof(T));
  }
  void bytes(char* data, std::size_t n) {
    in_.read(data, static_cast<std::streamsize>(n));
    check();
  }
  /// Reads an array's length and resizes `v` to it.
  template <class T, class A>
  void count(std::vector<T, A>& v) {
    std::uint64_t n = 0;
    pod(n);
    if (n > (std::uint64_t{1} << 34) / sizeof(T)) fail("an array length is implausible");
    v.resize(n);
  }
  /// Skips bytes the format keeps room in; their contents do not matter.
  void reserved(std::size_t n) {
    std::array<char, 64> skip{};
    for (std::size_t k = 0; k < n; k += skip.size())
      bytes(skip.data(), std::min(skip.size(), n - k));
  }
  [[noreturn]] void fail(const std::string& what) {
    throw std::runtime_error(path_ + ": checkpoint " + what);
  }

 private:
  void check() {
    if (!in_) fail("is truncated");
  }
  std::ifstream& in_;
  std::string path_;
};

// Whether the checksum at the end of a format-4 file matches the bytes before it. Checked before
// a single value is parsed, so a damaged array length never sizes an allocation.
bool checksum_matches(std::ifstream& in) {
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < static_cast<std::streamoff>(sizeof(kMagic) + sizeof(std::uint64_t))) return false;
  in.seekg(0);
  Checksum sum;
  std::vector<char> buf(std::size_t{1} << 20);
  for (std::streamoff left = size - static_cast<std::streamoff>(sizeof(std::uint64_t)); left > 0;) {
    const auto n = static_cast<std::streamsize>(
        std::min<std::streamoff>(left, static_cast<std::streamoff>(buf.size())));
    if (!in.read(buf.data(), n)) return false;
    sum.add(buf.data(), static_cast<std::size_t>(n));
    left -= n;
  }
  std::uint64_t stored = 0;
  if (!in.read(reinterpret_cast<char*>(&stored), sizeof stored)) return false;
  return stored == sum.value();
}

/// The walls' states, one fixed-size record each (see kWallRecordBytes).
template <class Archive, class WallsT>
void transfer_walls(Archive& ar, WallsT& walls) {
  ar.count(walls);
  for (auto& w : walls) {
    ar.pod(w.offset);
    ar.pod(w.velocity);
    ar.pod(w.enabled);
    ar.reserved(kWallReserved);
  }
}

/// The state's contents in file order, for writing (const State) and reading (State): one list,
/// so the reader cannot drift from the writer.
template <class Archive, class StateT>
void transfer_state(Archive& ar, StateT& s, int format) {
#define REPOSETWIN_TRANSFER_FIELD(type, name, doc) ar.vec(s.particles.name);
  REPOSETWIN_PARTICLE_CORE_FIELDS(REPOSETWIN_TRANSFER_FIELD)
  if (format >= 3) {
    REPOSETWIN_PARTICLE_CLUMP_FIELDS(REPOSETWIN_TRANSFER_FIELD)
  }
#undef REPOSETWIN_TRANSFER_FIELD
  if (format >= 3) {
#define REPOSETWIN_TRANSFER_BODY_FIELD(type, name, doc) ar.vec(s.bodies.name);
    REPOSETWIN_BODY_FIELDS(REPOSETWIN_TRANSFER_BODY_FIELD)
#undef REPOSETWIN_TRANSFER_BODY_FIELD
    ar.pod(s.next_body_id);
  }
  ar.pod(s.time);
  ar.pod(s.step);
  ar.pod(s.next_id);
  ar.pod(s.forces_valid);
  transfer_walls(ar, s.walls);
  ar.pod(s.neighbors.skin);
  ar.pod(s.neighbors.builds);
  ar.vec(s.neighbors.start);
  ar.vec(s.neighbors.second);
  ar.vec(s.neighbors.history);
  ar.vec(s.neighbors.in_start);
  ar.vec(s.neighbors.in_pairs);
  ar.vec(s.neighbors.x_at_build);
  if (format == 1) {  // each pair's overlap ratio: read and dropped
    HugeVector<double> overlap;
    ar.vec(overlap);
  }
}

}  // namespace

void write_checkpoint(const World& world, const std::string& path) {
  const State& s = world.state();
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(path + ": cannot write checkpoint");
    Writer w(out);
    w.bytes(kMagic, sizeof kMagic);
    w.pod(world.model().dt);
    w.pod<std::uint64_t>(world.model().walls.size());
    transfer_state(w, s, 4);
    w.checksum();
    out.flush();
    if (!out) {
      out.close();
      std::error_code ignored;
      std::filesystem::remove(tmp, ignored);  // a full disk must not leave half a file behind
      throw std::runtime_error(path + ": checkpoint write failed (disk full or not writable)");
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw std::runtime_error(path + ": cannot move the checkpoint into place");
}

void read_checkpoint(World& world, const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open checkpoint");
  char magic[8];
  Reader r(in, path);
  in.read(magic, sizeof magic);
  if (!in) r.fail("is not a ReposeTwin checkpoint");
  int format = 0;
  if (std::memcmp(magic, kMagic, sizeof kMagic) == 0) format = 4;
  if (std::memcmp(magic, kMagicFormat3, sizeof kMagicFormat3) == 0) format = 3;
  if (std::memcmp(magic, kMagicFormat2, sizeof kMagicFormat2) == 0) format = 2;
  if (std::memcmp(magic, kMagicFormat1, sizeof kMagicFormat1) == 0) format = 1;
  if (format == 0) r.fail("is not a ReposeTwin checkpoint");
  if (format >= 4) {
    if (!checksum_matches(in))
      r.fail("is damaged (its checksum does not match its contents); it cannot be resumed. "
             "Run again from the start with --force");
    in.clear();
    in.seekg(sizeof magic);
  }
  double dt = 0.0;
  r.pod(dt);
  if (dt != world.model().dt) r.fail("was made with another time step");
  std::uint64_t nwalls = 0;
  r.pod(nwalls);
  if (nwalls != world.model().walls.size()) r.fail("was made with another number of walls");
  State s;
  transfer_state(r, s, format);
  if (format >= 4) r.reserved(sizeof(std::uint64_t));  // the checksum, verified above
  if (in.peek() != std::ifstream::traits_type::eof()) r.fail("has data after its end");
  const std::size_t n = s.particles.x.size();
  if (format < 3) {  // spheres only
    s.particles.body.assign(n, -1);
    s.particles.component.assign(n, -1);
  }
#define REPOSETWIN_CHECK_FIELD(type, name, doc) \
  if (s.particles.name.size() != n) r.fail("has particle arrays of different lengths");
  REPOSETWIN_PARTICLE_FIELDS(REPOSETWIN_CHECK_FIELD)
#undef REPOSETWIN_CHECK_FIELD
  const std::size_t nb = s.bodies.x.size();
#define REPOSETWIN_CHECK_BODY_FIELD(type, name, doc) \
  if (s.bodies.name.size() != nb) r.fail("has body arrays of different lengths");
  REPOSETWIN_BODY_FIELDS(REPOSETWIN_CHECK_BODY_FIELD)
#undef REPOSETWIN_CHECK_BODY_FIELD
  for (std::size_t b = 0; b < nb; ++b) {
    const std::int32_t shape = s.bodies.shape[b];
    if (shape < 0 || static_cast<std::size_t>(shape) >= world.model().clumps.size())
      r.fail("has a body whose clump template is not in the model");
  }
  try {
    index_body_components(s.particles, nb, s.body_components);
  } catch (const std::logic_error&) {
    r.fail("has inconsistent clump components");
  }
  for (std::size_t b = 0; b < nb; ++b) {
    const std::size_t k =
        static_cast<std::size_t>(s.body_components.start[b + 1] - s.body_components.start[b]);
    if (k != world.model().clumps[static_cast<std::size_t>(s.bodies.shape[b])].size())
      r.fail("has a body whose components do not match its template");
  }
  NeighborList& nl = s.neighbors;
  if (s.walls.size() != nwalls) r.fail("has an inconsistent wall count");
  const std::size_t np = nl.second.size();
  if (nl.history.size() != np) r.fail("has an inconsistent neighbor list");
  for (std::int32_t j : nl.second)
    if (j < 0 || static_cast<std::size_t>(j) >= n) r.fail("has a neighbor index out of range");
  if (nl.in_pairs.size() != np) r.fail("has an inconsistent neighbor list");
  for (std::int32_t k : nl.in_pairs)
    if (k < 0 || static_cast<std::size_t>(k) >= np) r.fail("has a pair index out of range");
  derive_list_indices(nl);
  compute_clearances(nl, s.particles);
  s.reaction.assign(np, Reaction{});
  s.pair_live.assign(np, 1);
  nl.parallel_min = static_cast<std::size_t>(world.model().settings.parallel_min_particles);
  world.state() = std::move(s);
}

}  // namespace reposetwin::sim
