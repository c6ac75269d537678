// The loop's context (loop_stages.hpp): the settings checked before anything runs, the tests by
// role, the small reads every stage shares, and how the loop was made.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <set>
#include <stdexcept>

#include "experiments/io/format.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/loop/loop_stages.hpp"

namespace reposetwin::experiments::loop_detail {
namespace fs = std::filesystem;

namespace {

// The grid, the prior and the counts, each against its rule.
void check_numbers(const LoopSettings& s) {
  if (s.mu_grid.size() < 2 || !std::is_sorted(s.mu_grid.begin(), s.mu_grid.end()) ||
      std::adjacent_find(s.mu_grid.begin(), s.mu_grid.end()) != s.mu_grid.end() ||
      s.mu_grid.front() < 0.0)
    throw InputError("loop: mu_grid must hold at least two increasing values >= 0");
  if (s.grid_extensions < 0 || !(s.mu_max >= s.mu_grid.back()))
    throw InputError("loop: grid_extensions must be >= 0 and mu_max (" + std::to_string(s.mu_max) +
                     ") at least the grid's top");
  if (s.mu_prior.declared()) {
    const MuPrior& pr = s.mu_prior;
    if (!(pr.lo >= 0.0 && pr.hi > pr.lo && std::isfinite(pr.hi)))
      throw InputError("loop: --mu-range " + significant(pr.lo, 6) + "," + significant(pr.hi, 6) +
                       " must be two increasing values >= 0");
    if (s.mu_grid.front() < pr.lo - 1e-12 || s.mu_grid.back() > pr.hi + 1e-12)
      throw InputError("loop: --mu-grid " + significant(s.mu_grid.front(), 6) + "-" +
                       significant(s.mu_grid.back(), 6) + " leaves the declared --mu-range " +
                       significant(pr.lo, 6) + "-" + significant(pr.hi, 6) + " (" + pr.reason +
                       "): mu_r is never simulated outside its declared range");
  }
  if (s.probe_scalings < 0) throw InputError("loop: probe_scalings must be >= 0");
  if (s.seeds.size() < 2) throw InputError("loop: at least two seeds are needed (seed noise)");
}

// A declared hypothesis (--refit) must be a candidate this run traces, with room to refit it.
void check_declared_refit(const LoopContext& ctx) {
  const LoopSettings& s = ctx.s();
  const CandidateEffect* found = nullptr;
  try {
    found = &find_effect(s.refit);
  } catch (const std::invalid_argument& ex) {
    throw InputError("--refit: " + std::string(ex.what()));
  }
  if (!ctx.selected(*found))
    throw InputError("--refit " + s.refit + ": not among the candidates traced (" +
                     (s.candidates.empty() ? std::string("it is opt-in; name it in --candidates")
                                           : "--candidates names others") +
                     "); a declared hypothesis is fingerprinted like the others before its refit");
  if (s.max_effects < 1)
    throw InputError("--refit " + s.refit + " with --max-effects " + std::to_string(s.max_effects) +
                     ": a refit needs --max-effects of at least 1");
}

// The tests by role; throws when no test calibrates.
Roles roles_of(const LabData& data) {
  Roles r;
  for (std::size_t i = 0; i < data.tests.size(); ++i) {
    (data.tests[i].role == Role::kCalibrate ? r.calibrate : r.validate).push_back(i);
    r.traced.push_back(i);
  }
  if (r.calibrate.empty())
    throw InputError(data.file +
                     ": no test has role calibrate: mu_r is fitted on the calibration tests, "
                     "and at least one is needed");
  return r;
}

}  // namespace

LoopContext check_settings(const LabData& data, const std::string& out,
                           const LoopSettings& settings) {
  const LoopSettings& s = settings;
  if (s.html && !s.page)
    throw std::invalid_argument(
        "loop: html is set but no page writer is given (LoopSettings::page)");
  const fs::path loop_json = fs::path(out) / "loop.json";
  if (fs::exists(loop_json) && !s.force)
    throw InputError(loop_json.string() +
                     " already holds a finished loop; use --force to recompute it (the "
                     "simulation cache is kept) or another output folder");
  check_numbers(s);
  LoopContext ctx;
  ctx.data = &data;
  ctx.settings = &settings;
  ctx.out = out;
  if (!s.refit.empty()) check_declared_refit(ctx);
  for (const LabTest& t : data.tests) check_mu_key(t, s.mu_key);
  ctx.grid = s.mu_grid;
  ctx.roles = roles_of(data);
  ctx.design = describe_design(static_cast<int>(ctx.roles.calibrate.size()),
                               static_cast<int>(ctx.roles.validate.size()));
  ctx.roles.fitted = ctx.design.refit_on_all ? ctx.roles.traced : ctx.roles.calibrate;
  return ctx;
}

bool Roles::fits(std::size_t i) const {
  return std::find(fitted.begin(), fitted.end(), i) != fitted.end();
}

bool LoopContext::selected(const CandidateEffect& e) const {
  if (s().candidates.empty()) return !e.opt_in;
  return std::find(s().candidates.begin(), s().candidates.end(), e.name) != s().candidates.end();
}

void LoopContext::say(const std::string& m) const {
  if (s().progress) std::cerr << "[loop] " << m << std::endl;
}

double LoopContext::observed(std::size_t i, Channel channel) const {
  const LabTest& t = tests()[i];
  switch (channel) {
    case Channel::kAngle:
      return t.angle_deg;
    case Channel::kH:
      return t.height_mm.value_or(0.0);
    case Channel::kD:
      return t.diameter_mm.value_or(0.0);
    case Channel::kCrest:
      return t.crest_mm.value_or(0.0);
  }
  throw std::logic_error("loop: no channel " + std::to_string(static_cast<int>(channel)));
}

double LoopContext::effect_off(const CandidateEffect& e) const {
  return e.off_from_scene ? scene_value(tests().front(), e.key) : e.off;
}

double LoopContext::twin_value(const SimOutcome& o, Channel channel) const {
  switch (channel) {
    case Channel::kAngle:
      return twin_angle(o, s().angle);
    case Channel::kH:
      return o.height_mm;
    case Channel::kD:
      return o.diameter_mm;
    case Channel::kCrest:
      return o.crest_mm;
  }
  throw std::logic_error("loop: no channel " + std::to_string(static_cast<int>(channel)));
}

std::size_t LoopContext::nearest_grid_point(double mu) const {
  std::size_t node = 0;
  for (std::size_t j = 1; j < grid.size(); ++j)
    if (std::abs(grid[j] - mu) < std::abs(grid[node] - mu)) node = j;
  return node;
}

const Surface& PileStore::keep(Surface surface) {
  surfaces.push_back(std::make_unique<Surface>(std::move(surface)));
  return *surfaces.back();
}

LoopProvenance provenance(const LoopContext& ctx, const PileStore& store, const Surface& base) {
  const LoopSettings& s = ctx.s();
  LoopProvenance p;
  p.code_version = code_version();
  p.data = ctx.data->file;
  p.seeds = s.seeds;
  p.angle_measure = angle_measure_name(s.angle);
  p.angle_method = angle_measure_method(s.angle);
  p.lab_angle_source = lab_angle_source(s.angle);
  p.mu_grid = ctx.grid;
  p.mu_key = s.mu_key;
  p.image = to_json(photo_settings(s.image)).dump();
  p.max_pours = s.max_pours;
  p.refit_follow_ups = s.refit_follow_ups;
  p.cache = store.cache.dir();
  p.finished = utc_now();
  if (!base.raw.empty() && !base.raw[0].empty() && !base.raw[0][0].empty())
    p.run = base.raw[0][0][0].provenance;
  std::set<std::string> scenes;
  for (const LabTest& t : ctx.tests()) scenes.insert(t.scene_path);
  p.scenes.assign(scenes.begin(), scenes.end());
  return p;
}

}  // namespace reposetwin::experiments::loop_detail
