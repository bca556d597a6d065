/* ecrf decoder: C API. Depends on nothing but the C++ standard library inside.
 *
 * Functions return 0 or a negative error code (ECRF_ERR_*); the message of the last error is
 * available per handle (ecrf_scene_message). No function throws, aborts or reads outside the
 * buffers it is given; a stream is checked against the decoder limits before anything is
 * allocated. One scene handle is used by one thread at a time; rendering itself may use
 * several threads (ecrf_render_options.num_threads).
 *
 *   ecrf_scene* s = ecrf_scene_create();
 *   if (ecrf_scene_decode(s, bytes, size, ECRF_STORAGE_FLOAT32) < 0) puts(ecrf_scene_message(s));
 *   ecrf_render_options o; ecrf_render_options_default(&o);
 *   ecrf_scene_render(s, &camera, &o, rgba, NULL);
 *   ecrf_scene_destroy(s);
 */
#ifndef ECRF_DECODER_H_
#define ECRF_DECODER_H_

#include <stddef.h>
#include <stdint.h>

/* ECRF_API marks the C API, the only symbols libecrf_decoder.so exports (the library is built
 * with -fvisibility=hidden). Users of a Windows DLL define ECRF_DLL (the CMake target does). */
#ifndef ECRF_API
#if defined(_WIN32) || defined(__CYGWIN__)
#if defined(ECRF_BUILDING_DLL)
#define ECRF_API __declspec(dllexport)
#elif defined(ECRF_DLL)
#define ECRF_API __declspec(dllimport)
#else
#define ECRF_API
#endif
#elif defined(__GNUC__) && __GNUC__ >= 4
#define ECRF_API __attribute__((visibility("default")))
#else
#define ECRF_API
#endif
#endif

#ifdef __cplusplus
extern "C" {
#endif

#define ECRF_OK 0
#define ECRF_ERR_INVALID_ARGUMENT (-1)
#define ECRF_ERR_TRUNCATED (-2)
#define ECRF_ERR_CORRUPT (-3)
#define ECRF_ERR_UNSUPPORTED (-4)
#define ECRF_ERR_LIMIT (-5)
#define ECRF_ERR_CHECKSUM (-6)
#define ECRF_ERR_OUT_OF_MEMORY (-7)

/* Version of this library (not of the bitstream: ecrf_bitstream_version), written here only:
 * CMake's project version, the SONAME and ecrf_version() are read from these three lines. */
#define ECRF_VERSION_MAJOR 0
#define ECRF_VERSION_MINOR 2
#define ECRF_VERSION_PATCH 0

/* Library version as (major << 16) | (minor << 8) | patch, and as text. */
ECRF_API unsigned ecrf_version(void);
ECRF_API const char* ecrf_version_string(void);
/* Highest bitstream version this decoder reads, major and minor (1 and 6: it reads 1.0 to 1.6;
 * a file states its own, ecrf_scene_info). Print them as major.minor, as `ecrf --version` does. */
ECRF_API int ecrf_bitstream_version(void);
ECRF_API int ecrf_bitstream_version_minor(void);
/* Short name of an error code ("truncated", "corrupt", ...). */
ECRF_API const char* ecrf_error_name(int code);

typedef struct ecrf_scene ecrf_scene;

/* Defaults of the budgets of SPEC.md 8 (the decoder's own defaults are these values). */
#define ECRF_DEFAULT_MEMORY_BUDGET ((uint64_t)256 << 20) /* bytes per scene handle */
#define ECRF_DEFAULT_DECODE_BUDGET 1024                  /* work units per byte of the stream */
#define ECRF_DEFAULT_SAMPLE_BUDGET 16384                 /* samples per ray */
#define ECRF_DEFAULT_WORK_BUDGET 6000000                 /* multiply-adds per pixel */

#define ECRF_STORAGE_FLOAT32 0 /* grids as decoded (normative values) */
#define ECRF_STORAGE_INT16 1   /* grids rounded to 16-bit fixed point: half the memory */

typedef struct ecrf_scene_info {
  float aabb_min[3], aabb_max[3];
  int grid_res[3];
  int density_ranks[3];
  int appearance_ranks[3];
  int has_occupancy;
  int occupancy_res[3];
  int num_samples; /* samples per ray */
  float step_size; /* world units between samples */
  float near_plane, far_plane;
  float background[3];
  size_t stream_bytes;
  size_t grid_bytes; /* memory held by the decoded grids */
} ecrf_scene_info;

/* Pinhole camera. c2w: 3x4 row-major camera-to-world matrix (OpenGL: looks down -z, +y up).
 * Pixel (i, j) has direction c2w[:3,:3] * ((i + 0.5 - cx) / fx, -(j + 0.5 - cy) / fy, -1). */
typedef struct ecrf_camera {
  float c2w[12];
  float fx, fy, cx, cy;
  int width, height;
} ecrf_camera;

typedef struct ecrf_render_options {
  int num_threads;                /* 1: the calling thread only; 0: all hardware threads */
  int skip_empty_space;           /* 1: skip samples the occupancy mask proves empty */
  float early_stop_transmittance; /* stop a ray once its transmittance is below (0: off) */
  int max_samples;                /* cap on samples per ray (0: the scene's) */
  float step_scale;               /* sample spacing x this, sample count / this (1: the scene's;
                                     range [1/16, 64]); fewer samples, faster, less exact */
  float weight_threshold;         /* colour only samples of larger weight (< 0: the scene's) */
  int sample_budget;              /* refuse (ECRF_ERR_LIMIT) scenes whose rays take more samples
                                     than this after step_scale and max_samples (0: no limit;
                                     default ECRF_DEFAULT_SAMPLE_BUDGET) */
  uint64_t work_budget;           /* multiply-adds a view may spend per pixel on average
                                     (SPEC.md 8; 0: no limit; default ECRF_DEFAULT_WORK_BUDGET):
                                     refuse (ECRF_ERR_LIMIT) a scene one colour sample of which
                                     costs more, and a view that spends width x height x this */
} ecrf_render_options;

ECRF_API void ecrf_render_options_default(ecrf_render_options* options);

/* NULL when out of memory. */
ECRF_API ecrf_scene* ecrf_scene_create(void);
ECRF_API void ecrf_scene_destroy(ecrf_scene* scene);
/* Memory the next decodes may use for grids, occupancy mask and MLP (0: the default,
 * ECRF_DEFAULT_MEMORY_BUDGET); a stream that needs more fails with ECRF_ERR_LIMIT before
 * anything is allocated. */
ECRF_API int ecrf_scene_set_memory_budget(ecrf_scene* scene, uint64_t bytes);
/* Work the next decodes may spend (SPEC.md 8): 2^24 + units_per_byte x the stream's size, in
 * range-decoded symbols (a coded block's inverse DCT counts its time in symbols); 0: no limit;
 * default ECRF_DEFAULT_DECODE_BUDGET, 20 times what trained streams cost (the setting of a new
 * scene handle). A stream that costs more fails with
 * ECRF_ERR_LIMIT as soon as its work passes the budget. */
ECRF_API int ecrf_scene_set_decode_budget(ecrf_scene* scene, uint64_t units_per_byte);
/* Message of the last failed call on this scene ("" after a success). */
ECRF_API const char* ecrf_scene_message(const ecrf_scene* scene);

/* Decodes an .ecrf stream (the buffer is not kept). storage: ECRF_STORAGE_*. */
ECRF_API int ecrf_scene_decode(ecrf_scene* scene, const void* data, size_t size, int storage);
ECRF_API int ecrf_scene_get_info(const ecrf_scene* scene, ecrf_scene_info* info);

/* Read-only view of a decoded float32 tensor: grid 0 = density, 1 = appearance; tensor 0..2 =
 * planes [rows][columns][rank], 3..5 = lines [length][rank] (SPEC.md 6.4). shape receives up to
 * 3 sizes, outermost first; *count the number of floats. ECRF_ERR_INVALID_ARGUMENT for int16
 * storage. */
ECRF_API int ecrf_scene_tensor(const ecrf_scene* scene, int grid, int tensor, const float** data,
                               int shape[3], size_t* count);

/* What a renderer of its own (a GPU shader, SPEC.md section 7) needs besides the tensors. */
typedef struct ecrf_scene_field {
  float density_shift;    /* sigma = activation(density feature + density_shift) */
  float distance_scale;   /* alpha = 1 - exp(-sigma * (dist * distance_scale)) */
  float weight_threshold; /* the colour of a sample counts when its weight is larger */
  float occupancy_min[3], occupancy_max[3]; /* the mask's own box (has_occupancy) */
  int mlp_features;                         /* F: rows of the basis B */
  int mlp_products;      /* P: appearance products, the sum of the appearance ranks */
  int mlp_hidden;        /* H; 0: no MLP, spherical-harmonics colour (SPEC.md 7.6.2) */
  int mlp_feature_freqs; /* Ff */
  int mlp_viewdir_freqs; /* Fv */
  int mlp_inputs;        /* In = F + 3 + 2 F Ff + 6 Fv */
  size_t mlp_params;     /* floats of ecrf_scene_mlp_params */
} ecrf_scene_field;

ECRF_API int ecrf_scene_get_field(const ecrf_scene* scene, ecrf_scene_field* field);

/* The scene model of the decoded stream (SPEC.md 6.2). With ECRF_SCENE_UNBOUNDED the info's box
 * is the region of interest and the grids and the occupancy mask span the contracted cube
 * [-2, 2]^3 (SPEC.md 7.2.1); with ECRF_SCENE_FORWARD the box, grids and mask are in the
 * normalised device coordinates of the reference camera of ecrf_scene_ndc_frame
 * (SPEC.md 7.2.2). A renderer of its own must implement that section. */
#define ECRF_SCENE_OBJECT 0
#define ECRF_SCENE_UNBOUNDED 1
#define ECRF_SCENE_FORWARD 2
/* ECRF_SCENE_OBJECT, ECRF_SCENE_UNBOUNDED or ECRF_SCENE_FORWARD; ECRF_ERR_INVALID_ARGUMENT
 * before a decode. */
ECRF_API int ecrf_scene_model(const ecrf_scene* scene);

/* Where the scene's MLP runs (the MLPW head field, SPEC.md 6.6 and 7.6): ECRF_HEAD_MLP once per
 * coloured sample; ECRF_HEAD_DEFERRED once per ray, on the sum of its coloured samples' products
 * weighted by their weights, its colour times the sum of those weights. ECRF_ERR_INVALID_ARGUMENT
 * before a decode. */
#define ECRF_HEAD_MLP 0
#define ECRF_HEAD_DEFERRED 1
ECRF_API int ecrf_scene_head(const ecrf_scene* scene);

/* Hidden layers of the scene's MLP (the MLPW layers field, SPEC.md 6.6 and 7.6): 2, TensoRF's
 * Linear(H) ReLU Linear(H) ReLU before Linear(3); 1, one Linear(H) ReLU whose output W3 reads, and
 * ecrf_scene_mlp_params holds no W2 and b2 (bitstream 1.8). 2 for a stream without an MLP
 * (mlp_hidden 0). ECRF_ERR_INVALID_ARGUMENT before a decode. */
ECRF_API int ecrf_scene_mlp_layers(const ecrf_scene* scene);

/* How the density feature plus density_shift becomes sigma (the HEAD density_activation field,
 * SPEC.md 6.2 and 7.4): ECRF_DENSITY_SOFTPLUS, PyTorch's softplus with threshold 20 (every
 * stream before bitstream 1.9), or ECRF_DENSITY_RELU, max(x, 0) (1.9). ECRF_ERR_INVALID_ARGUMENT
 * before a decode. */
#define ECRF_DENSITY_SOFTPLUS 0
#define ECRF_DENSITY_RELU 1
ECRF_API int ecrf_scene_density_activation(const ecrf_scene* scene);

/* The bitstream version the decoded stream states (its file header, SPEC.md 2.1), as
 * (major << 8) | minor: 0x0106 is 1.6. Print it as major.minor, as `ecrf info` does.
 * ECRF_ERR_INVALID_ARGUMENT before a decode. */
ECRF_API int ecrf_scene_version(const ecrf_scene* scene);

/* The NDC frame of an ECRF_SCENE_FORWARD scene (the NDCP chunk, SPEC.md 6.2.1) as 15 floats: the
 * world-to-reference matrix [A | b] row-major (p_ref = A p + b), then 2 fx / width and
 * 2 fy / height of the reference camera, then its near plane. ECRF_ERR_INVALID_ARGUMENT for other
 * scene models or before a decode. */
ECRF_API int ecrf_scene_ndc_frame(const ecrf_scene* scene, float frame[15]);

/* The occupancy mask's bits, packed [z][y][x] with x fastest, LSB first (SPEC.md 6.3);
 * ECRF_ERR_INVALID_ARGUMENT when the scene has no mask. */
ECRF_API int ecrf_scene_occupancy(const ecrf_scene* scene, const uint8_t** bits, int res[3],
                                  size_t* bytes);

/* Copies the basis and MLP parameters, in MLPW order (SPEC.md 6.6: B, W1, b1, W2, b2, W3, b3),
 * into params; count must be ecrf_scene_field.mlp_params. */
ECRF_API int ecrf_scene_mlp_params(const ecrf_scene* scene, float* params, size_t count);

/* Renders one view. rgba8: width*height*4 bytes (alpha = opacity), rgb: width*height*3 floats
 * in [0, 1]; row-major from the top row; either may be NULL (not both). */
ECRF_API int ecrf_scene_render(ecrf_scene* scene, const ecrf_camera* camera,
                               const ecrf_render_options* options, uint8_t* rgba8, float* rgb);

/* Checks options against the decoded scene as ecrf_scene_render does before it renders anything
 * (option ranges, the sample budget, the work budget of one sample: SPEC.md 8), for renderers of
 * their own (a GPU shader) that want the same refusals. 0 or the error ecrf_scene_render would
 * return before rendering. */
ECRF_API int ecrf_scene_check_render(ecrf_scene* scene, const ecrf_render_options* options);

#ifdef __cplusplus
}
#endif

#endif /* ECRF_DECODER_H_ */
