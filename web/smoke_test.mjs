// Headless check of the WebAssembly decoder and of the viewer's JS (web/viewer.js): decodes
// tests/conformance/scene_builtin.ecrf, renders OrbitCamera(64, 64, 0.3, 0.45, 4.0) as the
// reference does (SPEC.md section 7: no early termination) and compares it with
// tests/conformance/scene_builtin.png (a conforming renderer reaches 40 dB). Prints the timings.
//
//   bash scripts/build-wasm.sh && node web/smoke_test.mjs
import {createRequire} from 'node:module';
import {readFileSync, statSync} from 'node:fs';
import {dirname, join} from 'node:path';
import {fileURLToPath} from 'node:url';
import {readPng} from './test/gpu_common.mjs';

const require = createRequire(import.meta.url);
const root = join(dirname(fileURLToPath(import.meta.url)), '..');
const wasmPath = join(root, 'build-wasm', 'ecrf_decoder.wasm');
const createEcrfDecoder = require(join(root, 'build-wasm', 'ecrf_decoder.js'));
const {orbitCamera, stripCamera, EcrfDecoder} = require(join(root, 'web', 'viewer.js'));

function compare(rgba, ref) {
  let se = 0, maxDiff = 0, differing = 0;
  const n = ref.width * ref.height;
  for (let p = 0; p < n; ++p) {
    for (let k = 0; k < 3; ++k) {
      const d = rgba[4 * p + k] - ref.data[ref.channels * p + (ref.channels === 1 ? 0 : k)];
      se += d * d;
      if (d !== 0) ++differing;
      maxDiff = Math.max(maxDiff, Math.abs(d));
    }
  }
  const mse = se / (3 * n);
  return {psnr: mse === 0 ? Infinity : 10 * Math.log10((255 * 255) / mse), maxDiff, differing};
}

function median(xs) {
  const s = [...xs].sort((a, b) => a - b);
  return s[s.length >> 1];
}

function time(reps, fn) {
  const ms = [];
  let result;
  for (let r = 0; r < reps; ++r) {
    const t0 = performance.now();
    result = fn();
    ms.push(performance.now() - t0);
  }
  return {ms: median(ms), result};
}

let passed = 0, failures = 0;
function check(ok, what) {
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
  if (ok) ++passed;
  else ++failures;
}

// wasmBinary: emscripten 3.1.6's loader would fetch() the file in node >= 18, which fails on a path.
const module = await createEcrfDecoder({wasmBinary: readFileSync(wasmPath)});
const stream = new Uint8Array(readFileSync(join(root, 'tests', 'conformance', 'scene_builtin.ecrf')));
const reference = readPng(new Uint8Array(readFileSync(join(root, 'tests', 'conformance', 'scene_builtin.png'))));
const reps = Number(process.env.REPS || 5);

const dec = new EcrfDecoder(module);
console.log(`decoder ${dec.version()}, wasm ${statSync(wasmPath).size} bytes`);
dec.decode(stream);  // warm-up (JIT tiers)
const decode = time(reps, () => dec.decode(stream));
const info = dec.info();
console.log(`scene_builtin.ecrf: ${stream.length} bytes, grid ${info.gridRes.join('x')}, ` +
            `ranks ${info.densityRanks} / ${info.appearanceRanks}, grids ${info.gridBytes} bytes, ` +
            `occupancy ${info.hasOccupancy ? info.occupancyRes.join('x') : 'none'}, ` +
            `${info.numSamples} samples/ray`);
console.log(`decode: ${decode.ms.toFixed(1)} ms (median of ${reps})`);
check(info.streamBytes === stream.length, 'info.stream_bytes is the file size');
check(info.gridRes.every((r) => r > 0) && info.numSamples > 0, 'info has a grid and samples');

const cam64 = orbitCamera(64, 64, 0.3, 0.45, 4.0);
const exact = {earlyStopTransmittance: 0};  // the reference process
dec.render(cam64, exact);
const r64 = time(reps, () => dec.render(cam64, exact));
const c = compare(r64.result, reference);
console.log(`render 64x64 (reference options): ${r64.ms.toFixed(1)} ms; vs scene_builtin.png ` +
            `PSNR ${c.psnr.toFixed(2)} dB, max diff ${c.maxDiff}, ${c.differing} of ${64 * 64 * 3} values differ`);
check(reference.width === 64 && reference.height === 64 && c.psnr >= 40, 'PSNR >= 40 dB against the reference render');

// The viewer's workers render strips of rows: they must put together the same image.
const strips = new Uint8ClampedArray(64 * 64 * 4);
for (let y0 = 0; y0 < 64; y0 += 24) {
  const rows = Math.min(24, 64 - y0);
  strips.set(dec.render(stripCamera(cam64, y0, rows), exact), y0 * 64 * 4);
}
check(strips.every((v, i) => v === r64.result[i]), 'strips of rows give the same image, bit for bit');

const d64 = time(reps, () => dec.render(cam64));
const cd = compare(d64.result, reference);
console.log(`render 64x64 (default options, as the viewer): ${d64.ms.toFixed(1)} ms; PSNR ${cd.psnr.toFixed(2)} dB`);
check(cd.psnr >= 40, 'default options also >= 40 dB');

const cam400 = orbitCamera(400, 400, 0.3, 0.45, 4.0);
dec.render(cam400);
const r400 = time(Math.max(1, Math.min(reps, 3)), () => dec.render(cam400));
console.log(`render 400x400 (default options, as the viewer): ${r400.ms.toFixed(1)} ms`);
check(r400.result.length === 400 * 400 * 4, '400x400 image');

// Budgets (SPEC.md 8) reach the C API: a work budget below what one sample costs refuses the
// scene before anything is rendered (checkRender is the GPU path's check), 0 lifts the limit.
const refusal = (fn) => { try { fn(); return ''; } catch (e) { return e.message; } };
const checked = refusal(() => dec.checkRender({workBudget: 1}));
check(checked.includes('(-5)') && checked.includes('work budget of 1 per pixel'),
      `checkRender refuses a work budget of 1: ${checked}`);
check(refusal(() => dec.render(cam64, {workBudget: 1})).includes('work budget'), 'so does render');
check(refusal(() => dec.checkRender()) === '', 'the default budgets accept scene_builtin');
const unlimited = dec.render(cam64, {workBudget: 0});
check(unlimited.every((v, i) => v === d64.result[i]), 'no work limit: the same image, bit for bit');
const wide = dec.render(cam64, {workBudget: 2 ** 40});  // above 2^32: both halves of the uint64
check(wide.every((v, i) => v === d64.result[i]), 'a work budget of 2^40: the same image');
const budgeted = new EcrfDecoder(module);
budgeted.setDecodeBudget(0);
check(refusal(() => budgeted.decode(stream)) === '', 'a decode budget of 0 (no limit) decodes');
budgeted.destroy();

let threw = '';
const bad = new EcrfDecoder(module);
try { bad.decode(stream.subarray(0, stream.length >> 1)); } catch (e) { threw = e.message; }
bad.destroy();
check(threw !== '', `a truncated stream is refused: ${threw}`);
dec.destroy();

console.log(`${passed} passed, ${failures} failed`);
process.exit(failures ? 1 : 0);
