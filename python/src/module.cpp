// The `orthofront` Python module (`_orthofront`, wrapped by orthofront/__init__.py): fields and
// series from numpy arrays or files, and stream, path and streak surfaces built by the library
// with the command line's options.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "jobs/edge_default.h"
#include "jobs/engine_options.h"
#include "jobs/option_spelling.h"
#include "jobs/path_job.h"
#include "jobs/path_run.h"
#include "jobs/time_arg.h"
#include "jobs/seed_spec.h"
#include "jobs/streak_job.h"
#include "jobs/streak_report.h"
#include "jobs/streak_run.h"
#include "jobs/stream_job.h"
#include "jobs/surface_kind.h"
#include "keyword_options.h"
#include "numpy_grid.h"
#include "orthofront/error.h"
#include "orthofront/field/grid_field.h"
#include "orthofront/field/unsteady.h"
#include "orthofront/io/error.h"
#include "orthofront/io/input_files.h"
#include "orthofront/io/mesh_io.h"
#include "orthofront/io/open_field.h"
#include "orthofront/io/report_json.h"
#include "orthofront/seed/seed.h"
#include "orthofront/spacetime/brick_cache.h"
#include "orthofront/spacetime/path_command_json.h"
#include "orthofront/spacetime/path_surface.h"
#include "orthofront/spacetime/streak_surface.h"

namespace py = pybind11;

namespace orthofront::python {

namespace {

/// A steady field: a numpy grid, a data file or an analytic field.
struct PyField {
  std::shared_ptr<const Field3> field;
  std::string name;
};

/// A time series: numpy steps or data files.
struct PySeries {
  std::shared_ptr<io::TimeSeries> series;
  std::string name;
};

/// Ctrl-C during a build: the engine asks between front steps, with the GIL released.
class InterruptCheck {
 public:
  bool keep_going() {
    if (raised_) return false;
    py::gil_scoped_acquire gil;
    raised_ = PyErr_CheckSignals() != 0;  // leaves KeyboardInterrupt set for rethrow()
    return !raised_;
  }
  /// With the GIL held, after the build.
  void rethrow_if_raised() const {
    if (raised_) throw py::error_already_set();
  }

 private:
  bool raised_ = false;
};

PyField resolve_field(const py::object& field) {
  if (py::isinstance<PyField>(field)) return field.cast<PyField>();
  if (py::isinstance<py::str>(field)) {
    const auto spec = field.cast<std::string>();
    return {io::open_field(spec), spec};
  }
  throw py::type_error("field must be an orthofront.Field or a string (a file or analytic name)");
}

/// `planar` (when given) says whether the seed came as (n, 2) points: z = 0, which only a 2D
/// field may take silently.
SeedCurve resolve_seed(const py::object& seed, bool closed, std::string& name,
                       bool* planar = nullptr) {
  if (py::isinstance<py::str>(seed)) {
    name = seed.cast<std::string>();
    return jobs::parse_seed(name);
  }
  // Doubles, as a seed string's numbers are read: float32 would move the seed by its rounding.
  using SeedArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
  const auto points = SeedArray::ensure(seed);
  if (!points || points.ndim() != 2 || (points.shape(1) != 2 && points.shape(1) != 3) ||
      points.shape(0) < 2)
    throw py::value_error(
        "seed must be a seed string (e.g. 'line:0,0,0:1,0,0') or an (n, 2) or "
        "(n, 3) array of at least 2 points");
  if (planar != nullptr) *planar = points.shape(1) == 2;
  std::vector<Vec3> polyline;
  const auto p = points.unchecked<2>();
  for (py::ssize_t i = 0; i < points.shape(0); ++i)
    polyline.emplace_back(p(i, 0), p(i, 1), points.shape(1) == 3 ? p(i, 2) : 0.0);
  name = "array of " + std::to_string(points.shape(0)) + " points";
  return SeedCurve::polyline(std::move(polyline), closed);
}

/// (n, 2) seed points on a 3D field would all sit at z = 0 without a word: refused.
void check_planar_seed(bool planar, int dimension, const std::string& field) {
  if (planar && dimension == 3)
    throw py::value_error("seed: (n, 2) points (x, y) on the 3D field '" + field +
                          "'; give (n, 3) points (x, y, z)");
}

/// The surface as numpy arrays plus its report (JSON text; the Python side loads it).
py::dict surface_dict(const Mesh& mesh, const nlohmann::json& report) {
  py::dict out = mesh_to_dict(mesh);
  out["report"] = report.dump();
  return out;
}

/// The keywords of stream_surface, path_surface or streak_surface (`kind`: stream, path,
/// streak), as option_schema lists them: the Python package builds their signatures and
/// docstrings from it.
py::list keyword_schema(const std::string& kind) {
  const std::optional<jobs::SurfaceKind> known = jobs::parse_surface_kind(kind);
  if (!known) throw py::value_error("kind must be stream, path or streak, got '" + kind + "'");
  const jobs::KindOptions options(*known);
  return option_schema(options.set);
}

py::dict stream_surface(const py::object& field_in, const py::object& seed_in, bool closed,
                        const py::kwargs& options) {
  jobs::SurfaceJob job;
  jobs::MemoryLimits limits;
  jobs::OptionSet set;
  jobs::add_stream_options(set, job, limits);
  parse_keywords(set, options);
  jobs::apply_memory_limits(set, limits, job.options);
  const PyField field = resolve_field(field_in);
  const SeedCurve curve = resolve_seed(seed_in, closed, job.seed);
  job.field = field.name;
  job.edge_given = set.given("edge");
  const Seed<3> seed = jobs::prepare_stream_seed(*field.field, curve, job);
  // The command line's warning of a run its rows alone would stop at the vertex cap, as a
  // Python warning.
  std::string cap = jobs::vertex_cap_warning(curve.length(), field.field->domain().extent(),
                                             job.options);
  if (!cap.empty()) {
    const std::string prefix = "orthofront: warning: ";
    if (cap.rfind(prefix, 0) == 0) cap.erase(0, prefix.size());
    while (!cap.empty() && cap.back() == '\n') cap.pop_back();
    cap = jobs::spell_options(cap, jobs::OptionSpelling::python);
    if (PyErr_WarnEx(PyExc_UserWarning, cap.c_str(), 1) != 0) throw py::error_already_set();
  }
  InterruptCheck interrupt;
  SurfaceResult result;
  jobs::DeviceUse device;
  {
    py::gil_scoped_release release;
    result = jobs::run_stream_job(
        *field.field, seed, job, [&](const Progress&) { return interrupt.keep_going(); }, {},
        &device);
  }
  interrupt.rethrow_if_raised();
  return surface_dict(result.mesh, jobs::stream_report(result.report, job, limits, device));
}

py::dict path_surface(const py::object& field_in, const py::object& seed_in, bool closed,
                      const py::kwargs& options) {
  jobs::PathArgs args;
  jobs::OptionSet set;
  jobs::add_path_options(set, args);
  parse_keywords(set, options);
  jobs::apply_memory_limits(set, args.limits, args.options);
  bool planar_seed = false;
  const SeedCurve seed = resolve_seed(seed_in, closed, args.seed, &planar_seed);
  jobs::check_seed_count(args.seed_count, args.options.max_vertices);

  std::unique_ptr<UnsteadyField> analytic;
  PySeries series;
  if (py::isinstance<PySeries>(field_in)) {
    series = field_in.cast<PySeries>();
  } else if (py::isinstance<py::str>(field_in)) {
    series.name = field_in.cast<std::string>();
    if (is_unsteady_field_name(series.name))
      analytic = make_unsteady_field(series.name);
    else
      series.series = io::open_time_series(series.name, "path surfaces");
  } else {
    throw py::type_error(
        "field must be an orthofront.Series or a string (an unsteady field "
        "name, or a series of files)");
  }
  args.field = series.name;
  check_planar_seed(planar_seed, analytic ? analytic->dimension() : series.series->geometry().dimension,
                    series.name);
  InterruptCheck interrupt;
  jobs::PathRun run;
  {
    py::gil_scoped_release release;
    run = jobs::run_path_surface(analytic ? nullptr : series.series.get(), analytic.get(), seed,
                                 args, set.given("edge"), [&] { return interrupt.keep_going(); });
  }
  interrupt.rethrow_if_raised();
  py::dict out = surface_dict(run.result.mesh, run.report);
  if (!run.lifted.positions.empty()) out["spacetime_vertices"] = mesh_to_dict(run.lifted)["vertices"];
  return out;
}

py::dict streak_surface(const py::object& field_in, const py::object& seed_in, bool closed,
                        const py::kwargs& options) {
  jobs::StreakArgs args;
  jobs::OptionSet set;
  jobs::add_streak_options(set, args);
  parse_keywords(set, options);
  if (args.frames.empty()) throw py::type_error("frames is required (the observation times)");
  bool planar_seed = false;
  const SeedCurve seed = resolve_seed(seed_in, closed, args.seed, &planar_seed);
  std::unique_ptr<UnsteadyField> analytic;
  PySeries series;
  if (py::isinstance<PySeries>(field_in)) {
    series = field_in.cast<PySeries>();
  } else if (py::isinstance<py::str>(field_in)) {
    series.name = field_in.cast<std::string>();
    if (is_unsteady_field_name(series.name))
      analytic = make_unsteady_field(series.name);
    else
      series.series = io::open_time_series(series.name, "streak surfaces");
  } else {
    throw py::type_error("field must be an orthofront.Series or a string");
  }
  args.field = series.name;
  check_planar_seed(planar_seed, analytic ? analytic->dimension() : series.series->geometry().dimension,
                    series.name);
  InterruptCheck interrupt;
  jobs::StreakRun run;
  {
    py::gil_scoped_release release;
    run = jobs::run_streak_surface(analytic ? nullptr : series.series.get(), analytic.get(), seed,
                                   set, args, [&] { return interrupt.keep_going(); });
  }
  interrupt.rethrow_if_raised();
  const nlohmann::json& report = run.report;
  const std::vector<spacetime::StreakFrame>& frames = run.frames;
  py::list frame_list;
  for (const spacetime::StreakFrame& f : frames) {
    py::dict d = mesh_to_dict(f.mesh);
    d["time"] = f.time;
    d["report"] = io::to_json(f.quality).dump();
    frame_list.append(d);
  }
  py::dict out;
  out["frames"] = frame_list;
  out["report"] = report.dump();
  return out;
}

}  // namespace

}  // namespace orthofront::python

namespace orthofront::python {
namespace {
// Messages name options as flags (--cache-budget); a Python user types keywords.
std::string python_spelling(const char* message) {
  return jobs::spell_options(message, jobs::OptionSpelling::python);
}
}  // namespace
}  // namespace orthofront::python

PYBIND11_MODULE(_orthofront, m) {
  using namespace orthofront;
  using namespace orthofront::python;
  // A Python session is one job: no file written through the module replaces one it read.
  static const io::InputScope session_inputs;
  m.doc() = "Flow-orthogonal stream, path and streak surfaces (the compiled part of orthofront)";
  m.attr("__version__") = ORTHOFRONT_VERSION;

  // Library errors as Python's: bad input is a ValueError, unreadable files an OSError.
  static py::exception<Error> error(m, "Error", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const io::IoError& e) {
      PyErr_SetString(PyExc_OSError, python_spelling(e.what()).c_str());
    } catch (const InvalidArgument& e) {
      PyErr_SetString(PyExc_ValueError, python_spelling(e.what()).c_str());
    } catch (const io::FormatError& e) {
      PyErr_SetString(PyExc_ValueError, python_spelling(e.what()).c_str());
    } catch (const Error& e) {
      error(python_spelling(e.what()).c_str());
    }
  });

  py::class_<PyField>(m, "Field", "A steady vector field: a grid from numpy, a file or analytic")
      .def(py::init([](const FloatArray& values, const py::object& origin,
                       const py::object& spacing, const py::object& axes, bool zero_is_no_data) {
             auto grid =
                 std::make_shared<VectorGrid>(grid_from_array(values, origin, spacing, axes));
             GridFieldOptions options;
             options.zero_is_no_data = zero_is_no_data;
             return PyField{std::make_shared<GridField>(std::move(grid), options), "numpy array"};
           }),
           py::arg("values"), py::kw_only(), py::arg("origin") = py::none(),
           py::arg("spacing") = py::none(), py::arg("axes") = py::none(),
           py::arg("zero_is_no_data") = true,
           "values: (ny, nx, 2) or (nz, ny, nx, 3), x fastest. NaN is no data, and so are zero "
           "vectors (land, solid cells), as in data files; zero_is_no_data=False makes zeros "
           "flow (stagnation points of a sampled analytic field)")
      .def_static(
          "open",
          [](const std::string& spec) {
            return PyField{io::open_field(spec), spec};
          },
          py::arg("spec"), "A data file (FILE.ext[:SELECTOR]) or an analytic field NAME[:k=v,...]")
      .def_property_readonly("name", [](const PyField& f) { return f.name; })
      .def("describe", [](const PyField& f) { return f.field->describe(); })
      .def("__repr__", [](const PyField& f) { return "<orthofront.Field " + f.name + ">"; });

  py::class_<PySeries>(m, "Series", "A time series of vector grids: numpy steps or files")
      .def(py::init([](const FloatArray& values, const py::object& times, const py::object& origin,
                       const py::object& spacing, const py::object& axes, bool zero_is_no_data) {
             return PySeries{std::shared_ptr<io::TimeSeries>(series_from_array(
                                 values, times, origin, spacing, axes, zero_is_no_data)),
                             "numpy array series"};
           }),
           py::arg("values"), py::arg("times"), py::kw_only(), py::arg("origin") = py::none(),
           py::arg("spacing") = py::none(), py::arg("axes") = py::none(),
           py::arg("zero_is_no_data") = true,
           "values: (nt, ny, nx, 2) or (nt, nz, ny, nx, 3); times: nt increasing numbers. NaN "
           "and zero vectors are no data, as in data files (zero_is_no_data=False: zeros are "
           "flow)")
      .def_static(
          "open",
          [](const std::string& spec) {
            return PySeries{
                std::shared_ptr<io::TimeSeries>(io::open_time_series(spec, "time series")), spec};
          },
          py::arg("spec"),
          "HDF5, NetCDF (file, glob or list), .pvd, a glob or list of grid files, OpenVDB")
      .def_property_readonly("name", [](const PySeries& s) { return s.name; })
      .def_property_readonly("times",
                             [](const PySeries& s) {
                               std::vector<double> t(s.series->step_count());
                               for (std::size_t i = 0; i < t.size(); ++i) t[i] = s.series->time(i);
                               return t;
                             })
      .def("describe", [](const PySeries& s) { return s.series->describe(); })
      .def("__len__", [](const PySeries& s) { return s.series->step_count(); })
      .def("__repr__", [](const PySeries& s) { return "<orthofront.Series " + s.name + ">"; });

  m.def("_keywords", &keyword_schema, py::arg("kind"));
  m.def("_stream_surface", &stream_surface, py::arg("field"), py::arg("seed"), py::kw_only(),
        py::arg("closed") = false);
  m.def("_path_surface", &path_surface, py::arg("field"), py::arg("seed"), py::kw_only(),
        py::arg("closed") = false);
  m.def("_streak_surface", &streak_surface, py::arg("field"), py::arg("seed"), py::kw_only(),
        py::arg("closed") = false);
  m.def(
      "_write_mesh",
      [](const py::array& vertices, const py::array& faces, const py::dict& attributes,
         const std::string& path) {
        io::write_mesh(mesh_from_arrays(vertices, faces, attributes), path);
      },
      py::arg("vertices"), py::arg("faces"), py::arg("attributes"), py::arg("path"));
}
