#pragma once
/// Resolves a --field argument to a field: an analytic name with parameters
/// ("lorenz:rho=28,reverse=1").
#include <memory>
#include <string>

#include "orthofront/field/field.h"

namespace orthofront::cli {

/// Throws InvalidArgument naming the unknown field or parameter.
std::unique_ptr<Field3> open_field(const std::string& spec);

}  // namespace orthofront::cli
