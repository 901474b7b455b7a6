#pragma once
/// The advancing front: vertices on their stream lines, each standing for a mesh vertex.
#include <cstdint>
#include <vector>

#include "orthofront/types.h"

namespace orthofront {

template <int N>
struct FrontVertex {
  Vec<N> x;       ///< current position on its stream line
  Vec<N> anchor;  ///< position of the mesh vertex that stands for it
  double s = 0;   ///< seed parameter (may exceed 1 on closed fronts: taken modulo 1)
  double t = 0;   ///< integration time in v since the seed
  std::int32_t mesh = -1;
  std::int32_t origin = -1;  ///< index in the previous front (-1: inserted this step)
};

/// One front line; a surface has several after rips, domain exits and no-data cuts.
template <int N>
struct Front {
  std::vector<FrontVertex<N>> v;
  bool closed = false;
  std::int32_t id = 0;
};

}  // namespace orthofront
