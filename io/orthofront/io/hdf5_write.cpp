// Writing the HDF5 layout: one field group per file, written under a temporary name.
#include <tbb/parallel_for.h>
#include <unistd.h>
#include <zlib.h>

#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <system_error>

#include "orthofront/error.h"
#include "orthofront/io/atomic_file.h"
#include "orthofront/io/error.h"
#include "orthofront/io/hdf5_detail.h"

namespace orthofront::io {

using detail::H5Id;

const char* to_string(Hdf5Storage storage) {
  switch (storage) {
    case Hdf5Storage::steady:
      return "steady";
    case Hdf5Storage::chunked:
      return "chunked";
    case Hdf5Storage::per_step:
      return "per-step";
    case Hdf5Storage::bricked:
      return "bricked";
  }
  return "?";
}

const char* to_string(Hdf5Codec codec) {
  switch (codec) {
    case Hdf5Codec::none:
      return "none";
    case Hdf5Codec::gzip:
      return "gzip";
    case Hdf5Codec::lz4:
      return "lz4";
    case Hdf5Codec::zstd:
      return "zstd";
  }
  return "?";
}

std::filesystem::path xdmf_path(const std::filesystem::path& file) {
  std::filesystem::path sidecar = file;
  return sidecar.replace_extension(".xmf");
}

namespace {

void check_grid(const GridGeometry& g, int components) {
  if (g.dimension != 2 && g.dimension != 3)
    throw InvalidArgument("HDF5 layout: dimension must be 2 or 3, got " +
                          std::to_string(g.dimension));
  if (components != 2 && components != 3)
    throw InvalidArgument("HDF5 layout: components must be 2 or 3, got " +
                          std::to_string(components));
  for (int a = 0; a < 3; ++a) {
    const auto n = g.size[static_cast<std::size_t>(a)];
    if (n < 1 || (a == 2 && g.dimension == 2 && n != 1))
      throw InvalidArgument("HDF5 layout: " + std::to_string(n) + " samples along axis " +
                            std::to_string(a) + " of a " + std::to_string(g.dimension) + "D grid");
    if (g.rectilinear() &&
        g.axes[static_cast<std::size_t>(a)].size() != static_cast<std::size_t>(n))
      throw InvalidArgument("HDF5 layout: rectilinear axis " + std::to_string(a) + " has " +
                            std::to_string(g.axes[static_cast<std::size_t>(a)].size()) +
                            " coordinates for " + std::to_string(n) + " samples");
  }
  if (g.rectilinear()) {
    for (int a = 0; a < 3; ++a) {
      const auto& axis = g.axes[static_cast<std::size_t>(a)];
      for (std::size_t i = 0; i < axis.size(); ++i)
        if (!std::isfinite(axis[i]) || (i > 0 && !(axis[i] > axis[i - 1])))
          throw InvalidArgument("HDF5 layout: rectilinear axis " + std::to_string(a) +
                                " must be finite and strictly increasing; entry " +
                                std::to_string(i) + " is " + std::to_string(axis[i]));
    }
  } else {
    for (int a = 0; a < g.dimension; ++a)
      if (!std::isfinite(g.spacing[a]) || !(g.spacing[a] > 0) || !std::isfinite(g.origin[a]))
        throw InvalidArgument("HDF5 layout: origin and spacing must be finite, spacing positive");
  }
}

void check_times(const std::vector<double>& times) {
  if (times.empty()) throw InvalidArgument("HDF5 layout: a time series needs at least one step");
  for (std::size_t i = 0; i < times.size(); ++i) {
    if (!std::isfinite(times[i]) || (i > 0 && !(times[i] > times[i - 1])))
      throw InvalidArgument("HDF5 layout: times must be finite and strictly increasing; time " +
                            std::to_string(i) + " is " + std::to_string(times[i]));
  }
}

// Why a write failed, as far as the file system tells: HDF5 reports only that it failed.
std::string failure_cause(const std::filesystem::path& file) {
  std::error_code error;
  std::filesystem::path dir = file.parent_path();
  if (dir.empty()) dir = ".";
  const auto space = std::filesystem::space(dir, error);
  if (!error && space.available < (std::size_t{1} << 20))
    return " (disk full: " + std::to_string(space.available) + " bytes free in " + dir.string() +
           ")";
  return errno != 0 ? " (" + std::generic_category().message(errno) + ")" : std::string();
}

void write_doubles_dataset(hid_t group, const char* name, std::span<const double> values,
                           const std::string& where) {
  const hsize_t n = values.size();
  H5Id space(H5Screate_simple(1, &n, nullptr), H5Sclose);
  H5Id set(
      H5Dcreate2(group, name, H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
      H5Dclose);
  if (!set.valid() ||
      H5Dwrite(set.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()) < 0)
    throw IoError("cannot write " + where + ": dataset '" + name + "'");
}

/// The shared writer: steady files are a "series" of one step with storage `steady`.
struct FieldWriter {
  std::filesystem::path file, temp;
  Hdf5Description description;
  Hdf5WriteOptions options;
  detail::SliceLayout layout;
  BrickLayout bricks;          // bricked storage
  Hdf5Codec codec = Hdf5Codec::none;
  int level = 0;
  std::vector<hsize_t> shape;  // one step
  H5Id h5file, group, dataset, steps_group;
  std::size_t written = 0;
  bool committed = false;

  FieldWriter(const std::filesystem::path& path, const GridGeometry& geometry, int components,
              std::vector<double> times, const Hdf5WriteOptions& opts, Hdf5Storage storage)
      : file(path), temp(temporary_path(path)), options(opts) {
    detail::silence_hdf5();
    check_grid(geometry, components);
    if (storage != Hdf5Storage::steady) check_times(times);
    if (options.gzip_level < 0 || options.gzip_level > 9)
      throw InvalidArgument("HDF5 layout: gzip level must be 0 (none) to 9, got " +
                            std::to_string(options.gzip_level));
    codec = options.codec != Hdf5Codec::none ? options.codec
            : options.gzip_level > 0         ? Hdf5Codec::gzip
                                             : Hdf5Codec::none;
    level = codec == Hdf5Codec::gzip ? (options.gzip_level > 0 ? options.gzip_level
                                                                : std::max(options.level, 1))
            : options.level > 0      ? options.level
                                     : detail::default_level(codec);
    if (level < 0 || level > 9)
      throw InvalidArgument("HDF5 layout: compression level must be 1 to 9, got " +
                            std::to_string(level));
    if (storage == Hdf5Storage::bricked && options.brick_size < 1)
      throw InvalidArgument("HDF5 layout: brick size must be at least 1 point, got " +
                            std::to_string(options.brick_size));
    detail::register_blosc_filter();
    check_writable(file);
    description.file = file;
    description.group = detail::normalize_group(options.group);
    description.storage = storage;
    description.geometry = geometry;
    description.components = components;
    description.times = std::move(times);
    description.units = options.units;
    description.fill_value = options.fill_value;
    description.zero_is_no_data = options.zero_is_no_data;
    description.gzip_level = codec == Hdf5Codec::gzip ? level : 0;
    description.dataset = detail::child_path(
        description.group, storage == Hdf5Storage::per_step ? "steps" : "velocity");
    layout = detail::slice_layout(geometry, components, options.max_chunk_bytes);
    shape = detail::step_shape(geometry, components);
    if (storage == Hdf5Storage::bricked) {
      bricks = BrickLayout::cubes(geometry, options.brick_size);
      description.brick = bricks.size;
      if (bricks.brick_points() * static_cast<std::size_t>(components) * sizeof(float) >=
          (std::size_t{1} << 32))
        throw InvalidArgument("HDF5 layout: a brick of " + std::to_string(options.brick_size) +
                              " points per axis exceeds HDF5's 4 GiB chunk limit");
    }

    h5file = H5Id(H5Fcreate(temp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
    if (!h5file.valid()) throw IoError("cannot create HDF5 file " + temp.string());
    try {
      create_structure();
    } catch (...) {
      discard();
      throw;
    }
  }

  ~FieldWriter() {
    if (!committed) discard();
  }
  FieldWriter(const FieldWriter&) = delete;
  FieldWriter& operator=(const FieldWriter&) = delete;

  void discard() {
    dataset.reset();
    steps_group.reset();
    group.reset();
    h5file.reset();
    std::error_code ignored;
    std::filesystem::remove(temp, ignored);
  }

  std::string where() const { return file.string() + " (group '" + description.group + "')"; }

  void create_structure() {
    if (description.group == "/") {
      group = H5Id(H5Gopen2(h5file.get(), "/", H5P_DEFAULT), H5Gclose);
    } else {
      H5Id links(H5Pcreate(H5P_LINK_CREATE), H5Pclose);
      H5Pset_create_intermediate_group(links.get(), 1);
      group = H5Id(H5Gcreate2(h5file.get(), description.group.c_str(), links.get(), H5P_DEFAULT,
                              H5P_DEFAULT),
                   H5Gclose);
    }
    if (!group.valid()) throw IoError("cannot create " + where());
    const hid_t g = group.get();
    const GridGeometry& geometry = description.geometry;
    detail::write_string_attribute(g, "orthofront_layout", "vector-grid");
    detail::write_int_attribute(g, "layout_version", 1);
    detail::write_int_attribute(g, "dimension", geometry.dimension);
    detail::write_int_attribute(g, "components", description.components);
    detail::write_string_attribute(g, "storage", to_string(description.storage));
    detail::write_string_attribute(g, "grid", geometry.rectilinear() ? "rectilinear" : "uniform");
    if (geometry.rectilinear()) {
      for (int a = 0; a < 3; ++a) {
        const std::string name(1, static_cast<char>('x' + a));
        write_doubles_dataset(g, name.c_str(), geometry.axes[static_cast<std::size_t>(a)], where());
      }
    } else {
      const double origin[3] = {geometry.origin.x(), geometry.origin.y(), geometry.origin.z()};
      const double spacing[3] = {geometry.spacing.x(), geometry.spacing.y(), geometry.spacing.z()};
      detail::write_doubles_attribute(g, "origin", origin);
      detail::write_doubles_attribute(g, "spacing", spacing);
    }
    if (!options.units.length.empty())
      detail::write_string_attribute(g, "units_length", options.units.length);
    if (!options.units.time.empty())
      detail::write_string_attribute(g, "units_time", options.units.time);
    if (!options.units.velocity.empty())
      detail::write_string_attribute(g, "units_velocity", options.units.velocity);
    if (options.fill_value) detail::write_float_attribute(g, "fill_value", *options.fill_value);
    detail::write_int_attribute(g, "zero_is_no_data", options.zero_is_no_data ? 1 : 0);

    if (description.storage != Hdf5Storage::steady)
      write_doubles_dataset(g, "times", description.times, where());
    if (has_step_axis(description.storage)) {
      std::vector<hsize_t> dims{description.times.size()};
      dims.insert(dims.end(), shape.begin(), shape.end());
      dataset = create_samples(g, "velocity", dims, true);
    } else if (description.storage == Hdf5Storage::per_step) {
      steps_group = H5Id(H5Gcreate2(g, "steps", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
      if (!steps_group.valid()) throw IoError("cannot create " + where() + ": group 'steps'");
    } else {
      dataset = create_samples(g, "velocity", shape, false);
    }
  }

  bool compressed() const { return codec != Hdf5Codec::none; }

  /// A float32 dataset of `dims`; chunked by slices (with a leading 1 for the step axis of a
  /// chunked series) when compressed or when `series` is set, contiguous otherwise.
  H5Id create_samples(hid_t location, const char* name, const std::vector<hsize_t>& dims,
                      bool series) {
    H5Id space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose);
    H5Id create(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    H5Pset_fill_time(create.get(), H5D_FILL_TIME_NEVER);
    if (series || compressed()) {
      std::vector<hsize_t> chunk = dims;
      if (series) chunk[0] = 1;
      chunk[series ? 1 : 0] = static_cast<hsize_t>(layout.chunk_slices);
      if (description.storage == Hdf5Storage::bricked) {
        // [1][bz][by][bx][C] (2D: [1][by][bx][C]).
        const std::size_t n = chunk.size();
        chunk[n - 2] = static_cast<hsize_t>(bricks.size[0]);
        chunk[n - 3] = static_cast<hsize_t>(bricks.size[1]);
        if (description.geometry.dimension == 3) chunk[n - 4] = static_cast<hsize_t>(bricks.size[2]);
      }
      H5Pset_chunk(create.get(), static_cast<int>(chunk.size()), chunk.data());
      if (codec == Hdf5Codec::gzip) {
        if (options.shuffle) H5Pset_shuffle(create.get());
        H5Pset_deflate(create.get(), static_cast<unsigned>(level));
      } else if (codec != Hdf5Codec::none) {
        std::size_t chunk_bytes = sizeof(float);
        for (hsize_t c : chunk) chunk_bytes *= c;
        const std::vector<unsigned> cd = detail::blosc_parameters(codec, level, chunk_bytes);
        H5Pset_filter(create.get(), kBloscFilterId, H5Z_FLAG_OPTIONAL, cd.size(), cd.data());
      }
    }
    H5Id set(H5Dcreate2(location, name, H5T_IEEE_F32LE, space.get(), H5P_DEFAULT, create.get(),
                        H5P_DEFAULT),
             H5Dclose);
    if (!set.valid()) throw IoError("cannot create " + where() + ": dataset '" + name + "'");
    return set;
  }

  void write_step(std::span<const float> values) {
    const std::size_t step_floats =
        description.geometry.point_count() * static_cast<std::size_t>(description.components);
    if (values.size() != step_floats)
      throw InvalidArgument("HDF5 layout: a step of " + where() + " needs " +
                            std::to_string(step_floats) + " floats, got " +
                            std::to_string(values.size()));
    const std::size_t total =
        description.storage == Hdf5Storage::steady ? 1 : description.times.size();
    if (written >= total)
      throw InvalidArgument("HDF5 layout: all " + std::to_string(total) + " steps of " + where() +
                            " are written already");
    std::vector<float> converted;
    if (options.fill_value) {
      converted.assign(values.begin(), values.end());
      for (float& v : converted)
        if (std::isnan(v)) v = *options.fill_value;
      values = converted;
    }
    hid_t target = dataset.get();
    H5Id step_set;
    if (description.storage == Hdf5Storage::per_step) {
      char name[32];
      std::snprintf(name, sizeof name, "%06zu", written);
      step_set = create_samples(steps_group.get(), name, shape, false);
      target = step_set.get();
    }
    const bool series_axis = has_step_axis(description.storage);
    if (description.storage == Hdf5Storage::bricked)
      write_bricks(target, values);
    else if (compressed() && (options.parallel_compression || codec != Hdf5Codec::gzip))
      write_compressed_chunks(target, values, series_axis);
    else
      write_plain(target, values, series_axis);
    ++written;
  }

  void write_plain(hid_t target, std::span<const float> values, bool series_axis) {
    H5Id memory(H5Screate_simple(static_cast<int>(shape.size()), shape.data(), nullptr), H5Sclose);
    H5Id file_space(H5Dget_space(target), H5Sclose);
    if (series_axis) {
      std::vector<hsize_t> start(shape.size() + 1, 0), count{1};
      start[0] = written;
      count.insert(count.end(), shape.begin(), shape.end());
      H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(),
                          nullptr);
    }
    if (H5Dwrite(target, H5T_NATIVE_FLOAT, memory.get(), file_space.get(), H5P_DEFAULT,
                 values.data()) < 0)
      throw IoError("cannot write step " + std::to_string(written) + " of " + where() +
                    failure_cause(temp));
  }

  /// Shuffle + deflate every chunk of the step in parallel, then store them in order with
  /// H5Dwrite_chunk. A chunk that deflate cannot shrink is stored as is, its filters marked as
  /// skipped in the filter mask (as HDF5's optional filters do).
  void write_compressed_chunks(hid_t target, std::span<const float> values, bool series_axis) {
    const std::int64_t chunks = layout.chunk_count();
    std::vector<std::vector<std::byte>> encoded(static_cast<std::size_t>(chunks));
    std::vector<std::uint32_t> masks(static_cast<std::size_t>(chunks), 0);
    const std::size_t slice_bytes = layout.slice_floats * sizeof(float);
    tbb::parallel_for(std::int64_t{0}, chunks, [&](std::int64_t c) {
      const std::int64_t first = c * layout.chunk_slices;
      const std::int64_t count = std::min(layout.chunk_slices, layout.slices - first);
      // HDF5 chunks are always whole: an edge chunk is padded (with zeros) past the last slice.
      const std::size_t bytes = static_cast<std::size_t>(layout.chunk_slices) * slice_bytes;
      const auto* source = reinterpret_cast<const std::byte*>(values.data()) +
                           static_cast<std::size_t>(first) * slice_bytes;
      std::vector<std::byte> padded;
      if (count < layout.chunk_slices) {
        padded.assign(bytes, std::byte{0});
        std::memcpy(padded.data(), source, static_cast<std::size_t>(count) * slice_bytes);
        source = padded.data();
      }
      masks[static_cast<std::size_t>(c)] =
          encode_chunk(source, bytes, encoded[static_cast<std::size_t>(c)]);
    });
    for (std::int64_t c = 0; c < chunks; ++c) {
      std::vector<hsize_t> offset(shape.size() + (series_axis ? 1 : 0), 0);
      if (series_axis) offset[0] = written;
      offset[series_axis ? 1 : 0] = static_cast<hsize_t>(c * layout.chunk_slices);
      const auto& chunk = encoded[static_cast<std::size_t>(c)];
      if (H5Dwrite_chunk(target, H5P_DEFAULT, masks[static_cast<std::size_t>(c)], offset.data(),
                         chunk.size(), chunk.data()) < 0)
        throw IoError("cannot write chunk " + std::to_string(c) + " of step " +
                      std::to_string(written) + " of " + where() + failure_cause(temp));
    }
  }

  /// Encodes one chunk with the dataset's filters into `out`; returns HDF5's filter mask (bits of
  /// the filters skipped: a chunk that gzip cannot shrink is stored raw, as HDF5's optional
  /// filters do).
  std::uint32_t encode_chunk(const std::byte* source, std::size_t bytes,
                             std::vector<std::byte>& out) const {
    if (codec == Hdf5Codec::none) {
      out.assign(source, source + bytes);
      return 0;
    }
    if (codec != Hdf5Codec::gzip) {
      out = detail::blosc_encode(source, bytes, codec, level);
      return 0;
    }
    const std::byte* unfiltered = source;
    std::vector<std::byte> shuffled;
    if (options.shuffle) {
      shuffled.resize(bytes);
      detail::shuffle4(source, bytes, shuffled.data());
      source = shuffled.data();
    }
    uLongf size = compressBound(static_cast<uLong>(bytes));
    out.resize(size);
    const int rc = compress2(reinterpret_cast<Bytef*>(out.data()), &size,
                             reinterpret_cast<const Bytef*>(source), static_cast<uLong>(bytes),
                             level);
    if (rc == Z_OK && size < bytes) {
      out.resize(size);
      return 0;
    }
    out.assign(unfiltered, unfiltered + bytes);  // every filter skipped
    return options.shuffle ? 0x3u : 0x1u;
  }

  /// Bricked storage: gathers every brick of the step (edge bricks padded with zeros, HDF5 chunks
  /// being whole), encodes them in parallel and stores them with H5Dwrite_chunk.
  void write_bricks(hid_t target, std::span<const float> values) {
    const std::size_t count = bricks.bricks();
    const auto c = static_cast<std::size_t>(description.components);
    const GridGeometry& g = description.geometry;
    std::vector<std::vector<std::byte>> encoded(count);
    std::vector<std::uint32_t> masks(count, 0);
    tbb::parallel_for(std::size_t{0}, count, [&](std::size_t b) {
      const auto bi = static_cast<std::int64_t>(b) % bricks.count[0];
      const auto bj = (static_cast<std::int64_t>(b) / bricks.count[0]) % bricks.count[1];
      const auto bk = static_cast<std::int64_t>(b) / (bricks.count[0] * bricks.count[1]);
      const std::int64_t i0 = bi * bricks.size[0], j0 = bj * bricks.size[1],
                         k0 = bk * bricks.size[2];
      const std::int64_t nx = std::min(bricks.size[0], g.size[0] - i0);
      std::vector<float> brick(bricks.brick_points() * c, 0.0f);
      for (std::int64_t k = 0; k < std::min(bricks.size[2], g.size[2] - k0); ++k)
        for (std::int64_t j = 0; j < std::min(bricks.size[1], g.size[1] - j0); ++j)
          std::memcpy(brick.data() + static_cast<std::size_t>((k * bricks.size[1] + j) *
                                                               bricks.size[0]) * c,
                      values.data() + g.index(i0, j0 + j, k0 + k) * c,
                      static_cast<std::size_t>(nx) * c * sizeof(float));
      masks[b] = encode_chunk(reinterpret_cast<const std::byte*>(brick.data()),
                              brick.size() * sizeof(float), encoded[b]);
    });
    for (std::size_t b = 0; b < count; ++b) {
      const auto bi = static_cast<std::int64_t>(b) % bricks.count[0];
      const auto bj = (static_cast<std::int64_t>(b) / bricks.count[0]) % bricks.count[1];
      const auto bk = static_cast<std::int64_t>(b) / (bricks.count[0] * bricks.count[1]);
      // [step][k0][j0][i0][0] (2D: [step][j0][i0][0]).
      std::array<hsize_t, 5> offset{written, 0, 0, 0, 0};
      const std::size_t n = shape.size() + 1;
      offset[n - 2] = static_cast<hsize_t>(bi * bricks.size[0]);
      offset[n - 3] = static_cast<hsize_t>(bj * bricks.size[1]);
      if (g.dimension == 3) offset[n - 4] = static_cast<hsize_t>(bk * bricks.size[2]);
      if (H5Dwrite_chunk(target, H5P_DEFAULT, masks[b], offset.data(), encoded[b].size(),
                         encoded[b].data()) < 0)
        throw IoError("cannot write brick " + std::to_string(b) + " of step " +
                      std::to_string(written) + " of " + where() + failure_cause(temp));
    }
  }

  void commit() {
    const std::size_t total =
        description.storage == Hdf5Storage::steady ? 1 : description.times.size();
    if (written != total)
      throw InvalidArgument("HDF5 layout: " + std::to_string(written) + " of " +
                            std::to_string(total) + " steps written to " + where());
    dataset.reset();
    steps_group.reset();
    group.reset();
    if (H5Fflush(h5file.get(), H5F_SCOPE_GLOBAL) < 0 || !h5file.reset())
      throw IoError("cannot write HDF5 file " + temp.string() + failure_cause(temp));
    std::error_code error;
    std::filesystem::rename(temp, file, error);
    if (error)
      throw IoError("cannot rename " + temp.string() + " to " + file.string() + ": " +
                    error.message());
    committed = true;
    if (options.xdmf && xdmf_readable(options)) {
      try {
        const std::string text = detail::xdmf_text(description, file.filename().string());
        write_atomically(xdmf_path(file), [&](std::ofstream& out) { out << text; });
      } catch (...) {
        std::filesystem::remove(file, error);
        throw;
      }
    } else if (options.xdmf) {
      std::filesystem::remove(xdmf_path(file), error);  // it described the file replaced
    }
  }
};

}  // namespace

struct Hdf5SeriesWriter::Impl : FieldWriter {
  using FieldWriter::FieldWriter;
};

Hdf5SeriesWriter::Hdf5SeriesWriter(const std::filesystem::path& file, const GridGeometry& geometry,
                                   int components, std::vector<double> times,
                                   const Hdf5WriteOptions& options)
    : impl_(std::make_unique<Impl>(file, geometry, components, std::move(times), options,
                                   options.storage == Hdf5Storage::steady
                                       ? Hdf5Storage::bricked
                                       : options.storage)) {}

Hdf5SeriesWriter::~Hdf5SeriesWriter() = default;

void Hdf5SeriesWriter::write_step(std::span<const float> values) {
  impl_->write_step(values);
}
std::size_t Hdf5SeriesWriter::steps_written() const {
  return impl_->written;
}
void Hdf5SeriesWriter::commit() {
  impl_->commit();
}

void write_hdf5_grid(const VectorGrid& grid, const std::filesystem::path& file,
                     const Hdf5WriteOptions& options) {
  FieldWriter writer(file, grid.geometry, grid.components, {}, options, Hdf5Storage::steady);
  writer.write_step(grid.values);
  writer.commit();
}

}  // namespace orthofront::io
