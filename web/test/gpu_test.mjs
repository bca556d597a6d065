// Browser test of the WebGL2 renderer (web/gpu_renderer.js) in headless chromium
// (SwiftShader): every scene vector of tests/conformance/manifest.json, all three scene models,
// every head (per sample, deferred, spherical harmonics), rendered at its exact camera against its
// reference PNG (PSNR >= 40 dB and the SPEC 7.7 pixel criterion required), empty-space
// skipping in contracted and NDC space (byte-identical), the viewer's GPU path for both, a
// larger orbit view of scene_builtin against the WebAssembly CPU renderer (>= 40 dB), the
// deferred-shading option, the limit errors, and no console errors.
//
//   node web/test/gpu_test.mjs        (needs build-wasm/ and `npm ci` in web/test)
import {readFileSync} from 'node:fs';
import {join} from 'node:path';
import {openBrowser, root, viewerFrameAndWasmReference} from './browser.mjs';
import {compare, fmtPsnr, fromBase64, manifestCamera, readPng} from './gpu_common.mjs';

let failures = 0;
function check(ok, what) {
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
  if (!ok) ++failures;
}

const started = Date.now();
const manifest = JSON.parse(readFileSync(join(root, 'tests/conformance/manifest.json'), 'utf8'));
const b = await openBrowser();
try {
  const page = await b.newPage();
  await page.goto(b.url('web/test/gpu_page.html'));
  await page.waitForFunction(() => window.gpuTest !== undefined);
  check(await page.evaluate(() => gpuTest.supported()), 'GpuRenderer.isSupported()');
  const conf = 'tests/conformance/';
  for (const v of manifest.scene_vectors) {
    const camera = manifestCamera(v.render.camera);
    const ref = readPng(new Uint8Array(readFileSync(join(root, conf, v.render.png))));
    // The reference renders use no early termination (SPEC 7.7): neither does this one.
    const r = await page.evaluate(([u, c]) => gpuTest.gpu(u, c, {earlyStop: 0}), [`../../${conf}${v.file}`, camera]);
    const c = compare(fromBase64(r.pixels), ref, camera.width, camera.height);
    const meets77 = c.within2 >= 0.99;
    // Every vector, every scene model and head, meets the 7.7 criterion (a flipped sign in the
    // harmonics of 7.6.2 still gave 42 dB on scene_sh_per_sample, but 698 pixels off by > 2).
    const model = v.scene_model || 'object';
    check(c.psnr >= 40 && meets77, `${v.file} (${model}): PSNR ${fmtPsnr(c.psnr)} dB, max diff ${c.maxDiff}, ${c.over2}/${c.pixels} ` +
          `pixels differ by > 2 (7.7 ${meets77 ? 'met' : 'NOT met'})`);
  }
  // Empty-space skipping in the contracted cube (7.2.1) and along the NDC line (7.2.2): the
  // vectors' 7x6x5 masks have no empty block, so their masks are resampled 8 times finer; skipping
  // must not change a single byte, and the image must still match the reference.
  for (const name of ['scene_unbounded', 'scene_forward_side_view']) {
    const v = manifest.scene_vectors.find((x) => x.file === `${name}.ecrf`);
    const camera = manifestCamera(v.render.camera);
    const ref = readPng(new Uint8Array(readFileSync(join(root, conf, v.render.png))));
    const r = await page.evaluate(([u, c]) => gpuTest.gpuFineMask(u, c, 8, [{earlyStop: 0}, {earlyStop: 0, skipEmptySpace: false}]),
                                  [`../../${conf}${v.file}`, camera]);
    const [skip, noSkip] = r.pixels.map(fromBase64);
    const c = compare(skip, ref, camera.width, camera.height);
    check(skip.every((x, k) => x === noSkip[k]) && c.psnr >= 40 && c.within2 >= 0.99,
          `${v.file}, ${r.res.join('x')} mask: empty-space skipping changes no byte; PSNR ${fmtPsnr(c.psnr)} dB`);
  }
  {
    const v = manifest.scene_vectors.find((x) => x.file === 'scene_quantized_mlp.ecrf');
    const camera = manifestCamera(v.render.camera);
    const ref = readPng(new Uint8Array(readFileSync(join(root, conf, v.render.png))));
    const r = await page.evaluate(([u, c]) => gpuTest.gpuTextureWeights(u, c, {earlyStop: 0}), [`../../${conf}${v.file}`, camera]);
    const c = compare(fromBase64(r.pixels), ref, camera.width, camera.height);
    check(c.psnr >= 40 && r.stats.mlpWeights === 'texture', `${v.file} with the MLP weights in a texture: PSNR ${fmtPsnr(c.psnr)} dB`);
  }
  // A larger view, default early stop on both sides.
  const url = `../../${conf}scene_builtin.ecrf`;
  const cam = await page.evaluate(() => gpuTest.orbit(80, 80, 1.1, 0.35, 3.6));
  const gpu = await page.evaluate(([u, c]) => gpuTest.gpu(u, c, {earlyStop: 1e-4, finish: true}), [url, cam]);
  const cpu = await page.evaluate(([u, c]) => gpuTest.cpu(u, c, {earlyStopTransmittance: 1e-4}), [url, cam]);
  const gp = fromBase64(gpu.pixels), cp = fromBase64(cpu.pixels);
  const c = compare(gp, cp, cam.width, cam.height);
  check(c.psnr >= 40, `scene_builtin 80x80 orbit, GPU vs wasm CPU: PSNR ${fmtPsnr(c.psnr)} dB, ` +
        `${c.over2} pixels > 2 codes (GPU ${gpu.ms[0].toFixed(0)} ms, CPU ${cpu.ms.toFixed(0)} ms)`);
  let alphaOk = true;
  for (let p = 0; p < cam.width * cam.height; ++p) alphaOk = alphaOk && Math.abs(gp[4 * p + 3] - cp[4 * p + 3]) <= 2;
  check(alphaOk, 'alpha (accumulated opacity) within 2 codes of the CPU renderer');
  // Deferred shading: an approximation, only required to stay recognisable.
  const def = await page.evaluate(([u, c]) => gpuTest.gpu(u, c, {earlyStop: 1e-4, deferred: true}), [url, cam]);
  const cd = compare(fromBase64(def.pixels), cp, cam.width, cam.height);
  check(cd.psnr >= 25, `deferred option (MLP once per pixel): PSNR ${fmtPsnr(cd.psnr)} dB vs CPU`);
  // Limits: a clear Error before anything is uploaded.
  const e1 = await page.evaluate((u) => gpuTest.limitError(u, {maxTextureSize: 64}), url);
  check(e1 && /texture size limit of 64/.test(e1), `texture limit: ${e1}`);
  const small = {maxUniformBlockSize: 4096, maxFragmentUniformBlocks: 4};
  const e2 = await page.evaluate(([u, l]) => gpuTest.limitError(u, l, 'ubo'), [url, small]);
  check(e2 && /uniform blocks/.test(e2), `uniform block limit: ${e2}`);
  const e2b = await page.evaluate(([u, l]) => gpuTest.limitError(u, l, 'auto'), [url, small]);
  check(e2b === null, 'auto falls back to the weight texture when the UBOs do not fit');
  const e3 = await page.evaluate((u) => gpuTest.limitError(u, {max3DTextureSize: 32}), url);
  check(e3 && /3D texture size limit/.test(e3), `3D texture limit: ${e3}`);
  const bad = await page.evaluate(async (u) => {
    try { await gpuTest.gpu(u, {...gpuTest.orbit(8, 8, 0, 0, 4), width: 0}); return null; } catch (e) { return e.message; }
  }, url);
  check(bad && /image size/.test(bad), `bad camera: ${bad}`);
  const errs = b.consoleErrors(page);
  check(errs.length === 0, `no console errors${errs.length ? ': ' + errs.join('; ') : ''}`);
  // The viewer keeps the GPU path for every scene model (?renderer=gpu stands for a hardware
  // WebGL2, which it would choose by itself; on SwiftShader it defaults to the CPU path).
  for (const name of ['scene_unbounded', 'scene_forward']) {
    const vp = await b.newPage({viewport: {width: 400, height: 300}});
    await vp.goto(b.url(`web/index.html?renderer=gpu&size=24&scene=../${conf}${name}.ecrf`));
    await vp.waitForFunction(() => window.ecrfViewer && (ecrfViewer.idle() || ecrfViewer.state.error), null, {timeout: 240000, polling: 100});
    const res = await (async () => {
      const st = await vp.evaluate(() => ({renderer: ecrfViewer.state.renderer, error: ecrfViewer.state.error}));
      const r = await viewerFrameAndWasmReference(vp, `../${conf}${name}.ecrf`);
      return {...st, ref: r.reference, img: r.frame, width: r.width, height: r.height};
    })().catch((e) => ({error: e.message}));
    const c = res.img ? compare(res.img, res.ref, res.width, res.height) : {psnr: -1};
    const verrs = b.consoleErrors(vp);
    check(res.renderer === 'gpu' && !res.error && c.psnr >= 40 && verrs.length === 0,
          `viewer, ${name}: ${res.renderer} path, ${res.width}x${res.height} frame vs the wasm renderer: PSNR ${fmtPsnr(c.psnr)} dB` +
          `${res.error ? `; error: ${res.error}` : ''}${verrs.length ? `; console: ${verrs.join('; ')}` : ''}`);
    await vp.context().close();
  }
} finally {
  await b.close();
}
console.log(`${failures ? 'FAILED' : 'passed'} in ${((Date.now() - started) / 1000).toFixed(1)} s`);
process.exit(failures ? 1 : 0);
