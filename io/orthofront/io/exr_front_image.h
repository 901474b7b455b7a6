#pragma once
/// The per-front quantities of a surface as an image (the paper's Figure 5 as data): one row per
/// front step, one column per bin of the seed parameter s, one FLOAT channel per quantity, written
/// as OpenEXR.
#include <cstdint>
#include <filesystem>

#include "orthofront/mesh/mesh.h"

namespace orthofront::io {

struct FrontImageOptions {
  /// Columns: bins of s over [0, 1] (column = round(s * (width - 1))). 0 selects the largest
  /// number of vertices any front step created (one column per stream line of the widest front).
  int s_bins = 0;
};

/// What was written.
struct FrontImageSummary {
  int width = 0;           ///< s bins
  int height = 0;          ///< front steps (max step + 1)
  std::size_t covered = 0;  ///< pixels with at least one vertex
};

/// Writes `mesh`'s per-vertex attributes over (s, step) to an OpenEXR image at `path`,
/// atomically (temporary name, then rename). FLOAT channels, ZIP compression:
/// - alpha, error, time: the mean over the vertices that fall into the pixel;
/// - speed: |x - x_prev| / (t - t_prev) from each vertex to its predecessor on the same stream
///   line (the vertex of the previous step with the same s), mean over the pixel;
/// - dtime: t - t_prev, the time a front step advanced the stream line (the time derivative of the
///   front position in step units);
/// - front_id: the smallest front id in the pixel;
/// - coverage: the number of vertices in the pixel (0 = no data; the other channels are NaN there).
/// Attributes: orthofront.channels (a description), orthofront.s_bins, orthofront.steps.
/// Throws InvalidArgument when the mesh lacks the s and step attributes (or has no vertices),
/// IoError naming the path.
FrontImageSummary write_front_image(const Mesh& mesh, const std::filesystem::path& path,
                                    const FrontImageOptions& options = {});

}  // namespace orthofront::io
