// The α system solver against long double references (dense SVD, sparse Householder QR), and the
// damping choice of μ against interval arithmetic and brute-force minimax.
#include <Eigen/Dense>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseQR>
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstddef>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "orthofront/solve/alpha_solver.h"

namespace {

using orthofront::AlphaSolver;
using orthofront::choose_damping_mu;
using orthofront::DampingChoice;
using LongVector = Eigen::Matrix<long double, Eigen::Dynamic, 1>;
using LongMatrix = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;
using Rng = std::mt19937_64;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double uniform(Rng& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}
double random_sign(Rng& rng) {
  return uniform(rng, -1, 1) < 0 ? -1.0 : 1.0;
}

struct System {
  std::vector<double> p, q, r;
  int n() const { return static_cast<int>(p.size()) + 1; }
};

struct Solution {
  std::vector<double> alpha, kernel;
  AlphaSolver::Result result;
};

Solution solve(AlphaSolver& solver, const System& system) {
  Solution s;
  s.alpha.assign(system.p.size() + 1, kNaN);  // NaN: every entry must be written
  s.kernel.assign(system.p.size() + 1, kNaN);
  s.result = solver.solve(system.p, system.q, system.r, s.alpha, s.kernel);
  return s;
}

// Entries uniform in [-1, 1]: condition numbers grow quickly with n.
System general_random(int n, Rng& rng) {
  System s;
  for (int i = 0; i + 1 < n; ++i) {
    s.p.push_back(uniform(rng, -1, 1));
    s.q.push_back(uniform(rng, -1, 1));
    s.r.push_back(uniform(rng, -1, 1));
  }
  return s;
}

// Random signs and magnitudes, |p| > |q| in the first half and |p| < |q| in the second, so the
// kernel peaks in the middle and the condition number stays moderate at any n (a 1e-10
// comparison is then meaningful).
System peaked_random(int n, Rng& rng) {
  System s;
  for (int i = 0; i + 1 < n; ++i) {
    const double big = uniform(rng, 0.5, 2.0);
    const double small = big * uniform(rng, 0.6, 1.0);
    const bool growing = 2 * i < n - 1;
    s.p.push_back(random_sign(rng) * (growing ? big : small));
    s.q.push_back(random_sign(rng) * (growing ? small : big));
    s.r.push_back(uniform(rng, -1, 1));
  }
  return s;
}

// A nearly orthogonal front: p_i ~ -|v_i|^2, q_i ~ |v_{i+1}|^2, small errors r.
System front_like(int n, Rng& rng) {
  System s;
  auto speed2 = [n](int i) { return 1 + 0.5 * std::sin(6.0 * i / std::max(n - 1, 1)); };
  for (int i = 0; i + 1 < n; ++i) {
    s.p.push_back(-speed2(i) + 1e-2 * uniform(rng, -1, 1));
    s.q.push_back(speed2(i + 1) + 1e-2 * uniform(rng, -1, 1));
    s.r.push_back(1e-3 * uniform(rng, -1, 1));
  }
  return s;
}

LongVector to_long(const std::vector<double>& x) {
  LongVector v(static_cast<Eigen::Index>(x.size()));
  for (std::size_t i = 0; i < x.size(); ++i) v[static_cast<Eigen::Index>(i)] = x[i];
  return v;
}

LongVector apply(const System& s, const LongVector& x) {
  LongVector y(s.n() - 1);
  for (int i = 0; i + 1 < s.n(); ++i) {
    y[i] = static_cast<long double>(s.p[i]) * x[i] + static_cast<long double>(s.q[i]) * x[i + 1];
  }
  return y;
}

double row_scale(const System& s) {
  double scale = 0;
  for (std::size_t i = 0; i < s.p.size(); ++i) {
    scale = std::max(scale, std::abs(s.p[i]) + std::abs(s.q[i]));
  }
  return scale;
}

// The orientation rule of the solver: more positive than negative entries, ties by the sum.
LongVector oriented(LongVector k) {
  const auto positive = (k.array() > 0).count();
  const auto negative = (k.array() < 0).count();
  if (negative > positive || (negative == positive && k.sum() < 0)) k = -k;
  return k;
}

struct Reference {
  LongVector alpha, kernel;
  long double condition = 0;  // only from the SVD
};

// Pseudo-inverse solution and null vector of the dense matrix, by SVD in long double.
Reference dense_reference(const System& s) {
  const int n = s.n();
  LongMatrix m = LongMatrix::Zero(n - 1, n);
  for (int i = 0; i + 1 < n; ++i) {
    m(i, i) = s.p[i];
    m(i, i + 1) = s.q[i];
  }
  Eigen::JacobiSVD<LongMatrix> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Reference ref;
  ref.alpha = svd.solve(-to_long(s.r));
  ref.kernel = oriented(svd.matrixV().col(n - 1));
  ref.condition = svd.singularValues()[0] / svd.singularValues()[n - 2];
  return ref;
}

// The same from a sparse Householder QR of M^T (COLAMD-permuted) in long double: M^T P = Q R, so
// k = Q e_n and α^L = Q [R_1^{-T} P^T (-r); 0]. O(n), so it reaches n = 2000 quickly.
Reference sparse_reference(const System& s) {
  const int n = s.n();
  using Sparse = Eigen::SparseMatrix<long double>;
  std::vector<Eigen::Triplet<long double>> entries;
  for (int i = 0; i + 1 < n; ++i) {
    entries.emplace_back(i, i, s.p[i]);
    entries.emplace_back(i + 1, i, s.q[i]);
  }
  Sparse mt(n, n - 1);
  mt.setFromTriplets(entries.begin(), entries.end());
  mt.makeCompressed();
  Eigen::SparseQR<Sparse, Eigen::COLAMDOrdering<int>> qr(mt);
  REQUIRE(qr.info() == Eigen::Success);
  REQUIRE(qr.rank() == n - 1);
  LongVector e_n = LongVector::Zero(n);
  e_n[n - 1] = 1;
  Reference ref;
  ref.kernel = oriented(qr.matrixQ() * e_n);
  const LongVector rhs = qr.colsPermutation().transpose() * (-to_long(s.r));
  const Sparse r1t = Sparse(qr.matrixR().topLeftCorner(n - 1, n - 1)).transpose();
  LongVector z = LongVector::Zero(n);
  z.head(n - 1) = r1t.triangularView<Eigen::Lower>().solve(rhs);
  ref.alpha = qr.matrixQ() * z;
  return ref;
}

// Properties that hold at any conditioning (backward stability, orientation), then the forward
// comparison with a reference.
void check_solution(const System& s, const Solution& sol, const Reference& ref, double tolerance) {
  const int n = s.n();
  INFO("n = " << n << ", min_pivot = " << sol.result.min_pivot);
  REQUIRE(sol.result.ok);
  CHECK(sol.result.min_pivot > 0);
  CHECK(sol.result.min_pivot <= 1);
  const LongVector alpha = to_long(sol.alpha);
  const LongVector k = to_long(sol.kernel);
  const long double scale = row_scale(s);
  const LongVector r = to_long(s.r);

  CHECK(std::abs(k.norm() - 1) <= 1e-13L);
  CHECK(apply(s, k).norm() <= 1e-13L * scale);
  CHECK((apply(s, alpha) + r).norm() <= 1e-13L * (scale * alpha.norm() + r.norm()));
  CHECK(std::abs(alpha.dot(k)) <= 1e-13L * alpha.norm());
  const auto positive = (k.array() > 0).count();
  const auto negative = (k.array() < 0).count();
  CHECK((positive > negative || (positive == negative && k.sum() >= 0)));

  const long double alpha_error = (alpha - ref.alpha).norm() / ref.alpha.norm();
  const long double kernel_error = (k - ref.kernel / ref.kernel.norm()).norm();
  INFO("alpha error " << static_cast<double>(alpha_error) << ", kernel error "
                      << static_cast<double>(kernel_error));
  CHECK(alpha_error <= tolerance);
  CHECK(kernel_error <= tolerance);
}

long double max_speed_long(const std::vector<double>& a, const std::vector<double>& k,
                           const std::vector<double>& s, long double mu) {
  long double speed = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (s[i] > 0) speed = std::max(speed, std::abs(a[i] + mu * k[i]) * s[i]);
  }
  return speed;
}

// Largest μ with max_i |a_i + μ k_i| s_i <= level, by interval arithmetic in long double.
long double largest_admissible(const std::vector<double>& a, const std::vector<double>& k,
                               const std::vector<double>& s, long double level) {
  long double hi = std::numeric_limits<long double>::infinity();
  for (std::size_t i = 0; i < a.size(); ++i) {
    const long double ks = static_cast<long double>(k[i]) * s[i];
    if (s[i] == 0 || ks == 0) continue;
    const long double as = static_cast<long double>(a[i]) * s[i];
    hi = std::min(hi, ks > 0 ? (level - as) / ks : (-level - as) / ks);
  }
  return hi;
}

struct Damping {
  std::vector<double> a, k, s;
};

Damping random_damping(int n, Rng& rng, double zero_speed_share) {
  Damping d;
  for (int i = 0; i < n; ++i) {
    d.a.push_back(uniform(rng, -1, 1));
    d.k.push_back(uniform(rng, -1, 1));
    d.s.push_back(uniform(rng, 0, 1) < zero_speed_share ? 0.0 : uniform(rng, 0.1, 2.0));
  }
  return d;
}

}  // namespace

TEST_CASE("alpha solver matches long double references", "[solve]") {
  AlphaSolver solver;  // one workspace across growing and shrinking n
  for (const int n : {2000, 2, 3, 10, 100, 1000, 10, 2}) {
    Rng rng(static_cast<unsigned>(n) * 7919u);
    INFO("front-like and peaked random, n = " << n);
    for (const System& s : {front_like(n, rng), peaked_random(n, rng)}) {
      const Solution sol = solve(solver, s);
      check_solution(s, sol, sparse_reference(s), 1e-10);
      if (n <= 100) check_solution(s, sol, dense_reference(s), 1e-10);
    }
  }
  for (const int n : {2, 3, 10, 100}) {
    Rng rng(static_cast<unsigned>(n) * 104729u);
    for (int trial = 0; trial < 5; ++trial) {
      // Condition numbers reach 1e5 and more here; the comparison allows for it.
      const System s = general_random(n, rng);
      const Reference ref = dense_reference(s);
      const double tolerance = std::max(1e-10, 1e-14 * static_cast<double>(ref.condition));
      INFO("uniform random, n = " << n << ", condition " << static_cast<double>(ref.condition));
      check_solution(s, solve(solver, s), ref, tolerance);
      check_solution(s, solve(solver, s), sparse_reference(s), tolerance);
    }
  }
}

TEST_CASE("alpha solver is unaffected by row scaling and extreme magnitudes", "[solve]") {
  // Scaling row i (p_i, q_i, r_i) leaves the solution set, the kernel and α^L unchanged; the
  // rotations see the same angles, so the results must agree to rounding.
  AlphaSolver solver;
  Rng rng(17);
  for (const int n : {2, 10, 500}) {
    for (const System& base : {front_like(n, rng), peaked_random(n, rng)}) {
      const Solution unscaled = solve(solver, base);
      System scaled = base;
      for (std::size_t i = 0; i < scaled.p.size(); ++i) {
        const double pick = uniform(rng, 0, 3);
        const double factor = pick < 1 ? 1e-6 : (pick < 2 ? 1.0 : 1e6);
        scaled.p[i] *= factor;
        scaled.q[i] *= factor;
        scaled.r[i] *= factor;
      }
      INFO("n = " << n);
      const Solution sol = solve(solver, scaled);
      check_solution(scaled, sol, sparse_reference(base), 1e-10);
      const LongVector a0 = to_long(unscaled.alpha), a1 = to_long(sol.alpha);
      const LongVector k0 = to_long(unscaled.kernel), k1 = to_long(sol.kernel);
      CHECK((a1 - a0).norm() <= 1e-13L * a0.norm());
      CHECK((k1 - k0).norm() <= 1e-13L);

      // One row far out of range in the middle of the system: the squared recurrence gives up
      // part-way and the direct form starts over.
      if (n > 2) {
        for (const double factor : {1e-200, 1e200}) {
          System one_row = base;
          const std::size_t i = one_row.p.size() / 2;
          one_row.p[i] *= factor;
          one_row.q[i] *= factor;
          one_row.r[i] *= factor;
          INFO("row " << i << " scaled by " << factor);
          const Solution e = solve(solver, one_row);
          REQUIRE(e.result.ok);
          CHECK((to_long(e.alpha) - a0).norm() <= 1e-13L * a0.norm());
          CHECK((to_long(e.kernel) - k0).norm() <= 1e-13L);
        }
      }

      // Whole systems near the ends of the double range: the squares in the rotations would
      // underflow or overflow.
      for (const double factor : {1e-170, 1e170}) {
        System extreme = base;
        for (std::size_t i = 0; i < extreme.p.size(); ++i) {
          extreme.p[i] *= factor;
          extreme.q[i] *= factor;
          extreme.r[i] *= factor;
        }
        INFO("global factor " << factor);
        const Solution e = solve(solver, extreme);
        REQUIRE(e.result.ok);
        CHECK((to_long(e.alpha) - a0).norm() <= 1e-13L * a0.norm());
        CHECK((to_long(e.kernel) - k0).norm() <= 1e-13L);
      }
    }
  }
}

TEST_CASE("alpha solver: squares that underflow or lose digits leave nothing wrong", "[solve]") {
  // Cases the squared recurrence of the forward pass must hand to the direct one: each gives
  // the same solution as a copy with the offending row scaled into the normal range (scaling a
  // row leaves the solution unchanged).
  AlphaSolver solver;
  const auto same_as_scaled = [&](const System& s, std::size_t row, double factor) {
    System scaled = s;
    scaled.p[row] *= factor;
    scaled.q[row] *= factor;
    scaled.r[row] *= factor;
    const Solution a = solve(solver, s), b = solve(solver, scaled);
    REQUIRE(a.result.ok);
    REQUIRE(b.result.ok);
    CHECK((to_long(a.alpha) - to_long(b.alpha)).norm() <= 1e-13L * to_long(b.alpha).norm());
    CHECK((to_long(a.kernel) - to_long(b.kernel)).norm() <= 1e-13L);
  };
  // d = 0 exactly and a q whose square underflows: a pivot of 1e-200, not a zero column.
  same_as_scaled({{0, 1, 1}, {1e-200, 1, 1}, {0.5, -1, 2}}, 0, 1e200);
  // p^2 d^2 below the normal range (digits lost) brought back up by the division.
  same_as_scaled({{2e-145, 1e-15, 1}, {0, 0, 1}, {1, 2, 3}}, 0, 1e145);
  // Pivots from 1e-140 to 1e140, all squares in range: their ratio 1e-280 is not lost.
  const Solution wide = solve(solver, {{1e-140, 1e140}, {0, 0}, {1, 1}});
  REQUIRE(wide.result.ok);
  CHECK(wide.result.min_pivot == Approx(1e-280).epsilon(1e-12));
}

TEST_CASE("alpha solver stays exact on fronts of 100,000 vertices", "[solve][heavy]") {
  // Rounding in the squared recurrence must not pile up along a long front.
  AlphaSolver solver;
  Rng rng(23);
  for (const System& s : {front_like(100'000, rng), peaked_random(100'000, rng)}) {
    const Solution sol = solve(solver, s);
    check_solution(s, sol, sparse_reference(s), 5e-14);
  }
}

TEST_CASE("alpha solver for n = 2 matches the closed form", "[solve]") {
  // M = [3 4]: α^L = -r (3, 4) / 25; k = ±(-4, 3) / 5, one entry of each sign, and the tie goes
  // to the positive sum.
  AlphaSolver solver;
  const System s{{3.0}, {4.0}, {5.0}};
  const Solution sol = solve(solver, s);
  REQUIRE(sol.result.ok);
  CHECK(sol.result.min_pivot == 1);
  CHECK(sol.alpha[0] == Approx(-0.6).epsilon(1e-15));
  CHECK(sol.alpha[1] == Approx(-0.8).epsilon(1e-15));
  CHECK(sol.kernel[0] == Approx(0.8).epsilon(1e-15));
  CHECK(sol.kernel[1] == Approx(-0.6).epsilon(1e-15));
}

TEST_CASE("alpha solver orients the kernel towards more positive entries", "[solve]") {
  AlphaSolver solver;
  struct Case {
    System system;
    std::vector<double> kernel;  // expected, before normalisation
  };
  const std::vector<Case> cases = {
      {{{1, 1}, {-1, 1}, {0.3, -0.2}}, {1, 1, -1}},                 // two of three positive
      {{{1, 1, 1}, {-2, 1, -1}, {0.1, 0.2, 0.3}}, {2, 1, -1, -1}},  // tie, positive sum
      {{{1, 5}, {-1, 1}, {0.5, 0.5}}, {1, 1, -5}},                  // more positive, negative sum
  };
  for (const Case& c : cases) {
    const LongVector expected = to_long(c.kernel).normalized();
    System negated = c.system;  // -M has the same kernel; its α^L is the one of -r
    for (double& x : negated.p) x = -x;
    for (double& x : negated.q) x = -x;
    const Solution a = solve(solver, c.system);
    const Solution b = solve(solver, negated);
    REQUIRE(a.result.ok);
    REQUIRE(b.result.ok);
    CHECK((to_long(a.kernel) - expected).norm() <= 1e-15L);
    CHECK((to_long(b.kernel) - expected).norm() <= 1e-15L);
    CHECK((to_long(a.alpha) + to_long(b.alpha)).norm() <= 1e-15L * to_long(a.alpha).norm());
  }
}

TEST_CASE("alpha solver reports rank deficiency and keeps its outputs meaningful", "[solve]") {
  // A zero pivot (rank < n-1) gives ok = false and min_pivot = 0. The kernel is still a unit
  // vector with M k = 0 and α ⟂ k; every equation except the one at the zero pivot holds, and
  // that one too when the system is consistent.
  AlphaSolver solver;
  struct Case {
    System system;
    int zero_pivot;
  };
  const std::vector<Case> cases = {
      {{{1, 2, 0, -1, 0.5}, {1, -1, 0, 2, 1}, {0.1, -0.2, 0.3, 0.4, -0.5}}, 2},  // zero row
      {{{0, 1, 2, 1.5, 1}, {1, -2, 1, 0, 1}, {0.1, -0.2, 0.3, 0.4, -0.5}}, 3},   // p_0 = q_3 = 0
      {{{1, 0}, {1, 0}, {0.25, 0.5}}, 1},                                        // last row zero
  };
  for (const Case& c : cases) {
    const int n = c.system.n();
    for (const bool consistent : {false, true}) {
      System s = c.system;
      if (consistent) {
        const LongVector target = LongVector::LinSpaced(n, 1.0L, 2.0L);
        const LongVector mx = apply(s, target);
        for (int i = 0; i + 1 < n; ++i) s.r[i] = -static_cast<double>(mx[i]);
      }
      INFO("zero pivot " << c.zero_pivot << (consistent ? ", consistent" : ""));
      const Solution sol = solve(solver, s);
      CHECK_FALSE(sol.result.ok);
      CHECK(sol.result.min_pivot == 0);
      const LongVector alpha = to_long(sol.alpha);
      const LongVector k = to_long(sol.kernel);
      CHECK(std::abs(k.norm() - 1) <= 1e-15L);
      CHECK(apply(s, k).norm() <= 1e-15L);
      CHECK(std::abs(alpha.dot(k)) <= 1e-15L * alpha.norm());
      const LongVector residual = apply(s, alpha) + to_long(s.r);
      for (int i = 0; i + 1 < n; ++i) {
        if (i != c.zero_pivot || consistent) CHECK(std::abs(residual[i]) <= 1e-14L);
      }
    }
  }
}

TEST_CASE("alpha solver handles n < 2 and rejects inconsistent sizes", "[solve]") {
  AlphaSolver solver;
  std::vector<double> alpha(1, kNaN), kernel(1, kNaN);
  const std::vector<double> none;
  const AlphaSolver::Result one = solver.solve(none, none, none, alpha, kernel);
  CHECK_FALSE(one.ok);
  CHECK(alpha[0] == 0);
  CHECK(kernel[0] == 1);
  std::vector<double> empty;
  CHECK_FALSE(solver.solve(none, none, none, empty, empty).ok);

  const std::vector<double> two(2, 1.0), three(3, 1.0);
  std::vector<double> out3(3), out4(4);
  CHECK_NOTHROW(solver.solve(two, two, two, out3, out3));
  CHECK_THROWS_AS(solver.solve(two, three, two, out3, out3), std::invalid_argument);
  CHECK_THROWS_AS(solver.solve(two, two, two, out3, out4), std::invalid_argument);
  CHECK_THROWS_AS(solver.solve(two, two, two, out4, out3), std::invalid_argument);
}

TEST_CASE("damping mu: the largest admissible mu when one exists", "[damping]") {
  Rng rng(5);
  AlphaSolver solver;
  std::vector<Damping> sets;
  {  // α^L and k^+ of a front, speeds |v| along it
    const int n = 200;
    const Solution sol = solve(solver, front_like(n, rng));
    Damping d{sol.alpha, sol.kernel, {}};
    for (int i = 0; i < n; ++i) d.s.push_back(std::sqrt(1 + 0.5 * std::sin(6.0 * i / (n - 1))));
    sets.push_back(d);
  }
  sets.push_back(random_damping(1000, rng, 0.1));
  for (const Damping& d : sets) {
    for (const double mu0 : {-0.5, 0.0, 0.3, 2.0}) {
      const double limit = static_cast<double>(1.05L * max_speed_long(d.a, d.k, d.s, mu0));
      INFO("n = " << d.a.size() << ", mu0 = " << mu0 << ", limit = " << limit);
      const DampingChoice c = choose_damping_mu(d.a, d.k, d.s, limit);
      const long double expected = largest_admissible(d.a, d.k, d.s, limit);
      CHECK(c.feasible);
      CHECK(c.mu > mu0);
      CHECK(std::abs(c.mu - expected) <= 1e-12L * std::abs(expected));
      const long double speed = max_speed_long(d.a, d.k, d.s, c.mu);
      CHECK(std::abs(speed - limit) <= 1e-12L * limit);
      CHECK(std::abs(c.max_speed - speed) <= 1e-15L * speed);
      const double beyond = c.mu + 1e-9 * std::max(1.0, std::abs(c.mu));
      CHECK(max_speed_long(d.a, d.k, d.s, beyond) > limit);
    }
  }
}

TEST_CASE("damping mu ignores vertices with zero speed", "[damping]") {
  Rng rng(11);
  const Damping d = random_damping(300, rng, 0.0);
  Damping padded;  // the same vertices, interleaved with still ones that would otherwise bind
  for (std::size_t i = 0; i < d.a.size(); ++i) {
    padded.a.push_back(d.a[i]);
    padded.k.push_back(d.k[i]);
    padded.s.push_back(d.s[i]);
    if (i % 3 == 0) {
      padded.a.push_back(i % 2 ? 1e6 : -1e6);
      padded.k.push_back(i % 4 ? 1e3 : 0.0);
      padded.s.push_back(0.0);
    }
  }
  for (const double limit : {5.0, 1e-3}) {  // feasible, infeasible
    const DampingChoice plain = choose_damping_mu(d.a, d.k, d.s, limit);
    const DampingChoice with_still = choose_damping_mu(padded.a, padded.k, padded.s, limit);
    CHECK(plain.feasible == (limit > 1));
    CHECK(with_still.feasible == plain.feasible);
    CHECK(with_still.mu == plain.mu);
    CHECK(with_still.max_speed == plain.max_speed);
  }
}

namespace {

// Exact minimax by enumeration: the minimum of max_i |A_i + μ K_i| lies where two of the 2n
// lines ±(A_i + μ K_i) cross. O(n^3).
long double brute_force_minimax(const Damping& d, long double& best_mu) {
  std::vector<long double> big_a, big_k;
  for (std::size_t i = 0; i < d.a.size(); ++i) {
    if (d.s[i] == 0) continue;
    big_a.push_back(static_cast<long double>(d.a[i]) * d.s[i]);
    big_k.push_back(static_cast<long double>(d.k[i]) * d.s[i]);
  }
  long double best = std::numeric_limits<long double>::infinity();
  for (std::size_t i = 0; i < big_a.size(); ++i) {
    for (std::size_t j = i; j < big_a.size(); ++j) {
      for (const long double sign : {-1.0L, 1.0L}) {
        const long double slope = big_k[i] - sign * big_k[j];
        if (slope == 0) continue;
        const long double mu = (sign * big_a[j] - big_a[i]) / slope;
        const long double f = max_speed_long(d.a, d.k, d.s, mu);
        if (f < best) {
          best = f;
          best_mu = mu;
        }
      }
    }
  }
  return best;
}

}  // namespace

TEST_CASE("damping mu: minimax mu when no mu meets the limit", "[damping]") {
  Rng rng(23);
  for (int trial = 0; trial < 20; ++trial) {
    const Damping d = random_damping(40, rng, 0.1);
    const double limit = 1e-2;
    long double best_mu = 0;
    const long double best = brute_force_minimax(d, best_mu);
    INFO("trial " << trial << ", brute-force mu " << static_cast<double>(best_mu));
    REQUIRE(best > limit);
    const DampingChoice c = choose_damping_mu(d.a, d.k, d.s, limit);
    CHECK_FALSE(c.feasible);
    CHECK(std::abs(c.mu - best_mu) <= 1e-12L * std::max(1.0L, std::abs(best_mu)));
    const long double speed = max_speed_long(d.a, d.k, d.s, c.mu);
    CHECK(speed <= best * (1 + 1e-14L));
    CHECK(std::abs(c.max_speed - speed) <= 1e-15L * speed);
    if (trial < 4) {  // a dense scan around the optimum finds nothing lower
      long double scan_min = std::numeric_limits<long double>::infinity();
      for (int step = -20000; step <= 20000; ++step) {
        scan_min = std::min(scan_min, max_speed_long(d.a, d.k, d.s, best_mu + step * 1e-4L));
      }
      CHECK(scan_min >= speed * (1 - 1e-14L));
    }
  }
}

TEST_CASE("damping mu: minimax over many nearly collinear breakpoints", "[damping]") {
  // Lines tangent to 1 + μ^2 at μ_i in [-0.9, 0.9]: their envelope has ~n breakpoints near the
  // optimum, the worst case for stepping from one pair of active lines to the next.
  Rng rng(31);
  const int n = 2000;
  Damping d;
  for (int i = 0; i < n; ++i) {
    const double mu_i = uniform(rng, -0.9, 0.9);
    const double s = uniform(rng, 0.5, 2.0);
    d.a.push_back((1 - mu_i * mu_i) / s);
    d.k.push_back(2 * mu_i / s);
    d.s.push_back(s);
  }
  const DampingChoice c = choose_damping_mu(d.a, d.k, d.s, 0.5);
  CHECK_FALSE(c.feasible);
  const long double speed = max_speed_long(d.a, d.k, d.s, c.mu);
  CHECK(speed <= 1);
  CHECK(std::abs(c.mu) <= 0.01);
  // Convex, so a local minimum is the global one.
  for (const long double delta : {1e-9L, 1e-7L, 1e-5L}) {
    CHECK(max_speed_long(d.a, d.k, d.s, c.mu + delta) >= speed * (1 - 1e-15L));
    CHECK(max_speed_long(d.a, d.k, d.s, c.mu - delta) >= speed * (1 - 1e-15L));
  }
  // Golden-section search in long double agrees.
  const long double golden = (std::sqrt(5.0L) - 1) / 2;
  long double lo = -1, hi = 1;
  for (int iteration = 0; iteration < 120; ++iteration) {
    const long double x1 = hi - golden * (hi - lo), x2 = lo + golden * (hi - lo);
    if (max_speed_long(d.a, d.k, d.s, x1) < max_speed_long(d.a, d.k, d.s, x2)) {
      hi = x2;
    } else {
      lo = x1;
    }
  }
  CHECK(std::abs(c.mu - (lo + hi) / 2) <= 1e-9L);
  CHECK(speed <= max_speed_long(d.a, d.k, d.s, (lo + hi) / 2) * (1 + 1e-15L));
}

TEST_CASE("damping mu: vertices the kernel does not move, and argument checks", "[damping]") {
  Rng rng(41);
  Damping d = random_damping(100, rng, 0.0);
  for (double& a : d.a) a *= 0.01;
  d.a.push_back(5.0);  // a moving vertex with k = 0: its speed 5 cannot be damped
  d.k.push_back(0.0);
  d.s.push_back(1.0);

  const DampingChoice over = choose_damping_mu(d.a, d.k, d.s, 1.0);
  CHECK_FALSE(over.feasible);
  CHECK(over.max_speed == Approx(5).epsilon(1e-14));
  const long double widest = largest_admissible(d.a, d.k, d.s, 5);  // all μ up to here are optimal
  CHECK(std::abs(over.mu - widest) <= 1e-12L * std::abs(widest));

  const DampingChoice under = choose_damping_mu(d.a, d.k, d.s, 10.0);
  CHECK(under.feasible);
  CHECK(std::abs(under.mu - largest_admissible(d.a, d.k, d.s, 10)) <= 1e-12L * under.mu);

  // Nothing bounds μ: the kernel vanishes on every moving vertex.
  const std::vector<double> a{0.5, 2, 3}, k{0, 0, 1}, s{1, 2, 0};
  const DampingChoice free_fast = choose_damping_mu(a, k, s, 3.0);
  CHECK(free_fast.mu == kInf);
  CHECK_FALSE(free_fast.feasible);
  CHECK(free_fast.max_speed == 4);
  const DampingChoice free_slow = choose_damping_mu(a, k, s, 4.5);
  CHECK(free_slow.mu == kInf);
  CHECK(free_slow.feasible);
  CHECK(free_slow.max_speed == 4);

  const std::vector<double> empty;
  CHECK(choose_damping_mu(empty, empty, empty, 1.0).feasible);
  CHECK_THROWS_AS(choose_damping_mu(a, k, s, 0.0), std::invalid_argument);
  CHECK_THROWS_AS(choose_damping_mu(a, k, s, -1.0), std::invalid_argument);
  CHECK_THROWS_AS(choose_damping_mu(a, k, s, kNaN), std::invalid_argument);
  CHECK_THROWS_AS(choose_damping_mu(a, k, empty, 1.0), std::invalid_argument);
}
