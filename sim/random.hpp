// Portable random numbers: the same seed gives the same sequence with every compiler and library.
//
// std::mt19937_64 is fully specified by the standard, but std::uniform_real_distribution and
// std::normal_distribution are not (libstdc++ and libc++ differ), so ReposeTwin draws its own
// variates from the raw engine output.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>

namespace reposetwin::sim {

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}

  /// Uniform in [0, 1), 53 random bits.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }

  /// Uniform in [a, b).
  double uniform(double a, double b) { return a + (b - a) * uniform(); }

  /// Standard normal by the Box-Muller transform (both variates used).
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u1 = uniform();
    while (u1 <= 0.0) u1 = uniform();
    const double u2 = uniform();
    const double r = std::sqrt(-2.0 * std::log(u1));
    const double a = 6.283185307179586476925 * u2;
    spare_ = r * std::sin(a);
    has_spare_ = true;
    return r * std::cos(a);
  }

  double normal(double mean, double sd) { return mean + sd * normal(); }

  /// Uniform integer in [0, n).
  std::uint64_t below(std::uint64_t n) { return static_cast<std::uint64_t>(uniform() * n) % n; }

 private:
  std::mt19937_64 engine_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace reposetwin::sim
