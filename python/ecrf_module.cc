// Python module `ecrf` over the C API of ecrf/decoder.h (pybind11). Decoding and rendering run
// without the GIL; a per-scene mutex keeps the C API's one-thread-per-handle rule.
#include <ecrf/decoder.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "decoder/camera.h"

namespace py = pybind11;

namespace {

PyObject* g_error = nullptr;         // ecrf.Error(ValueError)
PyObject* g_decode_error = nullptr;  // ecrf.DecodeError(ecrf.Error)

[[noreturn]] void Raise(PyObject* type, int code, const std::string& message) {
  py::object exc = py::reinterpret_borrow<py::object>(type)(message);
  exc.attr("code") = code;
  exc.attr("code_name") = ecrf_error_name(code);
  PyErr_SetObject(type, exc.ptr());
  throw py::error_already_set();
}

class Scene {
 public:
  Scene() : scene_(ecrf_scene_create()) {
    if (!scene_) throw std::bad_alloc();
  }
  ~Scene() { ecrf_scene_destroy(scene_); }
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  // Runs f(scene) with the GIL released and the scene locked; raises `type` on failure.
  template <typename F>
  void Call(PyObject* type, const char* what, F&& f) {
    int rc;
    std::string message;
    {
      py::gil_scoped_release release;
      std::lock_guard<std::mutex> lock(mutex_);
      rc = f(scene_);
      if (rc < 0) message = ecrf_scene_message(scene_);
    }
    if (rc < 0) {
      Raise(type, rc, std::string(what) + ": " + (message.empty() ? ecrf_error_name(rc) : message));
    }
  }
  // Quick queries take the lock only, with the GIL held.
  ecrf_scene* get() { return scene_; }
  std::mutex& mutex() { return mutex_; }

 private:
  ecrf_scene* scene_;
  std::mutex mutex_;
};

template <typename T>
py::tuple Tuple3(const T* v) {
  return py::make_tuple(v[0], v[1], v[2]);
}

py::dict Info(Scene& s) {
  ecrf_scene_info i;
  std::lock_guard<std::mutex> lock(s.mutex());
  ecrf_scene_get_info(s.get(), &i);
  py::dict d;
  d["aabb_min"] = Tuple3(i.aabb_min);
  d["aabb_max"] = Tuple3(i.aabb_max);
  d["grid_res"] = Tuple3(i.grid_res);
  d["density_ranks"] = Tuple3(i.density_ranks);
  d["appearance_ranks"] = Tuple3(i.appearance_ranks);
  d["has_occupancy"] = i.has_occupancy != 0;
  d["occupancy_res"] = Tuple3(i.occupancy_res);
  d["num_samples"] = i.num_samples;
  d["step_size"] = i.step_size;
  d["near_plane"] = i.near_plane;
  d["far_plane"] = i.far_plane;
  d["background"] = Tuple3(i.background);
  d["stream_bytes"] = i.stream_bytes;
  d["grid_bytes"] = i.grid_bytes;
  // "unbounded": aabb is the region of interest of a contracted scene (SPEC.md 7.2.1).
  // "forward": aabb is in the NDC of a reference camera (SPEC.md 7.2.2).
  const int model = ecrf_scene_model(s.get());
  d["scene_model"] = model == ECRF_SCENE_UNBOUNDED ? "unbounded"
                     : model == ECRF_SCENE_FORWARD ? "forward"
                                                   : "object";
  // "deferred": the MLP once per ray (SPEC.md 7.6); "mlp": once per coloured sample.
  d["head"] = ecrf_scene_head(s.get()) == ECRF_HEAD_DEFERRED ? "deferred" : "mlp";
  const int version = ecrf_scene_version(s.get());
  d["version"] = std::to_string(version >> 8) + "." + std::to_string(version & 0xff);
  float frame[15];
  if (ecrf_scene_ndc_frame(s.get(), frame) == ECRF_OK) {
    // A 3x4 world-to-reference matrix, the two NDC scales and the near plane (SPEC.md 6.2.1).
    py::list m;
    for (int k = 0; k < 12; ++k) m.append(frame[k]);
    d["ndc_world_to_ref"] = m;
    d["ndc_scale"] = py::make_tuple(frame[12], frame[13]);
    d["ndc_near_plane"] = frame[14];
  }
  return d;
}

py::dict Field(Scene& s) {
  ecrf_scene_field f;
  std::lock_guard<std::mutex> lock(s.mutex());
  ecrf_scene_get_field(s.get(), &f);
  py::dict d;
  d["density_shift"] = f.density_shift;
  d["distance_scale"] = f.distance_scale;
  d["weight_threshold"] = f.weight_threshold;
  d["occupancy_min"] = Tuple3(f.occupancy_min);
  d["occupancy_max"] = Tuple3(f.occupancy_max);
  d["mlp_features"] = f.mlp_features;
  d["mlp_products"] = f.mlp_products;
  d["mlp_hidden"] = f.mlp_hidden;
  d["mlp_layers"] = ecrf_scene_mlp_layers(s.get());  // 1 or 2 hidden layers (SPEC.md 6.6)
  // "softplus" or "relu" (SPEC.md 7.4)
  d["density_activation"] =
      ecrf_scene_density_activation(s.get()) == ECRF_DENSITY_RELU ? "relu" : "softplus";
  d["mlp_feature_freqs"] = f.mlp_feature_freqs;
  d["mlp_viewdir_freqs"] = f.mlp_viewdir_freqs;
  d["mlp_inputs"] = f.mlp_inputs;
  d["mlp_params"] = f.mlp_params;
  return d;
}

// A numpy array over memory the scene owns: `self` becomes its base, so it keeps the scene alive.
template <typename T>
py::array View(const py::object& self, std::vector<py::ssize_t> shape, const T* data) {
  py::array a(py::dtype::of<T>(), std::move(shape), {}, data, self);
  a.attr("flags").attr("writeable") = false;
  return a;
}

py::array Tensor(const py::object& self, int grid, int tensor) {
  Scene& s = self.cast<Scene&>();
  const float* data = nullptr;
  int shape[3];
  size_t count = 0;
  int rc;
  {
    std::lock_guard<std::mutex> lock(s.mutex());
    rc = ecrf_scene_tensor(s.get(), grid, tensor, &data, shape, &count);
  }
  if (rc < 0) {
    Raise(g_error, rc,
          "tensor: grid must be 0 (density) or 1 (appearance), tensor 0..5, and the "
          "scene decoded with storage='float32'");
  }
  if (tensor < 3) return View(self, {shape[0], shape[1], shape[2]}, data);
  return View(self, {shape[0], shape[1]}, data);
}

py::object Occupancy(const py::object& self, bool packed) {
  Scene& s = self.cast<Scene&>();
  const uint8_t* bits = nullptr;
  int res[3];
  size_t bytes = 0;
  {
    std::lock_guard<std::mutex> lock(s.mutex());
    if (ecrf_scene_occupancy(s.get(), &bits, res, &bytes) < 0) return py::none();
  }
  if (packed) return View(self, {static_cast<py::ssize_t>(bytes)}, bits);
  py::array_t<bool> mask({res[2], res[1], res[0]});
  bool* out = mask.mutable_data();
  const size_t n = static_cast<size_t>(res[0]) * res[1] * res[2];
  for (size_t i = 0; i < n; ++i) out[i] = (bits[i >> 3] >> (i & 7)) & 1;
  return std::move(mask);
}

py::array_t<float> MlpParams(Scene& s) {
  ecrf_scene_field f;
  {
    std::lock_guard<std::mutex> lock(s.mutex());
    ecrf_scene_get_field(s.get(), &f);
  }
  py::array_t<float> params(static_cast<py::ssize_t>(f.mlp_params));
  float* out = params.mutable_data();
  s.Call(g_error, "mlp_params",
         [&](ecrf_scene* e) { return ecrf_scene_mlp_params(e, out, f.mlp_params); });
  return params;
}

bool ReadFile(const std::string& path, std::vector<uint8_t>* bytes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  bytes->assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return !in.bad();
}

std::unique_ptr<Scene> Decode(const py::object& source, const std::string& storage,
                              const py::object& memory_budget, const py::object& decode_budget) {
  int kind;
  if (storage == "float32") {
    kind = ECRF_STORAGE_FLOAT32;
  } else if (storage == "int16") {
    kind = ECRF_STORAGE_INT16;
  } else {
    throw py::value_error("storage must be 'float32' or 'int16'");
  }
  auto scene = std::make_unique<Scene>();
  if (!memory_budget.is_none()) {
    const long long budget = memory_budget.cast<long long>();
    if (budget <= 0) throw py::value_error("memory_budget must be positive (None: the default)");
    std::lock_guard<std::mutex> lock(scene->mutex());
    ecrf_scene_set_memory_budget(scene->get(), static_cast<uint64_t>(budget));
  }
  if (!decode_budget.is_none()) {
    const long long per_byte = decode_budget.cast<long long>();
    if (per_byte < 0) throw py::value_error("decode_budget must be >= 0 (0: no limit)");
    std::lock_guard<std::mutex> lock(scene->mutex());
    ecrf_scene_set_decode_budget(scene->get(), static_cast<uint64_t>(per_byte));
  }
  if (py::isinstance<py::str>(source) || py::hasattr(source, "__fspath__")) {
    const std::string path = py::module_::import("os").attr("fspath")(source).cast<std::string>();
    std::vector<uint8_t> bytes;
    bool read;
    {
      py::gil_scoped_release release;
      read = ReadFile(path, &bytes);
    }
    if (!read) {
      PyErr_SetString(PyExc_OSError, ("cannot read " + path).c_str());
      throw py::error_already_set();
    }
    scene->Call(g_decode_error, path.c_str(), [&](ecrf_scene* e) {
      return ecrf_scene_decode(e, bytes.data(), bytes.size(), kind);
    });
  } else {
    // The buffer stays exported (hence unchanged) while the GIL is released.
    const py::buffer_info buf = py::reinterpret_borrow<py::buffer>(source).request();
    const size_t size = static_cast<size_t>(buf.size * buf.itemsize);
    scene->Call(g_decode_error, "decode",
                [&](ecrf_scene* e) { return ecrf_scene_decode(e, buf.ptr, size, kind); });
  }
  return scene;
}

py::array Render(Scene& s, const py::array_t<float, py::array::c_style | py::array::forcecast>& c2w,
                 float fx, float fy, float cx, float cy, int width, int height, int threads,
                 float early_stop, float step_scale, const py::object& weight_threshold,
                 bool skip_empty_space, int max_samples, int sample_budget, uint64_t work_budget,
                 bool rgb) {
  if (c2w.size() != 12 && c2w.size() != 16) throw py::value_error("c2w must be 3x4 or 4x4");
  if (width <= 0 || height <= 0) throw py::value_error("width and height must be positive");
  ecrf_camera cam;
  for (int k = 0; k < 12; ++k) cam.c2w[k] = c2w.data()[k];
  cam.fx = fx;
  cam.fy = fy;
  cam.cx = cx;
  cam.cy = cy;
  cam.width = width;
  cam.height = height;
  ecrf_render_options o;
  ecrf_render_options_default(&o);
  o.num_threads = threads;
  o.early_stop_transmittance = early_stop;
  o.step_scale = step_scale;
  o.weight_threshold = weight_threshold.is_none() ? -1.f : weight_threshold.cast<float>();
  o.skip_empty_space = skip_empty_space ? 1 : 0;
  o.max_samples = max_samples;
  o.sample_budget = sample_budget;
  o.work_budget = work_budget;
  if (rgb) {
    py::array_t<float> out({height, width, 3});
    float* p = out.mutable_data();
    s.Call(g_error, "render",
           [&](ecrf_scene* e) { return ecrf_scene_render(e, &cam, &o, nullptr, p); });
    return std::move(out);
  }
  py::array_t<uint8_t> out({height, width, 4});
  uint8_t* p = out.mutable_data();
  s.Call(g_error, "render",
         [&](ecrf_scene* e) { return ecrf_scene_render(e, &cam, &o, p, nullptr); });
  return std::move(out);
}

// The reference tools' orbit (decoder/camera.h, SPEC.md 7.1): the camera `ecrf render
// --orbit` uses, bit for bit, as (c2w, fx, fy, cx, cy).
py::tuple OrbitCamera(int width, int height, double azimuth_deg, double elevation_deg,
                      float radius) {
  if (width <= 0 || height <= 0 || !(radius > 0.f)) throw py::value_error("bad orbit camera");
  const ecrf::dec::Camera cam =
      ecrf::dec::OrbitCameraDegrees(width, height, azimuth_deg, elevation_deg, radius);
  py::array_t<float> c2w({3, 4});
  std::copy(cam.c2w, cam.c2w + 12, c2w.mutable_data());
  return py::make_tuple(c2w, cam.fx, cam.fy, cam.cx, cam.cy);
}

}  // namespace

PYBIND11_MODULE(ecrf, m) {
  m.doc() = "Decoder and renderer of ecrf compressed radiance fields";
  m.attr("__version__") = ecrf_version_string();
  m.attr("bitstream_version") = ecrf_bitstream_version();  // major: reads 1.0 to 1.<minor>
  m.attr("bitstream_version_minor") = ecrf_bitstream_version_minor();
  g_error =
      PyErr_NewExceptionWithDoc("ecrf.Error", "An ecrf call failed; .code is the ECRF_ERR_* code.",
                                PyExc_ValueError, nullptr);
  g_decode_error = PyErr_NewExceptionWithDoc("ecrf.DecodeError", "The stream could not be decoded.",
                                             g_error, nullptr);
  m.attr("Error") = py::handle(g_error);
  m.attr("ERR_INVALID_ARGUMENT") = ECRF_ERR_INVALID_ARGUMENT;
  m.attr("ERR_TRUNCATED") = ECRF_ERR_TRUNCATED;
  m.attr("ERR_CORRUPT") = ECRF_ERR_CORRUPT;
  m.attr("ERR_UNSUPPORTED") = ECRF_ERR_UNSUPPORTED;
  m.attr("ERR_LIMIT") = ECRF_ERR_LIMIT;
  m.attr("ERR_CHECKSUM") = ECRF_ERR_CHECKSUM;
  m.attr("ERR_OUT_OF_MEMORY") = ECRF_ERR_OUT_OF_MEMORY;
  m.attr("DecodeError") = py::handle(g_decode_error);

  ecrf_render_options defaults;
  ecrf_render_options_default(&defaults);

  py::class_<Scene>(m, "Scene", "A decoded scene (ecrf.decode)")
      .def_property_readonly("info", &Info, "ecrf_scene_info as a dict")
      .def_property_readonly("field", &Field, "ecrf_scene_field as a dict")
      .def("tensor", &Tensor, py::arg("grid"), py::arg("tensor"),
           "Read-only float32 view: grid 0 density / 1 appearance, tensor 0..2 planes "
           "[rows][columns][rank], 3..5 lines [length][rank]")
      .def("occupancy", &Occupancy, py::arg("packed") = false,
           "The occupancy mask as bool[z][y][x] (packed: the read-only bytes, x fastest, LSB "
           "first); None without a mask")
      .def("mlp_params", &MlpParams, "Basis and MLP parameters in MLPW order (float32 copy)")
      .def("render", &Render, py::arg("c2w"), py::arg("fx"), py::arg("fy"), py::arg("cx"),
           py::arg("cy"), py::arg("width"), py::arg("height"), py::kw_only(),
           py::arg("threads") = 0, py::arg("early_stop") = defaults.early_stop_transmittance,
           py::arg("step_scale") = defaults.step_scale, py::arg("weight_threshold") = py::none(),
           py::arg("skip_empty_space") = defaults.skip_empty_space != 0,
           py::arg("max_samples") = defaults.max_samples,
           py::arg("sample_budget") = defaults.sample_budget,
           py::arg("work_budget") = defaults.work_budget, py::arg("rgb") = false,
           "Renders one view: uint8 [height][width][4] RGBA, or with rgb=True float32 "
           "[height][width][3] in [0, 1]. threads: 0 (the default) all hardware threads, as the "
           "CLI.");
  m.def("decode", &Decode, py::arg("data"), py::arg("storage") = "float32",
        py::arg("memory_budget") = py::none(), py::arg("decode_budget") = py::none(),
        "Decodes an .ecrf stream from bytes-like data or a path; raises ecrf.DecodeError");
  m.def("orbit_camera", &OrbitCamera, py::arg("width"), py::arg("height"), py::arg("azimuth_deg"),
        py::arg("elevation_deg"), py::arg("radius"),
        "(c2w 3x4 float32, fx, fy, cx, cy) of the reference tools' orbit camera. Angles in "
        "degrees, as "
        "`ecrf render --elevation` and the web viewer: frame k of `ecrf render --orbit N` is "
        "orbit_camera(W, H, 360.0 * k / N, elevation_deg, radius), bit for bit.");
}
