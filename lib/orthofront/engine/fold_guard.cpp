#include "orthofront/engine/fold_guard.h"

#include <algorithm>

namespace orthofront {

namespace {

/// Calls visit(a, b) for each edge of a face that joins two different vertices.
template <class Visit>
void for_each_edge(const Face& face, Visit&& visit) {
  for (std::size_t k = 0; k < face.size; ++k) {
    const std::int32_t a = face.v[k], b = face.v[k + 1 == face.size ? 0 : k + 1];
    if (a != b) visit(a, b);
  }
}

}  // namespace

template <class Payload>
void FoldGuard::EdgeLists<Payload>::clear() {
  if (++generation_ == 0) {  // wrapped: no old head may read as current
    for (Head& h : heads_) h.generation = 0;
    generation_ = 1;
  }
  entries_.clear();
  free_ = kNone;
  vertex_end_ = 0;
}

template <class Payload>
void FoldGuard::EdgeLists<Payload>::grow_heads() {
  heads_.resize(std::max(static_cast<std::size_t>(vertex_end_), 2 * heads_.size()));
}

template <class Payload>
bool FoldGuard::EdgeLists<Payload>::remove(std::int32_t a, std::int32_t b) {
  const auto [lo, hi] = ordered(a, b);
  if (hi >= vertex_end_ || covered_head(lo) == kNone) return false;
  for (std::uint32_t* link = &heads_[static_cast<std::size_t>(lo)].first; *link != kNone;
       link = &entries_[*link].next) {
    const std::uint32_t e = *link;
    if (entries_[e].other != hi) continue;
    *link = entries_[e].next;
    entries_[e].next = free_;
    free_ = e;
    return true;
  }
  return false;
}

std::vector<BoundaryEdge> FoldGuard::boundary() {
  std::vector<BoundaryEdge> out;
  open_.for_each([&](std::int32_t lo, const EdgeLists<OpenEdge>::Entry& e) {
    const auto face = static_cast<std::int32_t>(e.payload.face);
    out.push_back(e.payload.forward ? BoundaryEdge{lo, e.other, face}
                                    : BoundaryEdge{e.other, lo, face});
  });
  return out;
}

void FoldGuard::rebuild(const Mesh& mesh) {
  checked_first_ = 0;
  checked_normals_.clear();
  open_.clear();
  add_to_boundary(mesh, 0, mesh.faces.size());
}

void FoldGuard::accept(const Mesh& mesh, std::size_t first_face) {
  add_to_boundary(mesh, first_face, mesh.faces.size());
}

void FoldGuard::add_to_boundary(const Mesh& mesh, std::size_t first, std::size_t end) {
  // The faces just checked are the ones accepted, their normals already known.
  const bool checked = first == checked_first_ && end - first == checked_normals_.size();
  if (checked && changes_known_ && first == changes_first_ && end == changes_end_) {
    apply_changes();
  } else {
    for (std::size_t f = first; f < end; ++f) {
      const Face& face = mesh.faces[f];
      const Vec3 normal = checked ? checked_normals_[f - first] : area_vector(mesh, face);
      for_each_edge(face, [&](std::int32_t a, std::int32_t b) {
        // An edge's second face puts it inside the surface.
        if (!open_.remove(a, b))
          open_.add(a, b, OpenEdge{normal, static_cast<std::uint32_t>(f), a < b});
      });
    }
  }
  checked_normals_.clear();
  changes_.clear();
  changes_known_ = false;
}

void FoldGuard::apply_changes() {
  // The same lists, in the same order, as looking every edge up again: an edge whose addition
  // was cancelled would have been added and taken out again, leaving the others' order alone.
  for (const BoundaryChange& c : changes_) {
    if (c.kind == BoundaryChange::add) {
      open_.add(c.a, c.b, OpenEdge{checked_normals_[c.face - checked_first_], c.face, c.a < c.b});
    } else if (c.kind == BoundaryChange::remove) {
      open_.remove(c.a, c.b);
    }
  }
}

std::vector<std::int32_t> FoldGuard::folded_vertices(const Mesh& mesh, std::size_t first_face,
                                                     std::size_t first_new_vertex) {
  // Parts of one step are checked one after another: keep their normals for accept().
  if (first_face != checked_first_ + checked_normals_.size()) {
    checked_first_ = first_face;
    checked_normals_.clear();
  }
  strip_.clear();
  changes_.clear();
  changes_first_ = first_face;
  changes_known_ = true;
  std::vector<std::int32_t> out;
  check_faces(mesh, first_face, first_new_vertex, out);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

void FoldGuard::check_faces(const Mesh& mesh, std::size_t begin, std::size_t first_new_vertex,
                            std::vector<std::int32_t>& out) {
  const Vec3* const positions = mesh.positions.data();
  const Face* const faces = mesh.faces.data();
  const std::size_t end = mesh.faces.size();
  const auto is_new = [&](std::int32_t v) {
    return v >= 0 && static_cast<std::size_t>(v) >= first_new_vertex;
  };
  // The new ends of a folded edge (a, b), or else the new corners of its face.
  const auto take = [&](std::size_t f, std::int32_t a, std::int32_t b) {
    const std::size_t before = out.size();
    for (const std::int32_t v : {a, b})
      if (is_new(v)) out.push_back(v);
    if (out.size() == before) {
      const Face& face = faces[f];
      for (std::size_t c = 0; c < face.size; ++c)
        if (is_new(face.v[c])) out.push_back(face.v[c]);
    }
  };
  for (std::size_t f = begin; f < end; ++f) {
    const Face& face = faces[f];
    // The area vector, not the unit normal: a fold is a negative dot product, whose sign does not
    // depend on the lengths (and a face's area vector is zero exactly where its normal is).
    const Vec3 n0 = area_vector(positions, face);
    checked_normals_.push_back(n0);
    const auto face_id = static_cast<std::uint32_t>(f);
    const bool has_area = n0.squaredNorm() > 0;
    for_each_edge(face, [&](std::int32_t a, std::int32_t b) {
      const auto folds_over = [&](std::uint32_t other, bool forward, const Vec3& n1) {
        if (other == face_id) return false;
        // Consistent neighbours walk the edge in opposite directions; undo a flip so that only
        // geometry decides, as the quality measure does.
        const double dot = forward == (a < b) ? -n0.dot(n1) : n0.dot(n1);
        return n1.squaredNorm() > 0 && dot < 0;
      };
      // Each pair of strip faces on an edge is compared once, when the second one comes. Every
      // face on the edge is counted, for the boundary change.
      bool folded = false, folds_open = false;
      std::size_t strip_faces = 0, open_faces = 0;
      std::uint32_t strip_change = kNoChange;
      strip_.any_of(a, b, [&](const StripEdge& other) {
        ++strip_faces;
        strip_change = other.change;
        if (has_area &&
            folds_over(other.face, other.forward, checked_normals_[other.face - checked_first_])) {
          folded = true;
          take(other.face, a, b);
        }
        return false;
      });
      open_.any_of(a, b, [&](const OpenEdge& other) {
        ++open_faces;
        folds_open = folds_open || (has_area && !folded &&
                                    folds_over(other.face, other.forward, other.normal));
        return false;
      });
      if (folded || folds_open) take(f, a, b);
      // Accepting adds an edge new to both lists, removes one on the boundary, and nothing for
      // the second strip face of an edge the first added; any other meeting is left to a lookup.
      std::uint32_t change = kNoChange;
      if (strip_faces == 0 && open_faces <= 1 && changes_.size() < kNoChange) {
        change = static_cast<std::uint32_t>(changes_.size());
        changes_.push_back(BoundaryChange{
            a, b, face_id, open_faces == 0 ? BoundaryChange::add : BoundaryChange::remove});
      } else if (strip_faces == 1 && open_faces == 0 && strip_change != kNoChange &&
                 changes_[strip_change].kind == BoundaryChange::add) {
        changes_[strip_change].kind = BoundaryChange::cancelled;
      } else {
        changes_known_ = false;
      }
      strip_.add(a, b, StripEdge{face_id, change, a < b});
    });
  }
  changes_end_ = end;
}

template class FoldGuard::EdgeLists<FoldGuard::StripEdge>;
template class FoldGuard::EdgeLists<FoldGuard::OpenEdge>;

}  // namespace orthofront
