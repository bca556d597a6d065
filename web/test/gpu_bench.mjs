// Speed and accuracy of the WebGL2 renderer on a real scene, in headless chromium (SwiftShader,
// i.e. on the CPU: the frame times are a lower bound of nothing but themselves; see the report for
// a desktop-GPU estimate). For each size: the native `ecrf render` of the same orbit camera
// (azimuth 0, elevation 30 degrees, radius 4, early stop 1e-4) is the reference; the GPU renders
// it (warm-up frame, then timed frames with finish) and the PSNR between them is printed.
//
//   node web/test/gpu_bench.mjs [SCENE.ecrf] [--sizes 400,800] [--frames 2 (0: first only)] [--band 50]
//                                     [--deferred] [--ecrf build/tools/ecrf]
import {execFileSync} from 'node:child_process';
import {mkdtempSync, readFileSync, rmSync} from 'node:fs';
import {tmpdir} from 'node:os';
import {join} from 'node:path';
import {openBrowser, root} from './browser.mjs';
import {compare, fmtPsnr, fromBase64, readPng} from './gpu_common.mjs';

const args = process.argv.slice(2);
const opt = (name, def) => { const i = args.indexOf(name); return i >= 0 ? args.splice(i, 2)[1] : def; };
const flag = (name) => { const i = args.indexOf(name); return i >= 0 ? (args.splice(i, 1), true) : false; };
const sizes = opt('--sizes', '400,800').split(',').map(Number);
const frames = Number(opt('--frames', '2'));
const band = Number(opt('--band', '50'));
const ecrf = opt('--ecrf', join(root, 'build/tools/ecrf'));
const deferred = flag('--deferred');
const scene = args[0] || '/work/sweeps/chair_v2/runs/lambda_2e-10_steps4/scene.ecrf';
const elevation = 30, radius = 4;

const b = await openBrowser();
const tmp = mkdtempSync(join(tmpdir(), 'ecrf-gpu-bench-'));
try {
  const page = await b.newPage();
  await page.goto(b.url('web/test/gpu_page.html'));
  await page.waitForFunction(() => window.gpuTest !== undefined);
  await page.evaluate(([n, s]) => gpuTest.load(n, s), ['scene', readFileSync(scene).toString('base64')]);
  console.log(`${scene}: ${readFileSync(scene).length} bytes`);
  for (const size of sizes) {
    const t0 = Date.now();
    const out = execFileSync(ecrf, ['render', scene, '--orbit', '1', '-W', `${size}`, '-H', `${size}`,
                                    '--elevation', `${elevation}`, '--radius', `${radius}`, '-o', tmp], {encoding: 'utf8'});
    const ref = readPng(new Uint8Array(readFileSync(join(tmp, 'orbit_000.png'))));
    console.log(`native ${size}x${size}: ${((Date.now() - t0) / 1000).toFixed(1)} s wall; ${out.trim()}`);
    const r = await page.evaluate(async ([size, el, rad, frames, band, deferred]) => {
      const cam = gpuTest.orbit(size, size, 0, el * Math.PI / 180, rad);
      const o = {earlyStop: 1e-4, bandRows: band, deferred};
      const first = await gpuTest.gpu('scene', cam, {...o, finish: true});  // setScene + compile + frame
      const again = frames > 0 ? gpuTest.renderAgain(cam, o, frames) : {ms: [], stats: first.stats};
      return {pixels: first.pixels, setMs: first.setMs, firstMs: first.ms[0], ms: again.ms, stats: again.stats};
    }, [size, elevation, radius, frames, band, deferred]);
    const c = compare(fromBase64(r.pixels), ref, size, size);
    const s = r.stats;
    console.log(`GPU ${size}x${size}${deferred ? ' (deferred)' : ''}: setScene ${r.setMs.toFixed(0)} ms, first frame ` +
                `${(r.firstMs / 1000).toFixed(1)} s, frames ${r.ms.map((x) => (x / 1000).toFixed(1)).join(', ')} s; ` +
                `PSNR vs native ${fmtPsnr(c.psnr)} dB, max diff ${c.maxDiff}, ${c.over2} pixels > 2 codes ` +
                `(${(100 * c.within2).toFixed(2)}% within 2); textures ${(s.textureBytes / 1048576).toFixed(1)} MiB, ` +
                `MLP weights in ${s.mlpWeights}, ${s.samplesPerRay} samples/ray`);
  }
  b.assertNoConsoleErrors(page);
} finally {
  await b.close();
  rmSync(tmp, {recursive: true, force: true});
}
