# Vector-grid readers and writers of real data formats (.vec, AmiraMesh, NRRD, VTK XML ImageData,
# legacy VTK, ParaView collections), their shared helpers and the file-per-step time series.
find_package(ZLIB REQUIRED)
find_package(BZip2 REQUIRED)  # NRRD's bzip2 encoding
target_sources(orthofront_io PRIVATE
  orthofront/io/zlib_codec.cpp
  orthofront/io/bzip2_codec.cpp
  orthofront/io/vtk_xml.cpp
  orthofront/io/grid_decode.cpp
  orthofront/io/vec_reader.cpp
  orthofront/io/amira_reader.cpp
  orthofront/io/nrrd_reader.cpp
  orthofront/io/vti_reader.cpp
  orthofront/io/vtk_legacy_reader.cpp
  orthofront/io/grid_file.cpp
  orthofront/io/grid_series.cpp
)
target_link_libraries(orthofront_io PRIVATE ZLIB::ZLIB BZip2::BZip2)

# OpenVDB: sparse vector grids (reader, writer, time series) and the field that samples them,
# in a module that orthofront_io loads on first use (vdb_module.h): linked, libopenvdb's
# start-up would be paid by every process, also those that read no .vdb file.
add_library(orthofront_vdb SHARED
  orthofront/io/vdb_grid.cpp
  orthofront/io/vdb_field.cpp
)
target_link_libraries(orthofront_vdb PUBLIC orthofront_io OpenVDB::openvdb
  PRIVATE orthofront_warnings)
# Installed beside liborthofront_io.so, where it is looked for first.
install(TARGETS orthofront_vdb LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
target_sources(orthofront_io PRIVATE orthofront/io/vdb_module.cpp)
target_link_libraries(orthofront_io PRIVATE ${CMAKE_DL_LIBS})

# OpenEXR: per-front quantities of a surface over (s, step) as a multi-channel float image.
target_sources(orthofront_io PRIVATE orthofront/io/exr_front_image.cpp)
target_link_libraries(orthofront_io PRIVATE OpenEXR::OpenEXR)
