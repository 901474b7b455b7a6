#include "orthofront/spacetime/bulk_front_integrator.h"

#include <algorithm>
#include <limits>

#include "orthofront/spacetime/bulk_flow_map.h"

namespace orthofront::spacetime {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}  // namespace

SharedBulkAdvance::SharedBulkAdvance(BrickCache& cache, advect::Device device,
                                     std::size_t device_bytes, bool merge,
                                     std::size_t concurrent_calls)
    : device_(device), device_bytes_(device_bytes), merge_(merge),
      concurrent_calls_(concurrent_calls),
      steps_(std::make_unique<CachedSteps>(cache)) {
  // Asked for by name: a missing device is an error at the start.
  if (device_ != advect::Device::auto_select) backend();
}

SharedBulkAdvance::~SharedBulkAdvance() = default;

advect::StepSource& SharedBulkAdvance::steps() { return *steps_; }

std::shared_ptr<advect::BatchAdvector> SharedBulkAdvance::backend() {
  std::lock_guard lock(mutex_);
  if (!made_) {
    made_ = true;
    if (device_ != advect::Device::auto_select || advect::cuda_available())
      backend_ = std::make_shared<advect::MergingAdvector>(
          advect::make_advector(device_ == advect::Device::auto_select ? advect::Device::cuda
                                                                       : device_,
                                device_bytes_),
          merge_, concurrent_calls_);
  }
  return backend_;
}

std::size_t SharedBulkAdvance::concurrent_calls() {
  std::lock_guard lock(mutex_);
  return backend_ ? backend_->concurrent_calls() : 0;
}

std::optional<advect::MergeStatistics> SharedBulkAdvance::merge_statistics() {
  std::lock_guard lock(mutex_);
  if (!backend_) return std::nullopt;
  return backend_->merge_statistics();
}

template <int N>
BulkFrontIntegrator<N>::BulkFrontIntegrator(advect::StepSource& steps,
                                            std::shared_ptr<advect::BatchAdvector> backend,
                                            BulkFrontOptions options)
    : BulkFrontIntegrator(steps, BackendFactory(), options) {
  backend_ = std::move(backend);
}

template <int N>
BulkFrontIntegrator<N>::BulkFrontIntegrator(advect::StepSource& steps, BackendFactory make_backend,
                                            BulkFrontOptions options)
    : steps_(steps), make_backend_(std::move(make_backend)), options_(options), lo_(kInf),
      hi_(-kInf) {
  advect::check_method(options_.method);
  // The series bounds the surface's time range as the lifted field's domain does.
  const std::vector<double>& times = steps_.times();
  if (!times.empty()) {
    options_.times.begin = std::max(options_.times.begin, times.front());
    options_.times.end = std::min(options_.times.end, times.back());
  }
}

template <int N>
bool BulkFrontIntegrator<N>::integrate(std::span<const Vec<N>> x, std::span<const double> tau,
                                       std::span<IntegrationResult<N>> out) {
  if (!backend_ && make_backend_) {
    backend_ = make_backend_();
    make_backend_ = nullptr;  // asked once
    if (!backend_) options_.min_vertices = std::numeric_limits<std::size_t>::max();
  }
  if (!backend_) return false;
  set_unmoved<N>(x, out);
  // A batch moves one way in time: vertices that go back (negative α kept) get a call of their own.
  run(x, tau, out, true);
  run(x, tau, out, false);
  return true;
}

template <int N>
void BulkFrontIntegrator<N>::run(std::span<const Vec<N>> x, std::span<const double> tau,
                                 std::span<IntegrationResult<N>> out, bool forward) {
  const double c = options_.time_scale, t_ref = options_.time_origin;
  index_.clear();
  for (std::size_t i = 0; i < x.size(); ++i)
    if (forward ? tau[i] > 0 : tau[i] < 0) index_.push_back(i);
  if (index_.empty()) return;
  const std::size_t n = index_.size();
  batch_.stop.clear();
  batch_.resize(n);
  batch_.stop.resize(n);
  std::fill(batch_.h.begin(), batch_.h.end(), 0.0);
  std::fill(batch_.evaluations.begin(), batch_.evaluations.end(), 0u);
  std::fill(batch_.status.begin(), batch_.status.end(), advect::ParticleStatus::moving);
  double horizon = forward ? -kInf : kInf;
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = index_[k];
    for (int a = 0; a < 3; ++a) batch_.x[static_cast<std::size_t>(a)][k] = a < d ? x[i][a] : 0.0;
    const double t = x[i][d] / c + t_ref;
    // Pseudo-time along the lifted field is physical time (its last component is c = dτ/ds).
    const double end = std::clamp(t + tau[i], options_.times.begin, options_.times.end);
    batch_.t[k] = t;
    batch_.stop[k] = end;
    horizon = forward ? std::max(horizon, end) : std::min(horizon, end);
    lo_ = std::min({lo_, t, end});
    hi_ = std::max({hi_, t, end});
  }
  const advect::AdvectionStatistics s = backend_->advect(steps_, batch_, horizon, options_.method);
  ++calls_;
  total_ += s;

  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = index_[k];
    IntegrationResult<N>& r = out[i];
    const double t0 = x[i][d] / c + t_ref;
    const double t = batch_.t[k];
    for (int a = 0; a < d; ++a) r.x[a] = batch_.x[static_cast<std::size_t>(a)][k];
    r.evaluations = static_cast<int>(std::min<std::uint32_t>(
        batch_.evaluations[k], static_cast<std::uint32_t>(std::numeric_limits<int>::max())));
    switch (batch_.status[k]) {
      case advect::ParticleStatus::moving:
        // At its end: the whole span, or the surface's time range ended it first.
        r.status = t == t0 + tau[i] ? FieldStatus::inside : FieldStatus::outside;
        r.reached = r.status == FieldStatus::inside ? tau[i] : t - t0;
        r.x[d] = r.status == FieldStatus::inside ? x[i][d] + c * tau[i] : c * (t - t_ref);
        break;
      case advect::ParticleStatus::no_data:
        r.status = FieldStatus::no_data;
        r.reached = t - t0;
        r.x[d] = c * (t - t_ref);
        break;
      case advect::ParticleStatus::left_domain:
      case advect::ParticleStatus::time_bounds:
        r.status = FieldStatus::outside;
        r.reached = t - t0;
        r.x[d] = c * (t - t_ref);
        break;
    }
  }
}

template <int N>
std::pair<double, double> BulkFrontIntegrator<N>::take_time_range() {
  const std::pair<double, double> r{lo_, hi_};
  lo_ = kInf;
  hi_ = -kInf;
  return r;
}

template class BulkFrontIntegrator<3>;
template class BulkFrontIntegrator<4>;

}  // namespace orthofront::spacetime
