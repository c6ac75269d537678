#include "sim/psd.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace reposetwin::sim {
namespace {

// A lab sheet writes 100 for the top sieve; allow for a decimal copied with rounding noise.
constexpr double kFullPassingTolerance = 1e-6;  // [%]
// Relative slack when comparing d_max or d_min to the table's end sizes (unit conversions).
constexpr double kSizeSlack = 1e-12;

std::string format_size(double d) {
  std::ostringstream s;
  s.precision(6);
  s << d << " m (" << d * 1e3 << " mm)";
  return s.str();
}

std::string format_number(double x) {
  std::ostringstream s;
  s.precision(10);
  s << x;
  return s.str();
}

// "[i]"; built with a stream, since GCC 12 warns falsely (-Wrestrict) on "[" + std::to_string(i).
std::string bracket(std::size_t i) {
  std::ostringstream s;
  s << '[' << i << ']';
  return s.str();
}

[[noreturn]] void psd_error(const std::string& message) {
  throw std::invalid_argument("PSD: " + message);
}

double mass_of_diameter(double d, double density) {
  return density * std::numbers::pi / 6.0 * d * d * d;
}

// One diameter from the normal N((a+b)/2, (sd_fraction (b-a))^2) clipped to [a, b] by rejection.
double draw_clipped_normal(double a, double b, double sd_fraction, Rng& rng) {
  const double mean = 0.5 * (a + b);
  const double sd = sd_fraction * (b - a);
  for (;;) {
    const double d = rng.normal(mean, sd);
    if (d >= a && d <= b) return d;
  }
}

}  // namespace

std::string to_string(FinesPolicy policy) {
  return policy == FinesPolicy::kDrop ? "drop" : "renormalise";
}

void validate_sieve_table(const SieveTable& table) {
  const std::size_t n = table.size.size();
  if (table.passing.size() != n) {
    psd_error("sieve table has " + std::to_string(n) + " sieve sizes but " +
              std::to_string(table.passing.size()) + " percent-passing values (must be equal)");
  }
  if (n < 2) {
    psd_error("sieve table has " + std::to_string(n) + " sieve(s); at least 2 are needed");
  }
  for (std::size_t i = 0; i < n; ++i) {
    const double d = table.size[i];
    const std::string at = bracket(i);
    if (!std::isfinite(d) || d <= 0.0) {
      psd_error("sieve size" + at + " = " + format_size(d) + " must be positive and finite");
    }
    if (i > 0 && !(d > table.size[i - 1])) {
      psd_error("sieve size" + at + " = " + format_size(d) + " is not larger than sieve size[" +
                std::to_string(i - 1) + "] = " + format_size(table.size[i - 1]) +
                " (sizes must be strictly increasing)");
    }
    const double p = table.passing[i];
    if (!std::isfinite(p) || p < 0.0 || p > 100.0) {
      psd_error("percent passing" + at + " = " + format_number(p) + " % is outside [0, 100]");
    }
    if (i > 0 && p < table.passing[i - 1]) {
      psd_error("percent passing" + at + " = " + format_number(p) + " % is below percent passing[" +
                std::to_string(i - 1) + "] = " + format_number(table.passing[i - 1]) +
                " % (the cumulative curve must be non-decreasing)");
    }
  }
  if (std::abs(table.passing.back() - 100.0) > kFullPassingTolerance) {
    psd_error("percent passing[" + std::to_string(n - 1) +
              "] = " + format_number(table.passing.back()) + " % at the largest sieve " +
              format_size(table.size.back()) +
              ": the table must reach 100 % (add the sieve that passes everything)");
  }
}

double percent_passing(const SieveTable& table, double d) {
  const auto& s = table.size;
  if (!(d >= s.front() * (1.0 - kSizeSlack) && d <= s.back() * (1.0 + kSizeSlack))) {
    psd_error("size " + format_size(d) + " is outside the sieve table [" + format_size(s.front()) +
              ", " + format_size(s.back()) + "]");
  }
  if (d <= s.front()) return table.passing.front();
  if (d >= s.back()) return table.passing.back();
  const auto it = std::upper_bound(s.begin(), s.end(), d);  // first size > d; it > begin
  const std::size_t j = static_cast<std::size_t>(it - s.begin());
  const double t = (d - s[j - 1]) / (s[j] - s[j - 1]);
  return table.passing[j - 1] + t * (table.passing[j] - table.passing[j - 1]);
}

ResolvedPsd resolve_psd(const PsdSpec& spec) {
  validate_sieve_table(spec.table);
  const auto& s = spec.table.size;
  ResolvedPsd r;
  r.fines = spec.fines;
  if (!std::isfinite(spec.interval_sd_fraction) || spec.interval_sd_fraction <= 0.0 ||
      spec.interval_sd_fraction > 1.0) {
    psd_error("interval_sd_fraction = " + format_number(spec.interval_sd_fraction) +
              " must lie in (0, 1]");
  }
  r.interval_sd_fraction = spec.interval_sd_fraction;
  if (!std::isfinite(spec.d_max))
    psd_error("d_max = " + format_number(spec.d_max) + " is not finite");
  if (!std::isfinite(spec.d_min))
    psd_error("d_min = " + format_number(spec.d_min) + " is not finite");
  r.d_max = spec.d_max > 0.0 ? spec.d_max : s.back();
  r.d_min = spec.d_min > 0.0 ? spec.d_min : s.front();
  if (r.d_max > s.back() * (1.0 + kSizeSlack)) {
    psd_error("d_max = " + format_size(r.d_max) + " is above the largest sieve size " +
              format_size(s.back()) + ": the table does not describe material that coarse");
  }
  if (r.d_min < s.front() * (1.0 - kSizeSlack)) {
    psd_error("d_min = " + format_size(r.d_min) + " is below the smallest sieve size " +
              format_size(s.front()) + ": the table does not describe material that fine");
  }
  r.d_max = std::min(r.d_max, s.back());
  r.d_min = std::max(r.d_min, s.front());
  if (!(r.d_min < r.d_max)) {
    psd_error("d_min = " + format_size(r.d_min) + " must be below d_max = " + format_size(r.d_max));
  }
  const double p_max = percent_passing(spec.table, r.d_max);
  const double p_min = percent_passing(spec.table, r.d_min);
  if (!(p_max > p_min)) {
    psd_error("no material between d_min = " + format_size(r.d_min) + " (" + format_number(p_min) +
              " % passing) and d_max = " + format_size(r.d_max) + " (" + format_number(p_max) +
              " % passing)");
  }
  r.scalped_fraction = 1.0 - p_max / 100.0;
  r.fines_fraction = p_min / p_max;
  r.simulated_mass_factor = spec.fines == FinesPolicy::kDrop ? 1.0 - r.fines_fraction : 1.0;

  std::vector<double> bounds{r.d_min};
  for (double d : s)
    if (d > r.d_min && d < r.d_max) bounds.push_back(d);
  bounds.push_back(r.d_max);
  double previous = p_min;
  for (std::size_t k = 0; k + 1 < bounds.size(); ++k) {
    const double p = k + 2 == bounds.size() ? p_max : percent_passing(spec.table, bounds[k + 1]);
    r.intervals.push_back({bounds[k], bounds[k + 1], (p - previous) / (p_max - p_min)});
    previous = p;
  }
  return r;
}

double clipped_normal_mean_cube(double lower, double upper, double sd_fraction) {
  constexpr int kSteps = 256;  // even; Simpson's rule, error far below 1e-6 relative here
  const double mean = 0.5 * (lower + upper);
  const double sd = sd_fraction * (upper - lower);
  const double h = (upper - lower) / kSteps;
  double weight = 0.0;
  double moment = 0.0;
  for (int i = 0; i <= kSteps; ++i) {
    const double x = lower + i * h;
    const double c = (i == 0 || i == kSteps) ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
    const double z = (x - mean) / sd;
    const double w = c * std::exp(-0.5 * z * z);
    weight += w;
    moment += w * x * x * x;
  }
  return moment / weight;
}

double expected_particle_count(const PsdSpec& spec, double target_mass, double density) {
  if (!(target_mass > 0.0) || !std::isfinite(target_mass)) {
    psd_error("target mass = " + format_number(target_mass) + " kg must be positive");
  }
  if (!(density > 0.0) || !std::isfinite(density)) {
    psd_error("density = " + format_number(density) + " kg/m^3 must be positive");
  }
  const ResolvedPsd r = resolve_psd(spec);
  const double simulated = target_mass * r.simulated_mass_factor;
  double count = 0.0;
  for (const auto& in : r.intervals) {
    if (in.mass_fraction <= 0.0) continue;
    const double mean_mass = density * std::numbers::pi / 6.0 *
                             clipped_normal_mean_cube(in.lower, in.upper, r.interval_sd_fraction);
    count += in.mass_fraction * simulated / mean_mass;
  }
  return count;
}

PsdSample sample_psd(const PsdSpec& spec, double target_mass, double density, Rng& rng) {
  PsdShape sphere;
  sphere.volume_per_cube = std::numbers::pi / 6.0;
  sphere.sphere = true;
  PsdSample out = sample_psd_shapes(spec, target_mass, density, {sphere}, rng);
  out.shape.clear();
  return out;
}

PsdSample sample_psd_shapes(const PsdSpec& spec, double target_mass, double density,
                            const std::vector<PsdShape>& shapes, Rng& rng) {
  if (!(target_mass > 0.0) || !std::isfinite(target_mass)) {
    psd_error("target mass = " + format_number(target_mass) + " kg must be positive");
  }
  if (!(density > 0.0) || !std::isfinite(density)) {
    psd_error("density = " + format_number(density) + " kg/m^3 must be positive");
  }
  if (shapes.empty()) psd_error("no grain shapes");
  double fraction_sum = 0.0, mean_volume = 0.0;
  for (std::size_t s = 0; s < shapes.size(); ++s) {
    const PsdShape& sh = shapes[s];
    if (!(sh.volume_per_cube > 0.0) || !std::isfinite(sh.volume_per_cube))
      psd_error("shape " + std::to_string(s) +
                " volume per cube = " + format_number(sh.volume_per_cube) + " must be positive");
    if (!(sh.mass_fraction >= 0.0) || !std::isfinite(sh.mass_fraction))
      psd_error("shape " + std::to_string(s) +
                " mass fraction = " + format_number(sh.mass_fraction) + " must not be negative");
    fraction_sum += sh.mass_fraction;
    mean_volume += sh.mass_fraction / sh.volume_per_cube;
  }
  if (std::abs(fraction_sum - 1.0) > 1e-9)
    psd_error("shape mass fractions sum to " + format_number(fraction_sum) + ", not 1");
  const ResolvedPsd r = resolve_psd(spec);
  const std::size_t k_count = r.intervals.size(), s_count = shapes.size();

  PsdSample out;
  PsdSummary& sum = out.summary;
  sum.target_mass = target_mass;
  sum.simulated_target_mass = target_mass * r.simulated_mass_factor;
  sum.d_min = r.d_min;
  sum.d_max = r.d_max;
  sum.fines_fraction = r.fines_fraction;
  sum.scalped_fraction = r.scalped_fraction;
  sum.fines = r.fines;
  sum.d_min_drawn = std::numeric_limits<double>::infinity();
  sum.d_max_drawn = 0.0;

  // Cells (interval k, shape s) at k * s_count + s.
  std::vector<double> target(k_count * s_count), drawn(k_count * s_count, 0.0);
  std::vector<double> drawn_k(k_count, 0.0);
  std::vector<std::size_t> count(k_count, 0);
  for (std::size_t k = 0; k < k_count; ++k)
    for (std::size_t s = 0; s < s_count; ++s)
      target[k * s_count + s] =
          r.intervals[k].mass_fraction * shapes[s].mass_fraction * sum.simulated_target_mass;
  // Refuse requests that would exhaust memory rather than fail deep inside a vector (the sphere
  // count scaled by the mean volume of a grain against a sphere's).
  const double expected = expected_particle_count(spec, target_mass, density) *
                          (std::numbers::pi / 6.0) * mean_volume;
  constexpr double kMaxParticles = 2e8;
  if (expected > kMaxParticles) {
    psd_error("target mass = " + format_number(target_mass) + " kg would need about " +
              format_number(expected) + " particles (limit " + format_number(kMaxParticles) +
              "); raise d_min");
  }
  out.diameter.reserve(static_cast<std::size_t>(expected * 1.01) + 16);
  out.shape.reserve(out.diameter.capacity());

  double total = 0.0;
  while (total < sum.simulated_target_mass) {
    // The cell furthest below its target mass; ties go to the smaller size, then to the
    // earlier shape. Cells with no mass in the table are never drawn from.
    std::size_t best = k_count * s_count;
    double best_deficit = -std::numeric_limits<double>::infinity();
    for (std::size_t c = 0; c < k_count * s_count; ++c) {
      if (r.intervals[c / s_count].mass_fraction <= 0.0 || shapes[c % s_count].mass_fraction <= 0)
        continue;
      const double deficit = target[c] - drawn[c];
      if (deficit > best_deficit) {
        best_deficit = deficit;
        best = c;
      }
    }
    const std::size_t k = best / s_count, s = best % s_count;
    const PsdInterval& in = r.intervals[k];
    const double d = draw_clipped_normal(in.lower, in.upper, r.interval_sd_fraction, rng);
    const double m = shapes[s].sphere ? mass_of_diameter(d, density)
                                      : density * shapes[s].volume_per_cube * d * d * d;
    out.diameter.push_back(d);
    out.shape.push_back(static_cast<std::int32_t>(s));
    drawn[best] += m;
    drawn_k[k] += m;
    count[k] += 1;
    total += m;
    sum.d_min_drawn = std::min(sum.d_min_drawn, d);
    sum.d_max_drawn = std::max(sum.d_max_drawn, d);
  }

  sum.drawn_mass = total;
  sum.count = out.diameter.size();
  for (std::size_t k = 0; k < k_count; ++k) {
    sum.intervals.push_back({r.intervals[k].lower, r.intervals[k].upper,
                             r.intervals[k].mass_fraction, drawn_k[k] / total, count[k]});
  }
  return out;
}

}  // namespace reposetwin::sim
