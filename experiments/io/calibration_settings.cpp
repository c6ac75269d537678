#include "experiments/io/calibration_settings.hpp"

#include <cmath>
#include <set>
#include <stdexcept>
#include <string>

#include "experiments/io/format.hpp"

namespace reposetwin::experiments {

void validate_target(const Target& target) {
  auto num = [](double v) { return significant(v, 10); };
  if (!std::isfinite(target.angle_deg) || target.angle_deg <= 0.0 || target.angle_deg >= 90.0)
    throw std::invalid_argument("calibration: target angle_deg = " + num(target.angle_deg) +
                                " is outside (0, 90) degrees");
  if (!std::isfinite(target.sd_deg) || target.sd_deg < 0.0)
    throw std::invalid_argument("calibration: target sd_deg = " + num(target.sd_deg) +
                                " must be a finite value >= 0");
}

void validate_bracket_settings(const BracketSettings& s) {
  auto num = [](double v) { return significant(v, 6); };
  if (!std::isfinite(s.mu_r_lo) || !std::isfinite(s.mu_r_hi) || s.mu_r_lo < 0.0 ||
      s.mu_r_hi <= s.mu_r_lo)
    throw std::invalid_argument("calibration: mu_r range [" + num(s.mu_r_lo) + ", " +
                                num(s.mu_r_hi) + "] is invalid (need 0 <= lo < hi)");
  if (s.mu_r_start && !(*s.mu_r_start >= s.mu_r_lo && *s.mu_r_start <= s.mu_r_hi))
    throw std::invalid_argument("calibration: mu_r_start = " + num(*s.mu_r_start) +
                                " is outside the mu_r range [" + num(s.mu_r_lo) + ", " +
                                num(s.mu_r_hi) + "]");
  if (!(s.slope_guess_deg > 0.0) || !std::isfinite(s.slope_guess_deg))
    throw std::invalid_argument("calibration: slope_guess_deg = " + num(s.slope_guess_deg) +
                                " must be > 0 (deg per unit mu_r)");
  if (std::set<std::uint64_t>(s.seeds.begin(), s.seeds.end()).size() < 2 ||
      s.seeds.size() != std::set<std::uint64_t>(s.seeds.begin(), s.seeds.end()).size())
    throw std::invalid_argument(
        "calibration: the bracketing driver needs at least two distinct "
        "seeds (the seed spread is its stop rule); it has " +
        std::to_string(s.seeds.size()));
  if (!(s.mu_r_tolerance > 0.0) || !std::isfinite(s.mu_r_tolerance))
    throw std::invalid_argument("calibration: mu_r_tolerance = " + num(s.mu_r_tolerance) +
                                " must be > 0");
  if (s.max_runs < 2 * static_cast<int>(s.seeds.size()))
    throw std::invalid_argument("calibration: max_simulations = " + std::to_string(s.max_runs) +
                                " is below the " + std::to_string(2 * s.seeds.size()) +
                                " pours of two points");
  if (!(s.max_jam_rate >= 0.0 && s.max_jam_rate < 1.0))
    throw std::invalid_argument("calibration: max_jam_rate = " + num(s.max_jam_rate) +
                                " must lie in [0, 1)");
}

}  // namespace reposetwin::experiments
