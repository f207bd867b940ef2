// adamesh._adamesh: the Python binding's compiled part. Thin: volumes in (numpy arrays borrowed,
// not copied), the library's calls with the GIL released, meshes and hierarchies out, adamesh
// errors as Python exceptions with the library's one-line messages. Argument checks, axis orders
// and dtype conversions live in python/adamesh/__init__.py.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <atomic>
#include <cstring>
#include <exception>
#include <memory>
#include <optional>
#include <string>

#include "adamesh/error.h"
#include "adamesh/extract.h"
#include "adamesh/input.h"
#include "adamesh/io.h"
#include "adamesh/metrics.h"
#include "adamesh/refine.h"
#include "adamesh/stats.h"
#include "adamesh/surfels.h"

namespace py = pybind11;
using namespace adamesh;

namespace {

// ------------------------------------------------------------------------------- errors

struct Exceptions {
  PyObject* error = nullptr;
  PyObject* usage = nullptr;
  PyObject* input = nullptr;
  PyObject* unsupported = nullptr;
  PyObject* output = nullptr;
  PyObject* internal = nullptr;
  PyObject* cancelled = nullptr;
};
Exceptions g_exc;

PyObject* new_exception(py::module_& m, const char* name, PyObject* bases, const char* doc) {
  const std::string full = std::string("adamesh.") + name;
  PyObject* e = PyErr_NewExceptionWithDoc(full.c_str(), doc, bases, nullptr);
  if (!e) throw py::error_already_set();
  m.add_object(name, py::handle(e));
  return e;
}

void register_exceptions(py::module_& m) {
  g_exc.error = new_exception(m, "Error", PyExc_Exception,
                              "Base class of adamesh's errors (str(e) is the CLI's one-line message).");
  auto two = [](PyObject* a, PyObject* b) {
    return py::make_tuple(py::handle(a), py::handle(b)).release().ptr();
  };
  g_exc.usage = new_exception(m, "UsageError", two(g_exc.error, PyExc_ValueError),
                              "Invalid arguments or options (CLI exit code 1).");
  g_exc.input = new_exception(m, "InputError", two(g_exc.error, PyExc_ValueError),
                              "Missing, truncated, corrupt or inconsistent input (exit code 2).");
  g_exc.unsupported = new_exception(m, "UnsupportedError", two(g_exc.error, PyExc_ValueError),
                                    "Valid input using a feature adamesh does not implement "
                                    "(exit code 3).");
  g_exc.output = new_exception(m, "OutputError", two(g_exc.error, PyExc_OSError),
                               "An output file could not be written (exit code 4).");
  g_exc.internal = new_exception(m, "InternalError", two(g_exc.error, PyExc_RuntimeError),
                                 "A broken invariant inside adamesh: a bug (exit code 5).");
  g_exc.cancelled = new_exception(m, "CancelledError", g_exc.error,
                                  "The call was cancelled (progress callback).");
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Error& e) {
      PyObject* type = g_exc.internal;
      switch (e.status()) {
        case Status::usage: type = g_exc.usage; break;
        case Status::invalid_input: type = g_exc.input; break;
        case Status::unsupported: type = g_exc.unsupported; break;
        case Status::output_failed: type = g_exc.output; break;
        case Status::cancelled: type = g_exc.cancelled; break;
        case Status::ok:
        case Status::internal: break;
      }
      PyErr_SetString(type, e.what());
    }
  });
}

// ------------------------------------------------------------------------------- volumes

/// A loaded or borrowed volume: the library's Input (samples, exact field, inside sign).
struct PyVolume {
  Input input;
};

ScalarType scalar_type_of(const py::dtype& dt) {
  const char kind = dt.kind();
  const auto size = dt.itemsize();
  if (kind == 'u' && size == 1) return ScalarType::u8;
  if (kind == 'i' && size == 1) return ScalarType::i8;
  if (kind == 'u' && size == 2) return ScalarType::u16;
  if (kind == 'i' && size == 2) return ScalarType::i16;
  if (kind == 'u' && size == 4) return ScalarType::u32;
  if (kind == 'i' && size == 4) return ScalarType::i32;
  if (kind == 'f' && size == 4) return ScalarType::f32;
  if (kind == 'f' && size == 8) return ScalarType::f64;
  throw Error(Status::usage, "Volume: unsupported sample type " +
                                 std::string(py::str(static_cast<const py::handle&>(dt))));
}

py::dtype dtype_of(ScalarType t) {
  switch (t) {
    case ScalarType::u8: return py::dtype::of<std::uint8_t>();
    case ScalarType::i8: return py::dtype::of<std::int8_t>();
    case ScalarType::u16: return py::dtype::of<std::uint16_t>();
    case ScalarType::i16: return py::dtype::of<std::int16_t>();
    case ScalarType::u32: return py::dtype::of<std::uint32_t>();
    case ScalarType::i32: return py::dtype::of<std::int32_t>();
    case ScalarType::f32: return py::dtype::of<float>();
    case ScalarType::f64: break;
  }
  return py::dtype::of<double>();
}

Vec3 vec3(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }

/// Borrows `array` (C-contiguous, shape (nz, ny, nx), native byte order, one of the eight sample
/// types: the Python layer converts everything else) as the samples of a volume.
PyVolume volume_from_array(py::array array, std::array<double, 3> spacing,
                           std::array<double, 3> origin, std::array<double, 9> direction,
                           double inside_sign, std::optional<double> default_iso,
                           const std::string& name, std::optional<double> nan_value) {
  if (array.ndim() != 3) throw Error(Status::usage, name + ": expected a 3-D array");
  if (!(array.flags() & py::array::c_style))
    throw Error(Status::internal, name + ": the samples are not C-contiguous");
  if (array.dtype().byteorder() == '>')
    throw Error(Status::internal, name + ": the samples are not in native byte order");
  Grid grid;
  grid.dims = {array.shape(2), array.shape(1), array.shape(0)};
  grid.spacing = vec3(spacing);
  grid.origin = vec3(origin);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) grid.direction.m[r][c] = direction[3 * r + c];
  Volume v;
  v.grid = grid;
  v.type = scalar_type_of(array.dtype());
  v.format = "numpy";
  v.source = name;
  const std::size_t bytes = checked_volume_bytes(grid.dims, v.type, name);
  if (nan_value) {
    // The replacement writes into the samples: work on a copy, never on the caller's array.
    v.data = SampleBuffer(bytes);
    std::memcpy(v.data.data(), array.data(), bytes);
  } else {
    auto* keep = new py::object(array);
    std::shared_ptr<const void> owner(keep, [](const void* p) {
      py::gil_scoped_acquire gil;
      delete static_cast<const py::object*>(p);
    });
    // Read only: nothing in the library writes a volume's samples (NaN replacement works on
    // the copy above), so read-only arrays are borrowed too.
    v.data = SampleBuffer(static_cast<std::byte*>(const_cast<void*>(array.data())), bytes,
                          std::move(owner));
  }
  InputOptions io;
  io.nan_value = nan_value;
  PyVolume out{make_input(std::move(v), name, inside_sign, io)};
  out.input.default_iso = default_iso;
  return out;
}

PyVolume load_volume(const std::string& spec, const InputOptions& options) {
  py::gil_scoped_release nogil;
  return PyVolume{load_input(spec, options)};
}

/// Read-only numpy view of the samples, shape (nz, ny, nx), kept alive by `self`.
py::array samples_view(py::object self) {
  const PyVolume& pv = self.cast<const PyVolume&>();
  const Volume& v = *pv.input.volume;
  const auto& d = v.grid.dims;
  const auto item = static_cast<py::ssize_t>(scalar_size(v.type));
  py::array a(dtype_of(v.type), {d[2], d[1], d[0]}, {item * d[0] * d[1], item * d[0], item},
              v.data.data(), self);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

// ------------------------------------------------------------------------------- meshes

/// A triangle mesh; vertices and faces are copied out as (n, 3) float64 / (m, 3) int32 arrays.
struct PyMesh {
  Mesh mesh;
};

py::array_t<double> vertices_of(const Mesh& m) {
  py::array_t<double> a(std::vector<py::ssize_t>{static_cast<py::ssize_t>(m.num_vertices()), 3});
  double* out = a.mutable_data();
  for (std::size_t i = 0; i < m.positions.size(); ++i) out[i] = m.positions[i];
  return a;
}

py::array_t<std::int32_t> faces_of(const Mesh& m) {
  py::array_t<std::int32_t> a(
      std::vector<py::ssize_t>{static_cast<py::ssize_t>(m.num_triangles()), 3});
  std::int32_t* out = a.mutable_data();
  for (std::size_t i = 0; i < m.triangles.size(); ++i)
    out[i] = static_cast<std::int32_t>(m.triangles[i]);
  return a;
}

Mesh mesh_from_arrays(py::array_t<double, py::array::c_style | py::array::forcecast> vertices,
                      py::array_t<std::int64_t, py::array::c_style | py::array::forcecast> faces) {
  if (vertices.ndim() != 2 || vertices.shape(1) != 3)
    throw Error(Status::usage, "Mesh: vertices must be an (n, 3) array");
  if (faces.ndim() != 2 || faces.shape(1) != 3)
    throw Error(Status::usage, "Mesh: faces must be an (m, 3) array");
  Mesh m;
  const auto nv = static_cast<std::size_t>(vertices.shape(0));
  m.positions.resize(3 * nv);
  const double* v = vertices.data();
  for (std::size_t i = 0; i < 3 * nv; ++i) m.positions[i] = static_cast<float>(v[i]);
  const auto nf = static_cast<std::size_t>(faces.shape(0));
  m.triangles.resize(3 * nf);
  const std::int64_t* f = faces.data();
  for (std::size_t i = 0; i < 3 * nf; ++i) {
    if (f[i] < 0 || static_cast<std::size_t>(f[i]) >= nv)
      throw Error(Status::usage, "Mesh: face " + std::to_string(i / 3) + " has vertex index " +
                                     std::to_string(f[i]) + ", outside 0.." +
                                     std::to_string(nv == 0 ? 0 : nv - 1));
    m.triangles[i] = static_cast<std::uint32_t>(f[i]);
  }
  return m;
}

void save_mesh(const Mesh& m, const std::string& path, bool ascii) {
  MeshWriteOptions wo;
  wo.ascii = ascii;
  py::gil_scoped_release nogil;
  write_mesh(m, path, wo);
}

// ------------------------------------------------------------------------------- hierarchy

struct PyHierarchy {
  Hierarchy h;
};

PyMesh cut(const PyHierarchy& self, std::optional<std::size_t> triangles, std::optional<int> level,
           std::optional<double> max_error, std::optional<std::size_t> splits, bool fit) {
  const int given = triangles.has_value() + level.has_value() + max_error.has_value() +
                    splits.has_value();
  if (given != 1)
    throw Error(Status::usage, "cut: give exactly one of triangles=, level=, max_error=, splits=");
  if (level && (*level < 0 || *level > 60)) throw Error(Status::usage, "cut: level must be 0..60");
  if (max_error && !(*max_error >= 0)) throw Error(Status::usage, "cut: max_error must be >= 0");
  py::gil_scoped_release nogil;
  CutMesh c = triangles   ? extract_triangles(self.h, *triangles)
              : level     ? extract_level(self.h, *level)
              : max_error ? extract_max_error(self.h, *max_error)
                          : extract_prefix(self.h, std::min(*splits, self.h.splits.size()));
  if (fit) fit_cut_to_finest(c, self.h);
  return {std::move(c.mesh)};
}

// ------------------------------------------------------------------------------- extract

/// Runs `work` without the GIL. The progress callback (the Python one, or none) is called with
/// the GIL held; Ctrl-C and exceptions raised by the callback abort the call and are re-raised.
template <class Work>
auto run_released(ExecutionContext& ctx, py::object progress, Work&& work) {
  std::atomic<bool> cancel{false};
  std::optional<py::error_already_set> raised;
  ctx.cancel = &cancel;
  ctx.progress = [&](const char* stage, double f) {
    py::gil_scoped_acquire gil;
    try {
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
      if (!progress.is_none()) progress(stage, f);
    } catch (py::error_already_set& e) {
      if (!raised) raised.emplace(std::move(e));
      cancel = true;
    }
  };
  try {
    py::gil_scoped_release nogil;
    auto out = work();
    ctx.progress = nullptr;
    return out;
  } catch (const Error& e) {
    ctx.progress = nullptr;
    if (raised && e.status() == Status::cancelled) throw std::move(*raised);
    throw;
  }
}

/// A source argument resolved while the GIL is held: a volume (kept alive by the Python object
/// the caller holds) or a spec to load.
struct Source {
  const Input* volume = nullptr;
  std::string spec;
};

Source resolve(py::handle source) {
  if (py::isinstance<PyVolume>(source)) return {&source.cast<const PyVolume&>().input, {}};
  return {nullptr, source.cast<std::string>()};
}

/// The input of `source`: the volume's, or `spec` loaded into `storage`. No Python calls.
const Input& input_of(const Source& source, const InputOptions& options, Input& storage) {
  if (source.volume) return *source.volume;
  storage = load_input(source.spec, options);
  return storage;
}

py::tuple run_extract(py::object source, ExtractOptions options, const InputOptions& input,
                      py::object progress) {
  const Source src = resolve(source);
  ExtractResult r = run_released(options.context, progress, [&] {
    if (src.volume) return extract(*src.volume, options);
    return extract(src.spec, options, input);
  });
  const std::string report = report_json(r.report);
  py::object hierarchy = py::none();
  if (r.hierarchy) hierarchy = py::cast(PyHierarchy{std::move(*r.hierarchy)});
  py::dict base;
  base["mesh"] = py::cast(PyMesh{std::move(r.base.mesh)});
  base["border"] = py::array_t<std::uint8_t>(r.base.border.size(), r.base.border.data());
  base["component"] = py::array_t<std::uint32_t>(r.base.component.size(), r.base.component.data());
  return py::make_tuple(PyMesh{std::move(r.mesh)}, base, hierarchy, report);
}

PyMesh run_mc(py::object source, std::optional<double> iso, const InputOptions& input, int threads) {
  ExecutionContext ctx;
  ctx.threads = threads;
  const Source src = resolve(source);
  return run_released(ctx, py::none(), [&] {
    Input loaded;
    const Input* in = &input_of(src, input, loaded);
    double value = 0;
    if (iso) value = *iso;
    else if (in->default_iso) value = *in->default_iso;
    else fail(Status::usage, in->spec + ": an iso-value is required for volume files");
    return PyMesh{marching_cubes(*in->volume, value, in->inside_sign, ctx)};  // no complex kept
  });
}

std::string run_stats(const PyMesh& mesh, py::object field, std::optional<double> iso,
                      const PyMesh* reference, std::int64_t samples, const InputOptions& input,
                      int threads) {
  ExecutionContext ctx;
  ctx.threads = threads;
  const bool with_field = !field.is_none();
  const Source src = with_field ? resolve(field) : Source{};
  return run_released(ctx, py::none(), [&] {
    MeshReport report = mesh_report(mesh.mesh, ctx);
    if (with_field) {
      Input loaded;
      const Input* in = &input_of(src, input, loaded);
      double value = 0;
      if (iso) value = *iso;
      else if (in->default_iso) value = *in->default_iso;
      else fail(Status::usage, in->spec + ": an iso-value is required for volume files");
      FieldErrorOptions fo;  // as `adamesh stats --field`
      fo.inside_sign = in->inside_sign;
      fo.max_step = in->volume->grid.min_spacing();
      fo.tolerance = 1e-5 * fo.max_step;
      fo.samples = samples;
      report.field = field_error(mesh.mesh, *in->field, value, fo, ctx);
      report.volume_bounds = vertices_outside_volume(mesh.mesh, in->volume->grid);
    }
    if (reference) {
      HausdorffOptions ho;
      ho.samples = samples;
      report.hausdorff = hausdorff(mesh.mesh, reference->mesh, ho, ctx);
    }
    return report_json(report);
  });
}

}  // namespace

PYBIND11_MODULE(_adamesh, m) {
  m.doc() = "adamesh's compiled core; use the `adamesh` package.";
  register_exceptions(m);

  py::class_<InputOptions>(m, "InputOptions")
      .def(py::init<>())
      .def_property(
          "dims", [](const InputOptions& o) { return o.raw.dims; },
          [](InputOptions& o, std::optional<std::array<std::int64_t, 3>> d) { o.raw.dims = d; })
      .def_property(
          "type", [](const InputOptions& o) {
            return o.raw.type ? std::optional<std::string>(to_string(*o.raw.type)) : std::nullopt;
          },
          [](InputOptions& o, std::optional<std::string> t) {
            if (!t) {
              o.raw.type.reset();
              return;
            }
            o.raw.type = parse_scalar_type(*t);
            if (!o.raw.type) throw Error(Status::usage, "unknown raw sample type '" + *t + "'");
          })
      .def_property(
          "spacing", [](const InputOptions& o) {
            return std::array<double, 3>{o.raw.spacing.x, o.raw.spacing.y, o.raw.spacing.z};
          },
          [](InputOptions& o, std::array<double, 3> s) { o.raw.spacing = vec3(s); })
      .def_property(
          "origin", [](const InputOptions& o) {
            return std::array<double, 3>{o.raw.origin.x, o.raw.origin.y, o.raw.origin.z};
          },
          [](InputOptions& o, std::array<double, 3> s) { o.raw.origin = vec3(s); })
      .def_property(
          "big_endian", [](const InputOptions& o) { return o.raw.big_endian; },
          [](InputOptions& o, bool b) { o.raw.big_endian = b; })
      .def_property(
          "header_bytes", [](const InputOptions& o) { return o.raw.header_bytes; },
          [](InputOptions& o, std::uint64_t b) { o.raw.header_bytes = b; })
      .def_property(
          "bounds",
          [](const InputOptions& o) -> std::optional<std::array<double, 6>> {
            if (!o.bounds) return std::nullopt;
            const Box& b = *o.bounds;
            return std::array<double, 6>{b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z};
          },
          [](InputOptions& o, std::optional<std::array<double, 6>> b) {
            if (!b) {
              o.bounds.reset();
              return;
            }
            const auto& v = *b;
            if (!(v[0] < v[3] && v[1] < v[4] && v[2] < v[5]))
              throw Error(Status::usage, "bounds needs xmin<xmax, ymin<ymax, zmin<zmax");
            o.bounds = Box{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}};
          })
      .def_readwrite("resolution", &InputOptions::resolution)
      .def_readwrite("nan_value", &InputOptions::nan_value)
      .def_readwrite("flip_inside", &InputOptions::flip_inside)
      .def_property(
          "label",
          [](const InputOptions& o) -> std::optional<std::string> {
            if (!o.label) return std::nullopt;
            return o.label->to_string();
          },
          [](InputOptions& o, std::optional<std::string> s) {
            if (s) o.label = parse_label_set(*s);
            else o.label.reset();
          });

  py::enum_<Budget>(m, "Budget")
      .value("none", Budget::none)
      .value("automatic", Budget::automatic)
      .value("levels", Budget::levels)
      .value("max_error", Budget::max_error)
      .value("triangles", Budget::triangles);
  py::enum_<LengthUnit>(m, "LengthUnit")
      .value("world", LengthUnit::world)
      .value("voxels", LengthUnit::voxels);

  // One line per ExtractOptions field: new options are exposed by adding a line here and a
  // keyword in adamesh.extract().
  py::class_<ExtractOptions>(m, "ExtractOptions")
      .def(py::init<>())
      .def_readwrite("iso", &ExtractOptions::iso)
      .def_readwrite("budget", &ExtractOptions::budget)
      .def_readwrite("levels", &ExtractOptions::levels)
      .def_readwrite("max_error", &ExtractOptions::max_error)
      .def_readwrite("triangles", &ExtractOptions::triangles)
      .def_readwrite("r_max", &ExtractOptions::r_max)
      .def_readwrite("r_min", &ExtractOptions::r_min)
      .def_readwrite("unit", &ExtractOptions::unit)
      .def_readwrite("min_component", &ExtractOptions::min_component)
      .def_readwrite("validate", &ExtractOptions::validate)
      .def_readwrite("min_cavity", &ExtractOptions::min_cavity)
      .def_readwrite("improve", &ExtractOptions::improve)
      .def_readwrite("max_handle", &ExtractOptions::max_handle)
      .def_property(
          "fit",
          [](const ExtractOptions& o) {
            return o.fit == ExtractOptions::Fit::l2        ? "l2"
                   : o.fit == ExtractOptions::Fit::surface ? "surface"
                                                           : "auto";
          },
          [](ExtractOptions& o, const std::string& f) {
            if (f == "l2") o.fit = ExtractOptions::Fit::l2;
            else if (f == "surface") o.fit = ExtractOptions::Fit::surface;
            else if (f == "auto") o.fit = ExtractOptions::Fit::automatic;
            else fail(Status::usage, "extract: fit must be 'auto', 'surface' or 'l2', not '" + f + "'");
          })
      .def_readwrite("measure_levels", &ExtractOptions::measure_levels)
      .def_property(
          "threads", [](const ExtractOptions& o) { return o.context.threads; },
          [](ExtractOptions& o, int t) { o.context.threads = t; });

  py::class_<PyVolume>(m, "_Volume")
      .def_property_readonly("samples", &samples_view)
      .def_property_readonly("dims", [](const PyVolume& v) { return v.input.volume->grid.dims; })
      .def_property_readonly("spacing", [](const PyVolume& v) {
        const Vec3& s = v.input.volume->grid.spacing;
        return std::array<double, 3>{s.x, s.y, s.z};
      })
      .def_property_readonly("origin", [](const PyVolume& v) {
        const Vec3& s = v.input.volume->grid.origin;
        return std::array<double, 3>{s.x, s.y, s.z};
      })
      .def_property_readonly("direction", [](const PyVolume& v) {
        const Mat3& d = v.input.volume->grid.direction;
        std::array<double, 9> out{};
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) out[3 * r + c] = d.m[r][c];
        return out;
      })
      .def_property_readonly("inside_sign", [](const PyVolume& v) { return v.input.inside_sign; })
      .def_property_readonly("default_iso", [](const PyVolume& v) { return v.input.default_iso; })
      .def_property_readonly("format", [](const PyVolume& v) { return v.input.volume->format; })
      .def_property_readonly("name", [](const PyVolume& v) { return v.input.spec; })
      .def_property_readonly("borrowed",
                             [](const PyVolume& v) { return v.input.volume->data.borrowed(); })
      .def("stats", [](const PyVolume& v) {
        VolumeStats st;
        {
          py::gil_scoped_release nogil;
          st = compute_stats(*v.input.volume);
        }
        py::dict d;
        d["samples"] = st.samples;
        d["nonfinite"] = st.nonfinite;
        d["min"] = st.min;
        d["max"] = st.max;
        d["mean"] = st.mean;
        py::dict pct;
        for (std::size_t i = 0; i < st.percentiles.size(); ++i)
          pct[py::int_(static_cast<int>(VolumeStats::kPercentileLevels[i]))] = st.percentiles[i];
        d["percentiles"] = pct;
        d["otsu"] = st.otsu;
        return d;
      });
  m.def("_volume_from_array", &volume_from_array);
  m.def("_load", &load_volume);

  py::class_<PyMesh>(m, "_Mesh")
      .def(py::init(
          [](py::array_t<double, py::array::c_style | py::array::forcecast> v,
             py::array_t<std::int64_t, py::array::c_style | py::array::forcecast> f) {
            return PyMesh{mesh_from_arrays(std::move(v), std::move(f))};
          }))
      .def_property_readonly("vertices", [](const PyMesh& m) { return vertices_of(m.mesh); })
      .def_property_readonly("faces", [](const PyMesh& m) { return faces_of(m.mesh); })
      .def_property_readonly("num_vertices", [](const PyMesh& m) { return m.mesh.num_vertices(); })
      .def_property_readonly("num_triangles",
                             [](const PyMesh& m) { return m.mesh.num_triangles(); })
      .def("save", [](const PyMesh& m, const std::string& path, bool ascii) {
        save_mesh(m.mesh, path, ascii);
      });
  m.def("_read_mesh", [](const std::string& path) {
    py::gil_scoped_release nogil;
    return PyMesh{read_mesh(path)};
  });

  py::class_<PyHierarchy>(m, "_Hierarchy")
      .def("cut", &cut, py::arg("triangles") = py::none(), py::arg("level") = py::none(),
           py::arg("max_error") = py::none(), py::arg("splits") = py::none(),
           py::arg("fit") = false)
      .def("save",
           [](const PyHierarchy& h, const std::string& path) {
             py::gil_scoped_release nogil;
             write_hierarchy(h.h, path);
           })
      .def_property_readonly("num_splits", [](const PyHierarchy& h) { return h.h.splits.size(); })
      .def_property_readonly("num_vertices", [](const PyHierarchy& h) { return h.h.num_vertices(); })
      .def_property_readonly("num_base_triangles",
                             [](const PyHierarchy& h) { return h.h.base_triangles.size(); })
      .def_property_readonly("iso", [](const PyHierarchy& h) { return h.h.iso; })
      .def_property_readonly("voxel", [](const PyHierarchy& h) { return h.h.voxel; });
  m.def("_read_hierarchy", [](const std::string& path, bool allow_partial) {
    HierarchyReadOptions o;
    o.allow_partial = allow_partial;
    py::gil_scoped_release nogil;
    return PyHierarchy{read_hierarchy(path, o)};
  });

  m.def("_extract", &run_extract);
  m.def("_mc", &run_mc);
  m.def("_stats", &run_stats);
  m.def("_shape_names", &shape_names);
}
