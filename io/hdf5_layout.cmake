# The project's HDF5 layout (docs/hdf5-layout.md): steady fields and time series, XDMF sidecars,
# raw chunk reads decoded (zlib + unshuffle) in parallel.
find_package(ZLIB REQUIRED)
# Blosc (lz4/zstd chunk codecs): Debian's libblosc-dev ships a pkg-config file, no CMake package.
find_package(PkgConfig REQUIRED)
pkg_check_modules(BLOSC REQUIRED IMPORTED_TARGET blosc)
target_sources(orthofront_io PRIVATE
  orthofront/io/hdf5_detail.cpp
  orthofront/io/hdf5_write.cpp
  orthofront/io/hdf5_read.cpp
)
# HDF5 is public: callers and tests may use the C API on the files (io depends on HDF5 by design).
target_link_libraries(orthofront_io PUBLIC hdf5::hdf5 PRIVATE ZLIB::ZLIB PkgConfig::BLOSC)
