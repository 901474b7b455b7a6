#include "orthofront/advect/resident_particles.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <vector>
#include <functional>
#include <string>

#include "orthofront/advect/advect_call.h"
#include "orthofront/error.h"

namespace orthofront::advect {
namespace {

/// Parked slots are marked time_bounds: no advect() moves them.
constexpr ParticleStatus kParked = ParticleStatus::time_bounds;

class HostResidentParticles final : public ResidentParticles {
 public:
  explicit HostResidentParticles(BatchAdvector& backend) : backend_(backend) {}

  void place(std::span<const std::uint32_t> slots, std::span<const std::array<double, 3>> x) override {
    check_placement(slots, x);
    if (slots.empty()) return;
    const std::size_t end = std::size_t{largest_slot(slots)} + 1;
    if (end > batch_.size()) {
      const std::size_t old = batch_.size();
      batch_.resize(std::max(end, old + old / 2));
      std::fill(batch_.status.begin() + static_cast<std::ptrdiff_t>(old), batch_.status.end(), kParked);
    }
    const auto put = [&](std::size_t i) {
      const std::size_t s = slots[i];
      for (std::size_t d = 0; d < 3; ++d) batch_.x[d][s] = x[i][d];
      batch_.status[s] = ParticleStatus::moving;
    };
    if (!placeable_in_parallel(slots, end)) {
      for (std::size_t i = 0; i < slots.size(); ++i) put(i);
      return;
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, slots.size(), 16384),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t i = r.begin(); i != r.end(); ++i) put(i);
                      });
  }

  void park(std::span<const std::uint32_t> slots) override {
    for (const std::uint32_t s : slots)
      if (s < batch_.size()) batch_.status[s] = kParked;
  }

  AdvectionStatistics advance(StepSource& source, double t_begin, double t_end,
                              const MethodOptions& options) override {
    check_method(options);
    plan_resident(source.times(), t_begin, t_end);
    const std::size_t moving = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, batch_.size(), 16384), std::size_t{0},
        [&](const tbb::blocked_range<std::size_t>& r, std::size_t count) {
          for (std::size_t i = r.begin(); i != r.end(); ++i) {
            if (batch_.status[i] != ParticleStatus::moving) continue;
            batch_.t[i] = t_begin;
            batch_.h[i] = 0;
            batch_.evaluations[i] = 0;
            ++count;
          }
          return count;
        },
        std::plus<>());
    if (moving == 0) return {};  // no step is read
    AdvectionStatistics stats = backend_.advect(source, batch_, t_end, options);
    stats.particles = moving;  // not the parked slots
    return stats;
  }

  View view() const override {
    View v;
    for (std::size_t d = 0; d < 3; ++d) v.x[d] = batch_.x[d].data();
    v.status = batch_.status.data();
    v.size = batch_.size();
    return v;
  }

 private:
  BatchAdvector& backend_;
  ParticleBatch batch_;
};

}  // namespace

void check_placement(std::span<const std::uint32_t> slots, std::span<const std::array<double, 3>> x) {
  if (slots.size() != x.size())
    throw InvalidArgument("resident particles: " + std::to_string(x.size()) + " positions for " +
                          std::to_string(slots.size()) + " slots");
}

bool placeable_in_parallel(std::span<const std::uint32_t> slots, std::size_t end) {
  if (slots.size() < kParallelPlacements) return false;
  std::vector<std::uint64_t> seen((end + 63) / 64, 0);  // a bit a slot
  return !tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, slots.size(), 16384), false,
      [&](const tbb::blocked_range<std::size_t>& r, bool repeated) {
        for (std::size_t i = r.begin(); i != r.end() && !repeated; ++i) {
          const std::uint64_t bit = std::uint64_t{1} << (slots[i] % 64);
          repeated = (std::atomic_ref(seen[slots[i] / 64]).fetch_or(bit, std::memory_order_relaxed) & bit) != 0;
        }
        return repeated;
      },
      [](bool a, bool b) { return a || b; });
}

std::uint32_t largest_slot(std::span<const std::uint32_t> slots) {
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, slots.size(), 65536), std::uint32_t{0},
      [&](const tbb::blocked_range<std::size_t>& r, std::uint32_t top) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) top = std::max(top, slots[i]);
        return top;
      },
      [](std::uint32_t a, std::uint32_t b) { return std::max(a, b); });
}

std::unique_ptr<ResidentParticles> make_host_resident_particles(BatchAdvector& backend) {
  return std::make_unique<HostResidentParticles>(backend);
}

std::unique_ptr<ResidentParticles> BatchAdvector::make_resident() {
  return make_host_resident_particles(*this);
}

}  // namespace orthofront::advect
