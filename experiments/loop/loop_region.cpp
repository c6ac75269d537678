#include "experiments/loop/loop_region.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <tuple>

#include "experiments/io/format.hpp"
#include "experiments/io/json_read.hpp"

namespace reposetwin::experiments {

namespace {

double chi2_at(const ProfileRow& r, double t) { return r.syy - 2.0 * t * r.sdy + t * t * r.sdd; }

// The best t of one row inside [lo, hi].
double best_t(const ProfileRow& r, double lo, double hi) {
  if (!(r.sdd > 0.0)) return std::clamp(0.0, lo, hi);
  return std::clamp(r.sdy / r.sdd, lo, hi);
}

// The chi^2 quantile with two degrees of freedom: -2 ln(1 - level).
double chi2_quantile_2dof(double level) { return -2.0 * std::log(1.0 - level); }

// The quasi-likelihood widening (design note): chi2_min / (n - 2) when above 1, else 1.
double widening_for(double chi2_min, int observations) {
  const int dof = observations - 2;
  return dof > 0 && chi2_min > dof ? chi2_min / dof : 1.0;
}

// The minimum of chi^2 over the rows, t at its best inside [t_lo, t_hi] on each; returns the
// row it is on.
std::size_t find_minimum(const std::vector<ProfileRow>& rows, double t_lo, double t_hi,
                         JointRegion& g) {
  std::size_t kbest = 0;
  g.chi2_min = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const double t = best_t(rows[k], t_lo, t_hi);
    const double c = chi2_at(rows[k], t);
    if (c < g.chi2_min) {
      g.chi2_min = c;
      g.mu = rows[k].mu;
      g.t = t;
      kbest = k;
    }
  }
  return kbest;
}

// The correlation of mu_r and t from the curvature at the optimum (row kbest): d2 chi^2 / dt2 =
// 2 sdd; along mu_r and across, by differences over the neighbouring rows (one-sided at an end
// of the scan).
double correlation_at(const std::vector<ProfileRow>& rows, std::size_t kbest, double t) {
  const std::size_t k0 = kbest == 0 ? 0 : (kbest + 1 == rows.size() ? kbest - 2 : kbest - 1);
  const ProfileRow &r0 = rows[k0], &r1 = rows[k0 + 1], &r2 = rows[k0 + 2];
  const double hm = 0.5 * (r2.mu - r0.mu);
  const double c0 = chi2_at(r0, t), c1 = chi2_at(r1, t), c2 = chi2_at(r2, t);
  const double h_mm = (c2 - 2.0 * c1 + c0) / (hm * hm);
  const double grad_t0 = -2.0 * r0.sdy + 2.0 * t * r0.sdd;
  const double grad_t2 = -2.0 * r2.sdy + 2.0 * t * r2.sdd;
  const double h_mt = (grad_t2 - grad_t0) / (r2.mu - r0.mu);
  const double h_tt = 2.0 * rows[kbest].sdd;
  const double det = h_mm * h_tt - h_mt * h_mt;
  if (h_mm > 0.0 && h_tt > 0.0 && det > 0.0)
    return -h_mt / std::sqrt(h_mm * h_tt);  // of the inverse: -H_mt / sqrt(H_mm H_tt)
  return std::copysign(1.0, -h_mt);  // flat along some direction: not separated
}

// The region in words, with why the data do not separate mu_r from the effect when they do not.
std::string region_statement(const JointRegion& g, int dof) {
  const std::string pct = significant(100.0 * g.level, 3) + "%";
  std::string text = "the " + pct + " joint region (profile likelihood over the simulated "
                     "surfaces) holds mu_r " + significant(g.mu_lo, 3) + "-" +
                     significant(g.mu_hi, 3) + " and t " + significant(g.t_lo, 3) + "-" +
                     significant(g.t_hi, 3) + ", correlation " + significant(g.correlation, 2);
  if (g.widening > 1.0)
    text += "; widened " + significant(std::sqrt(g.widening), 3) + "x for a chi^2 of " +
            significant(g.chi2_min, 3) + " on " + std::to_string(dof) + " degrees of freedom";
  if (!g.separated) {
    std::string why;
    if (std::abs(g.correlation) > 0.9) why = "mu_r and the effect move the piles alike";
    if (g.mu_at_bound)
      why += std::string(why.empty() ? "" : ", and ") + "the region reaches mu_r's range bound";
    if (g.t_at_bound)
      why += std::string(why.empty() ? "" : ", and ") + "the region reaches the effect's bound";
    text += "; the data do not separate mu_r from the effect (" + why +
            "): the interval is reported to the bound, widened, not as a value";
  }
  return text;
}

}  // namespace


JointRegion joint_region(const std::vector<ProfileRow>& rows, double t_lo, double t_hi,
                         int observations, double level) {
  if (rows.size() < 3) throw std::invalid_argument("joint_region: at least 3 mu_r rows needed");
  if (observations < 3) throw std::invalid_argument("joint_region: at least 3 observations needed");
  if (!(t_hi > t_lo)) throw std::invalid_argument("joint_region: empty t range");
  if (!(level > 0.0 && level < 1.0)) throw std::invalid_argument("joint_region: level in (0, 1)");
  JointRegion g;
  g.level = level;
  g.observations = observations;
  const std::size_t kbest = find_minimum(rows, t_lo, t_hi, g);
  const int dof = observations - 2;
  g.widening = widening_for(g.chi2_min, observations);
  g.chi2_limit = g.chi2_min + chi2_quantile_2dof(level) * g.widening;
  // The optimum's own row is inside its limit, so the extent exists.
  const RegionExtent e = *region_extent(rows, t_lo, t_hi, g.chi2_limit);
  g.mu_lo = e.mu_lo;
  g.mu_hi = e.mu_hi;
  g.t_lo = e.t_lo;
  g.t_hi = e.t_hi;
  g.mu_at_bound = e.mu_at_bound;
  g.t_at_bound = e.t_at_bound;
  g.correlation = correlation_at(rows, kbest, g.t);
  g.separated = std::abs(g.correlation) <= 0.9 && !g.mu_at_bound && !g.t_at_bound;
  g.statement = region_statement(g, dof);
  return g;
}

// The rows whose chi^2 dips below the limit, and on each the t interval below it.
std::optional<RegionExtent> region_extent(const std::vector<ProfileRow>& rows, double t_lo,
                                          double t_hi, double chi2_limit) {
  RegionExtent g;
  g.mu_lo = g.t_lo = std::numeric_limits<double>::infinity();
  g.mu_hi = g.t_hi = -std::numeric_limits<double>::infinity();
  const double eps = 1e-9 * std::max(1.0, t_hi - t_lo);
  bool any = false;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const ProfileRow& r = rows[k];
    double a, b;  // the row's t interval inside the region
    if (r.sdd > 0.0) {
      const double tu = r.sdy / r.sdd;
      const double floor = r.syy - r.sdy * tu;  // chi^2 at tu
      if (floor > chi2_limit) continue;
      const double half = std::sqrt((chi2_limit - floor) / r.sdd);
      a = std::max(t_lo, tu - half);
      b = std::min(t_hi, tu + half);
      if (a > b) continue;
    } else {
      if (r.syy > chi2_limit) continue;
      a = t_lo;
      b = t_hi;
    }
    any = true;
    g.mu_lo = std::min(g.mu_lo, r.mu);
    g.mu_hi = std::max(g.mu_hi, r.mu);
    g.t_lo = std::min(g.t_lo, a);
    g.t_hi = std::max(g.t_hi, b);
    if (k == 0 || k + 1 == rows.size()) g.mu_at_bound = true;
  }
  if (!any) return std::nullopt;
  g.t_at_bound = g.t_lo <= t_lo + eps || g.t_hi >= t_hi - eps;
  return g;
}

ValueRegion value_region(const std::vector<ChordScan>& chords, double off) {
  if (chords.empty()) throw std::invalid_argument("value_region: no chord");
  const ChordScan* best = &chords.front();
  for (const ChordScan& c : chords)
    if (c.region.chi2_min < best->region.chi2_min) best = &c;
  // The limit of the chord with the lowest chi2_min: its minimum plus the quantile, widened
  // for that minimum (joint_region), is the limit over all of them.
  ValueRegion v;
  v.chi2_limit = best->region.chi2_limit;
  v.value_lo = v.mu_lo = std::numeric_limits<double>::infinity();
  v.value_hi = v.mu_hi = -std::numeric_limits<double>::infinity();
  for (const ChordScan& c : chords) {
    const std::optional<RegionExtent> e = region_extent(c.rows, 0.0, c.t_max, v.chi2_limit);
    if (!e) continue;
    ++v.chords;
    const double a = off + e->t_lo * (c.p - off), b = off + e->t_hi * (c.p - off);
    v.value_lo = std::min({v.value_lo, a, b});
    v.value_hi = std::max({v.value_hi, a, b});
    v.mu_lo = std::min(v.mu_lo, e->mu_lo);
    v.mu_hi = std::max(v.mu_hi, e->mu_hi);
    v.mu_at_bound = v.mu_at_bound || e->mu_at_bound;
    v.t_at_bound = v.t_at_bound || e->t_at_bound;
  }
  return v;
}

std::vector<NextTestGain> rank_next_tests(const Eigen::Matrix2d& info,
                                          const std::vector<NextTest>& candidates) {
  std::vector<NextTestGain> out;
  Eigen::FullPivLU<Eigen::Matrix2d> lu(info);
  if (!lu.isInvertible()) return out;
  const Eigen::Matrix2d cov = info.inverse();
  for (const NextTest& c : candidates) {
    const Eigen::Matrix2d after = (info + c.added).inverse();
    NextTestGain g;
    g.name = c.name;
    g.mu_interval_ratio = std::sqrt(after(0, 0) / cov(0, 0));
    g.t_interval_ratio = std::sqrt(after(1, 1) / cov(1, 1));
    g.area_ratio = std::sqrt(after.determinant() / cov.determinant());
    out.push_back(g);
  }
  std::stable_sort(out.begin(), out.end(), [](const NextTestGain& a, const NextTestGain& b) {
    return a.t_interval_ratio < b.t_interval_ratio;
  });
  return out;
}

nlohmann::json to_json(const JointRegion& r) {
  return {{"method", "profile likelihood over the simulated response surfaces: chi2 <= chi2_min "
                     "+ q (two degrees of freedom), q scaled by chi2_min / (n - 2) when above 1"},
          {"level", r.level},
          {"mu_r", r.mu},
          {"t", r.t},
          {"chi2_min", r.chi2_min},
          {"observations", r.observations},
          {"widening", r.widening},
          {"chi2_limit", r.chi2_limit},
          {"mu_r_range", {r.mu_lo, r.mu_hi}},
          {"t_range", {r.t_lo, r.t_hi}},
          {"correlation", r.correlation},
          {"mu_r_at_bound", r.mu_at_bound},
          {"t_at_bound", r.t_at_bound},
          {"separated", r.separated},
          {"statement", r.statement}};
}

namespace {

// The two ends of the range j[key] [lo, hi].
std::pair<double, double> range_field(const nlohmann::json& j, const char* key) {
  const std::vector<double> r = numbers_field(j, key);
  if (r.size() != 2)
    throw JsonFieldError("/" + std::string(key), "has " + std::to_string(r.size()) +
                                                     " values, not the two ends of a range");
  return {r[0], r[1]};
}

}  // namespace

JointRegion joint_region_from_json(const nlohmann::json& j) {
  JointRegion r;
  r.level = number_field(j, "level");
  r.mu = number_field(j, "mu_r");
  r.t = number_field(j, "t");
  r.chi2_min = number_field(j, "chi2_min");
  r.observations = field<int>(j, "observations");
  r.widening = number_field(j, "widening");
  r.chi2_limit = number_field(j, "chi2_limit");
  std::tie(r.mu_lo, r.mu_hi) = range_field(j, "mu_r_range");
  std::tie(r.t_lo, r.t_hi) = range_field(j, "t_range");
  r.correlation = number_field(j, "correlation");
  r.mu_at_bound = field<bool>(j, "mu_r_at_bound");
  r.t_at_bound = field<bool>(j, "t_at_bound");
  r.separated = field<bool>(j, "separated");
  r.statement = field<std::string>(j, "statement");
  return r;
}

nlohmann::json to_json(const NextTestGain& g) {
  return {{"test", g.name},
          {"effect_interval_ratio", g.t_interval_ratio},
          {"mu_r_interval_ratio", g.mu_interval_ratio},
          {"region_area_ratio", g.area_ratio}};
}

NextTestGain next_test_gain_from_json(const nlohmann::json& j) {
  return {field<std::string>(j, "test"), number_field(j, "effect_interval_ratio"),
          number_field(j, "mu_r_interval_ratio"), number_field(j, "region_area_ratio")};
}

}  // namespace reposetwin::experiments
