// ecrf web viewer, core: the camera of the reference tools and a wrapper of the WebAssembly build of
// the embeddable decoder (scripts/build-wasm.sh). No DOM code: the page (viewer_page.js), the
// workers (decode_worker.js, render_worker.js) and node (web/smoke_test.mjs, which checks it
// against the conformance reference render) all load this same file. Plain script, no dependencies.
'use strict';

(function () {
  const f32 = Math.fround;

  // Port of ecrf::dec::OrbitCamera (decoder/ray_marcher.cc), in float32 arithmetic step by step:
  // orbit around the origin, +z up, camera looking at the origin (OpenGL: looks down -z, +y up).
  // Returns {c2w: 12 floats (3x4 row-major camera-to-world), fx, fy, cx, cy, width, height}.
  function orbitCamera(width, height, azimuthRad, elevationRad, radius) {
    const az = f32(azimuthRad), el = f32(elevationRad), r = f32(radius);
    const ce = f32(Math.cos(el)), se = f32(Math.sin(el));
    const ca = f32(Math.cos(az)), sa = f32(Math.sin(az));
    const pos = [f32(f32(r * ce) * ca), f32(f32(r * ce) * sa), f32(r * se)];
    const z = [f32(pos[0] / r), f32(pos[1] / r), f32(pos[2] / r)];  // camera +z (backwards)
    const up = [0, 0, 1];
    const x = [f32(f32(up[1] * z[2]) - f32(up[2] * z[1])),
               f32(f32(up[2] * z[0]) - f32(up[0] * z[2])),
               f32(f32(up[0] * z[1]) - f32(up[1] * z[0]))];
    const xn = f32(Math.sqrt(f32(f32(f32(x[0] * x[0]) + f32(x[1] * x[1])) + f32(x[2] * x[2]))));
    for (let a = 0; a < 3; ++a) x[a] = f32(x[a] / xn);
    const y = [f32(f32(z[1] * x[2]) - f32(z[2] * x[1])),
               f32(f32(z[2] * x[0]) - f32(z[0] * x[2])),
               f32(f32(z[0] * x[1]) - f32(z[1] * x[0]))];
    const c2w = new Array(12);
    for (let a = 0; a < 3; ++a) {
      c2w[4 * a + 0] = x[a];
      c2w[4 * a + 1] = y[a];
      c2w[4 * a + 2] = z[a];
      c2w[4 * a + 3] = pos[a];
    }
    const fov = f32(0.6911112070083618);
    const fx = f32(f32(0.5 * width) / f32(Math.tan(f32(0.5 * fov))));
    return {c2w, fx, fy: fx, cx: f32(0.5 * width), cy: f32(0.5 * height), width, height};
  }

  // Rows [y0, y0 + rows) of `camera`'s image as a camera of their own: the same rays, bit for bit
  // (the pixel offsets j + 0.5 - cy are exact in float32 either way).
  function stripCamera(camera, y0, rows) {
    return {...camera, height: rows, cy: f32(camera.cy - y0)};
  }

  // Byte offsets of the fields of the C structs of include/ecrf/decoder.h, and their sizes, on
  // wasm32 (int, float, size_t and pointers are 4 bytes; a uint64_t is 8, aligned to 8). Written
  // by hand, so the ctest WebViewerStructLayout (tests/web/check_struct_layout.py) compiles them
  // against the header for wasm32 and fails on any difference.
  const LAYOUT = {
    ecrf_scene_info: {
      sizeof: 112, aabb_min: 0, aabb_max: 12, grid_res: 24, density_ranks: 36,
      appearance_ranks: 48, has_occupancy: 60, occupancy_res: 64, num_samples: 76, step_size: 80,
      near_plane: 84, far_plane: 88, background: 92, stream_bytes: 104, grid_bytes: 108,
    },
    ecrf_camera: {sizeof: 72, c2w: 0, fx: 48, fy: 52, cx: 56, cy: 60, width: 64, height: 68},
    ecrf_render_options: {
      sizeof: 40, num_threads: 0, skip_empty_space: 4, early_stop_transmittance: 8,
      max_samples: 12, work_budget: 32,
    },
    ecrf_scene_field: {
      sizeof: 64, density_shift: 0, distance_scale: 4, weight_threshold: 8, occupancy_min: 12,
      occupancy_max: 24, mlp_features: 36, mlp_products: 40, mlp_hidden: 44,
      mlp_feature_freqs: 48, mlp_viewdir_freqs: 52, mlp_inputs: 56, mlp_params: 60,
    },
  };
  const INFO = LAYOUT.ecrf_scene_info, CAMERA = LAYOUT.ecrf_camera;
  const OPTIONS = LAYOUT.ecrf_render_options, FIELD = LAYOUT.ecrf_scene_field;

  // A non-negative integer (below 2^53) as the [low, high] 32-bit halves of a uint64_t.
  function u64Halves(value) {
    const v = Math.max(0, Math.floor(value));
    return [v % 4294967296, Math.floor(v / 4294967296)];
  }

  // One decoded scene over the C API of include/ecrf/decoder.h. `module` is the
  // instance that createEcrfDecoder() (build-wasm/ecrf_decoder.js) resolves to.
  class EcrfDecoder {
    constructor(module) {
      this.m = module;
      this.scene = module._ecrf_scene_create();
      if (!this.scene) throw new Error('ecrf_scene_create: out of memory');
      this.image = 0;
      this.imageBytes = 0;
    }

    // The library's version and the bitstreams it reads, as `ecrf --version` words them.
    version() {
      const m = this.m;
      return `${m.UTF8ToString(m._ecrf_version_string())}, reads bitstream 1.0 to ` +
             `${m._ecrf_bitstream_version()}.${m._ecrf_bitstream_version_minor()}`;
    }

    message() { return this.m.UTF8ToString(this.m._ecrf_scene_message(this.scene)); }

    // Decode work budget of the next decodes (SPEC.md 8): units per byte of the stream, 0 no limit.
    // (A uint64_t argument is passed as two 32-bit halves, low first: -sWASM_BIGINT=0.)
    setDecodeBudget(unitsPerByte) {
      this.m._ecrf_scene_set_decode_budget(this.scene, ...u64Halves(unitsPerByte));
    }

    // bytes: Uint8Array of a whole .ecrf file. Throws with the decoder's message on failure.
    decode(bytes, storage = 0) {
      const m = this.m;
      const ptr = m._malloc(Math.max(1, bytes.length));
      if (!ptr) throw new Error('out of memory copying the stream');
      m.HEAPU8.set(bytes, ptr);
      const rc = m._ecrf_scene_decode(this.scene, ptr, bytes.length, storage);
      m._free(ptr);
      if (rc < 0) throw new Error(`decode failed (${rc}): ${this.message()}`);
    }

    info() {
      const m = this.m;
      const p = m._malloc(INFO.sizeof);
      const rc = m._ecrf_scene_get_info(this.scene, p);
      if (rc < 0) { m._free(p); throw new Error(`ecrf_scene_get_info failed (${rc})`); }
      const f = (off, n) => Array.from(m.HEAPF32.subarray((p + off) >> 2, ((p + off) >> 2) + n));
      const i = (off, n) => Array.from(m.HEAP32.subarray((p + off) >> 2, ((p + off) >> 2) + n));
      const u = (off) => m.HEAP32[(p + off) >> 2] >>> 0;
      const version = m._ecrf_scene_version(this.scene);
      const info = {
        aabbMin: f(INFO.aabb_min, 3), aabbMax: f(INFO.aabb_max, 3), gridRes: i(INFO.grid_res, 3),
        densityRanks: i(INFO.density_ranks, 3), appearanceRanks: i(INFO.appearance_ranks, 3),
        hasOccupancy: i(INFO.has_occupancy, 1)[0] !== 0, occupancyRes: i(INFO.occupancy_res, 3),
        numSamples: i(INFO.num_samples, 1)[0], stepSize: f(INFO.step_size, 1)[0],
        nearPlane: f(INFO.near_plane, 1)[0], farPlane: f(INFO.far_plane, 1)[0],
        background: f(INFO.background, 3), streamBytes: u(INFO.stream_bytes),
        gridBytes: u(INFO.grid_bytes),
        // 0 object, 1 unbounded (SPEC.md 7.2.1: the box is the region of interest), 2 forward-facing
        // (7.2.2: the box is in NDC).
        sceneModel: m._ecrf_scene_model(this.scene),
        // 0 the MLP per coloured sample, 1 deferred (SPEC.md 7.6: once per ray).
        head: m._ecrf_scene_head(this.scene),
        // The bitstream version the file states (SPEC.md 2.1), as `ecrf info` prints it.
        version: `${version >> 8}.${version & 255}`,
      };
      m._free(p);
      if (info.sceneModel === 2) {
        // The reference camera of a forward-facing scene (SPEC.md 6.2.1): 3x4 world to reference,
        // 2 fx / width, 2 fy / height, near plane.
        const q = m._malloc(60);
        const rc2 = m._ecrf_scene_ndc_frame(this.scene, q);
        info.ndcFrame = rc2 < 0 ? null : Array.from(m.HEAPF32.subarray(q >> 2, (q >> 2) + 15));
        m._free(q);
      }
      return info;
    }

    // ecrf_render_options for `options` in the wasm heap at `opt` (one thread: no pthreads here).
    writeOptions(opt, options) {
      const m = this.m;
      m._ecrf_render_options_default(opt);
      const at = (offset) => (opt + offset) >> 2;
      m.HEAP32[at(OPTIONS.num_threads)] = 1;
      if (options.skipEmptySpace !== undefined) {
        m.HEAP32[at(OPTIONS.skip_empty_space)] = options.skipEmptySpace ? 1 : 0;
      }
      if (options.earlyStopTransmittance !== undefined) {
        m.HEAPF32[at(OPTIONS.early_stop_transmittance)] = options.earlyStopTransmittance;
      }
      if (options.maxSamples !== undefined) m.HEAP32[at(OPTIONS.max_samples)] = options.maxSamples;
      if (options.workBudget !== undefined) {
        m.HEAPU32.set(u64Halves(options.workBudget), at(OPTIONS.work_budget));
      }
    }

    // Throws with the decoder's message when ecrf_scene_render would refuse the scene with these
    // options before rendering (the sample budget, the work budget of one sample: SPEC.md 8); for
    // renderers of their own (the GPU path).
    checkRender(options = {}) {
      const m = this.m;
      const opt = m._malloc(OPTIONS.sizeof);
      this.writeOptions(opt, options);
      const rc = m._ecrf_scene_check_render(this.scene, opt);
      m._free(opt);
      if (rc < 0) throw new Error(`render refused (${rc}): ${this.message()}`);
    }

    // Renders `camera` (orbitCamera's shape) and returns a fresh Uint8ClampedArray of
    // width*height*4 RGBA bytes (alpha = opacity). Always one thread: no pthreads in this build.
    // options: {skipEmptySpace, earlyStopTransmittance, maxSamples, workBudget}; omitted fields
    // keep ecrf_render_options_default's values.
    render(camera, options = {}) {
      const m = this.m;
      const bytes = camera.width * camera.height * 4;
      if (bytes > this.imageBytes) {
        if (this.image) m._free(this.image);
        this.image = m._malloc(bytes);
        this.imageBytes = this.image ? bytes : 0;
        if (!this.image) throw new Error('out of memory for the image');
      }
      const cam = m._malloc(CAMERA.sizeof + OPTIONS.sizeof);
      const opt = cam + CAMERA.sizeof;
      const at = (offset) => (cam + offset) >> 2;
      m.HEAPF32.set(camera.c2w, at(CAMERA.c2w));
      m.HEAPF32[at(CAMERA.fx)] = camera.fx;
      m.HEAPF32[at(CAMERA.fy)] = camera.fy;
      m.HEAPF32[at(CAMERA.cx)] = camera.cx;
      m.HEAPF32[at(CAMERA.cy)] = camera.cy;
      m.HEAP32[at(CAMERA.width)] = camera.width;
      m.HEAP32[at(CAMERA.height)] = camera.height;
      this.writeOptions(opt, options);
      const rc = m._ecrf_scene_render(this.scene, cam, opt, this.image, 0);
      m._free(cam);
      if (rc < 0) throw new Error(`render failed (${rc}): ${this.message()}`);
      // Copy out: HEAPU8 is replaced when memory grows.
      return new Uint8ClampedArray(m.HEAPU8.subarray(this.image, this.image + bytes));
    }

    // Everything a renderer of its own needs (SPEC.md section 7), copied out of the wasm heap
    // into fresh typed arrays that can be transferred to another thread:
    // {info, field: {densityShift, densityRelu, distanceScale, weightThreshold, occupancyMin,
    //   occupancyMax,
    //   mlp: {features, products, hidden, featureFreqs, viewdirFreqs, inputs}},
    //  density, appearance: {planes: [3], lines: [3]} of {data: Float32Array, shape},
    //  occupancy: {bits: Uint8Array (packed [z][y][x], x fastest, LSB first), res} or null,
    //  mlpParams: Float32Array in MLPW order (B, W1, b1, W2, b2, W3, b3)}.
    // Plane shape [rows (along v), columns (along u), rank]; line shape [length, rank, 1].
    sceneData() {
      const m = this.m;
      const info = this.info();
      const scratch = m._malloc(FIELD.sizeof + 32);
      try {
        if (m._ecrf_scene_get_field(this.scene, scratch) < 0) throw new Error('ecrf_scene_get_field failed');
        const f = (off, n) => Array.from(m.HEAPF32.subarray((scratch + off) >> 2, ((scratch + off) >> 2) + n));
        const i = (off) => m.HEAP32[(scratch + off) >> 2];
        const field = {
          densityShift: f(FIELD.density_shift, 1)[0], distanceScale: f(FIELD.distance_scale, 1)[0],
          densityRelu: m._ecrf_scene_density_activation(this.scene) === 1,
          weightThreshold: f(FIELD.weight_threshold, 1)[0],
          occupancyMin: f(FIELD.occupancy_min, 3), occupancyMax: f(FIELD.occupancy_max, 3),
          mlp: {features: i(FIELD.mlp_features), products: i(FIELD.mlp_products),
                hidden: i(FIELD.mlp_hidden), featureFreqs: i(FIELD.mlp_feature_freqs),
                viewdirFreqs: i(FIELD.mlp_viewdir_freqs), inputs: i(FIELD.mlp_inputs),
                layers: m._ecrf_scene_mlp_layers(this.scene)},
        };
        const mlpCount = m.HEAP32[(scratch + FIELD.mlp_params) >> 2] >>> 0;
        const grid = (g) => {
          const out = {planes: [], lines: []};
          for (let t = 0; t < 6; ++t) {
            const dataPtr = scratch + FIELD.sizeof, shapePtr = dataPtr + 4, countPtr = dataPtr + 16;
            if (m._ecrf_scene_tensor(this.scene, g, t, dataPtr, shapePtr, countPtr) < 0) {
              throw new Error(`ecrf_scene_tensor(${g}, ${t}) failed: float32 storage only`);
            }
            const ptr = m.HEAP32[dataPtr >> 2] >>> 0, count = m.HEAP32[countPtr >> 2] >>> 0;
            const shape = Array.from(m.HEAP32.subarray(shapePtr >> 2, (shapePtr >> 2) + 3));
            const data = new Float32Array(m.HEAPF32.subarray(ptr >> 2, (ptr >> 2) + count));
            (t < 3 ? out.planes : out.lines).push({data, shape});
          }
          return out;
        };
        const density = grid(0), appearance = grid(1);
        let occupancy = null;
        if (info.hasOccupancy) {
          const bitsPtr = scratch + FIELD.sizeof, resPtr = bitsPtr + 4, bytesPtr = bitsPtr + 16;
          if (m._ecrf_scene_occupancy(this.scene, bitsPtr, resPtr, bytesPtr) < 0) throw new Error('ecrf_scene_occupancy failed');
          const ptr = m.HEAP32[bitsPtr >> 2] >>> 0, n = m.HEAP32[bytesPtr >> 2] >>> 0;
          occupancy = {bits: new Uint8Array(m.HEAPU8.subarray(ptr, ptr + n)),
                       res: Array.from(m.HEAP32.subarray(resPtr >> 2, (resPtr >> 2) + 3))};
        }
        const paramsPtr = m._malloc(Math.max(4, mlpCount * 4));
        if (!paramsPtr) throw new Error('out of memory copying the MLP');
        try {
          if (m._ecrf_scene_mlp_params(this.scene, paramsPtr, mlpCount) < 0) throw new Error('ecrf_scene_mlp_params failed');
          const mlpParams = new Float32Array(m.HEAPF32.subarray(paramsPtr >> 2, (paramsPtr >> 2) + mlpCount));
          return {info, field, density, appearance, occupancy, mlpParams};
        } finally {
          m._free(paramsPtr);
        }
      } finally {
        m._free(scratch);
      }
    }

    destroy() {
      if (this.image) this.m._free(this.image);
      if (this.scene) this.m._ecrf_scene_destroy(this.scene);
      this.image = this.scene = 0;
    }
  }

  const api = {orbitCamera, stripCamera, EcrfDecoder};
  if (typeof module !== 'undefined' && module.exports) module.exports = api;
  globalThis.ecrfWeb = api;
})();
