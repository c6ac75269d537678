// HugePageAllocator: large arrays are 2 MiB aligned (so they can sit on huge pages), small ones
// are ordinary, and both behave as std::vector (values, copies, growth across the threshold).
#include "sim/huge_pages.hpp"

#include <gtest/gtest.h>

#include <cstdint>

#include "sim/contact.hpp"

namespace reposetwin::sim {
namespace {

std::uintptr_t address(const void* p) { return reinterpret_cast<std::uintptr_t>(p); }

TEST(HugePages, LargeArraysAreHugePageAlignedSmallOnesAreNot) {
  const std::size_t large = kHugeArrayMinBytes / sizeof(Vec3) + 1;
  HugeVector<Vec3> a(large, Vec3(1, 2, 3));
  EXPECT_EQ(address(a.data()) % kHugePageBytes, 0u);
  // Below the threshold the standard allocator is used (alignment of an ordinary allocation).
  HugeVector<double> small(16, 1.0);
  EXPECT_NE(address(small.data()) % kHugePageBytes, 0u);
}

TEST(HugePages, BehavesAsAVector) {
  HugeVector<std::int32_t> v;
  const std::size_t n = 3 * kHugeArrayMinBytes / sizeof(std::int32_t);  // grows across it
  for (std::size_t i = 0; i < n; ++i) v.push_back(static_cast<std::int32_t>(i * 7));
  EXPECT_EQ(address(v.data()) % kHugePageBytes, 0u);
  HugeVector<std::int32_t> copy = v;
  ASSERT_EQ(copy.size(), n);
  EXPECT_NE(copy.data(), v.data());
  for (std::size_t i = 0; i < n; i += 997) EXPECT_EQ(copy[i], static_cast<std::int32_t>(i * 7));
  copy.resize(10);  // shrinking keeps the values in front
  copy.shrink_to_fit();
  EXPECT_EQ(copy.back(), 63);
  HugeVector<std::int32_t> moved = std::move(v);
  EXPECT_EQ(moved[n - 1], static_cast<std::int32_t>((n - 1) * 7));
}

}  // namespace
}  // namespace reposetwin::sim
