#include "experiments/export/particle_dump.hpp"

#include "experiments/io/numbers.hpp"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "experiments/io/files.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/vtk_output.hpp"

namespace reposetwin::experiments {

namespace {
// Dumps are streamed, not held: the bound is on time, a LIGGGHTS run of many snapshots of
// millions of grains.
constexpr std::uintmax_t kMaxDumpBytes = std::uintmax_t{64} << 30;
constexpr std::size_t kMaxLineBytes = std::size_t{1} << 20;
}  // namespace

ParticleDump read_particle_dump(const std::string& path) {
  // A FIFO would block the open and /dev/zero never ends: refused, by name and reason, first.
  check_input_file(path, kMaxDumpBytes);
  std::ifstream f(path);
  if (!f) throw InputError(path + ": cannot open the dump file");
  ParticleDump last;
  bool any = false;
  std::string line;
  long long n_line = 0;
  auto bad = [&](const std::string& what) {
    throw InputError(path + ":" + std::to_string(n_line) + ": " + what);
  };
  // A dump's lines are short (a header word, or a grain's dozen numbers); a file of one
  // gigabyte-long line is not a dump, and reading it whole would hold it all in memory first.
  std::vector<char> buffer(kMaxLineBytes + 1);
  auto getline = [&](std::ifstream& in, std::string& out) {
    in.getline(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    if (in.fail() && !in.eof() && in.gcount() == static_cast<std::streamsize>(buffer.size()) - 1) {
      bad("a line longer than " + std::to_string(kMaxLineBytes) + " bytes: not a dump file");
    }
    if (in.gcount() == 0 && in.fail()) return false;
    out.assign(buffer.data());
    in.clear(in.rdstate() & ~std::ios::failbit);
    return true;
  };
  // A count or a time step is decimal digits: atoll would read "0x10" as 0 and "1e2" as 1.
  auto count_of = [&](std::string text, const std::string& what) -> long long {
    while (!text.empty() && (text.back() == ' ' || text.back() == '\r' || text.back() == '\t'))
      text.pop_back();
    while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.erase(0, 1);
    const std::optional<std::uint64_t> v = parse_seed(text);
    if (!v || *v > 100'000'000'000ull) bad(what + " = \"" + text + "\" is not a whole number");
    return static_cast<long long>(*v);
  };
  while (getline(f, line)) {
    ++n_line;
    if (line.rfind("ITEM: TIMESTEP", 0) == 0) {
      ParticleDump snap;
      std::string v, count;
      ++n_line;
      if (!getline(f, v)) bad("a TIMESTEP without its value");
      snap.timestep = count_of(v, "TIMESTEP");
      long long n = -1;
      int ix = -1, iy = -1, iz = -1, ir = -1, columns = 0;
      while (getline(f, line)) {
        ++n_line;
        if (line.rfind("ITEM: NUMBER OF ATOMS", 0) == 0) {
          ++n_line;
          if (!getline(f, count)) bad("NUMBER OF ATOMS without its value");
          n = count_of(count, "NUMBER OF ATOMS");
          if (n > 100'000'000) bad("NUMBER OF ATOMS = " + count + " is above 100 million");
        } else if (line.rfind("ITEM: ATOMS", 0) == 0) {
          std::istringstream names(line.substr(11));
          std::string name;
          for (int k = 0; names >> name; ++k, ++columns) {
            if (name == "x") ix = k;
            if (name == "y") iy = k;
            if (name == "z") iz = k;
            if (name == "radius") ir = k;
          }
          break;
        }
      }
      if (n < 0) bad("a snapshot without NUMBER OF ATOMS");
      if (ix < 0 || iy < 0 || iz < 0 || ir < 0)
        bad("the ATOMS line must name the columns x, y, z and radius (dump custom ... x y z "
            "radius)");
      snap.x.reserve(static_cast<std::size_t>(n));
      for (long long i = 0; i < n; ++i) {
        ++n_line;
        if (!getline(f, line))
          bad("the snapshot ends after " + std::to_string(i) + " of " + std::to_string(n) +
              " atoms");
        // The columns measured are read by the one strict number reader (io/numbers.hpp): a
        // "nan", "inf", hex or out-of-range value is refused by name; the others are skipped.
        std::istringstream row(line);
        std::vector<double> v(static_cast<std::size_t>(columns));
        std::string token;
        for (int k = 0; k < columns; ++k) {
          if (!(row >> token)) bad("a row with fewer than " + std::to_string(columns) + " numbers");
          if (k != ix && k != iy && k != iz && k != ir) continue;
          const std::optional<double> c = parse_plain_decimal(token);
          if (!c) bad("\"" + token + "\", a number that is not finite or not a plain decimal");
          v[static_cast<std::size_t>(k)] = *c;
        }
        if (!(v[static_cast<std::size_t>(ir)] > 0)) bad("a radius that is not positive");
        snap.x.emplace_back(v[static_cast<std::size_t>(ix)], v[static_cast<std::size_t>(iy)],
                            v[static_cast<std::size_t>(iz)]);
        snap.radius.push_back(v[static_cast<std::size_t>(ir)]);
      }
      last = std::move(snap);
      any = true;
    }
  }
  if (!any) throw InputError(path + ": no snapshot (ITEM: TIMESTEP) in the dump file");
  return last;
}

ParticleDump read_particles(const std::string& path) {
  if (std::filesystem::path(path).extension() != ".vtp") return read_particle_dump(path);
  SnapshotParticles s;
  try {
    s = read_vtp(path);
  } catch (const std::exception& e) {
    throw InputError(e.what());  // read_vtp names the file
  }
  ParticleDump d;
  d.x = std::move(s.x);
  d.radius = std::move(s.radius);
  return d;
}

}  // namespace reposetwin::experiments
