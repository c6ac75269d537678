#include "experiments/loop/loop.hpp"

#include "experiments/campaign/case_runner.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <set>

#include "experiments/io/format.hpp"
#include "experiments/io/input_error.hpp"
#include "experiments/io/provenance.hpp"
#include "experiments/loop/loop_stages.hpp"

namespace reposetwin::experiments {
namespace fs = std::filesystem;
using nlohmann::json;

namespace loop_detail {

Loop::Loop(const LabData& data, const std::string& out, const LoopSettings& s)
    : data_(data),
      out_(out),
      s_(s),
      cache_(s.cache_dir.empty() ? (fs::path(out) / "cache").string() : s.cache_dir,
             {s.workers, s.progress}) {}

// The table of contents: each stage returns the records loop.json is made of.
json Loop::run() {
  check_settings();
  const auto t_start = std::chrono::steady_clock::now();
  LoopRecord rec;
  rec.tests = data_.tests;
  rec.rule = s_.rule;

  rec.design = design_;

  const Surface* base = &simulate_baseline();
  set_seed_noise(*base);
  rec.baseline = calibrate_baseline(*base);
  rec.grid = settle_grid(base, rec.baseline);

  LoopState state;
  state.model.terms = {{1.0, base}};
  state.fit = rec.baseline.fit;
  if (!design_.can_trace)
    rec.not_traced = design_.cannot.back();
  else if (rec.grid.at_bound && !rec.grid.beyond_prior && s_.at_bound != GridBound::kTrace)
    rec.not_traced = rec.grid.statement;
  if (rec.not_traced) {
    say("nothing traced: " + *rec.not_traced);
  } else {
    const std::size_t node = nearest_grid_point(rec.baseline.fit.mu);
    rec.fingerprints = fingerprint_candidates(*base, node, rec.unavailable);
    for (int it = 0; it < s_.max_effects + 1; ++it)
      if (!iterate(it, state, rec.fingerprints, node, rec.iterations)) break;
  }

  rec.final_model = final_record(state);
  rec.photo_pairs = photo_pairs(state);
  rec.provenance = provenance(*base);
  rec.simulations = {
      cache_.simulations_started(), cache_.photos_started(),
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count()};
  rec.summary = summarise(rec);
  return write(rec);
}

void Loop::say(const std::string& m) const {
  if (s_.progress) std::cerr << "[loop] " << m << std::endl;
}

std::vector<SimOutcome> Loop::pour(const std::vector<SimRequest>& req) {
  return run_repouring(req, s_.max_pours,
                       [this](const std::vector<SimRequest>& r) { return cache_.run(r); });
}

void Loop::check_settings() {
  if (s_.html && !s_.page)
    throw std::invalid_argument("loop: html is set but no page writer is given (LoopSettings::page)");
  const fs::path loop_json = fs::path(out_) / "loop.json";
  if (fs::exists(loop_json) && !s_.force)
    throw InputError(loop_json.string() +
                     " already holds a finished loop; use --force to recompute it (the "
                     "simulation cache is kept) or another output folder");
  if (s_.mu_grid.size() < 2 || !std::is_sorted(s_.mu_grid.begin(), s_.mu_grid.end()) ||
      std::adjacent_find(s_.mu_grid.begin(), s_.mu_grid.end()) != s_.mu_grid.end() ||
      s_.mu_grid.front() < 0.0)
    throw InputError("loop: mu_grid must hold at least two increasing values >= 0");
  if (s_.grid_extensions < 0 || !(s_.mu_max >= s_.mu_grid.back()))
    throw InputError("loop: grid_extensions must be >= 0 and mu_max (" +
                     std::to_string(s_.mu_max) + ") at least the grid's top");
  if (s_.mu_prior.declared()) {
    const MuPrior& pr = s_.mu_prior;
    if (!(pr.lo >= 0.0 && pr.hi > pr.lo && std::isfinite(pr.hi)))
      throw InputError("loop: --mu-range " + significant(pr.lo, 6) + "," + significant(pr.hi, 6) +
                       " must be two increasing values >= 0");
    if (s_.mu_grid.front() < pr.lo - 1e-12 || s_.mu_grid.back() > pr.hi + 1e-12)
      throw InputError("loop: --mu-grid " + significant(s_.mu_grid.front(), 6) + "-" +
                       significant(s_.mu_grid.back(), 6) + " leaves the declared --mu-range " +
                       significant(pr.lo, 6) + "-" + significant(pr.hi, 6) + " (" + pr.reason +
                       "): mu_r is never simulated outside its declared range");
  }
  if (s_.probe_scalings < 0) throw InputError("loop: probe_scalings must be >= 0");
  if (s_.seeds.size() < 2) throw InputError("loop: at least two seeds are needed (seed noise)");
  if (!s_.refit.empty()) check_declared_refit();
  for (const LabTest& t : data_.tests) check_mu_key(t, s_.mu_key);
  grid_ = s_.mu_grid;
  for (std::size_t i = 0; i < data_.tests.size(); ++i) {
    (data_.tests[i].role == Role::kCalibrate ? cal_ : val_).push_back(i);
    trace_.push_back(i);
  }
  if (cal_.empty())
    throw InputError(data_.file +
                     ": no test has role calibrate: mu_r is fitted on the calibration tests, "
                     "and at least one is needed");
  design_ = describe_design(static_cast<int>(cal_.size()), static_cast<int>(val_.size()));
  fit_ = design_.refit_on_all ? trace_ : cal_;
}

// A declared hypothesis (--refit) must be a candidate this run traces, with room to refit it.
void Loop::check_declared_refit() const {
  const CandidateEffect* found = nullptr;
  try {
    found = &find_effect(s_.refit);
  } catch (const std::invalid_argument& ex) {
    throw InputError("--refit: " + std::string(ex.what()));
  }
  if (!selected(*found))
    throw InputError("--refit " + s_.refit + ": not among the candidates traced (" +
                     (s_.candidates.empty() ? std::string("it is opt-in; name it in --candidates")
                                            : "--candidates names others") +
                     "); a declared hypothesis is fingerprinted like the others before its refit");
  if (s_.max_effects < 1)
    throw InputError("--refit " + s_.refit + " with --max-effects " +
                     std::to_string(s_.max_effects) +
                     ": a refit needs --max-effects of at least 1");
}

// The tests poured together (pour_groups, loop_sim.hpp), from the jams of every surface so far.
std::vector<std::vector<std::size_t>> Loop::pour_groups() const {
  std::vector<int> jams(data_.tests.size(), 0);
  for (std::size_t i = 0; i < jams.size(); ++i)
    for (const auto& surf : surfaces_)
      for (int c : surf->curve.at(i).clogged) jams[i] += c;
  return experiments::pour_groups(jams);
}

bool Loop::fitted(std::size_t i) const { return std::find(fit_.begin(), fit_.end(), i) != fit_.end(); }

// Throws when a pour of a test some fit of mu_r uses, repeated max_pours times, formed no pile: a
// run that formed no pile (clogged) has no angle, and averaging its 0 into the curve would be
// silent garbage. The caller decides (the baseline stops, a refit trial steps back). A held-out
// test's jam is not an error but its prediction (no_pile_reason): the lab poured it, and a twin
// that jams there is a finding about the twin, which must not stop the calibration tests' fit.
void Loop::require_pile(std::size_t i, std::size_t j, std::size_t r, const SimOutcome& o) const {
  if (o.pile || !fitted(i)) return;
  throw std::runtime_error("test " + data_.tests[i].id + " formed no pile at mu_r " +
                           std::to_string(grid_[j]) + ", seed " + std::to_string(s_.seeds[r]) +
                           ", in " + std::to_string(s_.max_pours) + " pour(s) (last: seed " +
                           std::to_string(o.seed) + ", " + o.sim_dir +
                           (o.no_pile.empty() ? "" : "; its photographs: " + o.no_pile) +
                           "): the loop needs a pile at every grid point");
}

// Every test's piles at every grid point and seed (by test, grid point, seed), poured group by
// group (pour_groups); throws at the first group with a fitted test that formed no pile.
std::vector<SimOutcome> Loop::pour_surface(const std::vector<EffectSetting>& effects) {
  const std::size_t g = grid_.size(), k = s_.seeds.size();
  std::vector<SimOutcome> out(data_.tests.size() * g * k);
  const std::vector<std::vector<std::size_t>> groups = pour_groups();
  if (groups.size() > 1) {
    std::string first;
    for (std::size_t i : groups[0]) first += (first.empty() ? "" : ", ") + data_.tests[i].id;
    say("pouring " + first +
        " first (pours jammed there before): a surface on which one forms no pile stops before "
        "the other tests are run");
  }
  for (const std::vector<std::size_t>& group : groups) {
    std::vector<SimRequest> req;
    for (std::size_t i : group)
      for (double m : grid_)
        for (std::uint64_t seed : s_.seeds)
          req.push_back(make_request(data_.tests[i], s_.mu_key, m, seed, effects, s_.image));
    const std::vector<SimOutcome> poured = pour(req);
    std::size_t q = 0;
    for (std::size_t i : group)
      for (std::size_t j = 0; j < g; ++j)
        for (std::size_t r = 0; r < k; ++r, ++q) {
          require_pile(i, j, r, poured[q]);
          out[(i * g + j) * k + r] = poured[q];
        }
  }
  return out;
}

// Where a test's pours (raw[grid][seed]) formed no pile, in words; empty when all formed one.
std::string Loop::no_pile_reason(std::size_t i,
                                 const std::vector<std::vector<SimOutcome>>& raw) const {
  std::string where;
  for (std::size_t j = 0; j < raw.size(); ++j)
    for (std::size_t r = 0; r < raw[j].size(); ++r)
      if (!raw[j][r].pile)
        where += (where.empty() ? "" : ", ") + ("mu_r " + significant(grid_[j], 3) + " seed " +
                                                std::to_string(s_.seeds[r]));
  if (where.empty()) return "";
  return "no pile predicted: the twin's pours of test " + data_.tests[i].id + " (held out) " +
         "formed no pile in " + std::to_string(s_.max_pours) + " pour(s) at " + where;
}

Surface Loop::simulate_surface(const std::vector<EffectSetting>& effects) {
  const std::size_t n = data_.tests.size(), g = grid_.size(), k = s_.seeds.size();
  const std::vector<SimOutcome> out = pour_surface(effects);
  Surface surf;
  surf.effects = effects;
  surf.curve.resize(n);
  surf.raw.assign(n, std::vector<std::vector<SimOutcome>>(g));
  std::size_t q = 0;
  for (std::size_t i = 0; i < n; ++i) {
    Curve& c = surf.curve[i];
    c.mu = grid_;
    std::vector<Observation> obs;
    for (std::size_t j = 0; j < g; ++j) {
      PerChannel<std::vector<double>> at;  // per seed
      int clogged = 0;
      for (std::size_t r = 0; r < k; ++r, ++q) {
        const SimOutcome& o = out[q];
        clogged += o.clogged_pours;
        surf.raw[i][j].push_back(o);
        if (!o.pile) {  // a held-out test's jam (require_pile): no value, and no curve below
          for (Channel ch : kAllChannels)
            at[ch].push_back(std::numeric_limits<double>::quiet_NaN());
          ++clogged;
          continue;
        }
        for (Channel ch : kAllChannels) at[ch].push_back(twin_value(o, ch));
        obs.push_back({grid_[j], o.seed, std::clamp(at[Channel::kAngle].back(), 0.0, 90.0)});
      }
      for (Channel ch : kAllChannels) {
        c.mean[ch].push_back(sample_stats(at[ch]).mean);
        c.seeds[ch].push_back(at[ch]);
      }
      c.clogged.push_back(clogged);
    }
    c.no_pile = no_pile_reason(i, surf.raw[i]);
    if (c.no_pile.empty()) {
      c.fit = fit_monotone(obs);
    } else {
      say(c.no_pile);
    }
  }
  return surf;
}

const Surface& Loop::simulate_baseline() {
  say("baseline: " + std::to_string(data_.tests.size()) + " tests x " +
      std::to_string(grid_.size()) + " mu_r x " + std::to_string(s_.seeds.size()) + " seeds");
  surfaces_.push_back(std::make_unique<Surface>(simulate_surface({})));
  return *surfaces_.back();
}

// One pile's value of a channel: the angle the loop compares (twin_angle), H, D or the crest
// width [deg or mm].
double Loop::twin_value(const SimOutcome& o, Channel channel) const {
  switch (channel) {
    case Channel::kAngle: return twin_angle(o, s_.angle);
    case Channel::kH: return o.height_mm;
    case Channel::kD: return o.diameter_mm;
    case Channel::kCrest: return o.crest_mm;
  }
  throw std::logic_error("loop: no channel " + std::to_string(static_cast<int>(channel)));
}

// The seed spread of one pile's value of a channel, pooled over every test and grid point. A
// crest width some photograph did not record (cached by an older version) gives NaN, so its
// channel is left out rather than given a made-up noise.
double Loop::pooled_seed_sd(const Surface& base, Channel channel) const {
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

// The seed noise every residual and prediction carries (loop.hpp's design note).
void Loop::set_seed_noise(const Surface& base) {
  crest_measured_ = std::any_of(data_.tests.begin(), data_.tests.end(),
                                [](const LabTest& t) { return t.crest_mm.has_value(); });
  for (Channel c : kAllChannels)
    noise_sd_[c] = c != Channel::kCrest || crest_measured_ ? pooled_seed_sd(base, c) : 0.0;
  seed_se_ = noise_sd_[Channel::kAngle] / std::sqrt(double(s_.seeds.size()));
  const double k = static_cast<double>(s_.seeds.size());
  auto sigma = [k](double sd, int repeats) { return std::sqrt(sd * sd / repeats + sd * sd / k); };
  for (Channel c : kAllChannels) {
    sigma_[c].clear();
    for (const LabTest& t : data_.tests) sigma_[c].push_back(sigma(noise_sd_[c], t.repeats));
  }
}

BaselineRecord Loop::calibrate_baseline(const Surface& base) const {
  BaselineRecord b;
  Model model;
  model.terms = {{1.0, &base}};
  b.fit = fit_mu(model, nullptr, s_.t_max, cal_);
  b.seed_sd_deg = noise_sd_[Channel::kAngle];
  b.seed_se_deg = seed_se_;
  b.residuals = residuals(model, b.fit.mu);
  b.rmse = rmse_by_role(b.residuals);
  for (std::size_t i = 0; i < data_.tests.size(); ++i) {
    const Curve& c = base.curve[i];
    BaselineCurve bc{data_.tests[i].id, c.mu, c.mean[Channel::kAngle], c.seeds[Channel::kAngle],
                     {}, c.clogged};
    for (const auto& at : base.raw[i]) {
      bc.pour_seeds.emplace_back();
      for (const SimOutcome& o : at) bc.pour_seeds.back().push_back(o.seed);
    }
    b.curves.push_back(bc);
    int jammed = 0;
    for (int x : c.clogged) jammed += x;
    if (jammed > 0)
      say("test " + data_.tests[i].id + ": " + std::to_string(jammed) +
          " baseline pour(s) formed no pile and were repeated with new seeds");
  }
  say("baseline mu_r = " + std::to_string(b.fit.mu) + ", calibration RMSE " +
      std::to_string(b.rmse.calibrate_deg) + " deg, seed sd " +
      std::to_string(noise_sd_[Channel::kAngle]) + " deg");
  return b;
}

// One iteration: trace, accept, refit by simulation, confirm. Returns whether the loop goes on.
bool Loop::iterate(int it, LoopState& state, const std::vector<FingerprintRecord>& fps,
                   std::size_t node, std::vector<IterationRecord>& iterations) {
  IterationRecord& iter = iterations.emplace_back(trace(it, state, fps));
  rank_candidates(iter.candidates);
  // The acceptance rule names contenders; the joint decision names one, or none when the data
  // cannot tell them apart or point at the measurement (loop_decision.hpp).
  if (iter.offset)  // else too few tests had a prediction to trace (trace's statement)
    iter.decision =
        decide_trace(iter.candidates, iter.joint, *iter.offset, *iter.mu_only, s_.rule);
  const RefitPick choice = pick_refit(iter.candidates, iter.decision, s_.refit, state.used);
  iter.declared = choice.declared;
  if (choice.declared) say("iteration " + std::to_string(it) + ": " + *choice.declared);
  const int best = choice.index;
  if (best < 0 || it == s_.max_effects) {
    if (best >= 0) {
      // A candidate is up for its refit, but the effect limit stops the loop before it
      // (--max-effects 0 traces and ranks only).
      iter.stopped = "max_effects (" + std::to_string(s_.max_effects) +
                     ") reached: " + iter.candidates[static_cast<std::size_t>(best)].name +
                     (choice.declared ? " was declared for refit" : " meets the acceptance rule") +
                     " but was not refitted";
      say("iteration " + std::to_string(it) + ": " + *iter.stopped);
    } else {
      say("iteration " + std::to_string(it) + ": " + iter.decision.statement);
    }
    return false;
  }
  const CandidateScore sc = iter.candidates[static_cast<std::size_t>(best)];
  const CandidateEffect& e = find_effect(sc.name);
  // A candidate admitted on the joint evidence alone (loop_decision.hpp) is refitted on it: its
  // strength is the joint fit's, and mu_r and the effect are fitted to every traced observable.
  // One that passed on the angle keeps the angle's strength and fit.
  double coef = sc.coef;
  std::vector<Channel> channels = {Channel::kAngle};
  if (!sc.accepted) {
    for (const JointScore& j : iter.joint)
      if (j.name == sc.name) coef = j.coef;
    for (const std::string& ch : iter.channels)
      if (const Channel c = channel_from_name(ch); c != Channel::kAngle) channels.push_back(c);
  }
  const double off = effect_off(e);
  const FingerprintRecord& fp =
      *std::find_if(fps.begin(), fps.end(), [&](const auto& f) { return f.name == e.name; });
  // c is in units of the probe the fingerprint was simulated at (scaled when the registry's
  // probe was lost in the seed noise).
  const double p1 = std::clamp(off + coef * (fp.probe - off), e.lo, e.hi);
  if (p1 == off) {
    // Only a declared hypothesis gets here (the rule's contenders lie in their range): its
    // traced strength points to the far side of its off value, where the effect cannot go.
    iter.stopped = e.name + ": its traced strength c = " + std::to_string(coef) +
                   " of its probe puts it at or beyond its off value " + std::to_string(off) +
                   " " + e.units + " (range " + std::to_string(e.lo) + " to " +
                   std::to_string(e.hi) + "); nothing to refit";
    say("iteration " + std::to_string(it) + ": " + *iter.stopped);
    return false;
  }
  say("iteration " + std::to_string(it) + ": " + e.name + " accepted (" +
      (sc.accepted ? sc.why : "on the joint fit") + "); linear estimate " + std::to_string(p1) +
      " " + e.units + ", simulating the grid");
  const Refit refit = refit_by_simulation(e, off, p1, coef, fp, grid_[node], state, channels);
  if (refit.trials.empty()) {
    iter.refit_failed = RefitFailed{e.name, refit.notes, p1};
    return false;
  }
  std::size_t pick = 0;
  for (std::size_t q = 1; q < refit.trials.size(); ++q)
    if (refit.trials[q].rmse < refit.trials[pick].rmse) pick = q;
  const Trial& best_trial = refit.trials[pick];
  const MuFit& joint = best_trial.joint;
  RefitSummary summary{e.name, p1, best_trial.p, joint.t, joint.mu, {}, refit.notes};
  for (const Trial& tr : refit.trials)
    summary.trials.push_back({tr.p, tr.fraction, tr.joint.t, tr.joint.mu, tr.rmse, tr.no_pile});
  const std::string reason = unconfirmed_reason(best_trial, state);
  if (!reason.empty()) {
    iter.not_confirmed = NotConfirmed{summary, best_trial.rmse, reason};
    say(e.name + ": not confirmed by the simulated refit (" + reason + "); not chosen");
    return false;
  }
  const double value = off + joint.t * (best_trial.p - off);
  ChosenEffect c;
  c.refit = summary;
  c.kind = e.kind == EffectKind::kPhysics ? "physics" : "measurement";
  c.key = e.key;
  c.units = e.units;
  c.off = off;
  c.probe = fp.probe;
  c.value = value;
  c.value_se = joint.t_se * std::abs(best_trial.p - off);
  c.t_at_limit = joint.t <= 0.0 || joint.t >= s_.t_max;
  c.mu_r_se = joint.mu_se;
  c.declared = choice.declared && iter.decision.named != e.name;
  if (joint.region) {
    c.region = joint.region;
    const double a = off + joint.region->t_lo * (best_trial.p - off);
    const double b = off + joint.region->t_hi * (best_trial.p - off);
    c.value_lo = std::min(a, b);
    c.value_hi = std::max(a, b);
    say(e.name + ": " + joint.region->statement + "; the value " + significant(c.value_lo, 3) +
        "-" + significant(c.value_hi, 3) + " " + e.units);
    // What would separate them: a repeat of each fitted test, as an independent observation
    // with that test's noise (the lab's repeat and the twin's seeds alike).
    std::vector<NextTest> repeats;
    for (const auto& [i, part] : joint.test_info)
      repeats.push_back({"a repeat of " + data_.tests[i].id, part});
    c.next_tests = rank_next_tests(joint.info, repeats);
    if (!c.next_tests.empty())
      say(e.name + ": " + c.next_tests.front().name + " would shrink its interval to " +
          significant(100.0 * c.next_tests.front().t_interval_ratio, 3) + "% (mu_r's to " +
          significant(100.0 * c.next_tests.front().mu_interval_ratio, 3) + "%)");
  }
  state.model = best_trial.model;
  state.fit = joint;
  state.effects.push_back({&e, value});
  state.used.insert(e.name);
  state.chosen.push_back(c);
  iter.chosen = c;
  return true;
}

FinalRecord Loop::final_record(const LoopState& state) const {
  FinalRecord f;
  f.fit = state.fit;
  f.effects = state.chosen;
  f.residuals = residuals(state.model, state.fit.mu);
  f.rmse = rmse_by_role(f.residuals);
  return f;
}

LoopProvenance Loop::provenance(const Surface& base) const {
  LoopProvenance p;
  p.code_version = code_version();
  p.data = data_.file;
  p.seeds = s_.seeds;
  p.angle_measure = angle_measure_name(s_.angle);
  p.angle_method = angle_measure_method(s_.angle);
  p.lab_angle_source = lab_angle_source(s_.angle);
  p.mu_grid = grid_;
  p.mu_key = s_.mu_key;
  p.image = to_json(photo_settings(s_.image)).dump();
  p.max_pours = s_.max_pours;
  p.cache = cache_.dir();
  p.finished = utc_now();
  if (!base.raw.empty() && !base.raw[0].empty() && !base.raw[0][0].empty())
    p.run = base.raw[0][0][0].provenance;
  std::set<std::string> scenes;
  for (const LabTest& t : data_.tests) scenes.insert(t.scene_path);
  p.scenes.assign(scenes.begin(), scenes.end());
  return p;
}

json Loop::write(const LoopRecord& rec) const {
  const json loop = to_json(rec);
  fs::create_directories(out_);
  if (s_.html) s_.page(loop, out_);
  write_json_atomic((fs::path(out_) / "loop.json").string(), loop);
  return loop;
}

}  // namespace loop_detail

LabData lab_angles(const LabData& data, AngleMeasure measure) {
  if (measure == AngleMeasure::kSlice)
    throw InputError(data.file +
                     ": the loop cannot compare the 'slice' angle (a protractor on "
                     "particle slices has no counterpart in a lab's photos or sheet); use image, "
                     "image_flank or particles");
  LabData out = data;
  for (LabTest& t : out.tests) {
    if (t.photos.empty()) continue;  // a typed angle (or H and D) is used as given
    if (measure == AngleMeasure::kImageFlank) {
      const json& f =
          t.photo_measurement.contains("flank_deg") ? t.photo_measurement["flank_deg"] : json();
      if (!f.is_object() || !f.contains("mean") || !f["mean"].is_number())
        throw InputError(data.file + " line " + std::to_string(t.line) + " (test " + t.id +
                         "), column photo: the photos' measurement has no flank angle");
      t.angle_deg = f["mean"].get<double>();
    }
    t.photo_measurement["compared_angle"] = {{"measure", angle_measure_name(measure)},
                                             {"angle_deg", t.angle_deg}};
  }
  return out;
}

std::string lab_angle_source(AngleMeasure measure) {
  if (measure == AngleMeasure::kImageFlank)
    return "tests with photos: the flank angle vision measured on them; tests with a typed "
           "angle (or H and D): that value, taken as the flank angle (the lab pile assumed a "
           "full cone)";
  return "tests with photos: atan(2H/D) vision measured on them; others: the typed angle (or "
         "atan(2H/D) of the typed H and D)";
}

double twin_angle(const SimOutcome& o, AngleMeasure measure) {
  if (measure == AngleMeasure::kSlice)
    throw std::runtime_error("the loop compares image, image_flank or particles angles, not slice");
  if (!o.pile) return 0.0;  // a pour without a measured pile has no angle to compare
  if (measure == AngleMeasure::kImageFlank && !std::isfinite(o.flank_deg))
    throw std::runtime_error(o.image_dir +
                             ": this photograph's measurement has no flank angle (made by an "
                             "older version); use a fresh --cache");
  // The campaign's selector (case_runner.hpp), on the loop's record in metres.
  PileMeasure pile;
  pile.theta_hd_deg = o.positions_angle_deg;
  const PhotoMeasure photo{o.angle_deg,          0.0,         1e-3 * o.height_mm,
                           1e-3 * o.diameter_mm, o.flank_deg, 1e-3 * o.crest_mm};
  return select_angle_deg(pile, photo, measure, o.image_dir);
}

std::string grid_bound_name(GridBound g) {
  switch (g) {
    case GridBound::kExtend:
      return "extend";
    case GridBound::kRefuse:
      return "refuse";
    case GridBound::kTrace:
      return "trace";
  }
  return "extend";
}

GridBound parse_grid_bound(const std::string& text, const std::string& option) {
  for (GridBound g : {GridBound::kExtend, GridBound::kRefuse, GridBound::kTrace})
    if (grid_bound_name(g) == text) return g;
  throw InputError(option + ": \"" + text + "\" is not one of extend, refuse, trace");
}

json run_loop(const LabData& data, const std::string& out_dir, const LoopSettings& settings) {
  const LabData compared = lab_angles(data, settings.angle);
  loop_detail::Loop loop(compared, out_dir, settings);
  return loop.run();
}

}  // namespace reposetwin::experiments
