// Piles poured through the store (loop_stages.hpp): every test on the grid at one setting of the
// effects as a surface of curves, and the seed noise pooled over the baseline's surface.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "experiments/io/format.hpp"
#include "experiments/loop/loop_stages.hpp"

namespace reposetwin::experiments::loop_detail {

namespace {

// The tests poured together (pour_groups, loop_sim.hpp), from the jams of every surface so far.
std::vector<std::vector<std::size_t>> pour_groups(const LoopContext& ctx, const PileStore& store) {
  std::vector<int> jams(ctx.tests().size(), 0);
  for (std::size_t i = 0; i < jams.size(); ++i)
    for (const auto& surf : store.surfaces)
      for (int c : surf->curve.at(i).clogged) jams[i] += c;
  return experiments::pour_groups(jams);
}

// Throws when a pour of a test some fit of mu_r uses, repeated max_pours times, formed no pile: a
// run that formed no pile (clogged) has no angle, and averaging its 0 into the curve would be
// silent garbage. The caller decides (the baseline stops, a refit trial steps back). A held-out
// test's jam is not an error but its prediction (no_pile_reason): the lab poured it, and a twin
// that jams there is a finding about the twin, which must not stop the calibration tests' fit.
void require_pile(const LoopContext& ctx, std::size_t i, std::size_t j, std::size_t r,
                  const SimOutcome& o) {
  if (o.pile || !ctx.roles.fits(i)) return;
  const LoopSettings& s = ctx.s();
  throw std::runtime_error("test " + ctx.tests()[i].id + " formed no pile at mu_r " +
                           std::to_string(ctx.grid[j]) + ", seed " + std::to_string(s.seeds[r]) +
                           ", in " + std::to_string(s.max_pours) + " pour(s) (last: seed " +
                           std::to_string(o.seed) + ", " + o.sim_dir +
                           (o.no_pile.empty() ? "" : "; its photographs: " + o.no_pile) +
                           "): the loop needs a pile at every grid point");
}

// Every test's piles at every grid point and seed (by test, grid point, seed), poured group by
// group (pour_groups); throws at the first group with a fitted test that formed no pile.
std::vector<SimOutcome> pour_surface(const LoopContext& ctx, PileStore& store,
                                     const std::vector<EffectSetting>& effects) {
  const LoopSettings& s = ctx.s();
  const std::size_t g = ctx.grid.size(), k = s.seeds.size();
  std::vector<SimOutcome> out(ctx.tests().size() * g * k);
  const std::vector<std::vector<std::size_t>> groups = pour_groups(ctx, store);
  if (groups.size() > 1) {
    std::string first;
    for (std::size_t i : groups[0]) first += (first.empty() ? "" : ", ") + ctx.tests()[i].id;
    ctx.say("pouring " + first +
            " first (pours jammed there before): a surface on which one forms no pile stops "
            "before the other tests are run");
  }
  for (const std::vector<std::size_t>& group : groups) {
    std::vector<SimRequest> req;
    for (std::size_t i : group)
      for (double m : ctx.grid)
        for (std::uint64_t seed : s.seeds)
          req.push_back(make_request(ctx.tests()[i], s.mu_key, m, seed, effects, s.image));
    const std::vector<SimOutcome> poured = pour(ctx, store, req);
    std::size_t q = 0;
    for (std::size_t i : group)
      for (std::size_t j = 0; j < g; ++j)
        for (std::size_t r = 0; r < k; ++r, ++q) {
          require_pile(ctx, i, j, r, poured[q]);
          out[(i * g + j) * k + r] = poured[q];
        }
  }
  return out;
}

// Where a test's pours (raw[grid][seed]) formed no pile, in words; empty when all formed one.
std::string no_pile_reason(const LoopContext& ctx, std::size_t i,
                           const std::vector<std::vector<SimOutcome>>& raw) {
  std::string where;
  for (std::size_t j = 0; j < raw.size(); ++j)
    for (std::size_t r = 0; r < raw[j].size(); ++r)
      if (!raw[j][r].pile)
        where += (where.empty() ? "" : ", ") + ("mu_r " + significant(ctx.grid[j], 3) + " seed " +
                                                std::to_string(ctx.s().seeds[r]));
  if (where.empty()) return "";
  return "no pile predicted: the twin's pours of test " + ctx.tests()[i].id + " (held out) " +
         "formed no pile in " + std::to_string(ctx.s().max_pours) + " pour(s) at " + where;
}

// Test i's curve from its piles `out` (grid point by seed, from `q` on), its raw outcomes into
// `raw` ([grid][seed]).
Curve curve_of(const LoopContext& ctx, std::size_t i, const std::vector<SimOutcome>& out,
               std::size_t& q, std::vector<std::vector<SimOutcome>>& raw) {
  const std::size_t g = ctx.grid.size(), k = ctx.s().seeds.size();
  Curve c;
  c.mu = ctx.grid;
  std::vector<Observation> obs;
  for (std::size_t j = 0; j < g; ++j) {
    PerChannel<std::vector<double>> at;  // per seed
    int clogged = 0;
    for (std::size_t r = 0; r < k; ++r, ++q) {
      const SimOutcome& o = out[q];
      clogged += o.clogged_pours;
      raw[j].push_back(o);
      if (!o.pile) {  // a held-out test's jam (require_pile): no value, and no curve below
        for (Channel ch : kAllChannels) at[ch].push_back(std::numeric_limits<double>::quiet_NaN());
        ++clogged;
        continue;
      }
      for (Channel ch : kAllChannels) at[ch].push_back(ctx.twin_value(o, ch));
      obs.push_back({ctx.grid[j], o.seed, std::clamp(at[Channel::kAngle].back(), 0.0, 90.0)});
    }
    for (Channel ch : kAllChannels) {
      c.mean[ch].push_back(sample_stats(at[ch]).mean);
      c.seeds[ch].push_back(at[ch]);
    }
    c.clogged.push_back(clogged);
  }
  c.no_pile = no_pile_reason(ctx, i, raw);
  if (c.no_pile.empty()) {
    c.fit = fit_monotone(obs);
  } else {
    ctx.say(c.no_pile);
  }
  return c;
}

// The seed spread of one pile's value of a channel, pooled over every test and grid point. A
// crest width some photograph did not record (cached by an older version) gives NaN, so its
// channel is left out rather than given a made-up noise.
double pooled_seed_sd(const Surface& base, Channel channel) {
  double ss = 0.0;
  int dof = 0;
  for (const Curve& c : base.curve) {
    if (!c.no_pile.empty()) continue;  // a held-out test the twin predicts no pile for
    for (const auto& a : c.seeds[channel]) {
      const double m = sample_stats(a).mean;
      if (channel == Channel::kCrest && !std::isfinite(m))
        return std::numeric_limits<double>::quiet_NaN();
      for (double x : a) ss += (x - m) * (x - m);
      dof += static_cast<int>(a.size()) - 1;
    }
  }
  const double sd = std::sqrt(ss / std::max(1, dof));
  return sd > 0.0 ? sd : 1e-3;
}

}  // namespace

// The cache's runs, a pour that formed no pile repeated with a new seed (settings.max_pours).
std::vector<SimOutcome> pour(const LoopContext& ctx, PileStore& store,
                             const std::vector<SimRequest>& requests) {
  return run_repouring(requests, ctx.s().max_pours,
                       [&store](const std::vector<SimRequest>& r) { return store.cache.run(r); });
}

Surface simulate_surface(const LoopContext& ctx, PileStore& store,
                         const std::vector<EffectSetting>& effects) {
  const std::size_t n = ctx.tests().size(), g = ctx.grid.size();
  const std::vector<SimOutcome> out = pour_surface(ctx, store, effects);
  Surface surf;
  surf.effects = effects;
  surf.curve.resize(n);
  surf.raw.assign(n, std::vector<std::vector<SimOutcome>>(g));
  std::size_t q = 0;
  for (std::size_t i = 0; i < n; ++i) surf.curve[i] = curve_of(ctx, i, out, q, surf.raw[i]);
  return surf;
}

// The seed noise every residual and prediction carries (loop.hpp's design note).
SeedNoise seed_noise(const LoopContext& ctx, const Surface& base) {
  const std::vector<LabTest>& tests = ctx.tests();
  SeedNoise n;
  n.crest_measured = std::any_of(tests.begin(), tests.end(),
                                 [](const LabTest& t) { return t.crest_mm.has_value(); });
  for (Channel c : kAllChannels)
    n.sd[c] = c != Channel::kCrest || n.crest_measured ? pooled_seed_sd(base, c) : 0.0;
  n.se = n.sd[Channel::kAngle] / std::sqrt(double(ctx.s().seeds.size()));
  const double k = static_cast<double>(ctx.s().seeds.size());
  auto sigma = [k](double sd, int repeats) { return std::sqrt(sd * sd / repeats + sd * sd / k); };
  for (Channel c : kAllChannels)
    for (const LabTest& t : tests) n.sigma[c].push_back(sigma(n.sd[c], t.repeats));
  return n;
}

}  // namespace reposetwin::experiments::loop_detail
