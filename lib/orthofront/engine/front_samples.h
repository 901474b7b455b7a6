#pragma once
/// What a step asks of the field along a front before it moves it: v and |v| at each vertex
/// (advect.h's sampling), and the α system's coefficients from v and J at each segment's midpoint
/// (alpha_step.h). All of it is a function of the vertices' positions alone: evaluated ahead on
/// another thread (samples_ahead.h) or in place, it is the same bits.
#include <cmath>
#include <cstddef>
#include <vector>

#include "orthofront/engine/front.h"
#include "orthofront/field/field.h"

namespace orthofront {

/// The field at a front's vertices.
template <int N>
struct VertexSamples {
  std::vector<Vec<N>> vel;
  std::vector<double> speed;  ///< |v| where the field is inside, else 0
  std::vector<FieldStatus> status;

  void resize(std::size_t n) {
    vel.resize(n);
    speed.resize(n);
    status.resize(n);
  }
};

/// v, |v| and the status at vertices [b, e) of the positions `x(i)`.
template <int N, class Position>
void sample_vertices(const Field<N>& field, const Position& x, std::size_t b, std::size_t e,
                     VertexSamples<N>& out) {
  for (std::size_t i = b; i < e; ++i) {
    const FieldStatus st = field.velocity(x(i), out.vel[i]);
    out.status[i] = st;
    out.speed[i] = st == FieldStatus::inside ? out.vel[i].norm() : 0.0;
  }
}

/// The α system's coefficients per segment (segment i joins vertex i to the next, and the last
/// one of a closed front its last vertex to its first): p_i α_i + q_i α_{i+1} = -r_i.
template <int N>
struct SegmentTerms {
  std::vector<double> p, q, r;
  std::vector<double> err;  ///< orthogonality error |cos(segment, v at its midpoint)|
  std::vector<char> ok;     ///< v and J were found at the midpoint (else the rest is unset)

  void resize(std::size_t segments) {
    p.resize(segments);
    q.resize(segments);
    r.resize(segments);
    err.resize(segments);
    ok.resize(segments);
  }
};

/// The terms of segments [b, e) of the `n` positions `x(i)`, from the velocities `vel` at the
/// vertices and v and J at each segment's midpoint.
template <int N, class Position>
void segment_terms(const Field<N>& field, const Position& x, std::size_t n,
                   const std::vector<Vec<N>>& vel, std::size_t b, std::size_t e,
                   SegmentTerms<N>& out) {
  Vec<N> vm;
  Mat<N> jm;
  for (std::size_t i = b; i < e; ++i) {
    const std::size_t j = next_index(i, n);
    const Vec<N> d = x(j) - x(i);
    const Vec<N> mid = 0.5 * (x(i) + x(j));
    if (field.velocity_jacobian(mid, vm, jm) != FieldStatus::inside) {
      out.ok[i] = 0;
      continue;
    }
    out.ok[i] = 1;
    out.p[i] = 0.5 * d.dot(jm * vel[i]) - vel[i].dot(vm);
    out.q[i] = 0.5 * d.dot(jm * vel[j]) + vel[j].dot(vm);
    out.r[i] = d.dot(vm);
    const double denom = d.norm() * vm.norm();
    out.err[i] = denom > 0 ? std::abs(out.r[i]) / denom : 0.0;
  }
}

}  // namespace orthofront
