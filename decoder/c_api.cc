// The C API of include/ecrf/decoder.h over SceneDecoder and RayMarcher.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>

#include "decoder/ray_marcher.h"
#include "decoder/scene_decoder.h"
#include "ecrf/decoder.h"

struct ecrf_scene {
  ecrf::dec::SceneField field;
  ecrf::dec::SceneInfo info;
  bool decoded = false;
  uint64_t memory_budget = ecrf::dec::kDefaultDecodeMemoryBudget;
  uint64_t decode_work_per_byte = ecrf::dec::kDefaultDecodeWorkPerByte;
  char message[512] = {0};
};

namespace {

int Record(ecrf_scene* scene, const ecrf::Status& status) {
  if (status.ok()) {
    scene->message[0] = '\0';
    return ECRF_OK;
  }
  std::snprintf(scene->message, sizeof(scene->message), "%s: %s",
                ecrf::ErrorCodeName(status.code()), status.message());
  return status.code();
}

ecrf::dec::RenderOptions ToRenderOptions(const ecrf_render_options* options) {
  ecrf::dec::RenderOptions o;
  if (options) {
    o.num_threads = options->num_threads;
    o.skip_empty_space = options->skip_empty_space != 0;
    o.early_stop_transmittance = options->early_stop_transmittance;
    o.max_samples = options->max_samples;
    o.step_scale = options->step_scale;
    o.weight_threshold = options->weight_threshold;
    o.sample_budget = options->sample_budget;
    o.work_budget = options->work_budget;
  }
  return o;
}

}  // namespace

extern "C" {

void ecrf_render_options_default(ecrf_render_options* o) {
  if (!o) return;
  const ecrf::dec::RenderOptions d;
  o->num_threads = d.num_threads;
  o->skip_empty_space = d.skip_empty_space ? 1 : 0;
  o->early_stop_transmittance = d.early_stop_transmittance;
  o->max_samples = d.max_samples;
  o->step_scale = d.step_scale;
  o->weight_threshold = d.weight_threshold;
  o->sample_budget = d.sample_budget;
  o->work_budget = d.work_budget;
}

ecrf_scene* ecrf_scene_create(void) { return new (std::nothrow) ecrf_scene(); }

int ecrf_scene_set_memory_budget(ecrf_scene* scene, uint64_t bytes) {
  if (!scene) return ECRF_ERR_INVALID_ARGUMENT;
  scene->memory_budget = bytes == 0 ? ecrf::dec::kDefaultDecodeMemoryBudget : bytes;
  scene->message[0] = '\0';
  return ECRF_OK;
}

int ecrf_scene_set_decode_budget(ecrf_scene* scene, uint64_t units_per_byte) {
  if (!scene) return ECRF_ERR_INVALID_ARGUMENT;
  scene->decode_work_per_byte = units_per_byte;
  scene->message[0] = '\0';
  return ECRF_OK;
}

void ecrf_scene_destroy(ecrf_scene* scene) { delete scene; }

const char* ecrf_scene_message(const ecrf_scene* scene) { return scene ? scene->message : ""; }

int ecrf_scene_decode(ecrf_scene* scene, const void* data, size_t size, int storage) {
  if (!scene) return ECRF_ERR_INVALID_ARGUMENT;
  scene->decoded = false;
  if (storage != ECRF_STORAGE_FLOAT32 && storage != ECRF_STORAGE_INT16) {
    return Record(scene, ecrf::Status::Error(ecrf::kErrInvalidArgument,
                                             "storage %d is neither FLOAT32 nor INT16", storage));
  }
  ecrf::dec::DecodeOptions options;
  options.max_memory_bytes = scene->memory_budget;
  options.work_per_byte = scene->decode_work_per_byte;
  options.storage = storage == ECRF_STORAGE_INT16 ? ecrf::dec::GridStorage::kInt16
                                                  : ecrf::dec::GridStorage::kFloat32;
  const ecrf::Status s = ecrf::dec::DecodeScene(static_cast<const uint8_t*>(data), size, options,
                                                &scene->field, &scene->info);
  scene->info.metadata = nullptr;  // points into the caller's buffer, which is not kept
  scene->info.metadata_size = 0;
  scene->decoded = s.ok();
  return Record(scene, s);
}

int ecrf_scene_get_info(const ecrf_scene* scene, ecrf_scene_info* out) {
  if (!scene || !out || !scene->decoded) return ECRF_ERR_INVALID_ARGUMENT;
  const ecrf::dec::SceneField& f = scene->field;
  const ecrf::SceneHeader& h = scene->info.header;
  std::memset(out, 0, sizeof(*out));
  for (int a = 0; a < 3; ++a) {
    out->aabb_min[a] = f.aabb_min[a];
    out->aabb_max[a] = f.aabb_max[a];
    out->grid_res[a] = f.res[a];
    out->density_ranks[a] = h.ranks[0][a];
    out->appearance_ranks[a] = h.ranks[1][a];
    out->occupancy_res[a] = scene->info.occupancy_res[a];
    out->background[a] = f.background[a];
  }
  out->has_occupancy = f.has_mask ? 1 : 0;
  out->num_samples = f.NumSamples();
  out->step_size = f.StepSize();
  out->near_plane = f.near_far[0];
  out->far_plane = f.near_far[1];
  out->stream_bytes = scene->info.stream_bytes;
  out->grid_bytes = f.density.StorageBytes() + f.appearance.StorageBytes();
  return ECRF_OK;
}

int ecrf_scene_tensor(const ecrf_scene* scene, int grid, int tensor, const float** data,
                      int shape[3], size_t* count) {
  if (!scene || !scene->decoded || !data || !shape || !count || grid < 0 || grid > 1 ||
      tensor < 0 || tensor > 5) {
    return ECRF_ERR_INVALID_ARGUMENT;
  }
  const ecrf::dec::VmGrid& g = grid == 0 ? scene->field.density : scene->field.appearance;
  if (g.storage != ecrf::dec::GridStorage::kFloat32) return ECRF_ERR_INVALID_ARGUMENT;
  const int m = tensor % 3;
  if (tensor < 3) {
    shape[0] = g.res[ecrf::kMatMode[m][1]];
    shape[1] = g.res[ecrf::kMatMode[m][0]];
    shape[2] = g.ranks[m];
    *data = g.plane_f32[m].data();
    *count = g.plane_count(m);
  } else {
    shape[0] = g.res[ecrf::kVecMode[m]];
    shape[1] = g.ranks[m];
    shape[2] = 1;
    *data = g.line_f32[m].data();
    *count = g.line_count(m);
  }
  return ECRF_OK;
}

int ecrf_scene_model(const ecrf_scene* scene) {
  if (!scene || !scene->decoded) return ECRF_ERR_INVALID_ARGUMENT;
  static_assert(ECRF_SCENE_OBJECT == static_cast<int>(ecrf::SceneModel::kObject) &&
                    ECRF_SCENE_UNBOUNDED == static_cast<int>(ecrf::SceneModel::kUnbounded) &&
                    ECRF_SCENE_FORWARD == static_cast<int>(ecrf::SceneModel::kForward),
                "C API scene models must equal the format's");
  return static_cast<int>(scene->field.scene_model);
}

int ecrf_scene_head(const ecrf_scene* scene) {
  if (!scene || !scene->decoded) return ECRF_ERR_INVALID_ARGUMENT;
  static_assert(ECRF_HEAD_MLP == static_cast<int>(ecrf::HeadKind::kPerSample) &&
                    ECRF_HEAD_DEFERRED == static_cast<int>(ecrf::HeadKind::kDeferred),
                "C API heads must equal the format's");
  return static_cast<int>(scene->field.head);
}

int ecrf_scene_mlp_layers(const ecrf_scene* scene) {
  if (!scene || !scene->decoded) return ECRF_ERR_INVALID_ARGUMENT;
  return scene->field.mlp.config().hidden_layers;
}

int ecrf_scene_density_activation(const ecrf_scene* scene) {
  if (!scene || !scene->decoded) return ECRF_ERR_INVALID_ARGUMENT;
  static_assert(ECRF_DENSITY_SOFTPLUS == static_cast<int>(ecrf::DensityActivation::kSoftplus) &&
                    ECRF_DENSITY_RELU == static_cast<int>(ecrf::DensityActivation::kRelu),
                "C API density activations must equal the format's");
  return static_cast<int>(scene->field.density_activation);
}

int ecrf_scene_version(const ecrf_scene* scene) {
  if (!scene || !scene->decoded) return ECRF_ERR_INVALID_ARGUMENT;
  return (static_cast<int>(scene->info.version_major) << 8) | scene->info.version_minor;
}

int ecrf_scene_ndc_frame(const ecrf_scene* scene, float frame[15]) {
  if (!scene || !frame || !scene->decoded ||
      scene->field.scene_model != ecrf::SceneModel::kForward) {
    return ECRF_ERR_INVALID_ARGUMENT;
  }
  const ecrf::NdcFrame& f = scene->field.ndc;
  for (int k = 0; k < 12; ++k) frame[k] = f.world_to_ref[k];
  frame[12] = f.scale[0];
  frame[13] = f.scale[1];
  frame[14] = f.near_plane;
  return ECRF_OK;
}

int ecrf_scene_get_field(const ecrf_scene* scene, ecrf_scene_field* out) {
  if (!scene || !out || !scene->decoded) return ECRF_ERR_INVALID_ARGUMENT;
  const ecrf::dec::SceneField& f = scene->field;
  std::memset(out, 0, sizeof(*out));
  out->density_shift = f.density_shift;
  out->distance_scale = f.distance_scale;
  out->weight_threshold = f.weight_threshold;
  if (f.has_mask) {
    for (int a = 0; a < 3; ++a) {
      out->occupancy_min[a] = f.mask.aabb_min()[a];
      out->occupancy_max[a] = f.mask.aabb_max()[a];
    }
  }
  const ecrf::dec::MlpConfig& c = f.mlp.config();
  out->mlp_features = c.feature_dim;
  out->mlp_products = c.num_products;
  out->mlp_hidden = c.hidden;
  out->mlp_feature_freqs = c.feature_pe_freqs;
  out->mlp_viewdir_freqs = c.viewdir_pe_freqs;
  out->mlp_inputs = c.input_dim();
  out->mlp_params = f.mlp.num_params();
  return ECRF_OK;
}

int ecrf_scene_occupancy(const ecrf_scene* scene, const uint8_t** bits, int res[3], size_t* bytes) {
  if (!scene || !scene->decoded || !bits || !res || !bytes || !scene->field.has_mask) {
    return ECRF_ERR_INVALID_ARGUMENT;
  }
  const ecrf::dec::OccupancyMask& m = scene->field.mask;
  for (int a = 0; a < 3; ++a) res[a] = m.res()[a];
  *bits = m.bits();
  *bytes = m.bits_bytes();
  return ECRF_OK;
}

int ecrf_scene_mlp_params(const ecrf_scene* scene, float* params, size_t count) {
  if (!scene || !scene->decoded || !params) return ECRF_ERR_INVALID_ARGUMENT;
  return scene->field.mlp.GetParams(params, count).code();
}

int ecrf_scene_check_render(ecrf_scene* scene, const ecrf_render_options* options) {
  if (!scene) return ECRF_ERR_INVALID_ARGUMENT;
  if (!scene->decoded) {
    return Record(scene,
                  ecrf::Status::Error(ecrf::kErrInvalidArgument, "render: no decoded scene"));
  }
  ecrf::dec::RenderOptions o = ToRenderOptions(options);
  // One workspace is enough to check.
  if (o.num_threads >= 0 && o.num_threads <= ecrf::dec::kMaxRenderThreads) o.num_threads = 1;
  ecrf::dec::RayMarcher marcher;
  return Record(scene, marcher.Init(&scene->field, o));
}

int ecrf_scene_render(ecrf_scene* scene, const ecrf_camera* camera,
                      const ecrf_render_options* options, uint8_t* rgba8, float* rgb) {
  if (!scene) return ECRF_ERR_INVALID_ARGUMENT;
  if (!scene->decoded || !camera) {
    return Record(scene, ecrf::Status::Error(ecrf::kErrInvalidArgument,
                                             "render: no decoded scene or no camera"));
  }
  const ecrf::dec::RenderOptions o = ToRenderOptions(options);
  ecrf::dec::Camera cam;
  std::memcpy(cam.c2w, camera->c2w, sizeof(cam.c2w));
  cam.fx = camera->fx;
  cam.fy = camera->fy;
  cam.cx = camera->cx;
  cam.cy = camera->cy;
  cam.width = camera->width;
  cam.height = camera->height;
  ecrf::dec::RayMarcher marcher;
  ecrf::Status s = marcher.Init(&scene->field, o);
  if (s.ok()) s = marcher.RenderImage(cam, rgba8, rgb);
  return Record(scene, s);
}

}  // extern "C"
