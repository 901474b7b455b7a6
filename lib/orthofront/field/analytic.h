#pragma once
/// Analytic test fields with exact Jacobians (the paper's synthetic data sets and classics).
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "orthofront/field/field.h"

namespace orthofront {

struct FieldParameter {
  std::string name;
  double default_value = 0;
  std::string help;
};

struct AnalyticFieldInfo {
  std::string name;                        ///< as used on the command line, e.g. "focus-sink"
  std::string formula;                     ///< v(x, y, z) in words/symbols
  std::string domain;                      ///< the domain in words, e.g. "[-3,3]^2 x [-1,1]"
  std::vector<FieldParameter> parameters;  ///< accepted by name in the spec
};

/// All analytic fields, in a stable order.
const std::vector<AnalyticFieldInfo>& analytic_fields();

/// Builds a field from "name" or "name:key=value,key=value" (e.g. "lorenz:rho=28,reverse=1").
/// Throws InvalidArgument naming the unknown field, unknown key or malformed value.
std::unique_ptr<Field3> make_analytic_field(std::string_view spec);

}  // namespace orthofront
