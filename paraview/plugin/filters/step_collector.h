#pragma once
/// A pipeline input's time steps, written one at a time as ParaView hands them over, into a
/// temporary series file in the project's HDF5 layout: a path or streak surface then streams
/// them through the brick cache, so memory stays at about one step however long the series.
/// The file (and its folder) go with the collector.
#include <cstddef>
#include <filesystem>
#include <memory>
#include <vector>

#include "orthofront/field/grid.h"
#include "orthofront/io/hdf5_layout.h"
#include "orthofront/io/time_series.h"

namespace orthofront::paraview {

class StepCollector {
 public:
  /// `times`: the steps to collect, increasing. Throws IoError where no temporary folder can be
  /// made.
  StepCollector(std::vector<double> times, bool zero_is_no_data);
  ~StepCollector();
  StepCollector(const StepCollector&) = delete;
  StepCollector& operator=(const StepCollector&) = delete;

  /// The next step's time.
  double next_time() const { return times_[written_]; }
  bool complete() const { return written_ == times_.size(); }
  std::size_t written() const { return written_; }
  std::size_t size() const { return times_.size(); }
  /// Writes the next step. Throws InvalidArgument where its grid differs from the first step's.
  void add(const VectorGrid& step);
  /// After the last step: the series (the collector must outlive it).
  std::unique_ptr<io::TimeSeries> open();

 private:
  std::vector<double> times_;
  bool zero_is_no_data_;
  std::size_t written_ = 0;
  std::filesystem::path folder_, file_;
  GridGeometry geometry_;
  int components_ = 0;
  std::unique_ptr<io::Hdf5SeriesWriter> writer_;
};

}  // namespace orthofront::paraview
