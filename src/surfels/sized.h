// Sizing of large output arrays: reserve, advise transparent huge pages for the block (Linux),
// then value-initialise. Page faults dominate first touch of multi-100 MB arrays; huge pages cut
// their number by 512. Purely a performance hint: the contents are those of v.assign(n, value).
#pragma once

#include <sys/mman.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace adamesh::detail {

template <class T>
void sized(std::vector<T>& v, std::size_t n, const T& value = T{}) {
  v.clear();
  v.reserve(n);
#ifdef MADV_HUGEPAGE
  constexpr std::uintptr_t kHuge = std::uintptr_t{1} << 21;
  const auto begin = reinterpret_cast<std::uintptr_t>(v.data());
  const std::uintptr_t end = begin + n * sizeof(T);
  const std::uintptr_t lo = (begin + kHuge - 1) & ~(kHuge - 1), hi = end & ~(kHuge - 1);
  if (hi > lo) madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_HUGEPAGE);
#endif
  v.assign(n, value);
}

}  // namespace adamesh::detail
