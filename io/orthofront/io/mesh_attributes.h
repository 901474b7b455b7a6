#pragma once
/// The per-vertex attributes of a Mesh by the names the mesh codecs store them under (internal).
#include <array>
#include <cstdint>
#include <vector>

#include "orthofront/mesh/mesh.h"

namespace orthofront::io::detail {

struct RealAttribute {
  const char* name;
  Mesh::Array<double> Mesh::*values;
};

struct IntAttribute {
  const char* name;
  Mesh::Array<std::int32_t> Mesh::*values;
};

inline constexpr std::array<RealAttribute, 7> kRealAttributes{{
    {"time", &Mesh::time},
    {"alpha", &Mesh::alpha},
    {"s", &Mesh::s},
    {"error", &Mesh::error},
    {"release_time", &Mesh::release_time},
    {"age", &Mesh::age},
    {"speed", &Mesh::speed},
}};

inline constexpr std::array<IntAttribute, 4> kIntAttributes{{
    {"front_id", &Mesh::front_id},
    {"step", &Mesh::step},
    {"particle_id", &Mesh::particle_id},
    {"on_path", &Mesh::on_path},
}};

/// An attribute is stored when it has one value per vertex; an empty array means "not recorded".
template <typename T>
bool is_recorded(const Mesh& mesh, const Mesh::Array<T>& values) {
  return !values.empty() && values.size() == mesh.positions.size();
}

}  // namespace orthofront::io::detail
