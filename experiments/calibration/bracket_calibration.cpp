#include "experiments/calibration/bracket_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>

#include "experiments/io/format.hpp"

namespace reposetwin::experiments {
namespace {

constexpr double kOvershoot = 1.25;  // a secant step is stretched by this to land past the target

// The driver's state: every pour so far and the callback that adds to it.
class PourLog {
 public:
  explicit PourLog(const PourBatchFn& pour) : pour_(pour) {}

  int runs() const { return static_cast<int>(pours.size()); }

  void run(const std::vector<double>& mus, const std::vector<std::uint64_t>& seeds) {
    std::vector<std::pair<double, std::uint64_t>> batch;
    for (double mu : mus)
      for (auto seed : seeds) batch.emplace_back(mu, seed);
    std::vector<Pour> got = pour_(batch);
    if (got.size() != batch.size())
      throw std::runtime_error("calibration: the pour callback returned " +
                               std::to_string(got.size()) + " outcomes for " +
                               std::to_string(batch.size()) + " pours");
    for (std::size_t i = 0; i < batch.size(); ++i) {
      Pour p = got[i];
      p.mu_r = batch[i].first;
      p.seed = batch[i].second;
      if (p.outcome == PourOutcome::kPile &&
          (!std::isfinite(p.angle_deg) || p.angle_deg < 0.0 || p.angle_deg > 90.0))
        throw std::runtime_error("calibration: pour at mu_r = " + significant(p.mu_r) + ", seed " +
                                 std::to_string(p.seed) + " formed a pile with angle " +
                                 significant(p.angle_deg) + " outside [0, 90] deg");
      pours.push_back(std::move(p));
    }
  }

  std::vector<Pour> pours;

 private:
  const PourBatchFn& pour_;
};

std::vector<PourPoint> points_of(const std::vector<Pour>& pours) {
  std::map<double, PourPoint> by_mu;
  for (const Pour& p : pours) {
    PourPoint& q = by_mu[p.mu_r];
    q.mu_r = p.mu_r;
    ++q.pours;
    if (p.outcome == PourOutcome::kPile) ++q.piles;
    if (p.outcome == PourOutcome::kJam) ++q.jams;
    if (p.outcome == PourOutcome::kPhysicsStop) ++q.physics_stops;
    if (p.outcome == PourOutcome::kTimeLimit) ++q.time_limits;
    if (p.outcome == PourOutcome::kNotSettled) ++q.unsettled;
  }
  std::vector<PourPoint> out;
  for (const auto& [mu, q] : by_mu) out.push_back(q);
  return out;
}

// A point's piles enter the fit only when its jam rate is within the usable range.
bool usable(const PourPoint& q, const BracketSettings& s) {
  return q.piles > 0 && q.jam_rate() <= s.max_jam_rate;
}

std::vector<Observation> usable_observations(const std::vector<Pour>& pours,
                                             const std::vector<PourPoint>& points,
                                             const BracketSettings& s,
                                             std::optional<std::uint64_t> only_seed = {}) {
  std::set<double> ok;
  for (const PourPoint& q : points)
    if (usable(q, s)) ok.insert(q.mu_r);
  std::vector<Observation> obs;
  for (const Pour& p : pours)
    if (p.outcome == PourOutcome::kPile && ok.count(p.mu_r) && (!only_seed || p.seed == *only_seed))
      obs.push_back({p.mu_r, p.seed, p.angle_deg});
  return obs;
}

// The lowest mu_r above every usable point whose pours jam too often: the search stays below it.
std::optional<double> jam_limit(const std::vector<PourPoint>& points, const BracketSettings& s) {
  double top_usable = -1.0;
  for (const PourPoint& q : points)
    if (usable(q, s)) top_usable = std::max(top_usable, q.mu_r);
  for (const PourPoint& q : points)
    if (q.mu_r > top_usable && q.jam_rate() > s.max_jam_rate) return q.mu_r;
  return std::nullopt;
}

// The crossing of `target` by the parabola through the three fitted points nearest to mu, inside
// their span; nothing when it has none there.
std::optional<double> parabola_root(const MonotoneFit& fit, double mu, double target) {
  std::vector<FitPoint> pts = fit.points;
  if (pts.size() < 3) return std::nullopt;
  std::sort(pts.begin(), pts.end(), [&](const FitPoint& a, const FitPoint& b) {
    return std::abs(a.mu_r - mu) < std::abs(b.mu_r - mu);
  });
  pts.resize(3);
  std::sort(pts.begin(), pts.end(),
            [](const FitPoint& a, const FitPoint& b) { return a.mu_r < b.mu_r; });
  const double x0 = pts[0].mu_r, x1 = pts[1].mu_r, x2 = pts[2].mu_r;
  const double y0 = pts[0].fitted_deg, y1 = pts[1].fitted_deg, y2 = pts[2].fitted_deg;
  // Newton form: y = y0 + d1 (x - x0) + d2 (x - x0)(x - x1).
  const double d01 = (y1 - y0) / (x1 - x0), d12 = (y2 - y1) / (x2 - x1);
  const double d2 = (d12 - d01) / (x2 - x0);
  const double a = d2, b = d01 - d2 * (x0 + x1), c = y0 - d01 * x0 + d2 * x0 * x1 - target;
  std::vector<double> roots;
  if (std::abs(a) < 1e-12 * std::max(1.0, std::abs(b))) {
    if (b != 0.0) roots.push_back(-c / b);
  } else {
    const double disc = b * b - 4.0 * a * c;
    if (disc < 0.0) return std::nullopt;
    roots.push_back((-b - std::sqrt(disc)) / (2.0 * a));
    roots.push_back((-b + std::sqrt(disc)) / (2.0 * a));
  }
  std::optional<double> best;
  for (double r : roots)
    if (r >= x0 && r <= x2 && (!best || std::abs(r - mu) < std::abs(*best - mu))) best = r;
  return best;
}

// The slope of the fit's segment around mu [deg per unit mu_r] (0 if flat or a single point).
double local_slope(const MonotoneFit& fit, double mu) {
  const auto& pts = fit.points;
  if (pts.size() < 2) return 0.0;
  std::size_t ib = 1;
  while (ib + 1 < pts.size() && pts[ib].mu_r < mu) ++ib;
  return (pts[ib].fitted_deg - pts[ib - 1].fitted_deg) / (pts[ib].mu_r - pts[ib - 1].mu_r);
}

// The uncertainty terms of a bracketed fit (see the design note). A seed's own crossing: its
// angle at the fitted mu_r (its own isotonic curve, or its nearest point carried along the
// mean fit's slope when mu_r lies outside its points) moved to the target along that slope, so a
// seed whose own points do not straddle the target still counts.
void assess(BracketCalibration& c, const MonotoneFit& fit, double mu, const Target& target,
            const BracketSettings& s) {
  c.seed_roots.clear();
  const double slope = local_slope(fit, mu);
  std::set<std::uint64_t> seeds;
  for (const Pour& p : c.pours) seeds.insert(p.seed);
  if (slope > 0.0) {
    for (auto seed : seeds) {
      const auto obs = usable_observations(c.pours, c.points, s, seed);
      if (obs.empty()) continue;
      const MonotoneFit own = fit_monotone(obs);
      const FitPoint& lo = own.points.front();
      const FitPoint& hi = own.points.back();
      double at = 0.0;
      if (mu < lo.mu_r) {
        at = lo.fitted_deg + slope * (mu - lo.mu_r);
      } else if (mu > hi.mu_r) {
        at = hi.fitted_deg + slope * (mu - hi.mu_r);
      } else {
        at = evaluate(own, mu);
      }
      c.seed_roots.push_back(mu - (at - target.angle_deg) / slope);
    }
  }
  const SampleStats st = sample_stats(c.seed_roots);
  c.mu_r_seed_se = st.n >= 2 ? st.sd / std::sqrt(static_cast<double>(st.n))
                             : std::numeric_limits<double>::infinity();
  const auto& pts = fit.points;
  std::size_t ib = 0;
  while (ib + 1 < pts.size() && pts[ib].mu_r < mu) ++ib;
  const double width = pts[ib].mu_r - pts[ib > 0 ? ib - 1 : 0].mu_r;
  if (auto q = parabola_root(fit, mu, target.angle_deg))
    c.mu_r_interpolation = std::abs(*q - mu);
  else
    c.mu_r_interpolation = 0.5 * width;
  c.mu_r_uncertainty = std::hypot(c.mu_r_seed_se, c.mu_r_interpolation);
}

// The next point once the target is bracketed: the fitted crossing, or, when that lies within
// half the tolerance of a point already run (a new point there would teach nothing about the
// curvature), a tolerance further into the bracket, so the interpolation error shrinks. Nothing
// when the seed spread alone is above the tolerance (a new point cannot help: more seeds would).
std::optional<double> step_in(const BracketCalibration& c, const MonotoneFit& fit, double mu,
                              const BracketSettings& s) {
  if (c.mu_r_seed_se > s.mu_r_tolerance) return std::nullopt;
  const auto& pts = fit.points;
  std::size_t ib = 0;
  while (ib + 1 < pts.size() && pts[ib].mu_r < mu) ++ib;
  const double lo = pts[ib > 0 ? ib - 1 : 0].mu_r, hi = pts[ib].mu_r;
  double next = mu;
  for (const PourPoint& q : c.points)
    if (std::abs(q.mu_r - mu) < 0.5 * s.mu_r_tolerance)
      next = q.mu_r + (q.mu_r - lo < hi - q.mu_r ? s.mu_r_tolerance : -s.mu_r_tolerance);
  if (!(next > lo && next < hi)) return std::nullopt;  // the bracket is already that narrow
  for (const PourPoint& q : c.points)
    if (std::abs(q.mu_r - next) < 0.5 * s.mu_r_tolerance) return std::nullopt;
  return next;
}

// The next point while the target is not bracketed: a secant step past the target from the
// nearest end of the fit, kept inside the range and below the jam limit. Nothing: the target is
// out of reach (`why` says how).
std::optional<double> step_out(const MonotoneFit& fit, const Target& target,
                               const std::vector<PourPoint>& points, const BracketSettings& s,
                               std::string& why) {
  const auto& pts = fit.points;
  const bool up = target.angle_deg > pts.back().fitted_deg;
  double slope = s.slope_guess_deg;
  if (pts.size() >= 2) {
    const FitPoint& a = up ? pts[pts.size() - 2] : pts[0];
    const FitPoint& b = up ? pts.back() : pts[1];
    const double sec = (b.fitted_deg - a.fitted_deg) / (b.mu_r - a.mu_r);
    if (sec > 0.0) slope = sec;
  }
  const FitPoint& end = up ? pts.back() : pts.front();
  double step = kOvershoot * (target.angle_deg - end.fitted_deg) / slope;
  if (std::abs(step) < 2.0 * s.mu_r_tolerance) step = std::copysign(2.0 * s.mu_r_tolerance, step);
  double next = end.mu_r + step;
  if (up) {
    const auto jam = jam_limit(points, s);
    const double limit = jam ? std::min(*jam, s.mu_r_hi) : s.mu_r_hi;
    if (jam && next >= *jam) {
      next = 0.5 * (end.mu_r + *jam);
      if (*jam - end.mu_r < s.mu_r_tolerance) {
        why = "the pours jam at mu_r " + significant(*jam) + " (jam rate above " +
              significant(s.max_jam_rate) +
              ") before the angle reaches the target; the highest usable point, mu_r " +
              significant(end.mu_r) + ", reaches " + significant(end.fitted_deg) + " deg";
        return std::nullopt;
      }
    }
    next = std::min(next, limit);
  } else {
    next = std::max(next, s.mu_r_lo);
  }
  for (const PourPoint& q : points)
    if (q.mu_r == next) {
      why = "the range end mu_r " + significant(next) + " reaches only " +
            significant(end.fitted_deg) + " deg";
      return std::nullopt;
    }
  return next;
}

// The pours without a pile, by their real stop ("2 jammed, 2 stopped by the time limit
// procedure.max_time_s"), for a message.
std::string stops_text(const std::vector<PourPoint>& points) {
  int jams = 0, limits = 0, unsettled = 0, stops = 0;
  for (const PourPoint& q : points) {
    jams += q.jams;
    limits += q.time_limits;
    unsettled += q.unsettled;
    stops += q.physics_stops;
  }
  std::string t;
  const auto add = [&t](int n, const std::string& what) {
    if (n > 0) t += (t.empty() ? "" : ", ") + std::to_string(n) + " " + what;
  };
  add(jams, "jammed");
  add(limits, "stopped by the time limit procedure.max_time_s");
  add(unsettled, "still moving at procedure.final_settle_max_s");
  add(stops, "stopped by the engine");
  return t;
}

// The next point while nothing usable exists yet: halfway down when every pour so far jammed
// (a lower mu_r flows); none when another stop took them (a time limit, the engine), which a
// lower mu_r does not cure, and the message names that stop.
std::optional<double> step_below_jams(const std::vector<PourPoint>& points,
                                      const BracketSettings& s, std::string& why) {
  const double lowest = points.front().mu_r;
  bool only_jams = true;
  for (const PourPoint& q : points)
    only_jams = only_jams && q.time_limits + q.unsettled + q.physics_stops == 0;
  if (!only_jams) {
    why = "no pour formed a pile, and not all for jams, which a lower mu_r would cure";
    return std::nullopt;
  }
  if (lowest - s.mu_r_lo < s.mu_r_tolerance) {
    why = "every pour jammed, down to mu_r " + significant(lowest);
    return std::nullopt;
  }
  return 0.5 * (s.mu_r_lo + lowest);
}

void finish(BracketCalibration& c, const Target& target, const BracketSettings& s,
            CalibrationStatus status, const std::string& note) {
  const auto obs = usable_observations(c.pours, c.points, s);
  if (!obs.empty()) {
    c.result = calibrate_observations(obs, target, s.bootstrap);
  } else {
    c.result = CalibrationResult{};
    c.result.target = target;
  }
  c.result.status = status;
  if (!c.result.mu_r) c.result.message.clear();  // the note says why there is no mu_r
  c.result.simulations = static_cast<int>(c.pours.size());
  std::string m = c.result.message.empty() ? std::string() : c.result.message + "; ";
  m += note.empty() ? std::string() : note + "; ";
  const std::string stops = stops_text(c.points);
  m += std::to_string(c.pours.size()) + " pile runs (" +
       (stops.empty() ? std::string("each formed a pile") : stops) + ")";
  if (c.bracketed)
    m += "; mu_r uncertainty " + significant(c.mu_r_uncertainty) + " (seed spread " +
         significant(c.mu_r_seed_se) + ", interpolation " + significant(c.mu_r_interpolation) +
         ") against the tolerance " + significant(s.mu_r_tolerance);
  c.result.message = m;
}

}  // namespace

std::string to_string(PourOutcome outcome) {
  switch (outcome) {
    case PourOutcome::kPile:
      return "pile";
    case PourOutcome::kJam:
      return "jam";
    case PourOutcome::kPhysicsStop:
      return "physics_stop";
    case PourOutcome::kTimeLimit:
      return "time_limit";
    case PourOutcome::kNotSettled:
      return "not_settled";
  }
  return "unknown";
}

BracketCalibration calibrate_bracket(const PourBatchFn& pour, const Target& target,
                                     const BracketSettings& s) {
  validate_target(target);
  validate_bracket_settings(s);
  if (!pour) throw std::invalid_argument("calibration: no pour callback");
  BracketCalibration c;
  PourLog log(pour);
  const int k = static_cast<int>(s.seeds.size());
  if (s.ends_first)
    log.run({s.mu_r_lo, s.mu_r_hi}, s.seeds);
  else
    log.run({s.mu_r_start.value_or(0.5 * (s.mu_r_lo + s.mu_r_hi))}, s.seeds);
  for (;;) {
    c.pours = log.pours;
    c.points = points_of(c.pours);
    const auto obs = usable_observations(c.pours, c.points, s);
    std::string why;
    std::optional<double> next;
    if (obs.empty()) {
      next = step_below_jams(c.points, s, why);
    } else {
      const MonotoneFit fit = fit_monotone(obs);
      const auto mu = invert(fit, target.angle_deg);
      c.bracketed = mu.has_value();
      if (!mu) {
        next = step_out(fit, target, c.points, s, why);
      } else {
        assess(c, fit, *mu, target, s);
        if (c.mu_r_uncertainty <= s.mu_r_tolerance) {
          finish(c, target, s, CalibrationStatus::kCalibrated, "");
          return c;
        }
        next = step_in(c, fit, *mu, s);
        if (!next)
          why = c.mu_r_seed_se > s.mu_r_tolerance
                    ? "the seed spread alone is above the tolerance: more seeds are needed"
                    : "the bracket is narrower than the tolerance";
      }
    }
    if (!next && !c.bracketed) {
      const bool low = !obs.empty() && target.angle_deg < fit_monotone(obs).points[0].fitted_deg;
      finish(c, target, s,
             low ? CalibrationStatus::kCannotReachLow : CalibrationStatus::kCannotReachHigh,
             "cannot reach: " + why);
      return c;
    }
    if (!next || log.runs() + k > s.max_runs) {
      // Out of runs, or a new point cannot help (the seed spread alone is above the tolerance):
      // the fit's mu_r stands, with the tolerance not met, and the message says which.
      const bool noise = !next && c.mu_r_seed_se > s.mu_r_tolerance;
      finish(c, target, s,
             noise ? CalibrationStatus::kSeedNoiseLimited : CalibrationStatus::kBudgetSpent,
             next ? "budget of " + std::to_string(s.max_runs) +
                        " pile runs spent before the mu_r tolerance of " +
                        significant(s.mu_r_tolerance) + " was met" +
                        (why.empty() ? std::string() : " (" + why + ")")
                  : "stopped after " + std::to_string(log.runs()) + " of " +
                        std::to_string(s.max_runs) + " pile runs before the mu_r tolerance of " +
                        significant(s.mu_r_tolerance) + " was met: " + why);
      return c;
    }
    log.run({*next}, s.seeds);
  }
}

CalibrationRecord calibration_record(const BracketCalibration& c, const BracketSettings& s) {
  CalibrationRecord r = calibration_record(c.result);
  r.method = CalibrationMethod::kBracket;
  for (const PourPoint& q : c.points)
    r.pour_counts.push_back({q.mu_r, q.pours, q.piles, q.jams, q.physics_stops, q.time_limits,
                             q.unsettled, q.jam_rate(),
                             q.piles > 0 && q.jam_rate() <= s.max_jam_rate});
  nlohmann::json pours = nlohmann::json::array();
  for (const Pour& p : c.pours) {
    nlohmann::json e = {{"mu_r", p.mu_r}, {"seed", p.seed}, {"outcome", to_string(p.outcome)}};
    e["angle_deg"] = p.outcome == PourOutcome::kPile ? nlohmann::json(p.angle_deg) : nullptr;
    if (!p.detail.empty()) e["detail"] = p.detail;
    pours.push_back(e);
  }
  const auto finite_or_null = [](double x) {
    return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json();
  };
  // The driver's working, written beside the record and read by no command (a person's, and
  // the tests'): the pours in order, the seeds, and the numbers of its stop rule.
  r.working = {
      {"method_text",
       "bracketing with a monotone fit and common random numbers (the same seeds at every mu_r); "
       "stops when the target is bracketed and the mu_r uncertainty (seed spread and "
       "interpolation, in quadrature) is below the tolerance; jammed pours counted as a jam rate"},
      {"pile_runs", c.pours.size()},
      {"pours", pours},
      {"bracketed", c.bracketed},
      {"seeds", s.seeds},
      {"seed_roots", c.seed_roots},
      {"mu_r_seed_se", finite_or_null(c.mu_r_seed_se)},
      {"mu_r_interpolation_error", c.mu_r_interpolation},
      {"mu_r_uncertainty", finite_or_null(c.mu_r_uncertainty)},
      {"mu_r_tolerance", s.mu_r_tolerance},
      {"max_runs", s.max_runs},
      {"max_jam_rate", s.max_jam_rate},
      {"slope_guess_deg", s.slope_guess_deg},
      {"mu_r_start", s.mu_r_start.value_or(0.5 * (s.mu_r_lo + s.mu_r_hi))},
      {"ends_first", s.ends_first}};
  return r;
}

}  // namespace reposetwin::experiments
