#pragma once
// A sampled series written as a bricked HDF5 file (default codec) and opened again: the streamed
// side of "streamed == in memory" tests.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <vector>

#include "orthofront/io/hdf5_layout.h"
#include "orthofront/spacetime/sampled_series.h"

namespace spacetime_test {

inline std::unique_ptr<orthofront::io::Hdf5TimeSeries> write_bricked(
    const std::filesystem::path& file, const orthofront::spacetime::SampledTimeSeries& memory,
    std::int64_t brick) {
  orthofront::io::Hdf5WriteOptions w;
  w.brick_size = brick;
  w.zero_is_no_data = false;
  w.xdmf = false;
  std::vector<double> times;
  for (std::size_t k = 0; k < memory.step_count(); ++k) times.push_back(memory.time(k));
  orthofront::io::Hdf5SeriesWriter writer(file, memory.geometry(), memory.components(), times, w);
  std::vector<float> values(memory.step_floats());
  for (std::size_t k = 0; k < times.size(); ++k) {
    memory.sample(k, values.data());
    writer.write_step(values);
  }
  writer.commit();
  return orthofront::io::open_hdf5_series(file);
}

}  // namespace spacetime_test
