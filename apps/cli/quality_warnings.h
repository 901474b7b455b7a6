#pragma once
/// \file
/// Warnings the commands print about a finished surface's mesh.

#include <cstddef>
#include <string>

namespace orthofront::cli {

/// The warning for a surface with faces of no area (empty when there are none). Such faces come
/// from a seed laid along the flow or through a critical point, where neighbouring stream lines
/// do not separate.
inline std::string degenerate_faces_warning(std::size_t degenerate, std::size_t faces) {
  if (degenerate == 0) return {};
  return "orthofront: warning: " + std::to_string(degenerate) + " of " + std::to_string(faces) +
         " faces are degenerate (no area): the seed runs along the flow or through a point of "
         "zero velocity, where neighbouring stream lines do not separate; lay the seed across "
         "the flow\n";
}

}  // namespace orthofront::cli
