#pragma once
/// A TimeSeries whose steps are an unsteady field sampled on a grid, computed when read: test
/// data and benchmark input of any size without a file.
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "orthofront/field/unsteady.h"
#include "orthofront/io/time_series.h"

namespace orthofront::spacetime {

class SampledTimeSeries : public io::TimeSeries {
 public:
  /// Non-owning: `flow` must outlive the series. `times` strictly increasing.
  SampledTimeSeries(const UnsteadyField& flow, GridGeometry grid, std::vector<double> times,
                    int components = 3)
      : flow_(flow), grid_(std::move(grid)), times_(std::move(times)), components_(components) {}

  std::size_t step_count() const override { return times_.size(); }
  double time(std::size_t step) const override { return times_.at(step); }
  const GridGeometry& geometry() const override { return grid_; }
  int components() const override { return components_; }
  std::string describe() const override { return "sampled " + flow_.describe(); }

  io::RawStep read_raw(std::size_t step) const override {
    io::RawStep raw;
    raw.step = step;
    std::vector<float> values(step_floats());
    sample(step, values.data());
    raw.bytes.resize(values.size() * sizeof(float));
    std::memcpy(raw.bytes.data(), values.data(), raw.bytes.size());
    return raw;
  }

  /// The floats of `step` (step_floats() of them), NaN outside the flow's domain; z-slices in
  /// parallel.
  void sample(std::size_t step, float* out) const {
    const double t = times_.at(step);
    const auto c = static_cast<std::size_t>(components_);
    tbb::parallel_for(std::int64_t{0}, grid_.size[2], [&](std::int64_t k) {
      for (std::int64_t j = 0; j < grid_.size[1]; ++j)
        for (std::int64_t i = 0; i < grid_.size[0]; ++i) {
          const Vec3 x(grid_.coordinate(0, i), grid_.coordinate(1, j), grid_.coordinate(2, k));
          Vec3 v;
          const bool ok = flow_.velocity(x, t, v) == FieldStatus::inside;
          float* p = out + grid_.index(i, j, k) * c;
          for (std::size_t a = 0; a < c; ++a)
            p[a] = ok ? static_cast<float>(v[static_cast<int>(a)])
                      : std::numeric_limits<float>::quiet_NaN();
        }
    });
  }

 private:
  const UnsteadyField& flow_;
  GridGeometry grid_;
  std::vector<double> times_;
  int components_;
};

/// Uniform grid over `box` (the first `dimension` axes) with `n` samples per axis.
inline GridGeometry uniform_grid(const Box<3>& box, int dimension, std::int64_t n) {
  GridGeometry g;
  g.dimension = dimension;
  for (int a = 0; a < 3; ++a) {
    const bool used = a < dimension;
    g.size[static_cast<std::size_t>(a)] = used ? n : 1;
    g.origin[a] = used ? box.lo[a] : 0.0;
    g.spacing[a] = used ? (box.hi[a] - box.lo[a]) / static_cast<double>(n - 1) : 1.0;
  }
  return g;
}

/// n + 1 equally spaced times from t0 to t1.
inline std::vector<double> uniform_times(double t0, double t1, std::size_t n) {
  std::vector<double> t(n + 1);
  for (std::size_t k = 0; k <= n; ++k)
    t[k] = t0 + (t1 - t0) * static_cast<double>(k) / static_cast<double>(n);
  return t;
}

}  // namespace orthofront::spacetime
