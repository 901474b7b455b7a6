// HugePageAllocator: large blocks start on a huge page; contents survive growth; the pages are
// huge where the system gives them.
#include <catch2/catch.hpp>

#include <cstdint>
#include <fstream>
#include <limits>
#include <new>
#include <sstream>
#include <string>
#include <vector>

#include "orthofront/huge_pages.h"
#include "orthofront/mesh/mesh.h"

using namespace orthofront;

namespace {

bool on_huge_page_boundary(const void* p) {
  return reinterpret_cast<std::uintptr_t>(p) % kHugePageBytes == 0;
}

/// The kernel's "AnonHugePages" of the mapping that holds `p`, in kB (-1: not found).
long anon_huge_kb_at(const void* p) {
  std::ifstream smaps("/proc/self/smaps");
  const auto at = reinterpret_cast<std::uintptr_t>(p);
  std::string line;
  bool inside = false;
  while (std::getline(smaps, line)) {
    std::uintptr_t lo = 0, hi = 0;
    char dash = 0;
    std::istringstream head(line);
    if (head >> std::hex >> lo >> dash >> hi && dash == '-') {
      inside = lo <= at && at < hi;
      continue;
    }
    if (inside && line.rfind("AnonHugePages:", 0) == 0) return std::stol(line.substr(14));
  }
  return -1;
}

/// Whether the system gives transparent huge pages to memory that asks (madvise or always).
bool huge_pages_on_request() {
  std::ifstream f("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string mode;
  std::getline(f, mode);
  return mode.find("[never]") == std::string::npos && !mode.empty();
}

/// The kernel's count of huge page faults that fell back to small pages (-1: unknown).
long huge_page_fallbacks() {
  std::ifstream vmstat("/proc/vmstat");
  std::string name;
  long value = 0;
  while (vmstat >> name >> value)
    if (name == "thp_fault_fallback") return value;
  return -1;
}

}  // namespace

TEST_CASE("huge pages: an array that grows by push_back keeps its values, large blocks aligned") {
  HugePageVector<double> values;
  std::vector<double> expected;
  bool saw_large = false;
  for (int i = 0; i < 600'000; ++i) {
    const double* before = values.data();
    values.push_back(0.5 * i);
    expected.push_back(0.5 * i);
    if (values.data() == before) continue;  // no new block
    if (values.capacity() * sizeof(double) >= kHugePageBlockBytes) {
      saw_large = true;
      CHECK(on_huge_page_boundary(values.data()));
    }
  }
  CHECK(saw_large);
  CHECK(values == expected);
  CHECK_FALSE(values == std::vector<double>(expected.begin(), expected.end() - 1));
  CHECK(std::vector<double>(values.begin(), values.end()) == expected);
}

TEST_CASE("huge pages: a surface's arrays are on huge pages where the system gives them") {
  const long fallbacks = huge_page_fallbacks();
  Mesh mesh;
  for (int i = 0; i < 300'000; ++i)
    mesh.add_vertex(Vec3(i, 0, 0), 0.1 * i, 1.0, 0.5, 0.0, 0, i);
  CHECK(on_huge_page_boundary(mesh.positions.data()));
  CHECK(on_huge_page_boundary(mesh.time.data()));
  CHECK(on_huge_page_boundary(mesh.step.data()));
  CHECK(mesh.positions[123'456] == Vec3(123'456, 0, 0));
  CHECK(mesh.step.back() == 299'999);
  if (!huge_pages_on_request()) {
    WARN("transparent huge pages are off here: not checked that the pages are huge");
    return;
  }
  if (huge_page_fallbacks() != fallbacks) {
    WARN("the system had no huge page free for some faults: not checked that the pages are huge");
    return;
  }
  // 300 k positions of 24 bytes: 7.2 MB, on whole huge pages once written.
  CHECK(anon_huge_kb_at(mesh.positions.data()) >= 6 * 1024);
}

TEST_CASE("huge pages: a block that cannot exist is refused, not wrapped to a small one") {
  HugePageAllocator<double> allocator;
  CHECK_THROWS_AS(allocator.allocate(std::numeric_limits<std::size_t>::max() / 4),
                  std::bad_array_new_length);
  double* small = allocator.allocate(16);
  small[15] = 1.0;
  allocator.deallocate(small, 16);
}
