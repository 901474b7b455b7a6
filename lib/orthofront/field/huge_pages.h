#pragma once
/// Transparent huge pages for large sample buffers. Interpolating a grid of hundreds of MiB, or
/// filling one from disk, in 4 KiB pages costs a TLB miss per cell lookup of a long front and a
/// page fault per 4 KiB read; 2 MiB pages remove most of both. Linux only; a no-op elsewhere.
#include <cstddef>
#include <cstdint>
#include <vector>

#ifdef __linux__
#include <sys/mman.h>
#endif

namespace orthofront {

/// Asks the kernel to back the whole 2 MiB pages inside [data, data + bytes) with huge pages.
/// Call before the memory is first touched; harmless when the system says no.
inline void advise_huge_pages(const void* data, std::size_t bytes) {
#ifdef __linux__
  constexpr std::uintptr_t huge = std::uintptr_t{2} << 20;
  const auto begin = reinterpret_cast<std::uintptr_t>(data);
  const std::uintptr_t first = (begin + huge - 1) & ~(huge - 1);
  const std::uintptr_t last = (begin + bytes) & ~(huge - 1);
  if (last > first) ::madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
#else
  (void)data, (void)bytes;
#endif
}

/// Reserves `count` elements of `values` on huge pages (then resize() touches them).
template <class T, class Allocator>
void reserve_huge_pages(std::vector<T, Allocator>& values, std::size_t count) {
  if (values.capacity() >= count) return;
  values.reserve(count);
  advise_huge_pages(values.data(), count * sizeof(T));
}

}  // namespace orthofront
