#pragma once
/// The "name" / "name:key=value,key=value" syntax of the analytic field factories (steady and
/// unsteady): parameter tables, parsing with messages that name the field, key and value.
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace orthofront {

enum class ParameterKind : unsigned char {
  real,      ///< any finite number
  positive,  ///< finite and > 0
  integer,   ///< integer in [lo, hi]
  flag,      ///< 0 or 1
};

struct ParameterSpec {
  const char* name;
  double default_value;
  const char* help;
  ParameterKind kind = ParameterKind::real;
  double lo = 0;  ///< integer: smallest accepted value
  double hi = 0;  ///< integer: largest accepted value
};

/// The field name of a spec: the text before the first ':', trimmed.
std::string_view field_spec_name(std::string_view spec);

struct ParsedParameters {
  std::vector<double> values;  ///< one per ParameterSpec, defaults where not given
  std::string description;     ///< "name:key=value,..." with every parameter
};

/// Parses the parameters of `spec` (after its first ':', if any) for the field `field` whose
/// parameters are `params`. `kind` names the family in messages ("analytic field").
/// Throws InvalidArgument naming the field and the malformed item, unknown or repeated key, or
/// unacceptable value.
ParsedParameters parse_field_parameters(std::string_view spec, std::string_view kind,
                                        std::string_view field,
                                        std::span<const ParameterSpec> params);

/// Six significant digits, as %g: short, readable descriptions ("beta=2.66667").
std::string format_parameter(double value);

/// "a, b, c": the names of a registry's entries (each with a `name` member), for messages.
template <class Registry>
std::string field_names(const Registry& registry) {
  std::string names;
  for (const auto& entry : registry) {
    if (!names.empty()) names += ", ";
    names += entry.name;
  }
  return names;
}

}  // namespace orthofront
