/* Times the embeddable decoder through its C API alone, so the same program builds against the
 * decoder sources of any commit (scripts/decoder-speed.sh compares two): decodes a stream, renders
 * VIEWS orbit views (radius 4, 30 degrees up, azimuths 360/VIEWS apart, as `ecrf render --orbit`)
 * REPS times, and prints the best repetition's milliseconds per view and a hash of every pixel
 * (FNV-1a over the RGBA bytes of all views) that tells whether two builds render the same image.
 *
 *   decoder_speed SCENE.ecrf [VIEWS [SIZE [THREADS [REPS [STEP_SCALE [EARLY_STOP]]]]]]
 *
 * defaults 4 400 2 4, and the library's render options (STEP_SCALE, EARLY_STOP: the renderer's
 * step_scale and early_stop_transmittance, SPEC.md 7.8).
 *
 * One output line: "ms_per_view=... decode_ms=... hash=... views=... size=... threads=..."
 * (decode_ms: reading and decoding the stream). */
#define _POSIX_C_SOURCE 199309L /* clock_gettime under -std=c99 */
#include <ecrf/decoder.h>

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "examples/example_util.h"

static double now_ms(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

int main(int argc, char** argv) {
  int views = 4, size = 400, threads = 2, reps = 4, v, r, rc = 0;
  size_t i, n;
  unsigned char* rgba;
  ecrf_scene* scene;
  ecrf_render_options options;
  double t0, decode_ms, best = -1.0;
  uint64_t hash = 1469598103934665603ull;

  if (argc < 2 || argc > 8) {
    fprintf(stderr,
            "usage: %s SCENE.ecrf [VIEWS [SIZE [THREADS [REPS [STEP_SCALE [EARLY_STOP]]]]]]\n",
            argv[0]);
    return 2;
  }
  if (argc > 2) views = atoi(argv[2]);
  if (argc > 3) size = atoi(argv[3]);
  if (argc > 4) threads = atoi(argv[4]);
  if (argc > 5) reps = atoi(argv[5]);
  if (views < 1 || views > 1000 || size < 1 || size > 8192 || threads < 0 || threads > 64 ||
      reps < 1 || reps > 100) {
    fprintf(stderr, "views 1..1000, size 1..8192, threads 0..64, reps 1..100\n");
    return 2;
  }
  t0 = now_ms();
  scene = decode_scene_file(argv[1], ECRF_STORAGE_FLOAT32);
  decode_ms = now_ms() - t0;
  if (!scene) return 1;
  ecrf_render_options_default(&options);
  options.num_threads = threads;
  if (argc > 6) options.step_scale = (float)atof(argv[6]);
  if (argc > 7) options.early_stop_transmittance = (float)atof(argv[7]);
  n = (size_t)size * (size_t)size * 4;
  rgba = (unsigned char*)malloc(n);
  if (!rgba) {
    ecrf_scene_destroy(scene);
    fprintf(stderr, "out of memory\n");
    return 1;
  }
  for (r = 0; r < reps && rc >= 0; ++r) {
    double total = 0.0;
    for (v = 0; v < views && rc >= 0; ++v) {
      ecrf_camera cam;
      /* Degrees to radians in double, as `ecrf render --orbit` converts them. */
      orbit_camera(&cam, size, size, (float)(2.0 * 3.14159265358979323846 * v / views),
                   (float)(30.0 * 3.14159265358979323846 / 180.0), 4.f);
      t0 = now_ms();
      rc = ecrf_scene_render(scene, &cam, &options, rgba, NULL);
      total += now_ms() - t0;
      if (r == 0) {
        for (i = 0; i < n; ++i) hash = (hash ^ rgba[i]) * 1099511628211ull;
      }
    }
    if (best < 0.0 || total < best) best = total;
  }
  if (rc < 0) {
    fprintf(stderr, "render: %s (%s)\n", ecrf_scene_message(scene), ecrf_error_name(rc));
  } else {
    printf(
        "ms_per_view=%.1f decode_ms=%.1f hash=%016llx views=%d size=%d threads=%d reps=%d "
        "step_scale=%g early_stop=%g\n",
        best / views, decode_ms, (unsigned long long)hash, views, size, threads, reps,
        (double)options.step_scale, (double)options.early_stop_transmittance);
  }
  free(rgba);
  ecrf_scene_destroy(scene);
  return rc < 0 ? 1 : 0;
}
