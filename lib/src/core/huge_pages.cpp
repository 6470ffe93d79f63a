#include "core/huge_pages.h"

#include <cstdint>
#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace lodkit::detail {

void advise_huge_pages(const void* data, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (data == nullptr || bytes < kHugePageBytes) return;
  // Out to whole huge pages: an allocation's first and last pages are shared with its neighbours, or
  // lie in a mapping that ends there (glibc's large blocks start 16 bytes into theirs). The advice is
  // only a hint for the pages it covers; parts of the range that are not mapped are passed over.
  constexpr std::uintptr_t kHuge = kHugePageBytes;
  const auto begin = reinterpret_cast<std::uintptr_t>(data);
  const std::uintptr_t first = begin & ~(kHuge - 1);
  const std::uintptr_t last = (begin + bytes + kHuge - 1) & ~(kHuge - 1);
  // A refusal (no THP in this kernel, or a hole in the range) leaves ordinary pages: no error.
  (void)madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
#else
  (void)data, (void)bytes;
#endif
}

}  // namespace lodkit::detail
