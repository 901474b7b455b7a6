#pragma once
/// Transparent huge pages for large buffers. Interpolating a grid of hundreds of MiB, or filling
/// one from disk, in 4 KiB pages costs a TLB miss per cell lookup of a long front and a page fault
/// per 4 KiB read; a mesh that grows to millions of vertices faults on every 4 KiB it first
/// writes. 2 MiB pages remove most of both. Linux only; a no-op elsewhere.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <new>
#include <vector>

#ifdef __linux__
#include <sys/mman.h>
#endif

namespace orthofront {

/// The size of a huge page, the alignment of a block on them.
inline constexpr std::size_t kHugePageBytes = std::size_t{2} << 20;

/// Asks the kernel to back the whole 2 MiB pages inside [data, data + bytes) with huge pages.
/// Call before the memory is first touched; harmless when the system says no.
inline void advise_huge_pages(const void* data, std::size_t bytes) {
#ifdef __linux__
  constexpr std::uintptr_t huge = kHugePageBytes;
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

/// The size from which a block is placed on huge pages of its own: half a page, so a block takes
/// at most twice its size (a surface's per-vertex arrays of 4 or 8 bytes pass 1 MiB at 128 k
/// and 256 k vertices).
inline constexpr std::size_t kHugePageBlockBytes = kHugePageBytes / 2;

/// std::allocator, but a block of kHugePageBlockBytes or more starts on a 2 MiB boundary and
/// fills whole huge pages, advised before they are touched: an array that grows by push_back
/// then faults 2 MiB at a time, the copies of each growth included (an unaligned block keeps its
/// ends, up to 4 MiB, in 4 KiB pages).
template <class T>
struct HugePageAllocator {
  using value_type = T;
  HugePageAllocator() = default;
  template <class U>
  HugePageAllocator(const HugePageAllocator<U>&) noexcept {}

  T* allocate(std::size_t n) {
    constexpr auto largest = static_cast<std::size_t>(std::numeric_limits<std::ptrdiff_t>::max());
    if (n > (largest - kHugePageBytes) / sizeof(T)) throw std::bad_array_new_length();
    const std::size_t bytes = n * sizeof(T);
    if (bytes < kHugePageBlockBytes) return std::allocator<T>{}.allocate(n);
    // Whole huge pages: the block's last bytes are not left in small ones.
    const std::size_t whole = (bytes + kHugePageBytes - 1) & ~(kHugePageBytes - 1);
    void* p = ::operator new(whole, std::align_val_t{kHugePageBytes});
    advise_huge_pages(p, whole);
    return static_cast<T*>(p);
  }
  void deallocate(T* p, std::size_t n) noexcept {
    if (n * sizeof(T) < kHugePageBlockBytes) {
      std::allocator<T>{}.deallocate(p, n);
      return;
    }
    ::operator delete(p, std::align_val_t{kHugePageBytes});
  }
  template <class U>
  bool operator==(const HugePageAllocator<U>&) const noexcept {
    return true;
  }
};

/// A growing array of HugePageAllocator.
template <class T>
using HugePageVector = std::vector<T, HugePageAllocator<T>>;

/// Equal to a std::vector with the same elements (the allocator is not part of the value).
template <class T>
bool operator==(const HugePageVector<T>& a, const std::vector<T>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end());
}

}  // namespace orthofront
