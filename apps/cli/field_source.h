#pragma once
/// Resolves a --field argument to a field: a data file "FILE.ext[:SELECTOR]" (dispatched on the
/// extension, see data_files.h; e.g. "flow.h5:/run1") or an analytic name with parameters
/// ("lorenz:rho=28,reverse=1").
#include <memory>
#include <string>

#include "orthofront/field/field.h"

namespace orthofront::cli {

/// Throws InvalidArgument naming the unknown field, parameter or file extension; IoError /
/// FormatError naming the file for unreadable data; InvalidArgument for a time series (a steady
/// field is needed).
std::unique_ptr<Field3> open_field(const std::string& spec);

}  // namespace orthofront::cli
