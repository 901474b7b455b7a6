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
# HDF5 is public in the build tree (the tests use the C API on the files); an installed
# orthofront_io keeps it to itself (no public header of the package needs it).
target_link_libraries(orthofront_io PUBLIC $<BUILD_INTERFACE:hdf5::hdf5>
  PRIVATE ZLIB::ZLIB PkgConfig::BLOSC)
