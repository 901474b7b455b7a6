#include "cli/field_source.h"

#include "orthofront/field/analytic.h"

namespace orthofront::cli {

std::unique_ptr<Field3> open_field(const std::string& spec) { return make_analytic_field(spec); }

}  // namespace orthofront::cli
