#include "sim/neighbor.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <type_traits>

namespace reposetwin::sim {
namespace {

void build_incoming(NeighborList& list, std::size_t n);

bool is_active(const ContactHistory& h) {
  return h.tangential.squaredNorm() > 0.0 || h.rolling.squaredNorm() > 0.0;
}

/// A dense grid over the particles' bounding box.
struct Grid {
  Vec3 origin;
  double h = 1.0;
  int nx = 1, ny = 1, nz = 1;
  int cell_of(const Vec3& x, int* ix, int* iy, int* iz) const {
    *ix = index((x.x() - origin.x()) / h, nx);
    *iy = index((x.y() - origin.y()) / h, ny);
    *iz = index((x.z() - origin.z()) / h, nz);
    return (*iz * ny + *iy) * nx + *ix;
  }
  // A coordinate in cells, clamped to [0, n - 1]; a NaN (a broken state, which the runner's
  // diagnose reports) goes to cell 0 instead of an undefined conversion.
  static int index(double q, int n) {
    if (!(q >= 0.0)) return 0;
    return q >= n - 1 ? n - 1 : static_cast<int>(q);
  }
};

Grid make_grid(const Particles& p, double skin) {
  // The box of the finite positions only: a non-finite one (the state is broken, and the
  // runner stops on it at its next check) must not make the box, and the cell search below,
  // unbounded.
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  double r_min = p.radius[0];
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.x[i].allFinite()) {
      lo = lo.cwiseMin(p.x[i]);
      hi = hi.cwiseMax(p.x[i]);
    }
    r_min = std::min(r_min, p.radius[i]);
  }
  if (!(lo.allFinite() && hi.allFinite())) lo = hi = Vec3::Zero();
  Grid g;
  g.origin = lo;
  g.h = 2.0 * r_min + skin;
  const Vec3 ext = hi - lo;
  // Keep the grid no larger than a few cells per particle (sparse or scattered particles).
  const double max_cells = 8.0 * static_cast<double>(p.size()) + 1000.0;
  for (;;) {
    const double cells = (std::floor(ext.x() / g.h) + 1) * (std::floor(ext.y() / g.h) + 1) *
                         (std::floor(ext.z() / g.h) + 1);
    if (cells <= max_cells) break;
    g.h *= 1.26;
  }
  g.nx = static_cast<int>(std::floor(ext.x() / g.h)) + 1;
  g.ny = static_cast<int>(std::floor(ext.y() / g.h)) + 1;
  g.nz = static_cast<int>(std::floor(ext.z() / g.h)) + 1;
  return g;
}

}  // namespace

void build_neighbor_list(Particles& p, NeighborList& list, bool sort_particles) {
  const std::size_t n = p.size();
  ++list.builds;
  // 1. Keep the old list: the histories of the pairs that persist are carried over from it
  // (step 4), found by their particles' old indices.
  const bool carry = list.start.size() == n + 1;
  list.old_start.swap(list.start);
  list.old_second.swap(list.second);
  list.old_history.swap(list.history);
  const HugeVector<std::int32_t>& old_start = list.old_start;
  const HugeVector<std::int32_t>& old_second = list.old_second;
  const HugeVector<ContactHistory>& old_history = list.old_history;
  list.start.assign(n + 1, 0);
  list.second.clear();
  list.history.clear();
  list.in_start.assign(n + 1, 0);
  list.in_pairs.clear();
  list.in_slot.clear();
  list.in_particle.clear();
  list.first.clear();
  list.clearance2.clear();
  list.x_at_build.assign(p.x.begin(), p.x.end());
  if (n == 0) return;

  // 2. Bin particles into cells (counting sort); optionally reorder them by cell.
  const Grid g = make_grid(p, list.skin);
  const std::size_t ncell = static_cast<std::size_t>(g.nx) * g.ny * g.nz;
  std::vector<std::int32_t> cell(n);
  std::vector<std::int32_t> cell_start(ncell + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    int ix, iy, iz;
    cell[i] = g.cell_of(p.x[i], &ix, &iy, &iz);
    ++cell_start[cell[i] + 1];
  }
  for (std::size_t c = 0; c < ncell; ++c) cell_start[c + 1] += cell_start[c];
  std::vector<std::size_t> order(n);
  {
    std::vector<std::int32_t> fill(cell_start.begin(), cell_start.end() - 1);
    for (std::size_t i = 0; i < n; ++i) order[fill[cell[i]]++] = i;
  }
  // from_old[i]: the index particle i had before this build.
  std::vector<std::size_t> from_old(n);
  if (sort_particles) {
    p.permute(order);
    list.x_at_build.assign(p.x.begin(), p.x.end());
    from_old.swap(order);
    std::iota(order.begin(), order.end(), std::size_t{0});
  } else {
    std::iota(from_old.begin(), from_old.end(), std::size_t{0});
  }
  // order[k] = particle index of the k-th entry in cell order.

  // 3. Each particle collects its partners: no larger than itself, within 2 r_i + skin, and not
  // of its own clump. The clump test is compiled only into the search of a world with clumps
  // (kClumps), so a world of spheres runs the search it always did.
  const double skin = list.skin;
  const std::int32_t* const body = p.body.data();
  bool clumps = false;
  for (std::size_t i = 0; i < n && !clumps; ++i) clumps = body[i] >= 0;
  auto for_each_partner = [&](std::size_t i, auto clumps_tag, auto&& emit) {
    constexpr bool kClumps = decltype(clumps_tag)::value;
    const Vec3 xi = p.x[i];
    const double ri = p.radius[i];
    // The cells within 2 r_i + skin of x_i along each axis (the cells' lower edges are at
    // origin + c h; cell_of truncates, which is floor for coordinates above the origin).
    const double reach = 2.0 * ri + skin;
    int lo[3], hi[3];
    const int cells[3] = {g.nx, g.ny, g.nz};
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::clamp(static_cast<int>(std::floor((xi[a] - reach - g.origin[a]) / g.h)), 0,
                         cells[a] - 1);
      hi[a] = std::clamp(static_cast<int>(std::floor((xi[a] + reach - g.origin[a]) / g.h)), 0,
                         cells[a] - 1);
    }
    for (int z = lo[2]; z <= hi[2]; ++z) {
      for (int y = lo[1]; y <= hi[1]; ++y) {
        const int row = (z * g.ny + y) * g.nx;
        for (std::int32_t k = cell_start[row + lo[0]]; k < cell_start[row + hi[0] + 1]; ++k) {
          const std::size_t j = order[k];
          const double rj = p.radius[j];
          const double cut = ri + rj + skin;
          // Partners no larger than i (ties: the higher index); one branch, rarely taken.
          const bool smaller = (rj < ri) | ((rj == ri) & (j > i));
          if constexpr (kClumps) {
            const bool other = (body[i] < 0) | (body[i] != body[j]);
            if (smaller & other & ((xi - p.x[j]).squaredNorm() < cut * cut))
              emit(static_cast<std::int32_t>(j));
          } else {
            if (smaller & ((xi - p.x[j]).squaredNorm() < cut * cut))
              emit(static_cast<std::int32_t>(j));
          }
        }
      }
    }
  };
  // One search per particle, in chunks of consecutive particles, each chunk's partners
  // collected apart and then copied into the CSR in particle order (whichever thread searched).
  constexpr std::size_t kChunk = 256;
  const std::size_t chunks = (n + kChunk - 1) / kChunk;
  std::vector<std::vector<std::int32_t>> found(chunks);
#pragma omp parallel for schedule(dynamic, 1) if (n > list.parallel_min)
  for (std::size_t c = 0; c < chunks; ++c) {
    std::vector<std::int32_t>& out = found[c];
    for (std::size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) {
      const std::size_t from = out.size();
      auto emit = [&](std::int32_t j) { out.push_back(j); };
      if (clumps) {
        for_each_partner(i, std::true_type{}, emit);
      } else {
        for_each_partner(i, std::false_type{}, emit);
      }
      std::sort(out.begin() + static_cast<std::ptrdiff_t>(from), out.end());
      list.start[i + 1] = static_cast<std::int32_t>(out.size() - from);
    }
  }
  for (std::size_t i = 0; i < n; ++i) list.start[i + 1] += list.start[i];
  list.second.resize(list.start[n]);
  list.history.assign(list.start[n], ContactHistory{});
#pragma omp parallel for schedule(static) if (n > list.parallel_min)
  for (std::size_t c = 0; c < chunks; ++c)
    std::copy(found[c].begin(), found[c].end(), list.second.begin() + list.start[c * kChunk]);

  // 4. Carry histories over from the old list (a pair listed the other way round there has its
  // springs negated). Only springs that are not zero are copied.
  if (carry) {
    // The position of old pair (a, b) in the old list, or -1.
    auto old_pair = [&](std::size_t a, std::size_t b) -> std::int32_t {
      for (std::int32_t k = old_start[a]; k < old_start[a + 1]; ++k)
        if (static_cast<std::size_t>(old_second[k]) == b) return k;
      return -1;
    };
#pragma omp parallel for schedule(dynamic, 256) if (n > list.parallel_min)
    for (std::size_t i = 0; i < n; ++i) {
      for (std::int32_t k = list.start[i]; k < list.start[i + 1]; ++k) {
        const std::size_t a = from_old[i], b = from_old[static_cast<std::size_t>(list.second[k])];
        if (const std::int32_t o = old_pair(a, b); o >= 0 && is_active(old_history[o])) {
          list.history[k] = old_history[o];
        } else if (const std::int32_t r = old_pair(b, a); r >= 0 && is_active(old_history[r])) {
          list.history[k].tangential = -old_history[r].tangential;
          list.history[k].rolling = -old_history[r].rolling;
        }
      }
    }
  }

  // 5. Incoming CSR: for each particle, the pairs where it is second, in pair order.
  build_incoming(list, n);
  compute_clearances(list, p);
}

void compute_clearances(NeighborList& list, const Particles& p) {
  const std::size_t n = list.start.size() > 0 ? list.start.size() - 1 : 0;
  list.clearance2.assign(list.second.size(), 0.0);
  if (list.x_at_build.size() != n || p.size() != n) return;  // no list: nothing skipped
  // Half the gap, less one part in a million: the margin covers the roundings of the distances
  // and displacements compared (a few parts in 1e16), so a skipped pair never touches.
  constexpr double kShrink = 0.5 * (1.0 - 1e-6);
#pragma omp parallel for schedule(static) if (n > list.parallel_min)
  for (std::size_t i = 0; i < n; ++i) {
    for (std::int32_t k = list.start[i]; k < list.start[i + 1]; ++k) {
      const std::size_t j = static_cast<std::size_t>(list.second[k]);
      const double gap = (list.x_at_build[i] - list.x_at_build[j]).norm() -
                         (p.radius[i] + p.radius[j]);
      if (gap > 1e-12 * (p.radius[i] + p.radius[j])) {
        const double half = kShrink * gap;
        list.clearance2[k] = half * half;
      }
    }
  }
}

namespace {

void build_incoming(NeighborList& list, std::size_t n) {
  list.in_start.assign(n + 1, 0);
  for (std::int32_t j : list.second) ++list.in_start[j + 1];
  for (std::size_t i = 0; i < n; ++i) list.in_start[i + 1] += list.in_start[i];
  list.in_pairs.resize(list.second.size());
  std::vector<std::int32_t> fill(list.in_start.begin(), list.in_start.end() - 1);
  for (std::size_t k = 0; k < list.second.size(); ++k)
    list.in_pairs[fill[list.second[k]]++] = static_cast<std::int32_t>(k);
  derive_list_indices(list);
}

}  // namespace

void derive_list_indices(NeighborList& list) {
  list.in_slot.resize(list.in_pairs.size());
  for (std::size_t q = 0; q < list.in_pairs.size(); ++q)
    list.in_slot[list.in_pairs[q]] = static_cast<std::int32_t>(q);
  list.in_particle.resize(list.in_pairs.size());
  for (std::size_t i = 0; i + 1 < list.in_start.size(); ++i)
    for (std::int32_t q = list.in_start[i]; q < list.in_start[i + 1]; ++q)
      list.in_particle[q] = static_cast<std::int32_t>(i);
  list.first.resize(list.second.size());
  for (std::size_t i = 0; i + 1 < list.start.size(); ++i)
    for (std::int32_t k = list.start[i]; k < list.start[i + 1]; ++k)
      list.first[k] = static_cast<std::int32_t>(i);
}

void compact_neighbor_list(NeighborList& list, const std::vector<char>& keep) {
  const std::size_t n_old = keep.size();
  if (list.start.size() != n_old + 1) {  // no valid list: the next step rebuilds
    list.x_at_build.clear();
    return;
  }
  std::vector<std::int32_t> remap(n_old, -1);
  std::int32_t n = 0;
  for (std::size_t i = 0; i < n_old; ++i)
    if (keep[i]) remap[i] = n++;
  HugeVector<std::int32_t> start(n + 1, 0), second;
  HugeVector<ContactHistory> history;
  HugeVector<double> clearance2;
  HugeVector<Vec3> x_at_build;
  const bool clearances = list.clearance2.size() == list.second.size();
  for (std::size_t i = 0; i < n_old; ++i) {
    if (!keep[i]) continue;
    for (std::int32_t k = list.start[i]; k < list.start[i + 1]; ++k) {
      const std::int32_t j = remap[list.second[k]];
      if (j < 0) continue;
      second.push_back(j);
      history.push_back(list.history[k]);
      if (clearances) clearance2.push_back(list.clearance2[k]);
    }
    start[remap[i] + 1] = static_cast<std::int32_t>(second.size());
    x_at_build.push_back(list.x_at_build[i]);
  }
  list.start.swap(start);
  list.second.swap(second);
  list.history.swap(history);
  list.clearance2.swap(clearance2);  // kept particles keep their build positions
  list.x_at_build.swap(x_at_build);
  build_incoming(list, static_cast<std::size_t>(n));
}

std::vector<std::pair<std::int32_t, std::int32_t>> brute_force_pairs(const Particles& p,
                                                                     double cutoff_extra) {
  std::vector<std::pair<std::int32_t, std::int32_t>> out;
  for (std::size_t i = 0; i < p.size(); ++i) {
    for (std::size_t j = i + 1; j < p.size(); ++j) {
      if (p.body[i] >= 0 && p.body[i] == p.body[j]) continue;  // one clump's components
      const double cut = p.radius[i] + p.radius[j] + cutoff_extra;
      if ((p.x[i] - p.x[j]).squaredNorm() < cut * cut)
        out.emplace_back(static_cast<std::int32_t>(i), static_cast<std::int32_t>(j));
    }
  }
  return out;
}

}  // namespace reposetwin::sim
