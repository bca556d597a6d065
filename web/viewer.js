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

  // Byte layouts of the C structs on wasm32 (int, float, size_t and pointers are 4 bytes).
  const INFO_BYTES = 112, CAMERA_BYTES = 72, OPTIONS_BYTES = 40, FIELD_BYTES = 64;
  // Offset of ecrf_render_options.work_budget (a uint64_t, 8-byte aligned after seven 4-byte fields).
  const WORK_BUDGET_OFFSET = 32;

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

    version() { return this.m.UTF8ToString(this.m._ecrf_version_string()); }

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
      const p = m._malloc(INFO_BYTES);
      const rc = m._ecrf_scene_get_info(this.scene, p);
      if (rc < 0) { m._free(p); throw new Error(`ecrf_scene_get_info failed (${rc})`); }
      const f = (off, n) => Array.from(m.HEAPF32.subarray((p + off) >> 2, ((p + off) >> 2) + n));
      const i = (off, n) => Array.from(m.HEAP32.subarray((p + off) >> 2, ((p + off) >> 2) + n));
      const u = (off) => m.HEAP32[(p + off) >> 2] >>> 0;
      const info = {
        aabbMin: f(0, 3), aabbMax: f(12, 3), gridRes: i(24, 3), densityRanks: i(36, 3),
        appearanceRanks: i(48, 3), hasOccupancy: i(60, 1)[0] !== 0, occupancyRes: i(64, 3),
        numSamples: i(76, 1)[0], stepSize: f(80, 1)[0], nearPlane: f(84, 1)[0],
        farPlane: f(88, 1)[0], background: f(92, 3), streamBytes: u(104), gridBytes: u(108),
        // 0 object, 1 unbounded (SPEC.md 7.2.1: the box is the region of interest), 2 forward-facing
        // (7.2.2: the box is in NDC).
        sceneModel: m._ecrf_scene_model(this.scene),
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
      const o = opt >> 2;
      m.HEAP32[o + 0] = 1;  // num_threads
      if (options.skipEmptySpace !== undefined) m.HEAP32[o + 1] = options.skipEmptySpace ? 1 : 0;
      if (options.earlyStopTransmittance !== undefined) m.HEAPF32[o + 2] = options.earlyStopTransmittance;
      if (options.maxSamples !== undefined) m.HEAP32[o + 3] = options.maxSamples;
      if (options.workBudget !== undefined) {
        m.HEAPU32.set(u64Halves(options.workBudget), (opt + WORK_BUDGET_OFFSET) >> 2);
      }
    }

    // Throws with the decoder's message when ecrf_scene_render would refuse the scene with these
    // options before rendering (the sample budget, the work budget of one sample: SPEC.md 8); for
    // renderers of their own (the GPU path).
    checkRender(options = {}) {
      const m = this.m;
      const opt = m._malloc(OPTIONS_BYTES);
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
      const cam = m._malloc(CAMERA_BYTES + OPTIONS_BYTES);
      const opt = cam + CAMERA_BYTES;
      const c = cam >> 2;
      m.HEAPF32.set(camera.c2w, c);
      m.HEAPF32[c + 12] = camera.fx;
      m.HEAPF32[c + 13] = camera.fy;
      m.HEAPF32[c + 14] = camera.cx;
      m.HEAPF32[c + 15] = camera.cy;
      m.HEAP32[c + 16] = camera.width;
      m.HEAP32[c + 17] = camera.height;
      this.writeOptions(opt, options);
      const rc = m._ecrf_scene_render(this.scene, cam, opt, this.image, 0);
      m._free(cam);
      if (rc < 0) throw new Error(`render failed (${rc}): ${this.message()}`);
      // Copy out: HEAPU8 is replaced when memory grows.
      return new Uint8ClampedArray(m.HEAPU8.subarray(this.image, this.image + bytes));
    }

    // Everything a renderer of its own needs (SPEC.md section 7), copied out of the wasm heap
    // into fresh typed arrays that can be transferred to another thread:
    // {info, field: {densityShift, distanceScale, weightThreshold, occupancyMin, occupancyMax,
    //   mlp: {features, products, hidden, featureFreqs, viewdirFreqs, inputs}},
    //  density, appearance: {planes: [3], lines: [3]} of {data: Float32Array, shape},
    //  occupancy: {bits: Uint8Array (packed [z][y][x], x fastest, LSB first), res} or null,
    //  mlpParams: Float32Array in MLPW order (B, W1, b1, W2, b2, W3, b3)}.
    // Plane shape [rows (along v), columns (along u), rank]; line shape [length, rank, 1].
    sceneData() {
      const m = this.m;
      const info = this.info();
      const scratch = m._malloc(FIELD_BYTES + 32);
      try {
        if (m._ecrf_scene_get_field(this.scene, scratch) < 0) throw new Error('ecrf_scene_get_field failed');
        const f = (off, n) => Array.from(m.HEAPF32.subarray((scratch + off) >> 2, ((scratch + off) >> 2) + n));
        const i = (off) => m.HEAP32[(scratch + off) >> 2];
        const field = {
          densityShift: f(0, 1)[0], distanceScale: f(4, 1)[0], weightThreshold: f(8, 1)[0],
          occupancyMin: f(12, 3), occupancyMax: f(24, 3),
          mlp: {features: i(36), products: i(40), hidden: i(44), featureFreqs: i(48),
                viewdirFreqs: i(52), inputs: i(56)},
        };
        const mlpCount = m.HEAP32[(scratch + 60) >> 2] >>> 0;
        const grid = (g) => {
          const out = {planes: [], lines: []};
          for (let t = 0; t < 6; ++t) {
            const dataPtr = scratch + FIELD_BYTES, shapePtr = dataPtr + 4, countPtr = dataPtr + 16;
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
          const bitsPtr = scratch + FIELD_BYTES, resPtr = bitsPtr + 4, bytesPtr = bitsPtr + 16;
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
