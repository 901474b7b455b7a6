#pragma once
/// One particle through one slab: fixed-step RK4, or Dormand-Prince 5(4) with per-particle step
/// control (the controller of integrate/runge_kutta.h: same coefficients, growth and rejection
/// rules, no growth right after a rejection; the factor norm^(-1/5) by a fixed Newton
/// iteration). Written once for the CPU and a CUDA kernel: plain arrays, no Eigen, no exceptions.
#include <cstdint>

#include "orthofront/advect/particle_status.h"
#include "orthofront/advect/slab.h"
#include "orthofront/integrate/kinks.h"

namespace orthofront::advect {

enum class Method : unsigned char { rk4 = 0, dopri5 = 1 };

/// How particles are integrated (trivially copyable: kernels take it by value).
struct MethodOptions {
  Method method = Method::dopri5;
  double rk4_step = 0.01;       ///< RK4: largest step, time units (each slab span is cut evenly)
  double absolute = 1e-9;       ///< DOPRI5: error tolerance, world units
  double relative = 1e-9;
  std::uint32_t max_evaluations = 1'000'000;  ///< per particle and call; beyond it: no_data

  bool operator==(const MethodOptions&) const = default;
};

/// The state one thread advances: position, time, last accepted step size (DOPRI5's start in the
/// next slab), counters and status.
struct ParticleState {
  double x[3] = {0, 0, 0};
  double t = 0;
  double h = 0;
  std::uint32_t evaluations = 0;
  std::uint32_t steps = 0;  ///< accepted steps
  ParticleStatus status = ParticleStatus::moving;
};

namespace detail {

ORTHOFRONT_HD inline ParticleStatus stopped_by(SampleStatus s) {
  return s == SampleStatus::outside ? ParticleStatus::left_domain : ParticleStatus::no_data;
}

/// norm^(-1/5) for the step controller, from + - * only: scaled by powers of 32 (exact) into
/// [1, 32), then five Newton steps y <- y (6 - x y^5) / 5 for x^(-1/5) (no division: the chain is
/// multiplications) from a cubic in x within 12 % of it; the error about squares each step, so
/// five reach an ulp. IEEE arithmetic rounds these the same on the host and on a device (FMA
/// contraction off), where pow() may differ in the last bit: CPU and GPU then accept the same
/// steps. Outside [1e-5, 1e5] the controller clamps anyway.
ORTHOFRONT_HD inline double inverse_fifth_root(double norm) {
  double x = min_of(max_of(norm, 1e-5), 1e5), scale = 1;
  while (x >= 32) x *= 1.0 / 32, scale *= 0.5;
  while (x < 1) x *= 32, scale *= 2;
  // Least squares in the relative error of x^(-1/5) on [1, 32].
  double y = ((-2.8540615257565233e-05 * x + 0.0019249552067709173) * x - 0.04623515363461173) * x +
             0.930256075646323;
  for (int i = 0; i < 5; ++i) {
    const double y2 = y * y;
    y = y * (6.0 - x * (y2 * y2 * y)) * 0.2;
  }
  return y * scale;
}

}  // namespace detail

/// Advances p from p.t to t_end (both inside [s.t0, s.t1]) with n = ⌈|t_end - p.t| / step⌉ equal
/// RK4 steps. A stage outside the grid or without data stops the particle at the start of that
/// step with the matching status.
template <int Axes, int Components, bool Rectilinear>
ORTHOFRONT_HD inline void advance_rk4(const SlabView& s, ParticleState& p, double t_end,
                                      const MethodOptions& o) {
  const double span = t_end - p.t;
  if (span == 0) return;
  const double n_real = detail::abs_of(span) / o.rk4_step;
  std::int64_t n = static_cast<std::int64_t>(n_real);
  if (static_cast<double>(n) < n_real) ++n;
  if (n < 1) n = 1;
  const double dt = span / static_cast<double>(n);
  const double t_start = p.t;
  for (std::int64_t i = 0; i < n; ++i) {
    const double t = p.t;
    double k1[3], k2[3], k3[3], k4[3], y[3] = {p.x[0], p.x[1], p.x[2]};
    SampleStatus st = sample_slab<Axes, Components, Rectilinear>(s, p.x, t, k1);
    if (st == SampleStatus::inside) {
      for (int d = 0; d < 3; ++d) y[d] = p.x[d] + 0.5 * dt * k1[d];
      st = sample_slab<Axes, Components, Rectilinear>(s, y, t + 0.5 * dt, k2);
    }
    if (st == SampleStatus::inside) {
      for (int d = 0; d < 3; ++d) y[d] = p.x[d] + 0.5 * dt * k2[d];
      st = sample_slab<Axes, Components, Rectilinear>(s, y, t + 0.5 * dt, k3);
    }
    if (st == SampleStatus::inside) {
      for (int d = 0; d < 3; ++d) y[d] = p.x[d] + dt * k3[d];
      st = sample_slab<Axes, Components, Rectilinear>(s, y, t + dt, k4);
    }
    p.evaluations += 4;
    if (st != SampleStatus::inside) {
      p.status = detail::stopped_by(st);
      return;
    }
    for (int d = 0; d < Axes; ++d)
      p.x[d] += dt / 6.0 * (k1[d] + 2.0 * k2[d] + 2.0 * k3[d] + k4[d]);
    p.t = i + 1 == n ? t_end : t_start + static_cast<double>(i + 1) * dt;
    ++p.steps;
  }
}

/// Advances p from p.t to t_end (both inside [s.t0, s.t1]) with Dormand-Prince 5(4), starting
/// from the step size p.h the particle ended its last slab with (the whole span when 0).
template <int Axes, int Components, bool Rectilinear>
ORTHOFRONT_HD inline void advance_dopri5(const SlabView& s, ParticleState& p, double t_end,
                                         const MethodOptions& o) {
  constexpr double c2 = 1.0 / 5, c3 = 3.0 / 10, c4 = 4.0 / 5, c5 = 8.0 / 9;
  constexpr double a21 = 1.0 / 5;
  constexpr double a31 = 3.0 / 40, a32 = 9.0 / 40;
  constexpr double a41 = 44.0 / 45, a42 = -56.0 / 15, a43 = 32.0 / 9;
  constexpr double a51 = 19372.0 / 6561, a52 = -25360.0 / 2187, a53 = 64448.0 / 6561,
                   a54 = -212.0 / 729;
  constexpr double a61 = 9017.0 / 3168, a62 = -355.0 / 33, a63 = 46732.0 / 5247,
                   a64 = 49.0 / 176, a65 = -5103.0 / 18656;
  constexpr double b1 = 35.0 / 384, b3 = 500.0 / 1113, b4 = 125.0 / 192, b5 = -2187.0 / 6784,
                   b6 = 11.0 / 84;
  constexpr double e1 = 71.0 / 57600, e3 = -71.0 / 16695, e4 = 71.0 / 1920,
                   e5 = -17253.0 / 339200, e6 = 22.0 / 525, e7 = -1.0 / 40;

  const double tau = t_end - p.t;
  if (tau == 0) return;
  const double dir = tau > 0 ? 1.0 : -1.0;
  const double span = detail::abs_of(tau);
  double h = p.h > 0 ? detail::min_of(p.h, span) : span;
  const double h_min = span * 1e-12;
  const double t_start = p.t;
  const std::uint32_t budget = p.evaluations + o.max_evaluations;

  double k1[3], k2[3], k3[3], k4[3], k5[3], k6[3], k7[3], y[3], z[3];
  SampleStatus st = sample_slab<Axes, Components, Rectilinear>(s, p.x, p.t, k1);
  ++p.evaluations;
  if (st != SampleStatus::inside) {
    p.status = detail::stopped_by(st);
    return;
  }
  double done = 0;
  double planned = h;  // the controller's step before a cut to the span's end
  int rejections_in_row = 0;
  bool rejected_before = false;  // the last attempt was rejected: the next accepted one keeps h
  while (done < span) {
    // Cell-aware steps (integrate/kinks.h): end a step that would cross a cell face just past it.
    double step = h;
    bool clipped = false;
    {
      const double w[3] = {dir * k1[0], dir * k1[1], dir * k1[2]};
      const double face = detail::next_face<Axes, Rectilinear>(s.grid, p.x, w, kKinkMargin * h);
      if (face >= 0 && face + kKinkMargin * h < h) {
        step = face + kKinkMargin * h;
        clipped = true;
      }
    }
    bool last = false;
    planned = h;
    if (span - done <= step * (1 + 1e-12)) {
      step = span - done;
      last = true;
      clipped = false;
    }
    const double sh = dir * step;
    const double t = t_start + dir * done;
    for (int d = 0; d < 3; ++d) z[d] = p.x[d] + sh * (a21 * k1[d]);
    st = sample_slab<Axes, Components, Rectilinear>(s, z, t + c2 * sh, k2);
    if (st == SampleStatus::inside) {
      for (int d = 0; d < 3; ++d) z[d] = p.x[d] + sh * (a31 * k1[d] + a32 * k2[d]);
      st = sample_slab<Axes, Components, Rectilinear>(s, z, t + c3 * sh, k3);
    }
    if (st == SampleStatus::inside) {
      for (int d = 0; d < 3; ++d) z[d] = p.x[d] + sh * (a41 * k1[d] + a42 * k2[d] + a43 * k3[d]);
      st = sample_slab<Axes, Components, Rectilinear>(s, z, t + c4 * sh, k4);
    }
    if (st == SampleStatus::inside) {
      for (int d = 0; d < 3; ++d)
        z[d] = p.x[d] + sh * (a51 * k1[d] + a52 * k2[d] + a53 * k3[d] + a54 * k4[d]);
      st = sample_slab<Axes, Components, Rectilinear>(s, z, t + c5 * sh, k5);
    }
    if (st == SampleStatus::inside) {
      for (int d = 0; d < 3; ++d)
        z[d] = p.x[d] +
               sh * (a61 * k1[d] + a62 * k2[d] + a63 * k3[d] + a64 * k4[d] + a65 * k5[d]);
      st = sample_slab<Axes, Components, Rectilinear>(s, z, t + sh, k6);
    }
    if (st == SampleStatus::inside) {
      for (int d = 0; d < 3; ++d)
        y[d] = p.x[d] + sh * (b1 * k1[d] + b3 * k3[d] + b4 * k4[d] + b5 * k5[d] + b6 * k6[d]);
      st = sample_slab<Axes, Components, Rectilinear>(s, y, last ? t_end : t + sh, k7);
    }
    p.evaluations += 6;
    if (p.evaluations > budget) {
      p.status = ParticleStatus::no_data;
      return;
    }
    if (st != SampleStatus::inside) {
      h = 0.5 * step;
      if (h < h_min || ++rejections_in_row > 60) {
        p.status = detail::stopped_by(st);
        return;
      }
      continue;
    }
    double norm = 0;
    for (int d = 0; d < Axes; ++d) {
      const double err =
          sh * (e1 * k1[d] + e3 * k3[d] + e4 * k4[d] + e5 * k5[d] + e6 * k6[d] + e7 * k7[d]);
      const double scale =
          o.absolute + o.relative * detail::max_of(detail::abs_of(p.x[d]), detail::abs_of(y[d]));
      norm = detail::max_of(norm, detail::abs_of(err) / scale);
    }
    if (norm <= 1.0) {
      for (int d = 0; d < 3; ++d) {
        p.x[d] = y[d];
        k1[d] = k7[d];  // first same as last
      }
      done = last ? span : done + step;
      p.t = last ? t_end : t_start + dir * done;
      ++p.steps;
      rejections_in_row = 0;
      // The root only where it decides: not after the slab's last step (the planned step goes
      // on), nor where the growth is capped (0.9 norm^(-1/5) > 5.04 below 1.8e-4). A step cut
      // short at a face says nothing against the controller's size.
      if (last) {
        h = planned;
      } else {
        double next = step;
        if (!rejected_before)
          next *=
              norm < 1.8e-4 ? 5.0 : detail::min_of(5.0, 0.9 * detail::inverse_fifth_root(norm));
        else if (norm >= 1.8e-4)
          next *= detail::min_of(1.0, 0.9 * detail::inverse_fifth_root(norm));
        h = clipped ? detail::max_of(h, next) : next;
      }
      rejected_before = false;
    } else {
      rejected_before = true;
      // (0.9 norm^(-1/5) < 0.197 from 2000 on: the cut is capped at 0.2.)
      h = step *
          (norm >= 2000 ? 0.2 : detail::max_of(0.2, 0.9 * detail::inverse_fifth_root(norm)));
      if (h < h_min || ++rejections_in_row > 60) {
        p.status = ParticleStatus::no_data;  // step control failed: no usable flow
        return;
      }
    }
  }
  p.h = h;
}

/// True when a particle at time t moves inside the slab [t0, t1] on its way to t_end: the slab
/// holds t, the far end excluded (a particle on a step time belongs to the next slab it enters).
ORTHOFRONT_HD inline bool in_slab(double t0, double t1, bool forward, double t, double t_end) {
  if (t == t_end) return false;
  return forward ? (t >= t0 && t < t1) : (t <= t1 && t > t0);
}

/// Where a particle moving in slab [t0, t1] stops: t_end, or the slab's far end.
ORTHOFRONT_HD inline double slab_end(double t0, double t1, bool forward, double t_end) {
  return forward ? detail::min_of(t_end, t1) : detail::max_of(t_end, t0);
}

/// The method `o` names.
template <int Axes, int Components, bool Rectilinear>
ORTHOFRONT_HD inline void advance_particle(const SlabView& s, ParticleState& p, double t_end,
                                           const MethodOptions& o) {
  if (o.method == Method::rk4)
    advance_rk4<Axes, Components, Rectilinear>(s, p, t_end, o);
  else
    advance_dopri5<Axes, Components, Rectilinear>(s, p, t_end, o);
}

}  // namespace orthofront::advect
