#pragma once
/// Calls f.template operator()<Axes, Components, Rectilinear>() for the grid's kind: the eight
/// kernel instantiations a backend compiles, chosen once per slab rather than per sample.
#include "orthofront/advect/slab.h"

namespace orthofront::advect {

template <class F>
void dispatch_grid(const GridView& g, F&& f) {
  const int kind = (g.axes == 3 ? 4 : 0) | (g.components == 3 ? 2 : 0) | (g.rectilinear ? 1 : 0);
  switch (kind) {
    case 0: f.template operator()<2, 2, false>(); break;
    case 1: f.template operator()<2, 2, true>(); break;
    case 2: f.template operator()<2, 3, false>(); break;
    case 3: f.template operator()<2, 3, true>(); break;
    case 4: f.template operator()<3, 2, false>(); break;
    case 5: f.template operator()<3, 2, true>(); break;
    case 6: f.template operator()<3, 3, false>(); break;
    default: f.template operator()<3, 3, true>(); break;
  }
}

}  // namespace orthofront::advect
