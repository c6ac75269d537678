// The baseline stages (loop.hpp's design note): every test simulated on the mu_r grid without
// effects, mu_r calibrated with its residuals, and the grid extended while mu_r sits on its bound.
#include <algorithm>
#include <cmath>

#include "experiments/io/format.hpp"
#include "experiments/loop/loop_stages.hpp"

namespace reposetwin::experiments::loop_detail {

namespace {

BaselineRecord calibrate_baseline(const LoopContext& ctx, const Surface& base) {
  BaselineRecord b;
  Model model;
  model.terms = {{1.0, &base}};
  b.fit = fit_mu(ctx, model, nullptr, ctx.s().t_max, ctx.roles.calibrate);
  b.seed_sd_deg = ctx.noise.sd[Channel::kAngle];
  b.seed_se_deg = ctx.noise.se;
  b.residuals = residuals(ctx, model, b.fit.mu);
  b.rmse = rmse_by_role(b.residuals);
  for (std::size_t i = 0; i < ctx.tests().size(); ++i) {
    const Curve& c = base.curve[i];
    BaselineCurve bc{ctx.tests()[i].id,        c.mu, c.mean[Channel::kAngle],
                     c.seeds[Channel::kAngle], {},   c.clogged};
    for (const auto& at : base.raw[i]) {
      bc.pour_seeds.emplace_back();
      for (const SimOutcome& o : at) bc.pour_seeds.back().push_back(o.seed);
    }
    b.curves.push_back(bc);
    int jammed = 0;
    for (int x : c.clogged) jammed += x;
    if (jammed > 0)
      ctx.say("test " + ctx.tests()[i].id + ": " + std::to_string(jammed) +
              " baseline pour(s) formed no pile and were repeated with new seeds");
  }
  ctx.say("baseline mu_r = " + std::to_string(b.fit.mu) + ", calibration RMSE " +
          std::to_string(b.rmse.calibrate_deg) + " deg, seed sd " +
          std::to_string(ctx.noise.sd[Channel::kAngle]) + " deg");
  return b;
}

// The baseline on ctx's grid from its simulated surface: the seed noise, then mu_r.
Baseline calibrated(LoopContext ctx, const Surface& surface) {
  ctx.noise = seed_noise(ctx, surface);
  BaselineRecord record = calibrate_baseline(ctx, surface);
  return {std::move(ctx), &surface, std::move(record)};
}

// mu_r on an end of its grid cannot take up what it should, and the tracing would hand the rest
// to the effects (an unbounded mu_r correction is no answer: beyond the grid a constant offset is
// not a mu_r change). So the grid grows beyond that end (next_grid_point); the baseline is
// simulated there (the other points come from the cache) and mu_r calibrated again. Returns
// what stopped the growth short of the bound, or empty.
std::string extend_grid(Baseline& b, PileStore& store, std::vector<double>& added) {
  while (b.record.fit.at_edge) {
    const std::vector<double>& grid = b.ctx.grid;
    const bool low = b.record.fit.mu <= grid.front() + 1e-12;
    const GridGrowth g = next_grid_point(grid, low, static_cast<int>(added.size()), b.ctx.s());
    if (!g.next) return g.stop;
    b.ctx.say("mu_r " + std::to_string(b.record.fit.mu) + " on the grid's " +
              (low ? "low" : "high") + " end: adding mu_r = " + std::to_string(*g.next));
    LoopContext wider = b.ctx;
    wider.grid.insert(low ? wider.grid.begin() : wider.grid.end(), *g.next);
    added.push_back(*g.next);
    const Surface& surface = store.keep(simulate_surface(wider, store, {}));
    b = calibrated(std::move(wider), surface);
  }
  return "";
}

// The grid's outcome in words: mu_r inside it, beyond the declared range, or on its bound.
std::string grid_statement(const Baseline& b, const GridRecord& g, const std::string& limit) {
  const LoopSettings& s = b.ctx.s();
  std::string added;
  for (double a : g.added) added += (added.empty() ? "" : ", ") + significant(a, 3);
  const std::string mu = significant(b.record.fit.mu, 3);
  if (!g.at_bound)
    return g.added.empty() ? "mu_r " + mu + " lies inside the grid"
                           : "mu_r " + mu + " lies inside the grid extended by " + added;
  if (g.beyond_prior)
    return "mu_r alone needs a value beyond its declared range " + significant(s.mu_prior.lo, 3) +
           "-" + significant(s.mu_prior.hi, 3) + " (" + s.mu_prior.reason +
           ") to fit the data: it sits at " + mu +
           (g.added.empty() ? std::string() : " after adding " + added) +
           ". That is evidence for an effect mu_r lacks, so the candidates are traced "
           "and refitted jointly with mu_r held inside that range";
  return "mu_r " + mu + " sits on the grid's bound" +
         (g.added.empty() ? std::string() : " after adding " + added) +
         (limit.empty() ? "" : " (" + limit + ")") +
         (s.at_bound == GridBound::kTrace
              ? "; traced with the mu_r correction held inside the grid (--at-bound "
                "trace): what mu_r cannot take up is left to the candidates"
              : "; nothing is traced: what mu_r cannot take up would be handed to the "
                "effects (a wider --mu-grid, more --grid-extensions, or --at-bound "
                "trace to trace anyway)");
}

}  // namespace

GridGrowth next_grid_point(const std::vector<double>& grid, bool low, int added,
                           const LoopSettings& s) {
  const MuPrior& prior = s.mu_prior;
  const double floor = prior.declared() ? prior.lo : 0.0;
  const double ceiling = prior.declared() ? std::min(prior.hi, s.mu_max) : s.mu_max;
  const double end = low ? grid.front() : grid.back();
  if (low ? end <= floor + 1e-12 : end >= ceiling - 1e-12) {
    const bool at_prior =
        prior.declared() && (low ? end <= prior.lo + 1e-12 : end >= prior.hi - 1e-12);
    return {std::nullopt, at_prior ? "the declared range's end"
                          : low    ? "mu_r cannot go below 0"
                                   : "mu_max " + significant(s.mu_max, 3) + " reached"};
  }
  const int allowed = s.at_bound == GridBound::kExtend ? s.grid_extensions : 0;
  if (added < allowed && grid.size() >= 2) {
    const double step = low ? grid[1] - grid[0] : grid.back() - grid[grid.size() - 2];
    return {low ? std::max(floor, end - step) : std::min(ceiling, end + step), ""};
  }
  if (prior.declared()) return {low ? floor : ceiling, ""};
  return {std::nullopt, ""};
}

Baseline baseline(const LoopContext& ctx, PileStore& store) {
  ctx.say("baseline: " + std::to_string(ctx.tests().size()) + " tests x " +
          std::to_string(ctx.grid.size()) + " mu_r x " + std::to_string(ctx.s().seeds.size()) +
          " seeds");
  return calibrated(ctx, store.keep(simulate_surface(ctx, store, {})));
}

GridRecord settle_grid(Baseline& b, PileStore& store) {
  const LoopSettings& s = b.ctx.s();
  GridRecord g;
  g.initial = b.ctx.grid;
  g.policy = grid_bound_name(s.at_bound);
  const std::string limit = extend_grid(b, store, g.added);
  const std::vector<double>& grid = b.ctx.grid;
  g.final_grid = grid;
  g.at_bound = b.record.fit.at_edge;
  if (const MuPrior& prior = s.mu_prior; prior.declared()) {
    g.prior = std::make_pair(prior.lo, prior.hi);
    g.prior_reason = prior.reason;
    const bool low = b.record.fit.mu <= grid.front() + 1e-12;
    g.beyond_prior =
        g.at_bound && (low ? grid.front() <= prior.lo + 1e-12 : grid.back() >= prior.hi - 1e-12);
  }
  g.statement = grid_statement(b, g, limit);
  return g;
}

std::optional<std::string> not_traced(const LoopContext& ctx, const GridRecord& grid) {
  if (!ctx.design.can_trace) return ctx.design.cannot.back();
  if (grid.at_bound && !grid.beyond_prior && ctx.s().at_bound != GridBound::kTrace)
    return grid.statement;
  return std::nullopt;
}

}  // namespace reposetwin::experiments::loop_detail
