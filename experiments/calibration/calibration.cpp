#include "experiments/calibration/calibration.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>

#include "experiments/io/format.hpp"
#include "sim/random.hpp"

namespace reposetwin::experiments {
namespace {

constexpr double kLowQuantile = 0.025;   // lower end of the reported 95% interval
constexpr double kHighQuantile = 0.975;  // upper end of the reported 95% interval

std::string num(double v) { return significant(v, 10); }

// The bootstrap's random stream is the project's one (sim/random.hpp: portable, 53-bit uniforms
// in [0, 1), Box-Muller normals); the chi-square draw is a sum of squared normals.
using Rng = sim::Rng;

double chi_square(Rng& rng, int dof) {
  double s = 0.0;
  for (int i = 0; i < dof; ++i) {
    const double z = rng.normal();
    s += z * z;
  }
  return s;
}

// Weighted pool-adjacent-violators: the non-decreasing sequence closest to y in weighted least
// squares (Barlow et al. 1972).
std::vector<double> pool_adjacent_violators(const std::vector<double>& y,
                                            const std::vector<double>& w) {
  struct Block {
    double sum_w, sum_wy;
    std::size_t count;
    double mean() const { return sum_wy / sum_w; }
  };
  std::vector<Block> blocks;
  for (std::size_t i = 0; i < y.size(); ++i) {
    blocks.push_back({w[i], w[i] * y[i], 1});
    while (blocks.size() > 1 && blocks[blocks.size() - 2].mean() > blocks.back().mean()) {
      Block b = blocks.back();
      blocks.pop_back();
      blocks.back().sum_w += b.sum_w;
      blocks.back().sum_wy += b.sum_wy;
      blocks.back().count += b.count;
    }
  }
  std::vector<double> out;
  out.reserve(y.size());
  for (const auto& b : blocks) out.insert(out.end(), b.count, b.mean());
  return out;
}

// Piecewise-linear evaluation on sorted knots x with values f; x must lie in [x.front(), x.back()].
double interpolate(const std::vector<double>& x, const std::vector<double>& f, double at) {
  if (x.size() == 1) return f[0];
  auto it = std::upper_bound(x.begin(), x.end(), at);
  std::size_t k = (it == x.end()) ? x.size() - 2 : static_cast<std::size_t>(it - x.begin()) - 1;
  if (k + 1 >= x.size()) k = x.size() - 2;
  const double t = (at - x[k]) / (x[k + 1] - x[k]);
  return f[k] + t * (f[k + 1] - f[k]);
}

// Generalised inverse of a non-decreasing piecewise-linear curve: the middle of {x : f(x) = t}.
std::optional<double> inverse(const std::vector<double>& x, const std::vector<double>& f,
                              double t) {
  const std::size_t n = x.size();
  if (t < f.front() || t > f.back()) return std::nullopt;
  double a = x.front();
  if (f.front() < t) {
    for (std::size_t k = 0; k + 1 < n; ++k) {
      if (f[k + 1] >= t) {
        a = x[k] + (t - f[k]) / (f[k + 1] - f[k]) * (x[k + 1] - x[k]);
        break;
      }
    }
  }
  double b = x.back();
  if (f.back() > t) {
    for (std::size_t k = n - 1; k > 0; --k) {
      if (f[k - 1] <= t) {
        b = x[k - 1] + (t - f[k - 1]) / (f[k] - f[k - 1]) * (x[k] - x[k - 1]);
        break;
      }
    }
  }
  return 0.5 * (a + b);
}

double quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const std::size_t i = static_cast<std::size_t>(pos);
  if (i + 1 >= v.size()) return v.back();
  return v[i] + (pos - static_cast<double>(i)) * (v[i + 1] - v[i]);
}

std::vector<double> knots(const MonotoneFit& fit) {
  std::vector<double> x;
  for (const auto& p : fit.points) x.push_back(p.mu_r);
  return x;
}
std::vector<double> fitted(const MonotoneFit& fit) {
  std::vector<double> f;
  for (const auto& p : fit.points) f.push_back(p.fitted_deg);
  return f;
}

// One bootstrap replicate of the fitted values (see the design note in the header).
std::vector<double> replicate_fit(const MonotoneFit& fit, Rng& rng) {
  double var = 0.0;
  if (fit.noise_dof > 0)
    var = fit.noise_dof * fit.noise_sd_deg * fit.noise_sd_deg /
          std::max(chi_square(rng, fit.noise_dof), 1e-12);
  std::vector<double> y, w;
  for (const auto& p : fit.points) {
    y.push_back(p.mean_deg + std::sqrt(var / p.n) * rng.normal());
    w.push_back(p.n);
  }
  return pool_adjacent_violators(y, w);
}

void check_bootstrap(const BootstrapSettings& b) {
  if (b.replicates < 100)
    throw std::invalid_argument(
        "calibration: bootstrap.replicates = " + std::to_string(b.replicates) + " is below 100");
}

}  // namespace

std::string to_string(CalibrationStatus status) {
  switch (status) {
    case CalibrationStatus::kCalibrated:
      return "calibrated";
    case CalibrationStatus::kBudgetSpent:
      return "budget_spent";
    case CalibrationStatus::kSeedNoiseLimited:
      return "seed_noise_limited";
    case CalibrationStatus::kCannotReachLow:
      return "cannot_reach_low";
    case CalibrationStatus::kCannotReachHigh:
      return "cannot_reach_high";
  }
  return "unknown";
}

void validate_observations(const std::vector<Observation>& observations) {
  if (observations.empty())
    throw std::invalid_argument("calibration: no observations (the data set is empty)");
  for (std::size_t i = 0; i < observations.size(); ++i) {
    const auto& o = observations[i];
    const std::string at = "calibration: observation " + std::to_string(i) + " (seed " +
                           std::to_string(o.seed) + "): ";
    if (!std::isfinite(o.mu_r) || o.mu_r < 0.0)
      throw std::invalid_argument(at + "mu_r = " + num(o.mu_r) + " is not a finite value >= 0");
    if (!std::isfinite(o.angle_deg) || o.angle_deg < 0.0 || o.angle_deg > 90.0)
      throw std::invalid_argument(at + "angle_deg = " + num(o.angle_deg) +
                                  " is outside [0, 90] degrees");
  }
}

MonotoneFit fit_monotone(const std::vector<Observation>& observations) {
  validate_observations(observations);
  std::vector<Observation> sorted = observations;
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const Observation& a, const Observation& b) { return a.mu_r < b.mu_r; });
  MonotoneFit fit;
  double ss_within = 0.0;
  for (std::size_t i = 0; i < sorted.size();) {
    std::size_t j = i;
    double sum = 0.0;
    while (j < sorted.size() && sorted[j].mu_r == sorted[i].mu_r) sum += sorted[j++].angle_deg;
    FitPoint p;
    p.mu_r = sorted[i].mu_r;
    p.n = static_cast<int>(j - i);
    p.mean_deg = sum / p.n;
    double ss = 0.0;
    for (std::size_t k = i; k < j; ++k)
      ss += (sorted[k].angle_deg - p.mean_deg) * (sorted[k].angle_deg - p.mean_deg);
    p.sd_deg = p.n > 1 ? std::sqrt(ss / (p.n - 1)) : 0.0;
    ss_within += ss;
    fit.noise_dof += p.n - 1;
    fit.points.push_back(p);
    i = j;
  }
  fit.noise_sd_deg = fit.noise_dof > 0 ? std::sqrt(ss_within / fit.noise_dof) : 0.0;
  std::vector<double> y, w;
  for (const auto& p : fit.points) {
    y.push_back(p.mean_deg);
    w.push_back(p.n);
  }
  const auto f = pool_adjacent_violators(y, w);
  for (std::size_t i = 0; i < f.size(); ++i) fit.points[i].fitted_deg = f[i];
  return fit;
}

double evaluate(const MonotoneFit& fit, double mu_r) {
  if (fit.points.empty()) throw std::invalid_argument("calibration: evaluate on an empty fit");
  const double lo = fit.points.front().mu_r, hi = fit.points.back().mu_r;
  if (!(mu_r >= lo && mu_r <= hi))
    throw std::invalid_argument("calibration: mu_r = " + num(mu_r) +
                                " is outside the fitted span [" + num(lo) + ", " + num(hi) +
                                "]; a monotone fit is not extrapolated");
  return interpolate(knots(fit), fitted(fit), mu_r);
}

std::optional<double> invert(const MonotoneFit& fit, double angle_deg) {
  if (fit.points.empty()) throw std::invalid_argument("calibration: invert on an empty fit");
  return inverse(knots(fit), fitted(fit), angle_deg);
}

CalibrationResult calibrate_observations(const std::vector<Observation>& observations,
                                         const Target& target, const BootstrapSettings& bootstrap) {
  validate_target(target);
  check_bootstrap(bootstrap);
  CalibrationResult r;
  r.target = target;
  r.fit = fit_monotone(observations);
  r.observations = observations;
  r.simulations = static_cast<int>(observations.size());
  const auto x = knots(r.fit);
  const auto f = fitted(r.fit);
  r.reachable_low_deg = f.front();
  r.reachable_high_deg = f.back();
  const auto mu = inverse(x, f, target.angle_deg);
  if (!mu) {
    const bool low = target.angle_deg < f.front();
    r.status = low ? CalibrationStatus::kCannotReachLow : CalibrationStatus::kCannotReachHigh;
    r.message = "cannot reach: the target angle " + num(target.angle_deg) + " deg lies " +
                (low ? "below" : "above") + " the angles the mu_r range [" + num(x.front()) + ", " +
                num(x.back()) + "] reaches (" + num(f.front()) + " to " + num(f.back()) + " deg)";
    return r;
  }
  r.mu_r = *mu;
  r.fitted_angle_deg = interpolate(x, f, *mu);

  Rng rng(bootstrap.rng_seed);
  std::vector<double> mus, angles;
  int below = 0, above = 0;
  for (int b = 0; b < bootstrap.replicates; ++b) {
    const auto fb = replicate_fit(r.fit, rng);
    const double tb = target.angle_deg + target.sd_deg * rng.normal();
    angles.push_back(interpolate(x, fb, *mu));
    if (auto m = inverse(x, fb, tb)) {
      mus.push_back(*m);
    } else if (tb < fb.front()) {
      mus.push_back(x.front());
      ++below;
    } else {
      mus.push_back(x.back());
      ++above;
    }
  }
  r.mu_r_low = quantile(mus, kLowQuantile);
  r.mu_r_high = quantile(mus, kHighQuantile);
  r.interval_open_low = below > kLowQuantile * bootstrap.replicates;
  r.interval_open_high = above > (1.0 - kHighQuantile) * bootstrap.replicates;
  r.fitted_angle_halfwidth_deg =
      0.5 * (quantile(angles, kHighQuantile) - quantile(angles, kLowQuantile));
  r.mu_r_replicates = std::move(mus);
  r.status = CalibrationStatus::kCalibrated;
  r.message = "calibrated mu_r = " + num(*mu) + " (95% interval " + num(r.mu_r_low) + " to " +
              num(r.mu_r_high) + ")";
  if (r.fit.noise_dof == 0)
    r.message += "; no point has two seeds, so run-to-run noise is not in the interval";
  if (r.interval_open_low || r.interval_open_high)
    r.message += "; the interval reaches an end of the evaluated mu_r range and may extend beyond";
  return r;
}

namespace {

void check_driver_settings(const CalibrationSettings& s, int reserve) {
  if (!std::isfinite(s.mu_r_lo) || !std::isfinite(s.mu_r_hi) || s.mu_r_lo < 0.0 ||
      s.mu_r_hi <= s.mu_r_lo)
    throw std::invalid_argument("calibration: mu_r range [" + num(s.mu_r_lo) + ", " +
                                num(s.mu_r_hi) + "] is invalid (need 0 <= lo < hi)");
  if (s.seeds_per_point < 1)
    throw std::invalid_argument(
        "calibration: seeds_per_point = " + std::to_string(s.seeds_per_point) + " must be >= 1");
  if (!std::isfinite(s.tolerance_deg) || s.tolerance_deg <= 0.0)
    throw std::invalid_argument("calibration: tolerance_deg = " + num(s.tolerance_deg) +
                                " must be > 0");
  if (s.max_simulations < 2 * s.seeds_per_point + reserve)
    throw std::invalid_argument(
        "calibration: max_simulations = " + std::to_string(s.max_simulations) + " is below the " +
        std::to_string(2 * s.seeds_per_point + reserve) + " needed for the range ends" +
        (s.confirm_bracket ? " and the confirmation" : ""));
}

// The driver's observations and the callback that adds to them: each call runs seeds_per_point
// seeds at every mu_r asked for, continuing the seeds a point already has.
class ObservationLog {
 public:
  ObservationLog(const SimulateBatchFn& simulate, const CalibrationSettings& s)
      : simulate_(simulate), s_(s) {}

  void run(const std::vector<double>& mus) {
    std::vector<std::pair<double, std::uint64_t>> batch;
    for (double mu : mus) {
      const auto done = static_cast<std::uint64_t>(std::count_if(
          obs.begin(), obs.end(), [&](const Observation& o) { return o.mu_r == mu; }));
      for (int j = 0; j < s_.seeds_per_point; ++j)
        batch.emplace_back(mu, s_.first_seed + done + j);
    }
    const auto angles = simulate_(batch);
    if (angles.size() != batch.size())
      throw std::runtime_error("calibration: simulate returned " + std::to_string(angles.size()) +
                               " angles for " + std::to_string(batch.size()) + " runs");
    for (std::size_t i = 0; i < batch.size(); ++i) {
      if (!std::isfinite(angles[i]) || angles[i] < 0.0 || angles[i] > 90.0)
        throw std::runtime_error("calibration: simulation at mu_r = " + num(batch[i].first) +
                                 ", seed " + std::to_string(batch[i].second) + " returned angle " +
                                 num(angles[i]) + " outside [0, 90] deg");
      obs.push_back({batch[i].first, batch[i].second, angles[i]});
    }
  }

  std::vector<Observation> obs;

 private:
  const SimulateBatchFn& simulate_;
  const CalibrationSettings& s_;
};

// The fitted points around the calibrated mu_r: pts[ia].mu_r <= mu <= pts[ib].mu_r.
struct Bracket {
  std::size_t ia = 0, ib = 0;
  double span_deg = 0.0;  // fitted angle change across the bracket [deg]
};

Bracket bracket_of(const MonotoneFit& fit, double mu) {
  const auto& pts = fit.points;
  std::size_t ib = 0;
  while (ib < pts.size() && pts[ib].mu_r < mu) ++ib;
  const std::size_t ia = (ib < pts.size() && pts[ib].mu_r == mu) ? ib : ib - 1;
  return {ia, ib, pts[ib].fitted_deg - pts[ia].fitted_deg};
}

// Confirmation: the search stopped because the bracket points' data looked good enough, so
// those data are biased towards optimism. Fresh seeds at the bracket points replace them in the
// final fit (on synthetic tests this restores the 95% interval's coverage).
CalibrationResult confirm_bracket(ObservationLog& log, const MonotoneFit& fit, const Bracket& b,
                                  const Target& target, const CalibrationSettings& s,
                                  CalibrationStatus status, const std::string& budget_note) {
  const auto& pts = fit.points;
  std::vector<double> bracket = {pts[b.ia].mu_r};
  if (pts[b.ib].mu_r != pts[b.ia].mu_r) bracket.push_back(pts[b.ib].mu_r);
  const std::size_t searched = log.obs.size();
  log.run(bracket);
  if (bracket.size() == 1) log.run(bracket);  // the same number of fresh runs either way
  std::vector<Observation> kept, excluded;
  for (std::size_t i = 0; i < log.obs.size(); ++i) {
    const bool at_bracket =
        std::find(bracket.begin(), bracket.end(), log.obs[i].mu_r) != bracket.end();
    (at_bracket && i < searched ? excluded : kept).push_back(log.obs[i]);
  }
  CalibrationResult fin = calibrate_observations(kept, target, s.bootstrap);
  fin.simulations = static_cast<int>(log.obs.size());
  fin.excluded = std::move(excluded);
  if (fin.mu_r) {
    fin.status = status;
    fin.message += budget_note + "; confirmed with fresh seeds at the bracket points";
  }
  return fin;
}

// The next mu_r to run. Splitting the bracket only helps while its expected angle span
// (wide-baseline slope of the fit, from one point beyond each side, times its width) exceeds
// the noise of a point mean; below that, new points crowd together and their noisy means make
// the interpolant steep, so more seeds go to the nearest bracket point instead.
double next_mu_r(const CalibrationResult& r, const Bracket& b, const CalibrationSettings& s) {
  const auto& pts = r.fit.points;
  const double mu = *r.mu_r;
  const std::size_t wa = b.ia > 0 ? b.ia - 1 : b.ia, wb = b.ib + 1 < pts.size() ? b.ib + 1 : b.ib;
  const double wide_slope =
      pts[wb].mu_r > pts[wa].mu_r
          ? (pts[wb].fitted_deg - pts[wa].fitted_deg) / (pts[wb].mu_r - pts[wa].mu_r)
          : 0.0;
  const double point_se = r.fit.noise_sd_deg / std::sqrt(static_cast<double>(s.seeds_per_point));
  const bool resolvable = wide_slope * (pts[b.ib].mu_r - pts[b.ia].mu_r) > 2.0 * point_se;
  if (b.span_deg > 2.0 * s.tolerance_deg && resolvable) {
    const double lo = pts[b.ia].mu_r, hi = pts[b.ib].mu_r, w = hi - lo;
    return std::clamp(mu, lo + 0.25 * w, hi - 0.25 * w);
  }
  return (mu - pts[b.ia].mu_r <= pts[b.ib].mu_r - mu) ? pts[b.ia].mu_r : pts[b.ib].mu_r;
}

}  // namespace

CalibrationResult calibrate_batch(const SimulateBatchFn& simulate, const Target& target,
                                  const CalibrationSettings& s) {
  validate_target(target);
  check_bootstrap(s.bootstrap);
  const int reserve = s.confirm_bracket ? 2 * s.seeds_per_point : 0;  // for the confirmation
  check_driver_settings(s, reserve);
  if (!simulate) throw std::invalid_argument("calibration: no simulate callback");
  const int k = s.seeds_per_point;
  ObservationLog log(simulate, s);
  auto budget_left = [&] { return s.max_simulations - reserve - static_cast<int>(log.obs.size()); };

  log.run({s.mu_r_lo, s.mu_r_hi});
  for (;;) {
    CalibrationResult r = calibrate_observations(log.obs, target, s.bootstrap);
    const auto& pts = r.fit.points;
    if (!r.mu_r) {
      // Outside the reachable range: only worth more seeds if the noise could explain the gap.
      const FitPoint& end =
          (r.status == CalibrationStatus::kCannotReachLow) ? pts.front() : pts.back();
      const double se = r.fit.noise_sd_deg / std::sqrt(static_cast<double>(end.n));
      if (r.fit.noise_dof > 0 && std::abs(target.angle_deg - end.fitted_deg) < 2.0 * se &&
          budget_left() >= k) {
        log.run({end.mu_r});
        continue;
      }
      return r;
    }
    const Bracket b = bracket_of(r.fit, *r.mu_r);
    const bool converged =
        b.span_deg <= 2.0 * s.tolerance_deg && r.fitted_angle_halfwidth_deg <= s.tolerance_deg;
    if (!converged && budget_left() >= k) {
      log.run({next_mu_r(r, b, s)});
      continue;
    }
    const CalibrationStatus status =
        converged ? CalibrationStatus::kCalibrated : CalibrationStatus::kBudgetSpent;
    const std::string budget_note =
        converged ? std::string()
                  : "; budget of " + std::to_string(s.max_simulations) +
                        " simulations spent before the tolerance of " + num(s.tolerance_deg) +
                        " deg was met";
    if (s.confirm_bracket) return confirm_bracket(log, r.fit, b, target, s, status, budget_note);
    r.status = status;
    r.message += budget_note +
                 "; not confirmed: on synthetic tests this 95% interval held the truth about 87% "
                 "of the time";
    return r;
  }
}

CalibrationResult calibrate(const SimulateFn& simulate, const Target& target,
                            const CalibrationSettings& settings) {
  if (!simulate) throw std::invalid_argument("calibration: no simulate callback");
  return calibrate_batch(
      [&](const std::vector<std::pair<double, std::uint64_t>>& batch) {
        std::vector<double> out;
        for (const auto& [mu, seed] : batch) out.push_back(simulate(mu, seed));
        return out;
      },
      target, settings);
}

Prediction predict(const MonotoneFit& fit, double mu_r, const BootstrapSettings& bootstrap) {
  check_bootstrap(bootstrap);
  Prediction p;
  p.mu_r = mu_r;
  p.angle_deg = evaluate(fit, mu_r);
  p.seed_sd_deg = fit.noise_sd_deg;
  const auto x = knots(fit);
  Rng rng(bootstrap.rng_seed);
  std::vector<double> angles;
  for (int b = 0; b < bootstrap.replicates; ++b)
    angles.push_back(interpolate(x, replicate_fit(fit, rng), mu_r));
  p.low_deg = quantile(angles, kLowQuantile);
  p.high_deg = quantile(angles, kHighQuantile);
  return p;
}

Prediction predict(const MonotoneFit& fit, const CalibrationResult& calibrated,
                   const BootstrapSettings& bootstrap) {
  check_bootstrap(bootstrap);
  if (!calibrated.mu_r || calibrated.mu_r_replicates.empty())
    throw std::invalid_argument("calibration: predict needs a calibrated result; status is " +
                                to_string(calibrated.status));
  Prediction p;
  p.mu_r = *calibrated.mu_r;
  p.angle_deg = evaluate(fit, p.mu_r);
  p.seed_sd_deg = fit.noise_sd_deg;
  const auto x = knots(fit);
  for (double m : {calibrated.mu_r_low, calibrated.mu_r_high})
    if (m < x.front() || m > x.back())
      throw std::invalid_argument("calibration: the calibrated mu_r interval [" +
                                  num(calibrated.mu_r_low) + ", " + num(calibrated.mu_r_high) +
                                  "] is not inside the predicting fit's span [" + num(x.front()) +
                                  ", " + num(x.back()) + "]");
  Rng rng(bootstrap.rng_seed);
  std::vector<double> angles;
  const auto& reps = calibrated.mu_r_replicates;
  for (int b = 0; b < bootstrap.replicates; ++b) {
    const double m = std::clamp(reps[static_cast<std::size_t>(b) % reps.size()], x.front(),
                                x.back());  // replicates beyond the 95% interval only
    angles.push_back(interpolate(x, replicate_fit(fit, rng), m));
  }
  p.low_deg = quantile(angles, kLowQuantile);
  p.high_deg = quantile(angles, kHighQuantile);
  return p;
}

nlohmann::json to_json(const MonotoneFit& fit) {
  nlohmann::json pts = nlohmann::json::array();
  for (const auto& p : fit.points)
    pts.push_back({{"mu_r", p.mu_r},
                   {"n", p.n},
                   {"mean_deg", p.mean_deg},
                   {"sd_deg", p.sd_deg},
                   {"fitted_deg", p.fitted_deg}});
  return {{"method", kMonotoneFitMethod},
          {"points", pts},
          {"noise_sd_deg", fit.noise_sd_deg},
          {"noise_dof", fit.noise_dof}};
}

nlohmann::json to_json(const Prediction& p) {
  return {{"mu_r", p.mu_r},
          {"angle_deg", p.angle_deg},
          {"interval_deg", {p.low_deg, p.high_deg}},
          {"interval_level", 0.95},
          {"seed_sd_deg", p.seed_sd_deg}};
}

SampleStats sample_stats(const std::vector<double>& values) {
  SampleStats s;
  s.n = static_cast<int>(values.size());
  if (values.empty()) return s;
  for (double x : values) s.mean += x;
  s.mean /= s.n;
  if (s.n > 1) {
    for (double x : values) s.sd += (x - s.mean) * (x - s.mean);
    s.sd = std::sqrt(s.sd / (s.n - 1));
  }
  return s;
}

}  // namespace reposetwin::experiments
