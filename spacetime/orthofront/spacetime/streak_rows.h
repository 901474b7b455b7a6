#pragma once
/// The rows of a streak surface over (s, τ): the particles released together at one time τ,
/// ordered by their seed parameter s. Two neighbouring rows join into a strip of faces by
/// walking both in s: a shared s closes a quad, otherwise the row whose next s comes first gives
/// a triangle; so the mesh stays conforming while rows are refined apart.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "orthofront/advect/particle_status.h"
#include "orthofront/field/unsteady.h"
#include "orthofront/mesh/mesh.h"
#include "orthofront/spacetime/length_limit.h"
#include "orthofront/types.h"

namespace orthofront::spacetime {

/// No slot in the resident particle set.
inline constexpr std::uint32_t kNoSlot = ~std::uint32_t{0};

/// Fewer particles than this are handled in turn: waking the threads costs more.
inline constexpr std::size_t kParallelParticles = 32768;

/// A particle of a row. Its slot in the resident set and its status share a word: 40 bytes
/// instead of 48, as the passes over the rows of ten million particles are bound by memory.
class StreakParticle {
 public:
  /// Slots are below this (where slots are handed out, more particles are refused).
  static constexpr std::uint32_t kSlots = (std::uint32_t{1} << 30) - 1;

  double s = 0;
  Vec3 x = Vec3::Zero();
  std::int32_t id = 0;

  advect::ParticleStatus status() const {
    return static_cast<advect::ParticleStatus>(word_ >> kSlotBits);
  }
  void set_status(advect::ParticleStatus status) {
    word_ = (word_ & kSlots) | (static_cast<std::uint32_t>(status) << kSlotBits);
  }
  bool alive() const { return word_ < (std::uint32_t{1} << kSlotBits); }  // status moving
  /// In the resident set (moving particles only), if there is one; else kNoSlot.
  std::uint32_t slot() const { return (word_ & kSlots) == kSlots ? kNoSlot : word_ & kSlots; }
  void set_slot(std::uint32_t slot) {
    word_ = (word_ & ~kSlots) | (slot == kNoSlot ? kSlots : slot);
  }

 private:
  static constexpr int kSlotBits = 30;
  static_assert(static_cast<unsigned>(advect::ParticleStatus::time_bounds) < 4, "two bits of status");
  std::uint32_t word_ = kSlots;  // status moving (0) in the top bits, no slot
};
static_assert(sizeof(StreakParticle) == 40);

struct StreakRow {
  double tau = 0;                  ///< release time
  std::vector<StreakParticle> p;   ///< by increasing s
  /// Coarsening's first candidate: no particle before it can go. Found by refinement's first
  /// pass (the row is in cache there), kept as particles are inserted after it; 1 when unknown.
  std::size_t coarsen_from = 1;
};

/// Runs f(r) for r in [0, n), rows in parallel (each row's work is independent of the others'),
/// or in turn where the work is too small to wake the threads for (`parallel` false).
template <class F>
void for_each_row(std::size_t n, const F& f, bool parallel = true) {
  if (!parallel) {
    for (std::size_t r = 0; r < n; ++r) f(r);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t r = range.begin(); r != range.end(); ++r) f(r);
                    });
}

/// The particles of all rows.
std::size_t particle_count(const std::vector<StreakRow>& rows);

/// The largest distance between the live particles of rows a and b that share a seed
/// parameter; or, as soon as one is longer than `stop` for certain, that one: callers only
/// compare the result with stop's limit, and rows that far apart are found out at their first
/// pair beyond.
double row_distance(const StreakRow& a, const StreakRow& b, const LengthLimit& stop);

/// Hands the faces of the strip between rows a and b to `face`, in order. va, vb: their
/// particles' vertices, -1 for stopped ones (faces with one are left out). Rows of a closed
/// seed curve close up: the strip also joins their last particles to their first.
template <class F>
void for_each_strip_face(const StreakRow& a, const StreakRow& b, bool closed,
                         const std::vector<std::int32_t>& va, const std::vector<std::int32_t>& vb,
                         const F& face) {
  const auto& A = a.p;
  const auto& B = b.p;
  const std::size_t na = A.size(), nb = B.size();
  const std::size_t ea = closed ? na : na - 1, eb = closed ? nb : nb - 1;
  const auto sa = [&](std::size_t i) { return i >= na ? A[i - na].s + 1.0 : A[i].s; };
  const auto sb = [&](std::size_t k) { return k >= nb ? B[k - nb].s + 1.0 : B[k].s; };
  std::size_t i = 0, k = 0;
  while (i < ea || k < eb) {
    const std::int32_t a0 = va[i % na], b0 = vb[k % nb];
    const bool step_a = i < ea && (k == eb || sa(i + 1) <= sb(k + 1));
    const bool step_b = k < eb && (i == ea || sb(k + 1) <= sa(i + 1));
    if (step_a && step_b) {
      const std::int32_t a1 = va[(i + 1) % na], b1 = vb[(k + 1) % nb];
      if (a0 >= 0 && a1 >= 0 && b1 >= 0 && b0 >= 0) face(Face{{a0, a1, b1, b0}, 4});
      ++i, ++k;
    } else if (step_a) {
      const std::int32_t a1 = va[(i + 1) % na];
      if (a0 >= 0 && a1 >= 0 && b0 >= 0) face(Face{{a0, a1, b0, -1}, 3});
      ++i;
    } else {
      const std::int32_t b1 = vb[(k + 1) % nb];
      if (a0 >= 0 && b1 >= 0 && b0 >= 0) face(Face{{a0, b1, b0, -1}, 3});
      ++k;
    }
  }
}

/// Writes the rows at time t into `mesh`: the live particles as vertices, row after row (with
/// release_time, s, age, speed in `flow` (2D: in the plane) and particle_id), and the strips
/// between neighbouring rows as faces, in row order. The mesh's arrays are reused where they
/// are large enough. Returns how many particles had stopped (no vertex).
std::size_t mesh_rows(const std::vector<StreakRow>& rows, bool closed, double t,
                      const UnsteadyField& flow, Mesh& mesh);

}  // namespace orthofront::spacetime
