#include "sim/huge_pages.hpp"

#include <sys/mman.h>

namespace reposetwin::sim {

void advise_huge_pages(void* p, std::size_t bytes) {
#ifdef MADV_HUGEPAGE
  // A refusal (no transparent huge pages, or disabled) leaves ordinary pages: nothing to report.
  (void)madvise(p, bytes, MADV_HUGEPAGE);
#else
  (void)p;
  (void)bytes;
#endif
}

}  // namespace reposetwin::sim
