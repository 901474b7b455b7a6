#pragma once
/// Command-line values of the grid commands (generate, orthofront-bench grid): resolutions, boxes, the
/// compression and the HDF5 storage.
#include <array>
#include <cstdint>
#include <string>

#include "orthofront/io/hdf5_layout.h"
#include "orthofront/types.h"

namespace orthofront::jobs {

/// "NX,NY,NZ" or "NX,NY" (NZ = 1: a 2D grid). Throws InvalidArgument naming the bad part.
std::array<std::int64_t, 3> parse_resolution(const std::string& text);
/// "xmin,ymin,zmin:xmax,ymax,zmax"; with `planar` also "xmin,ymin:xmax,ymax" (z unbounded).
/// Messages name `option`.
Box<3> parse_box(const std::string& text, const std::string& option = "--box", bool planar = false);
/// A chunk codec and its level.
struct Compression {
  io::Hdf5Codec codec = io::Hdf5Codec::none;
  int level = 0;
};
/// "none", or "lz4", "zstd", "gzip" with an optional ":LEVEL" (1-9; defaults 5, 1, 4).
Compression parse_compression(const std::string& text);
void apply_compression(const Compression& compression, io::Hdf5WriteOptions& options);
/// What `Wrote FILE` goes on with for an HDF5 file written with `options`: " and FILE.xmf", or
/// why there is no sidecar (ParaView cannot decode Blosc) and how to get one.
std::string sidecar_text(const io::Hdf5WriteOptions& options, const std::string& file);
/// "bricked", "chunked" or "per-step".
io::Hdf5Storage parse_layout(const std::string& text);

}  // namespace orthofront::jobs
