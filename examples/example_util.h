/* What the C programs beside the library share: reading a whole file, decoding a stream file
 * into a scene, and SPEC.md 7.1's orbit camera. Used by examples/decode_render.c and
 * benchmarks/decoder_speed.c (static inline, so a program that needs one of them builds without
 * warnings about the other). Plain C99. */
#ifndef ECRF_EXAMPLES_EXAMPLE_UTIL_H_
#define ECRF_EXAMPLES_EXAMPLE_UTIL_H_

#include <ecrf/decoder.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

/* The bytes of the file at path (malloc'd; the caller frees them) and their count in *size; NULL
 * when it cannot be read. */
static inline unsigned char* read_file(const char* path, size_t* size) {
  FILE* f = fopen(path, "rb");
  unsigned char* data = NULL;
  long n;
  if (!f) return NULL;
  if (fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) >= 0 && fseek(f, 0, SEEK_SET) == 0) {
    data = (unsigned char*)malloc(n > 0 ? (size_t)n : 1);
    if (data && fread(data, 1, (size_t)n, f) != (size_t)n) {
      free(data);
      data = NULL;
    }
    *size = (size_t)n;
  }
  fclose(f);
  return data;
}

/* The stream file at path decoded into a new scene (grids in `storage`); NULL, with the reason on
 * stderr, when it cannot be read or decoded. The caller destroys the scene. */
static inline ecrf_scene* decode_scene_file(const char* path, int storage) {
  size_t size = 0;
  unsigned char* bytes = read_file(path, &size);
  ecrf_scene* scene;
  int rc;
  if (!bytes) {
    fprintf(stderr, "cannot read %s\n", path);
    return NULL;
  }
  scene = ecrf_scene_create();
  if (!scene) {
    free(bytes);
    fprintf(stderr, "out of memory\n");
    return NULL;
  }
  rc = ecrf_scene_decode(scene, bytes, size, storage);
  free(bytes);
  if (rc < 0) {
    fprintf(stderr, "%s: %s (%s)\n", path, ecrf_scene_message(scene), ecrf_error_name(rc));
    ecrf_scene_destroy(scene);
    return NULL;
  }
  return scene;
}

/* SPEC.md 7.1 (informative OrbitCamera): on a sphere of `radius` around the origin, looking at
 * it, z up; azimuth and elevation in radians (benchmarks/decoder_speed.c's views). People type
 * degrees: orbit_camera_degrees. */
static inline void orbit_camera(ecrf_camera* cam, int width, int height, float az, float el,
                                float radius) {
  const float pos[3] = {radius * cosf(el) * cosf(az), radius * cosf(el) * sinf(az),
                        radius * sinf(el)};
  const float z[3] = {pos[0] / radius, pos[1] / radius, pos[2] / radius};
  float x[3] = {-z[1], z[0], 0.f}; /* (0, 0, 1) x z */
  const float xn = sqrtf(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
  float y[3];
  int a;
  for (a = 0; a < 3; ++a) x[a] /= xn;
  y[0] = z[1] * x[2] - z[2] * x[1];
  y[1] = z[2] * x[0] - z[0] * x[2];
  y[2] = z[0] * x[1] - z[1] * x[0];
  for (a = 0; a < 3; ++a) {
    cam->c2w[4 * a + 0] = x[a];
    cam->c2w[4 * a + 1] = y[a];
    cam->c2w[4 * a + 2] = z[a];
    cam->c2w[4 * a + 3] = pos[a];
  }
  cam->width = width;
  cam->height = height;
  cam->fx = cam->fy = 0.5f * (float)width / tanf(0.5f * 0.6911112070083618f);
  cam->cx = 0.5f * (float)width;
  cam->cy = 0.5f * (float)height;
}

/* orbit_camera with azimuth and elevation in degrees, as `ecrf render --orbit`, Python and the web
 * viewer take them (frame k of `ecrf render --orbit N` is azimuth 360 k / N). */
static inline void orbit_camera_degrees(ecrf_camera* cam, int width, int height, float az_deg,
                                        float el_deg, float radius) {
  orbit_camera(cam, width, height, az_deg * 0.017453292519943295f, el_deg * 0.017453292519943295f,
               radius);
}

#endif /* ECRF_EXAMPLES_EXAMPLE_UTIL_H_ */
