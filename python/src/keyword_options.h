#pragma once
/// Python keyword arguments as command-line options: `edge=0.05, mu_mode="paper"` is parsed as
/// `--edge 0.05 --mu-mode paper` by the same CLI11 definitions the commands use, so the module
/// takes the command line's names, defaults and checks.
#include <pybind11/pybind11.h>

#include <CLI/CLI.hpp>

namespace orthofront::python {

/// Parses `options` with `command`. True adds a flag, False and None leave it out, a tuple is
/// joined with ':' (--release 0:1) and a list with ',' (--frames 1,2,3). Throws TypeError for a
/// keyword the command does not take and ValueError for a value it refuses, both naming the
/// keyword.
void parse_keywords(CLI::App& command, const pybind11::kwargs& options);

/// The keywords `command` takes, in its order, each a dict: `name` (the keyword), `option` (the
/// flag), `type` (CLI11's type name: FLOAT, INT, UINT, TEXT, ...), `default` (its text; empty:
/// none), `flag` (takes no value) and `help`. Hidden options and --help are left out.
pybind11::list option_schema(const CLI::App& command);

}  // namespace orthofront::python
