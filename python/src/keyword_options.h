#pragma once
/// Python keyword arguments as a job's options (jobs/option_set.h): the same names as the
/// command line's, '_' for '-', with the same defaults and checks.
#include <pybind11/pybind11.h>

#include "jobs/option_set.h"

namespace orthofront::python {

/// Parses `keywords` into `options`: an unknown keyword or a missing required one is a
/// TypeError, a value the option refuses a ValueError naming the keyword. None leaves the default.
void parse_keywords(jobs::OptionSet& options, const pybind11::kwargs& keywords);

/// The options the keywords set, one dict each (name, option, type, default, flag, help, unit,
/// group, choices, required).
pybind11::list option_schema(const jobs::OptionSet& options);

}  // namespace orthofront::python
