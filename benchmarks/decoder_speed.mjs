// The WebAssembly counterpart of benchmarks/decoder_speed.c, for scripts/decoder-speed.sh --wasm:
// loads an emscripten build of the decoder's C API (nothing of web/, so it runs against the
// decoder of any commit), decodes a stream, renders VIEWS orbit views REPS times on one thread
// (as the viewer's workers do) and prints the same line as the C program (with a 32-bit hash).
//
//   node benchmarks/decoder_speed.mjs MODULE.js SCENE.ecrf [VIEWS [SIZE [REPS [STEP_SCALE
//                                     [EARLY_STOP]]]]]
import {createRequire} from 'node:module';
import {readFileSync} from 'node:fs';

const [modulePath, scenePath, viewsArg = '4', sizeArg = '400', repsArg = '3', stepArg,
       earlyArg] = process.argv.slice(2);
if (!modulePath || !scenePath) {
  console.error('usage: node decoder_speed.mjs MODULE.js SCENE.ecrf [VIEWS [SIZE [REPS]]]');
  process.exit(2);
}
const views = Number(viewsArg), size = Number(sizeArg), reps = Number(repsArg);
const require = createRequire(import.meta.url);
const create = require(modulePath);
const m = await create({wasmBinary: readFileSync(modulePath.replace(/\.js$/, '.wasm'))});

const bytes = new Uint8Array(readFileSync(scenePath));
const scene = m._ecrf_scene_create();
const data = m._malloc(bytes.length);
m.HEAPU8.set(bytes, data);
let t0 = performance.now();
let rc = m._ecrf_scene_decode(scene, data, bytes.length, 0);
const decodeMs = performance.now() - t0;
m._free(data);
if (rc < 0) {
  console.error(`decode failed (${rc})`);
  process.exit(1);
}
// ecrf_render_options: the library's defaults, one thread (the build has no pthreads).
const options = m._malloc(64);
m._ecrf_render_options_default(options);
m.HEAP32[options >> 2] = 1;
// early_stop_transmittance and step_scale: floats 2 and 4 of the struct.
if (earlyArg !== undefined) m.HEAPF32[(options >> 2) + 2] = Number(earlyArg);
if (stepArg !== undefined) m.HEAPF32[(options >> 2) + 4] = Number(stepArg);
// ecrf_camera: c2w[12], fx, fy, cx, cy (floats), width, height (ints).
const camera = m._malloc(72);
const rgba = m._malloc(size * size * 4);

function orbit(azDeg, elDeg, radius) {
  const az = Math.fround(azDeg * Math.PI / 180), el = Math.fround(elDeg * Math.PI / 180);
  const pos = [radius * Math.cos(el) * Math.cos(az), radius * Math.cos(el) * Math.sin(az),
               radius * Math.sin(el)];
  const z = pos.map((v) => v / radius);
  let x = [-z[1], z[0], 0];
  const xn = Math.hypot(...x);
  x = x.map((v) => v / xn);
  const y = [z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2], z[0] * x[1] - z[1] * x[0]];
  const f = new Float32Array(m.HEAPF32.buffer, camera, 16);
  for (let a = 0; a < 3; ++a) {
    f[4 * a] = x[a];
    f[4 * a + 1] = y[a];
    f[4 * a + 2] = z[a];
    f[4 * a + 3] = pos[a];
  }
  f[12] = f[13] = 0.5 * size / Math.tan(0.5 * 0.6911112070083618);
  f[14] = f[15] = 0.5 * size;
  m.HEAP32[(camera >> 2) + 16] = size;
  m.HEAP32[(camera >> 2) + 17] = size;
}

let best = Infinity, hash = 0x811c9dc5;  // FNV-1a, 32 bits
for (let r = 0; r < reps; ++r) {
  let total = 0;
  for (let v = 0; v < views; ++v) {
    orbit(360 * v / views, 30, 4);
    t0 = performance.now();
    rc = m._ecrf_scene_render(scene, camera, options, rgba, 0);
    total += performance.now() - t0;
    if (rc < 0) {
      console.error(`render failed (${rc})`);
      process.exit(1);
    }
    if (r === 0) {
      const px = new Uint8Array(m.HEAPU8.buffer, rgba, size * size * 4);
      for (let i = 0; i < px.length; ++i) {
        hash = Math.imul(hash ^ px[i], 0x01000193) >>> 0;
      }
    }
  }
  best = Math.min(best, total);
}
console.log(`ms_per_view=${(best / views).toFixed(1)} decode_ms=${decodeMs.toFixed(1)} ` +
            `hash=${hash.toString(16).padStart(8, '0')} views=${views} size=${size} threads=1 ` +
            `reps=${reps} step_scale=${m.HEAPF32[(options >> 2) + 4]} ` +
            `early_stop=${m.HEAPF32[(options >> 2) + 2]}`);
