/* Decodes an .ecrf file with the C API and renders one orbit view to a binary PPM.
 *
 *   decode_render scene.ecrf out.ppm [width height azimuth elevation radius]
 *
 * Azimuth and elevation in degrees, as `ecrf render --orbit`, Python and the web viewer take
 * them; the defaults (200x200, 17, 29, 4) suit the Blender-style scenes (z up, cameras 4 units
 * from the origin). Plain C99: builds against an installed ecrf with CMake
 * (examples/CMakeLists.txt) or with `cc decode_render.c $(pkg-config --cflags --libs ecrf-decoder) -lm`. */
#include <ecrf/decoder.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "example_util.h"

static int write_ppm(const char* path, const unsigned char* rgba, int width, int height) {
  FILE* f = fopen(path, "wb");
  size_t i, n = (size_t)width * (size_t)height;
  int ok;
  if (!f) return 0;
  ok = fprintf(f, "P6\n%d %d\n255\n", width, height) > 0;
  for (i = 0; ok && i < n; ++i) ok = fwrite(rgba + 4 * i, 1, 3, f) == 3;
  return fclose(f) == 0 && ok;
}

int main(int argc, char** argv) {
  unsigned char* rgba;
  ecrf_scene* scene;
  ecrf_scene_info info;
  ecrf_render_options options;
  ecrf_camera cam;
  int width = 200, height = 200, rc;
  float az_deg = 17.f, el_deg = 29.f, radius = 4.f;

  if (argc != 3 && argc != 8) {
    fprintf(stderr, "usage: %s scene.ecrf out.ppm [width height azimuth elevation radius]\n", argv[0]);
    return 2;
  }
  if (argc == 8) {
    width = atoi(argv[3]);
    height = atoi(argv[4]);
    az_deg = (float)atof(argv[5]);
    el_deg = (float)atof(argv[6]);
    radius = (float)atof(argv[7]);
    if (width <= 0 || height <= 0 || width > 8192 || height > 8192 || !(radius > 0.f) ||
        !(el_deg >= -89.f && el_deg <= 89.f)) {
      fprintf(stderr, "bad camera arguments\n");
      return 2;
    }
  }
  printf("ecrf decoder %s (reads bitstream %d.0 to %d.%d)\n", ecrf_version_string(),
         ecrf_bitstream_version(), ecrf_bitstream_version(), ecrf_bitstream_version_minor());
  scene = decode_scene_file(argv[1], ECRF_STORAGE_FLOAT32);
  if (!scene) return 1;
  ecrf_scene_get_info(scene, &info);
  printf("%s: %zu bytes, grid %dx%dx%d, density ranks %d/%d/%d, appearance ranks %d/%d/%d\n",
         argv[1], info.stream_bytes, info.grid_res[0], info.grid_res[1], info.grid_res[2],
         info.density_ranks[0], info.density_ranks[1], info.density_ranks[2],
         info.appearance_ranks[0], info.appearance_ranks[1], info.appearance_ranks[2]);
  printf("box [%g %g %g]..[%g %g %g], %d samples per ray, step %g, occupancy %s, grids %zu bytes\n",
         info.aabb_min[0], info.aabb_min[1], info.aabb_min[2], info.aabb_max[0], info.aabb_max[1],
         info.aabb_max[2], info.num_samples, info.step_size, info.has_occupancy ? "yes" : "no",
         info.grid_bytes);

  orbit_camera_degrees(&cam, width, height, az_deg, el_deg, radius);
  ecrf_render_options_default(&options);
  options.num_threads = 0;
  rgba = (unsigned char*)malloc((size_t)width * (size_t)height * 4);
  if (!rgba) {
    ecrf_scene_destroy(scene);
    fprintf(stderr, "out of memory\n");
    return 1;
  }
  rc = ecrf_scene_render(scene, &cam, &options, rgba, NULL);
  if (rc < 0) {
    fprintf(stderr, "render: %s (%s)\n", ecrf_scene_message(scene), ecrf_error_name(rc));
  } else if (!write_ppm(argv[2], rgba, width, height)) {
    fprintf(stderr, "cannot write %s\n", argv[2]);
    rc = -1;
  } else {
    printf("wrote %s (%dx%d)\n", argv[2], width, height);
  }
  free(rgba);
  ecrf_scene_destroy(scene);
  return rc < 0 ? 1 : 0;
}
