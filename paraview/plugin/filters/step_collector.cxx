#include "step_collector.h"

#include <cstdlib>
#include <string>
#include <system_error>

#include "orthofront/error.h"
#include "orthofront/io/error.h"

namespace orthofront::paraview {

StepCollector::StepCollector(std::vector<double> times, bool zero_is_no_data)
    : times_(std::move(times)), zero_is_no_data_(zero_is_no_data) {
  std::string pattern = (std::filesystem::temp_directory_path() / "orthofront-paraview-XXXXXX").string();
  if (mkdtemp(pattern.data()) == nullptr)
    throw io::IoError("cannot make a temporary folder for the time steps under " +
                      std::filesystem::temp_directory_path().string());
  folder_ = pattern;
  file_ = folder_ / "steps.h5";
}

StepCollector::~StepCollector() {
  writer_.reset();  // removes an unfinished file
  std::error_code ignored;
  std::filesystem::remove_all(folder_, ignored);
}

void StepCollector::add(const VectorGrid& step) {
  if (complete()) throw InvalidArgument("more time steps than asked for");
  const GridGeometry& g = step.geometry;
  if (!writer_) {
    geometry_ = g;
    components_ = step.components;
    io::Hdf5WriteOptions options;
    options.xdmf = false;
    options.zero_is_no_data = zero_is_no_data_;
    writer_ = std::make_unique<io::Hdf5SeriesWriter>(file_, g, step.components, times_, options);
  } else if (g.dimension != geometry_.dimension || g.size != geometry_.size ||
             g.origin != geometry_.origin || g.spacing != geometry_.spacing ||
             step.components != components_) {
    throw InvalidArgument("the input's grid changes at time " + std::to_string(times_[written_]) +
                          ": every time step must have the first step's extent, origin and spacing");
  }
  writer_->write_step(step.values);
  ++written_;
}

std::unique_ptr<io::TimeSeries> StepCollector::open() {
  if (!complete()) throw InvalidArgument("the time steps are not all collected");
  writer_->commit();
  writer_.reset();
  return io::open_hdf5_series(file_);
}

}  // namespace orthofront::paraview
