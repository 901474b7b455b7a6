#include "orthofront/spacetime/bulk_flow_map.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstring>

namespace orthofront::spacetime {

CachedSteps::CachedSteps(BrickCache& cache) : cache_(cache) {
  // What acquire() pins at once beside the band: one group of bricks being gathered. (A step of
  // one unit lies in the band already: the band holds the steps a front samples.)
  const std::size_t bricks = cache.layout().bricks();
  if (bricks > 1) cache.reserve_units(std::min(bricks, kGatherBricks));
}

const float* CachedSteps::acquire(std::size_t step) {
  if (const auto it = held_.find(step); it != held_.end()) return it->second.data;
  const io::BrickLayout& layout = cache_.layout();
  const GridGeometry& g = geometry();
  const auto c = static_cast<std::size_t>(components());
  const auto key = [&](std::size_t b) {
    return BrickKey{static_cast<std::uint32_t>(step), static_cast<std::uint32_t>(b)};
  };
  Held h;
  if (layout.bricks() == 1 && layout.size == g.size) {
    const BrickKey whole = key(0);
    h.pins = cache_.acquire_all(std::span<const BrickKey>(&whole, 1));
    h.data = h.pins.front().data();
    return held_.emplace(step, std::move(h)).first->second.data;
  }
  h.gathered.resize(g.point_count() * c);
  gather(step, h.gathered.data());
  h.data = h.gathered.data();
  return held_.emplace(step, std::move(h)).first->second.data;
}

void CachedSteps::copy_step(std::size_t step, float* to) {
  const io::BrickLayout& layout = cache_.layout();
  const bool held = held_.count(step) > 0;
  if (held || (layout.bricks() == 1 && layout.size == geometry().size)) {
    advect::copy_floats(acquire(step), to, geometry().point_count() * static_cast<std::size_t>(components()));
    if (!held) release(step);  // a step held by acquire() stays held
    return;
  }
  gather(step, to);
}

void CachedSteps::gather(std::size_t step, float* to) {
  const io::BrickLayout& layout = cache_.layout();
  const GridGeometry& g = geometry();
  const auto c = static_cast<std::size_t>(components());
  const auto key = [&](std::size_t b) {
    return BrickKey{static_cast<std::uint32_t>(step), static_cast<std::uint32_t>(b)};
  };
  // Rows of each brick into their place in the step (edge bricks are padded past the grid), a
  // group of bricks at a time: beside a path surface's band, the cache need not hold a whole step.
  const std::size_t bricks = layout.bricks();
  for (std::size_t first = 0; first < bricks; first += kGatherBricks) {
    const std::size_t last = std::min(bricks, first + kGatherBricks);
    std::vector<BrickKey> keys;
    for (std::size_t b = first; b < last; ++b) keys.push_back(key(b));
    // The handles come resident units first: each is placed by its own key.
    const std::vector<BrickCache::Handle> pins = cache_.acquire_all(keys);
    // Bricks fill disjoint parts of the step: in parallel.
    tbb::parallel_for(std::size_t{0}, pins.size(), [&](std::size_t p) {
      const BrickCache::Handle& pin = pins[p];
      const auto index = static_cast<std::int64_t>(pin.key().brick);
      const std::int64_t bi = index % layout.count[0];
      const std::int64_t bj = index / layout.count[0] % layout.count[1];
      const std::int64_t bk = index / (layout.count[0] * layout.count[1]);
      const float* brick = pin.data();
      const std::int64_t i0 = bi * layout.size[0], j0 = bj * layout.size[1], k0 = bk * layout.size[2];
      const std::int64_t ni = std::min(layout.size[0], g.size[0] - i0);
      for (std::int64_t k = 0; k < std::min(layout.size[2], g.size[2] - k0); ++k)
        for (std::int64_t j = 0; j < std::min(layout.size[1], g.size[1] - j0); ++j) {
          const std::size_t from =
              static_cast<std::size_t>((k * layout.size[1] + j) * layout.size[0]) * c;
          std::memcpy(to + g.index(i0, j0 + j, k0 + k) * c, brick + from,
                      static_cast<std::size_t>(ni) * c * sizeof(float));
        }
    });
  }
}

void CachedSteps::release(std::size_t step) { held_.erase(step); }

BulkFlowMap::BulkFlowMap(advect::StepSource& steps, std::unique_ptr<advect::BatchAdvector> backend,
                         advect::MethodOptions method)
    : steps_(steps), backend_(std::move(backend)), method_(method), name_(backend_->name()) {}

Advected BulkFlowMap::advect(const Vec3& x, double t0, double t1) const {
  Vec3 p = x;
  ParticleStatus status = ParticleStatus::moving;
  const std::size_t evaluations = advect_all(std::span<Vec3>(&p, 1), std::span<const double>(&t0, 1), t1,
                                             std::span<ParticleStatus>(&status, 1));
  Advected out;
  out.x = p;
  out.status = status;
  out.t = status == ParticleStatus::moving ? t1 : t0;
  out.evaluations = static_cast<int>(evaluations);
  return out;
}

std::unique_lock<std::mutex> BulkFlowMap::call_lock() const {
  std::unique_lock lock(call_mutex_, std::defer_lock);
  if (backend_->max_concurrent_calls() <= 1) lock.lock();
  return lock;
}

std::size_t BulkFlowMap::advect_all(std::span<Vec3> x, std::span<const double> t0, double t1,
                                    std::span<ParticleStatus> status) const {
  const std::unique_lock call = call_lock();
  std::unique_ptr<advect::ParticleBatch> taken;
  {
    std::lock_guard lock(mutex_);
    if (batches_.empty()) {
      taken = std::make_unique<advect::ParticleBatch>();
    } else {
      taken = std::move(batches_.back());
      batches_.pop_back();
    }
  }
  // Back into the pool however the call ends.
  struct PutBack {
    const BulkFlowMap& map;
    std::unique_ptr<advect::ParticleBatch>& batch;
    ~PutBack() {
      std::lock_guard lock(map.mutex_);
      map.batches_.push_back(std::move(batch));
    }
  } put_back{*this, taken};
  advect::ParticleBatch& batch = *taken;
  batch.resize(x.size());
  const auto each = [n = x.size()](auto&& f) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 16384),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t i = r.begin(); i != r.end(); ++i) f(i);
                      });
  };
  each([&](std::size_t i) {
    for (int d = 0; d < 3; ++d) batch.x[static_cast<std::size_t>(d)][i] = x[i][d];
    batch.t[i] = t0[i];
    batch.h[i] = 0;
    batch.evaluations[i] = 0;
    batch.status[i] = ParticleStatus::moving;
  });
  const advect::AdvectionStatistics s = backend_->advect(steps_, batch, t1, method_);
  each([&](std::size_t i) {
    for (int d = 0; d < 3; ++d) x[i][d] = batch.x[static_cast<std::size_t>(d)][i];
    status[i] = batch.status[i];
  });
  std::lock_guard lock(mutex_);
  total_ += s;
  batch_total_ += s;
  return s.evaluations;
}

std::unique_ptr<advect::ResidentParticles> BulkFlowMap::make_resident() const {
  std::lock_guard lock(mutex_);
  return backend_->make_resident();
}

std::size_t BulkFlowMap::advance(advect::ResidentParticles& particles, double t0, double t1) const {
  const std::unique_lock call = call_lock();
  const advect::AdvectionStatistics s = particles.advance(steps_, t0, t1, method_);
  std::lock_guard lock(mutex_);
  total_ += s;
  return s.evaluations;
}

advect::AdvectionStatistics BulkFlowMap::statistics() const {
  std::lock_guard lock(mutex_);
  return total_;
}

advect::AdvectionStatistics BulkFlowMap::batch_statistics() const {
  std::lock_guard lock(mutex_);
  return batch_total_;
}

}  // namespace orthofront::spacetime
