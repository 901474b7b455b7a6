#pragma once
/// Internal helpers of the HDF5 layout: owning HDF5 ids, attribute access, the chunk encoding
/// (byte shuffle + deflate) shared by the writer and the reader, and the XDMF sidecar.
#include <hdf5.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "orthofront/io/hdf5_layout.h"

namespace orthofront::io::detail {

/// Owns one HDF5 id and closes it with the matching H5?close.
class H5Id {
 public:
  using Closer = herr_t (*)(hid_t);
  H5Id() = default;
  H5Id(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  H5Id(H5Id&& other) noexcept { *this = std::move(other); }
  H5Id& operator=(H5Id&& other) noexcept {
    if (this != &other) {
      reset();
      id_ = std::exchange(other.id_, H5I_INVALID_HID);
      closer_ = other.closer_;
    }
    return *this;
  }
  H5Id(const H5Id&) = delete;
  H5Id& operator=(const H5Id&) = delete;
  ~H5Id() { reset(); }

  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  /// Closes now; returns false when closing failed (a file close flushes: that can fail).
  bool reset() {
    bool ok = true;
    if (id_ >= 0 && closer_ != nullptr) ok = closer_(id_) >= 0;
    id_ = H5I_INVALID_HID;
    return ok;
  }

 private:
  hid_t id_ = H5I_INVALID_HID;
  Closer closer_ = nullptr;
};

/// Turns off HDF5's printing of its error stack (the project reports errors itself). Idempotent.
void silence_hdf5();

/// The innermost description on HDF5's error stack of this thread ("truncated file: eof = 1000,
/// sblock->base_addr = 0, stored_eof = 5769"), for messages; empty when the stack is empty.
std::string hdf5_error_cause();


/// "/" for "", "/", and "a/b/" -> "/a/b".
std::string normalize_group(const std::string& group);
/// group + "/" + name without doubling the slash at the root.
std::string child_path(const std::string& group, const std::string& name);

// --- attributes ------------------------------------------------------------------------------
bool has_attribute(hid_t object, const char* name);
void write_string_attribute(hid_t object, const char* name, const std::string& value);
void write_int_attribute(hid_t object, const char* name, int value);
void write_float_attribute(hid_t object, const char* name, float value);
void write_doubles_attribute(hid_t object, const char* name, std::span<const double> values);
/// Empty optional when absent. Throws FormatError "<where>: attribute '<name>' ..." when the
/// attribute exists but is not of the expected kind.
std::optional<std::string> read_string_attribute(hid_t object, const char* name,
                                                 const std::string& where);
std::optional<std::vector<double>> read_doubles_attribute(hid_t object, const char* name,
                                                          const std::string& where);

// --- chunk encoding ----------------------------------------------------------------------------
/// Registers the Blosc filter (id 32001) with HDF5 once per process, so datasets compressed with
/// lz4 or zstd can be created and read through HDF5's own pipeline too.
void register_blosc_filter();
/// Blosc compressor name of a codec ("lz4", "zstd") and the default level.
const char* blosc_compressor(Hdf5Codec codec);
int default_level(Hdf5Codec codec);
/// The filter's 7 parameters as hdf5-blosc writes them: filter revision, Blosc format version,
/// type size, chunk bytes, level, shuffle, compressor code.
std::vector<unsigned> blosc_parameters(Hdf5Codec codec, int level, std::size_t chunk_bytes);
/// Compresses `bytes` floats-worth of data with Blosc (byte shuffle, one thread per call).
std::vector<std::byte> blosc_encode(const std::byte* data, std::size_t bytes, Hdf5Codec codec,
                                    int level);
/// Decodes one Blosc frame into `out`, which must be exactly the frame's decoded size; throws
/// FormatError naming `context` on damaged data.
void blosc_decode(const std::byte* data, std::size_t size, std::span<std::byte> out,
                  const std::string& context);

/// HDF5's shuffle filter for 4-byte elements: byte b of element i goes to b * n + i.
void shuffle4(const std::byte* in, std::size_t bytes, std::byte* out);
void unshuffle4(const std::byte* in, std::size_t bytes, std::byte* out);

/// Where the slowest spatial axis of a step lies and how it is chunked: a step is `slices`
/// slices (z for 3D, y for 2D) of `slice_floats` floats; a chunk holds `chunk_slices` slices.
struct SliceLayout {
  std::int64_t slices = 0;
  std::size_t slice_floats = 0;
  std::int64_t chunk_slices = 0;
  std::int64_t chunk_count() const { return (slices + chunk_slices - 1) / chunk_slices; }
};
SliceLayout slice_layout(const GridGeometry& geometry, int components, std::size_t max_chunk_bytes);

/// Dataset shape of one step: [nz][ny][nx][C] (3D) or [ny][nx][C] (2D).
std::vector<hsize_t> step_shape(const GridGeometry& geometry, int components);

// --- XDMF ---------------------------------------------------------------------------------------
/// The sidecar text for `description`, whose samples live in `h5_name` (a path relative to the
/// sidecar, normally the file name).
std::string xdmf_text(const Hdf5Description& description, const std::string& h5_name);

}  // namespace orthofront::io::detail
