#include "vtkOrthofrontSurfaceFilter.h"

#include <charconv>
#include <cmath>
#include <exception>
#include <memory>
#include <vector>

#include "jobs/option_spelling.h"
#include "jobs/output_notes.h"
#include "jobs/path_run.h"
#include "jobs/streak_report.h"
#include "jobs/streak_run.h"
#include "jobs/surface_kind.h"
#include "orthofront/error.h"
#include "orthofront/field/grid_field.h"
#include "orthofront/seed/seed_curve.h"
#include "dataset_grid.h"
#include "mesh_polydata.h"
#include "paraview_names.h"
#include "step_collector.h"
#include "vtkDataArray.h"
#include "vtkDataSet.h"
#include "vtkDataSetAttributes.h"
#include "vtkDemandDrivenPipeline.h"
#include "vtkFieldData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkPolyData.h"
#include "vtkStreamingDemandDrivenPipeline.h"

namespace {

using namespace orthofront;

// The shortest text that reads back as exactly `value` (as the schema parses it).
std::string number(double value) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, value).ptr;
  return std::string(text, end);
}

/// The options stored by the setters, parsed into `options` as the command line parses its
/// flags; a from-data option left at 0 (or empty) is not given. Errors name the property.
void parse_options(const std::map<std::string, std::string>& stored, jobs::KindOptions& options) {
  for (const jobs::OptionSpec& spec : options.set.specs()) {
    const auto given = stored.find(spec.name);
    if (given == stored.end() || !orthofront::paraview::on_panel(spec)) continue;
    const std::string& text = given->second;
    if (orthofront::paraview::from_data(spec) && (text.empty() || text == "0")) continue;
    try {
      options.set.set(spec.name, text);
    } catch (const InvalidArgument& e) {
      throw InvalidArgument(orthofront::paraview::property_label(spec.name) + ": " + e.what());
    }
  }
}

std::string line_seed_name(const Vec3& p1, const Vec3& p2) {
  return "line:" + number(p1.x()) + "," + number(p1.y()) + "," + number(p1.z()) + ":" +
         number(p2.x()) + "," + number(p2.y()) + "," + number(p2.z());
}

std::string option_text(const std::map<std::string, std::string>& stored, const char* option) {
  const auto it = stored.find(option);
  return it == stored.end() ? std::string() : it->second;
}


/// The input times from the last at or before lo to the first at or after hi.
std::vector<double> times_covering(const std::vector<double>& times, double lo, double hi) {
  std::size_t first = 0, last = times.size() - 1;
  while (first + 1 < times.size() && times[first + 1] <= lo) ++first;
  while (last > 0 && times[last - 1] >= hi) --last;
  if (last <= first)
    throw InvalidArgument("the input's times " + number(times.front()) + " to " +
                          number(times.back()) + " do not cover " + number(lo) + " to " +
                          number(hi) + " with two steps or more");
  return {times.begin() + static_cast<std::ptrdiff_t>(first),
          times.begin() + static_cast<std::ptrdiff_t>(last) + 1};
}

/// The input and its selected vectors as a grid, or InvalidArgument saying what is missing.
std::shared_ptr<const VectorGrid> input_grid(vtkInformationVector** inputVector,
                                             vtkDataArray* vectors) {
  vtkDataSet* data = vtkDataSet::GetData(inputVector[0]);
  if (data == nullptr) throw InvalidArgument("the input is not a dataset");
  if (vectors == nullptr)
    throw InvalidArgument("the input has no point vector array (choose one under Vectors)");
  return orthofront::paraview::dataset_grid(data, vectors);
}

}  // namespace

struct vtkOrthofrontSurfaceFilter::Run {
  std::unique_ptr<orthofront::paraview::StepCollector> steps;
  vtkMTimeType key = 0;
};

vtkOrthofrontSurfaceFilter::vtkOrthofrontSurfaceFilter(const char* kind) : Kind(kind) {
  this->SetNumberOfInputPorts(1);
  this->SetInputArrayToProcess(0, 0, 0, vtkDataObject::FIELD_ASSOCIATION_POINTS,
                               vtkDataSetAttributes::VECTORS);
}

vtkOrthofrontSurfaceFilter::~vtkOrthofrontSurfaceFilter() = default;

void vtkOrthofrontSurfaceFilter::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Kind: " << this->Kind << "\n";
  os << indent << "Point1: " << this->Point1[0] << " " << this->Point1[1] << " " << this->Point1[2] << "\n";
  os << indent << "Point2: " << this->Point2[0] << " " << this->Point2[1] << " " << this->Point2[2] << "\n";
  for (const auto& [name, value] : this->Options) os << indent << name << ": " << value << "\n";
}

int vtkOrthofrontSurfaceFilter::FillInputPortInformation(int, vtkInformation* info) {
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkDataSet");  // dataset_grid() says which
  return 1;
}

void vtkOrthofrontSurfaceFilter::StoreOption(const char* option, const std::string& text) {
  std::string& stored = this->Options[option];
  if (stored == text) return;
  stored = text;
  this->Modified();
}

void vtkOrthofrontSurfaceFilter::SetOptionValue(const char* option, double value) {
  this->StoreOption(option, number(value));
}
void vtkOrthofrontSurfaceFilter::SetOptionValue(const char* option, int value) {
  this->StoreOption(option, std::to_string(value));
}
void vtkOrthofrontSurfaceFilter::SetOptionValue(const char* option, vtkIdType value) {
  this->StoreOption(option, std::to_string(value));
}
void vtkOrthofrontSurfaceFilter::SetOptionValue(const char* option, int value, bool) {
  this->StoreOption(option, value != 0 ? "true" : "false");
}
void vtkOrthofrontSurfaceFilter::SetOptionValue(const char* option, int index,
                                                std::initializer_list<const char*> words) {
  // An index outside the words reaches the schema as itself, which refuses it by name.
  const std::string text = index >= 0 && static_cast<std::size_t>(index) < words.size()
                               ? std::string(words.begin()[index])
                               : std::to_string(index);
  this->StoreOption(option, text);
}
void vtkOrthofrontSurfaceFilter::SetOptionValue(const char* option, const char* value) {
  this->StoreOption(option, value ? value : "");
}

namespace {

// What a built surface depends on: the filter's properties and everything upstream.
vtkMTimeType pipeline_key(vtkAlgorithm* filter) {
  auto* upstream = vtkDemandDrivenPipeline::SafeDownCast(filter->GetInputExecutive(0, 0));
  return std::max(filter->GetMTime(), upstream ? upstream->GetPipelineMTime() : vtkMTimeType{0});
}

}  // namespace

int vtkOrthofrontSurfaceFilter::RequestInformation(vtkInformation*,
                                                   vtkInformationVector** inputVector,
                                                   vtkInformationVector* outputVector) {
  vtkInformation* in = inputVector[0]->GetInformationObject(0);
  vtkInformation* out = outputVector->GetInformationObject(0);
  this->InputTimes.clear();
  if (in->Has(vtkStreamingDemandDrivenPipeline::TIME_STEPS())) {
    const double* times = in->Get(vtkStreamingDemandDrivenPipeline::TIME_STEPS());
    this->InputTimes.assign(times, times + in->Length(vtkStreamingDemandDrivenPipeline::TIME_STEPS()));
  }
  out->Remove(vtkStreamingDemandDrivenPipeline::TIME_STEPS());
  out->Remove(vtkStreamingDemandDrivenPipeline::TIME_RANGE());
  if (this->Kind != "streak") return 1;
  // The frames are the output's time steps: named, or the input's steps after the release.
  this->FrameTimes.clear();
  try {
    const std::string frames = option_text(this->Options, "frames");
    if (!frames.empty()) {
      this->FrameTimes = jobs::parse_streak_frames(frames);
    } else if (!this->InputTimes.empty()) {
      const std::string release = option_text(this->Options, "release");
      const double begin = release.empty() ? this->InputTimes.front()
                                           : jobs::parse_streak_release(release).first;
      for (const double t : this->InputTimes)
        if (t > begin) this->FrameTimes.push_back(t);
    }
  } catch (const std::exception&) {
    this->FrameTimes.clear();  // RequestData says what is wrong
  }
  if (!this->FrameTimes.empty()) {
    out->Set(vtkStreamingDemandDrivenPipeline::TIME_STEPS(), this->FrameTimes.data(),
             static_cast<int>(this->FrameTimes.size()));
    const double range[2] = {this->FrameTimes.front(), this->FrameTimes.back()};
    out->Set(vtkStreamingDemandDrivenPipeline::TIME_RANGE(), range, 2);
  }
  return 1;
}

std::vector<double> vtkOrthofrontSurfaceFilter::NeededTimes() const {
  if (this->InputTimes.size() < 2)
    throw InvalidArgument("the input has " + std::to_string(this->InputTimes.size()) +
                          " time steps: a " + this->Kind +
                          " surface needs a time series (open its files as one reader)");
  const std::vector<double>& times = this->InputTimes;
  if (this->Kind == "path") {
    const std::string t0 = option_text(this->Options, "t0"), t1 = option_text(this->Options, "t1");
    const double a = t0.empty() ? times.front() : jobs::parse_time_number(t0, "T0");
    const double b = t1.empty() ? times.back() : jobs::parse_time_number(t1, "T1");
    return times_covering(times, std::min(a, b), std::max(a, b));
  }
  const std::string release = option_text(this->Options, "release");
  const double begin = release.empty() ? times.front() : jobs::parse_streak_release(release).first;
  if (this->FrameTimes.empty())
    throw InvalidArgument("Frames: no observation time after the release begins at " +
                          number(begin));
  return times_covering(times, begin, this->FrameTimes.back());
}

int vtkOrthofrontSurfaceFilter::RequestUpdateExtent(vtkInformation*,
                                                    vtkInformationVector** inputVector,
                                                    vtkInformationVector*) {
  if (this->Kind == "stream") return 1;
  vtkInformation* in = inputVector[0]->GetInformationObject(0);
  if (!this->Collecting) {
    if (!this->Surfaces.empty() && this->SurfacesKey == pipeline_key(this))
      return 1;  // built: any frame is served from them
    this->Surfaces.clear();
    auto run = std::make_unique<Run>();
    run->key = pipeline_key(this);
    try {
      run->steps = std::make_unique<orthofront::paraview::StepCollector>(this->NeededTimes(),
                                                                          this->ZerosAreNoData != 0);
    } catch (const std::exception& e) {
      this->Report = e.what();  // RequestData reports it
      return 1;
    }
    this->Report.clear();
    this->Collecting = std::move(run);
  }
  in->Set(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP(),
          this->Collecting->steps->next_time());
  return 1;
}

int vtkOrthofrontSurfaceFilter::RequestData(vtkInformation* request,
                                            vtkInformationVector** inputVector,
                                            vtkInformationVector* outputVector) {
  vtkPolyData* output = vtkPolyData::GetData(outputVector);
  try {
    if (this->Kind == "stream") {
      this->RunStream(inputVector, output);
      return 1;
    }
    if (this->Collecting) {
      this->CollectStep(request, inputVector);
      if (this->Collecting) return 1;  // CONTINUE_EXECUTING: the next step comes
    } else if (this->Surfaces.empty()) {
      throw InvalidArgument(this->Report.empty() ? "no surface was built" : this->Report);
    }
    this->OutputFrame(outputVector);
  } catch (const std::exception& e) {
    this->Collecting.reset();
    this->Surfaces.clear();
    request->Remove(vtkStreamingDemandDrivenPipeline::CONTINUE_EXECUTING());
    output->Initialize();
    vtkErrorMacro(<< jobs::spell_options(e.what(), jobs::OptionSpelling::paraview));
    return 0;
  }
  return 1;
}

void vtkOrthofrontSurfaceFilter::CollectStep(vtkInformation* request,
                                             vtkInformationVector** inputVector) {
  orthofront::paraview::StepCollector& steps = *this->Collecting->steps;
  steps.add(*input_grid(inputVector, this->GetInputArrayToProcess(0, inputVector)));
  // Reading the steps is the first half of the work shown.
  this->UpdateProgress(0.5 * static_cast<double>(steps.written()) / static_cast<double>(steps.size()));
  if (!steps.complete()) {
    request->Set(vtkStreamingDemandDrivenPipeline::CONTINUE_EXECUTING(), 1);
    return;
  }
  request->Remove(vtkStreamingDemandDrivenPipeline::CONTINUE_EXECUTING());
  const std::unique_ptr<Run> run = std::move(this->Collecting);
  const std::unique_ptr<io::TimeSeries> series = run->steps->open();
  vtkDataArray* vectors = this->GetInputArrayToProcess(0, inputVector);
  const std::string field = std::string("ParaView input, array '") +
                            (vectors && vectors->GetName() ? vectors->GetName() : "") + "'";
  const Vec3 p1(this->Point1[0], this->Point1[1], this->Point1[2]);
  const Vec3 p2(this->Point2[0], this->Point2[1], this->Point2[2]);
  const SeedCurve curve = SeedCurve::polyline({p1, p2}, false);
  const auto keep_going = [this] { return this->GetAbortExecute() == 0; };
  jobs::KindOptions options(*jobs::parse_surface_kind(this->Kind));
  parse_options(this->Options, options);
  if (this->Kind == "path") {
    jobs::PathArgs& args = options.path;
    args.field = field;
    args.seed = line_seed_name(p1, p2);
    if (!options.set.given("t0")) args.t0_text = number(series->time(0));
    if (!options.set.given("t1")) args.t1_text = number(series->time(series->step_count() - 1));
    jobs::apply_memory_limits(options.set, args.limits, args.options);
    jobs::check_seed_count(args.seed_count, args.options.max_vertices);
    jobs::PathRun result = jobs::run_path_surface(series.get(), nullptr, curve, args,
                                                  options.set.given("edge"), keep_going);
    result.result.mesh.notes = jobs::output_notes("path", field, series.get());
    vtkNew<vtkPolyData> surface;
    orthofront::paraview::mesh_to_polydata(result.result.mesh, surface);
    this->Report = result.report.dump(2);
    orthofront::paraview::add_text(surface->GetFieldData(), "orthofront_report", this->Report);
    this->Surfaces.emplace_back(surface);
    if (!result.result.report.complete)
      vtkWarningMacro(<< "the path surface is not complete (stopped: "
                      << to_string(result.result.report.stop_reason) << ")");
  } else {
    jobs::StreakArgs& args = options.streak;
    args.field = field;
    args.seed = line_seed_name(p1, p2);
    if (!options.set.given("release"))
      options.set.set("release", number(this->InputTimes.front()) + ":" +
                                     number(this->InputTimes.back()));
    if (!options.set.given("frames")) {
      std::string list;
      for (const double t : this->FrameTimes) list += (list.empty() ? "" : ",") + number(t);
      options.set.set("frames", list);
    }
    jobs::StreakRun result =
        jobs::run_streak_surface(series.get(), nullptr, curve, options.set, args, keep_going);
    this->Report = result.report.dump(2);
    const jobs::MeshNotes notes = jobs::output_notes("streak", field, series.get());
    for (spacetime::StreakFrame& frame : result.frames) {
      frame.mesh.notes = notes;
      vtkNew<vtkPolyData> surface;
      orthofront::paraview::mesh_to_polydata(frame.mesh, surface);
      orthofront::paraview::add_text(surface->GetFieldData(), "orthofront_report", this->Report);
      this->Surfaces.emplace_back(surface);
    }
    if (result.frames.size() < this->FrameTimes.size())
      vtkWarningMacro(<< "the streak surface stopped after " << result.frames.size() << " of "
                      << this->FrameTimes.size() << " frames: "
                      << jobs::spell_options(result.result.message, jobs::OptionSpelling::paraview));
    if (this->Surfaces.empty()) throw InvalidArgument("the streak surface made no frame: " + result.result.message);
  }
  this->SurfacesKey = run->key;
}

void vtkOrthofrontSurfaceFilter::OutputFrame(vtkInformationVector* outputVector) {
  vtkInformation* out = outputVector->GetInformationObject(0);
  vtkPolyData* output = vtkPolyData::GetData(outputVector);
  std::size_t frame = 0;
  if (this->Kind == "streak" && out->Has(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP())) {
    // The last frame at or before the time asked for (the first before them all).
    const double t = out->Get(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP());
    while (frame + 1 < this->Surfaces.size() && frame + 1 < this->FrameTimes.size() &&
           this->FrameTimes[frame + 1] <= t)
      ++frame;
  }
  output->ShallowCopy(this->Surfaces[frame]);
  if (this->Kind == "streak" && frame < this->FrameTimes.size())
    output->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), this->FrameTimes[frame]);
}

void vtkOrthofrontSurfaceFilter::RunStream(vtkInformationVector** inputVector, vtkPolyData* output) {
  vtkDataArray* vectors = this->GetInputArrayToProcess(0, inputVector);
  const std::shared_ptr<const VectorGrid> grid = input_grid(inputVector, vectors);
  jobs::KindOptions options(jobs::SurfaceKind::stream);
  parse_options(this->Options, options);
  jobs::SurfaceJob& job = options.stream;
  jobs::apply_memory_limits(options.set, options.stream_limits, job.options);
  GridFieldOptions field_options;
  field_options.zero_is_no_data = this->ZerosAreNoData != 0;
  const GridField field(grid, field_options);
  const Vec3 p1(this->Point1[0], this->Point1[1], this->Point1[2]);
  const Vec3 p2(this->Point2[0], this->Point2[1], this->Point2[2]);
  const SeedCurve curve = SeedCurve::polyline({p1, p2}, false);
  job.seed = line_seed_name(p1, p2);
  job.field = std::string("ParaView input, array '") + (vectors->GetName() ? vectors->GetName() : "") + "'";
  job.edge_given = options.set.given("edge");
  const Seed<3> seed = jobs::prepare_stream_seed(field, curve, job);
  const std::string cap =
      jobs::vertex_cap_warning(curve.length(), field.domain().extent(), job.options);
  if (!cap.empty()) vtkWarningMacro(<< jobs::spell_options(cap, jobs::OptionSpelling::paraview));
  SurfaceResult result = jobs::run_stream_job(
      field, seed, job,
      [this](const orthofront::Progress& p) {
        if (p.max_steps > 0) this->UpdateProgress(static_cast<double>(p.step) / p.max_steps);
        return this->GetAbortExecute() == 0;
      },
      {}, nullptr);
  result.mesh.notes = jobs::output_notes("stream", job.field, nullptr);
  output->Initialize();
  orthofront::paraview::mesh_to_polydata(result.mesh, output);
  this->Report = jobs::stream_report(result.report, job, options.stream_limits, {}).dump(2);
  orthofront::paraview::add_text(output->GetFieldData(), "orthofront_report", this->Report);
  if (!result.report.complete)
    vtkWarningMacro(<< "the surface is not complete (stopped: "
                    << to_string(result.report.stop_reason) << ")");
}
