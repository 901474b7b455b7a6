#pragma once
/// What each fuzz target does with one input, shared with the test that replays every input
/// that once failed (fuzz/regressions/). An input passes when the reader either returns
/// something consistent or throws one of the project's own errors (a message for the user).
/// Anything else escaping — std::bad_alloc, std::length_error, an OpenVDB or HDF5 exception that
/// was not turned into a message — is a finding and is not caught here.
#include <string>
#include <string_view>

namespace orthofront::fuzz {

/// The fuzz targets by name ("grid_nrrd", "hdf5", "parse_seed", ...).
const char* const kTargets[] = {"grid_vec",  "grid_am",    "grid_nrrd",   "grid_nhdr",   "grid_vti",
                                "grid_vtk",  "grid_vdb",   "vdb_file",    "hdf5",        "netcdf",
                                "pvd",       "mesh_vtp",   "mesh_ply",    "mesh_obj",    "parse_seed",
                                "parse_field", "parse_bytes", "job_file", "checkpoint"};

/// Runs target `target` on `input`. Returns false when the reader returned something
/// inconsistent (values missing from a grid, a face naming a vertex that does not exist).
/// Throws std::invalid_argument for an unknown target name.
bool exercise(std::string_view target, std::string_view input);

}  // namespace orthofront::fuzz
