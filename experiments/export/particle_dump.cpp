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
  while (std::getline(f, line)) {
    ++n_line;
    if (line.rfind("ITEM: TIMESTEP", 0) == 0) {
      ParticleDump snap;
      std::string v, count;
      ++n_line;
      if (!std::getline(f, v)) bad("a TIMESTEP without its value");
      snap.timestep = std::atoll(v.c_str());
      long long n = -1;
      int ix = -1, iy = -1, iz = -1, ir = -1, columns = 0;
      while (std::getline(f, line)) {
        ++n_line;
        if (line.rfind("ITEM: NUMBER OF ATOMS", 0) == 0) {
          ++n_line;
          if (!std::getline(f, count)) bad("NUMBER OF ATOMS without its value");
          n = std::atoll(count.c_str());
          if (n < 0 || n > 100'000'000) bad("NUMBER OF ATOMS = " + count + " is not a count");
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
        if (!std::getline(f, line)) bad("the snapshot ends after " + std::to_string(i) + " of " +
                                        std::to_string(n) + " atoms");
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
