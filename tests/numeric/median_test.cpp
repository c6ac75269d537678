// The one median of sim/ and vision/ (numeric/median.hpp): its documented rule for empty, odd
// and even samples, checked against a sort-based oracle on random samples.
#include "numeric/median.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace reposetwin::numeric {
namespace {

// The definition: sort, then the middle value or the mean of the two middle values.
double sorted_median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

TEST(Median, EmptyIsNaNOddIsTheMiddleEvenIsTheMeanOfTheTwoMiddle) {
  EXPECT_TRUE(std::isnan(median({})));
  EXPECT_EQ(median({7.0}), 7.0);
  EXPECT_EQ(median({3.0, -1.0, 2.0}), 2.0);
  EXPECT_EQ(median({4.0, 1.0}), 2.5);
  EXPECT_EQ(median({10.0, 1.0, 3.0, 2.0}), 2.5);  // not the upper middle 3, nor the lower 2
  EXPECT_EQ(median({5.0, 5.0, 1.0, 9.0}), 5.0);   // ties
  const std::vector<double> v = {3.0, 1.0, 2.0};
  (void)median(v);
  EXPECT_EQ(v, (std::vector<double>{3.0, 1.0, 2.0})) << "the caller's sample is not reordered";
}

TEST(Median, AgreesWithSortingOnRandomSamples) {
  std::uint64_t x = 88172645463325252ull;  // xorshift64: the same draws everywhere
  auto next = [&] {
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    return static_cast<double>(x % 1000) / 10.0;  // many ties among 1,000 values
  };
  for (std::size_t n = 1; n <= 40; ++n)
    for (int trial = 0; trial < 25; ++trial) {
      std::vector<double> v(n);
      for (double& e : v) e = next();
      EXPECT_EQ(median(v), sorted_median(v)) << "n " << n;
    }
}

}  // namespace
}  // namespace reposetwin::numeric
