#include "orthofront/engine/options.h"

namespace orthofront {

const char* to_string(Method method) {
  return method == Method::orthogonal ? "orthogonal" : "timeline";
}
const char* to_string(MuMode mode) {
  return mode == MuMode::damping ? "damping" : "paper";
}
const char* to_string(NegativeAlpha mode) {
  return mode == NegativeAlpha::clamp ? "clamp" : "keep";
}
const char* to_string(Insertion mode) {
  switch (mode) {
    case Insertion::linear:
      return "linear";
    case Insertion::cubic:
      return "cubic";
    case Insertion::streamline:
      return "streamline";
    case Insertion::previous_row:
      return "previous-row";
  }
  return "?";
}
const char* to_string(RowSkip mode) {
  switch (mode) {
    case RowSkip::off:
      return "off";
    case RowSkip::vertex:
      return "vertex";
    case RowSkip::run:
      return "run";
  }
  return "?";
}
const char* to_string(IntegratorKind kind) {
  return kind == IntegratorKind::dopri5 ? "dopri5" : "rk4";
}

}  // namespace orthofront
