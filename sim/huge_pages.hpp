// Large arrays on transparent huge pages.
//
// Design note. The pair loop reads each partner's data from arrays of tens of megabytes at
// addresses that follow the neighbor list, not memory order. With 4 KiB pages a 50,000-sphere
// heap touches about ten thousand pages per step, more than the second-level TLB holds, so many
// reads first walk the page table. With 2 MiB pages the same arrays take a few dozen TLB entries
// (bench/README.md: 5-8% of the step on the standard heap, the results unchanged).
// Linux gives huge pages to a region only on request (madvise) under Debian's default setting
// (/sys/kernel/mm/transparent_hugepage/enabled = madvise): HugePageAllocator allocates arrays of
// at least kHugeArrayMinBytes aligned to 2 MiB and asks for huge pages before the first write;
// smaller arrays, and systems without transparent huge pages, get ordinary memory. Whether the
// kernel grants the request changes the speed, never a value.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <new>
#include <vector>

namespace reposetwin::sim {

inline constexpr std::size_t kHugePageBytes = std::size_t{2} << 20;  // [bytes]
/// Arrays from this size on are put on huge pages (at most one huge page each is partly unused).
inline constexpr std::size_t kHugeArrayMinBytes = std::size_t{128} << 10;  // [bytes]

/// Asks the kernel to back [p, p + bytes) with huge pages (no effect where unsupported).
void advise_huge_pages(void* p, std::size_t bytes);

/// std::allocator, except that arrays of at least kHugeArrayMinBytes are 2 MiB aligned and advised
/// for huge pages (advise_huge_pages) before anything is written to them.
template <class T>
struct HugePageAllocator {
  using value_type = T;
  HugePageAllocator() = default;
  template <class U>
  HugePageAllocator(const HugePageAllocator<U>&) {}

  T* allocate(std::size_t n) {
    constexpr std::size_t kMaxBytes = static_cast<std::size_t>(PTRDIFF_MAX) - kHugePageBytes;
    if (n > kMaxBytes / sizeof(T)) throw std::bad_array_new_length();
    const std::size_t bytes = n * sizeof(T);
    if (bytes < kHugeArrayMinBytes) return std::allocator<T>{}.allocate(n);
    const std::size_t rounded = (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
    void* p = std::aligned_alloc(kHugePageBytes, rounded);
    if (p == nullptr) throw std::bad_alloc();
    advise_huge_pages(p, rounded);
    return static_cast<T*>(p);
  }
  void deallocate(T* p, std::size_t n) {
    if (n * sizeof(T) < kHugeArrayMinBytes) {
      std::allocator<T>{}.deallocate(p, n);
      return;
    }
    std::free(p);
  }
  template <class U>
  bool operator==(const HugePageAllocator<U>&) const { return true; }
};

/// A std::vector whose storage, once large, is on huge pages.
template <class T>
using HugeVector = std::vector<T, HugePageAllocator<T>>;

}  // namespace reposetwin::sim
