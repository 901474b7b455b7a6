#pragma once
/// Why a particle stopped. One definition for the CPU code, the flow maps of spacetime/ and the
/// CUDA kernels (an unsigned char, so a device array of them is one byte a particle).

namespace orthofront::advect {

enum class ParticleStatus : unsigned char {
  moving = 0,       ///< reached the requested time (or is still on its way)
  left_domain = 1,  ///< left the spatial domain (x is the last point inside)
  no_data = 2,      ///< entered a cell without flow (solid, fill value, NaN) or stalled
  time_bounds = 3,  ///< the requested time lies outside the field's time range
};

const char* to_string(ParticleStatus status);

}  // namespace orthofront::advect
