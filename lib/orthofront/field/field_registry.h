#pragma once
/// The one shape of the analytic field registries (steady fields in analytic.cpp, unsteady ones in
/// unsteady.cpp): entries with a name, formula, domain, parameter table and factory, and the
/// lookup, listing and "name:key=value" construction both families share.
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "orthofront/error.h"
#include "orthofront/field/analytic.h"
#include "orthofront/field/field_spec.h"

namespace orthofront {

template <class Made>
struct FieldEntry {
  using Factory = std::unique_ptr<Made> (*)(std::span<const double> p, std::string description);
  const char* name;
  const char* formula;
  const char* domain;
  std::vector<ParameterSpec> params;
  Factory make;
};

template <class Made>
const FieldEntry<Made>* find_field(const std::vector<FieldEntry<Made>>& registry,
                                   std::string_view name) {
  for (const FieldEntry<Made>& candidate : registry)
    if (name == candidate.name) return &candidate;
  return nullptr;
}

/// The entries as AnalyticFieldInfo, for `orthofront fields` and the Python module.
template <class Made>
std::vector<AnalyticFieldInfo> describe_fields(const std::vector<FieldEntry<Made>>& registry) {
  std::vector<AnalyticFieldInfo> result;
  for (const FieldEntry<Made>& field : registry) {
    AnalyticFieldInfo info{field.name, field.formula, field.domain, {}};
    for (const ParameterSpec& param : field.params)
      info.parameters.push_back({param.name, param.default_value, param.help});
    result.push_back(std::move(info));
  }
  return result;
}

/// Builds the field a spec names. `family` names the registry in messages ("analytic field"),
/// `known` introduces the list of its names ("known fields").
template <class Made>
std::unique_ptr<Made> make_field(const std::vector<FieldEntry<Made>>& registry,
                                 std::string_view spec, std::string_view family,
                                 std::string_view known) {
  const std::string_view name = field_spec_name(spec);
  const FieldEntry<Made>* field = find_field(registry, name);
  if (field == nullptr)
    throw InvalidArgument("unknown " + std::string(family) + " '" + std::string(name) + "'; " +
                          std::string(known) + ": " + field_names(registry));
  ParsedParameters parsed = parse_field_parameters(spec, family, field->name, field->params);
  return field->make(parsed.values, std::move(parsed.description));
}

/// The axis-aligned box [x0, x1] x [y0, y1] x [z0, z1].
inline Box<3> make_box(double x0, double x1, double y0, double y1, double z0, double z1) {
  Box<3> box;
  box.lo = Vec3(x0, y0, z0);
  box.hi = Vec3(x1, y1, z1);
  return box;
}

}  // namespace orthofront
