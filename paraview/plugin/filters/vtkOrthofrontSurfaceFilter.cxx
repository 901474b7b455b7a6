#include "vtkOrthofrontSurfaceFilter.h"

#include <cmath>
#include <cstdio>
#include <exception>
#include <memory>
#include <vector>

#include "jobs/edge_default.h"
#include "jobs/surface_kind.h"
#include "orthofront/error.h"
#include "orthofront/field/grid_field.h"
#include "orthofront/io/mesh_attributes.h"
#include "orthofront/io/report_json.h"
#include "orthofront/seed/seed_curve.h"
#include "paraview_names.h"
#include "vtkCellArray.h"
#include "vtkDataArray.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkMatrix3x3.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkStringArray.h"

namespace {

using namespace orthofront;

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

/// The image's vectors as a grid: 2D where the image is one slice thick (x, y of each vector),
/// 3D otherwise. Throws InvalidArgument naming what does not fit.
std::shared_ptr<const VectorGrid> image_grid(vtkImageData* image, vtkDataArray* vectors) {
  int extent[6];
  image->GetExtent(extent);
  double origin[3], spacing[3];
  image->GetOrigin(origin);
  image->GetSpacing(spacing);
  if (vtkMatrix3x3* direction = image->GetDirectionMatrix(); direction && !direction->IsIdentity())
    throw InvalidArgument("the input image is rotated (its direction matrix is not the "
                          "identity); resample it to an axis-aligned image first");
  const int dims[3] = {extent[1] - extent[0] + 1, extent[3] - extent[2] + 1,
                       extent[5] - extent[4] + 1};
  auto grid = std::make_shared<VectorGrid>();
  GridGeometry& g = grid->geometry;
  g.dimension = dims[2] == 1 ? 2 : 3;
  for (int a = 0; a < 3; ++a) {
    g.size[static_cast<std::size_t>(a)] = dims[a];
    g.origin[a] = origin[a] + extent[2 * a] * spacing[a];
    g.spacing[a] = spacing[a];
  }
  if (g.dimension == 2) g.spacing.z() = 1;
  const int components = vectors->GetNumberOfComponents();
  if (components < g.dimension || components > 3)
    throw InvalidArgument("the vector array '" + std::string(vectors->GetName() ? vectors->GetName() : "") +
                          "' has " + std::to_string(components) + " components; a " +
                          std::to_string(g.dimension) + "D image needs " +
                          std::to_string(g.dimension) + (g.dimension == 2 ? " or 3" : ""));
  const vtkIdType points = vectors->GetNumberOfTuples();
  if (static_cast<std::size_t>(points) != g.point_count())
    throw InvalidArgument("the vector array has " + std::to_string(points) +
                          " tuples for an image of " + std::to_string(g.point_count()) + " points");
  grid->components = g.dimension;
  grid->values.resize(g.point_count() * static_cast<std::size_t>(g.dimension));
  double tuple[3];
  for (vtkIdType i = 0; i < points; ++i) {  // VTK's point order is x fastest, as the grid's
    vectors->GetTuple(i, tuple);
    for (int c = 0; c < g.dimension; ++c)
      grid->values[static_cast<std::size_t>(i) * static_cast<std::size_t>(g.dimension) +
                   static_cast<std::size_t>(c)] = static_cast<float>(tuple[c]);
  }
  return grid;
}

/// The mesh as polydata: points, polygons (triangles and quads) and the recorded attributes.
void mesh_to_polydata(const Mesh& mesh, vtkPolyData* out) {
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(static_cast<vtkIdType>(mesh.vertex_count()));
  for (std::size_t i = 0; i < mesh.vertex_count(); ++i)
    points->SetPoint(static_cast<vtkIdType>(i), mesh.positions[i].data());
  vtkNew<vtkCellArray> polys;
  for (const Face& face : mesh.faces) {
    vtkIdType ids[4];
    for (int c = 0; c < face.size; ++c) ids[c] = face.v[static_cast<std::size_t>(c)];
    polys->InsertNextCell(face.size, ids);
  }
  out->SetPoints(points);
  out->SetPolys(polys);
  for (const auto& a : io::detail::kRealAttributes) {
    if (!io::detail::is_recorded(mesh, mesh.*a.values)) continue;
    vtkNew<vtkDoubleArray> array;
    array->SetName(a.name);
    array->SetNumberOfValues(static_cast<vtkIdType>(mesh.vertex_count()));
    for (std::size_t i = 0; i < mesh.vertex_count(); ++i)
      array->SetValue(static_cast<vtkIdType>(i), (mesh.*a.values)[i]);
    out->GetPointData()->AddArray(array);
  }
  for (const auto& a : io::detail::kIntAttributes) {
    if (!io::detail::is_recorded(mesh, mesh.*a.values)) continue;
    vtkNew<vtkIntArray> array;
    array->SetName(a.name);
    array->SetNumberOfValues(static_cast<vtkIdType>(mesh.vertex_count()));
    for (std::size_t i = 0; i < mesh.vertex_count(); ++i)
      array->SetValue(static_cast<vtkIdType>(i), (mesh.*a.values)[i]);
    out->GetPointData()->AddArray(array);
  }
}

void add_text(vtkFieldData* data, const char* name, const std::string& text) {
  vtkNew<vtkStringArray> array;
  array->SetName(name);
  array->InsertNextValue(text);
  data->AddArray(array);
}

}  // namespace

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
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkImageData");
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

int vtkOrthofrontSurfaceFilter::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                                            vtkInformationVector* outputVector) {
  vtkImageData* image = vtkImageData::GetData(inputVector[0]);
  vtkPolyData* output = vtkPolyData::GetData(outputVector);
  vtkDataArray* vectors = this->GetInputArrayToProcess(0, inputVector);
  if (image == nullptr || output == nullptr) {
    vtkErrorMacro(<< "the input is not a vtkImageData");
    return 0;
  }
  if (vectors == nullptr) {
    vtkErrorMacro(<< "the input has no point vector array (choose one under Vectors)");
    return 0;
  }
  const std::optional<jobs::SurfaceKind> kind = jobs::parse_surface_kind(this->Kind);
  if (kind != jobs::SurfaceKind::stream) {
    vtkErrorMacro(<< "the " << this->Kind << " surface filter is not built in this plugin");
    return 0;
  }
  try {
    jobs::KindOptions options(*kind);
    for (const jobs::OptionSpec& spec : options.set.specs()) {
      const auto given = this->Options.find(spec.name);
      if (given == this->Options.end() || !orthofront::paraview::on_panel(spec)) continue;
      const std::string& text = given->second;
      if (orthofront::paraview::from_data(spec) && (text.empty() || text == "0")) continue;
      try {
        options.set.set(spec.name, text);
      } catch (const InvalidArgument& e) {
        throw InvalidArgument(orthofront::paraview::property_label(spec.name) + ": " + e.what());
      }
    }
    jobs::SurfaceJob& job = options.stream;
    jobs::apply_memory_limits(options.set, options.stream_limits, job.options);
    GridFieldOptions field_options;
    field_options.zero_is_no_data = this->ZerosAreNoData != 0;
    const GridField field(image_grid(image, vectors), field_options);
    const Vec3 p1(this->Point1[0], this->Point1[1], this->Point1[2]);
    const Vec3 p2(this->Point2[0], this->Point2[1], this->Point2[2]);
    const SeedCurve curve = SeedCurve::polyline({p1, p2}, false);
    job.seed = "line:" + number(p1.x()) + "," + number(p1.y()) + "," + number(p1.z()) + ":" +
               number(p2.x()) + "," + number(p2.y()) + "," + number(p2.z());
    job.field = std::string("ParaView input, array '") + (vectors->GetName() ? vectors->GetName() : "") + "'";
    job.edge_given = options.set.given("edge");
    const Seed<3> seed = jobs::prepare_stream_seed(field, curve, job);
    const std::string cap =
        jobs::vertex_cap_warning(curve.length(), field.domain().extent(), job.options);
    if (!cap.empty()) vtkWarningMacro(<< cap);
    const SurfaceResult result = jobs::run_stream_job(
        field, seed, job,
        [this](const orthofront::Progress& p) {
          if (p.max_steps > 0) this->UpdateProgress(static_cast<double>(p.step) / p.max_steps);
          return this->GetAbortExecute() == 0;
        },
        {}, nullptr);
    mesh_to_polydata(result.mesh, output);
    nlohmann::json report = io::to_json(result.report);
    report["field"] = job.field;
    report["seed"] = job.seed;
    report["seed_count"] = job.seed_count;
    jobs::add_edge_keys(report, {job.options.edge, job.edge_source});
    report["complete"] = result.report.complete;
    report["limits"] = options.stream_limits.to_json();
    this->Report = report.dump(2);
    add_text(output->GetFieldData(), "orthofront_report", this->Report);
    add_text(output->GetFieldData(), "orthofront_seed", job.seed);
    if (!result.report.complete)
      vtkWarningMacro(<< "the surface is not complete (stopped: "
                      << to_string(result.report.stop_reason) << ")");
  } catch (const std::exception& e) {
    output->Initialize();
    vtkErrorMacro(<< e.what());
    return 0;
  }
  return 1;
}
