// Browser test of the interactive viewer (web/index.html) in headless chromium: both
// renderers against the wasm reference render, mouse / wheel / keyboard / touch controls, the size
// cap, bad and missing files, file://, a phone viewport, and no console errors.
//
//   node web/test/viewer_test.mjs         (needs build-wasm/ and web/test/node_modules)
import {existsSync, readFileSync} from 'node:fs';
import {join} from 'node:path';
import {pathToFileURL} from 'node:url';
import {openBrowser, root, viewerFrameAndWasmReference} from './browser.mjs';

const SCENE = '../tests/conformance/scene_builtin.ecrf';
const PAGE = 'web/index.html';
const hasGpu = existsSync(join(root, 'web', 'gpu_renderer.js'));
const t0 = Date.now();
let failures = 0;
// ONLY=cpu,forward,size,share,missing,phone,gpu runs some sections (while debugging).
const only = process.env.ONLY ? new Set(process.env.ONLY.split(',')) : null;
const run = (section) => !only || only.has(section);

function check(ok, what) {
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what} [${((Date.now() - t0) / 1000).toFixed(0)} s]`);
  if (!ok) ++failures;
}

// Console errors, minus the 404s a check provokes on purpose.
function watchConsole(page) {
  const errors = [];
  page.on('console', (msg) => {
    if (msg.type() !== 'error') return;
    errors.push({text: msg.text(), url: (msg.location() && msg.location().url) || ''});
  });
  page.on('pageerror', (err) => errors.push({text: `page error: ${err.message}`, url: ''}));
  return (what, allowed = () => false) => {
    const gpuAbsent = (e) => !hasGpu && /404|ERR_FILE_NOT_FOUND/.test(e.text) && /gpu_renderer\.js$/.test(e.url);
    const bad = errors.filter((e) => !allowed(e) && !gpuAbsent(e));
    check(bad.length === 0, `${what}: no console errors${bad.length ? `: ${bad.map((e) => `${e.text} ${e.url}`).join('; ')}` : ''}`);
  };
}

async function open(b, query, options = {}) {
  const page = await b.newPage({viewport: {width: 800, height: 500}, ...options});
  const consoleCheck = watchConsole(page);
  await page.goto(b.url(`${PAGE}?${query}`));
  return {page, consoleCheck};
}

const state = (page) => page.evaluate(() => {
  const v = window.ecrfViewer;
  return {renderer: v.state.renderer, view: v.state.view, frames: v.frames, error: v.state.error,
          status: v.state.status, scene: !!v.state.scene, last: v.state.lastFrame && {...v.state.lastFrame}};
});

// Until the image on screen is the full-resolution image of the current view.
async function waitIdle(page, timeout = 90000) {
  await page.waitForFunction(() => window.ecrfViewer && window.ecrfViewer.idle(), null, {timeout, polling: 50});
}

async function waitError(page, timeout = 30000) {
  await page.waitForFunction(() => window.ecrfViewer && window.ecrfViewer.state.error, null, {timeout, polling: 50});
  return (await state(page)).error;
}

// Drops the first 100 bytes of the test scene on the page (the whole page is the drop zone) and
// returns the error the viewer then shows.
async function dropTruncatedScene(page) {
  await page.evaluate(async (scene) => {
    const bytes = new Uint8Array(await (await fetch(scene)).arrayBuffer()).slice(0, 100);
    const dt = new DataTransfer();
    dt.items.add(new File([bytes], 'truncated.ecrf'));
    document.body.dispatchEvent(new DragEvent('drop', {dataTransfer: dt, bubbles: true, cancelable: true}));
  }, SCENE);
  return waitError(page);
}

// PSNR over RGB of the viewer's last full frame (read back through the hook, not a screenshot)
// against EcrfDecoder.render of the same camera, run in the page by the wasm decoder.
async function psnrAgainstWasm(page, scene = SCENE) {
  const {frame, reference, width, height} = await viewerFrameAndWasmReference(page, scene);
  if (!frame) return {psnr: -1, size: 'no image'};
  let se = 0;
  for (let p = 0; p < width * height; ++p) {
    for (let k = 0; k < 3; ++k) se += (frame[4 * p + k] - reference[4 * p + k]) ** 2;
  }
  const mse = se / (3 * width * height);
  return {psnr: mse === 0 ? Infinity : 10 * Math.log10(65025 / mse), size: `${width}x${height}`};
}

const pixelsKey = (page) => page.evaluate(() => {
  const img = ecrfViewer.readPixels();
  let h = 0;
  for (let i = 0; i < img.data.length; ++i) h = (h * 31 + img.data[i]) | 0;
  return h;
});

async function canvasBox(page) {
  return page.evaluate(() => {
    const r = document.getElementById('view').getBoundingClientRect();
    return {x: r.x, y: r.y, width: r.width, height: r.height};
  });
}

// Mouse drag, wheel and keyboard on a page that shows a scene.
async function controlsChecks(page, label) {
  const before = await state(page);
  const key0 = await pixelsKey(page);
  const box = await canvasBox(page);
  const cx = box.x + box.width / 2, cy = box.y + box.height / 2;
  await page.mouse.move(cx, cy);
  await page.mouse.down();
  await page.mouse.move(cx + 60, cy + 20, {steps: 4});
  await page.mouse.up();
  await waitIdle(page);
  const dragged = await state(page);
  check(dragged.view.az !== before.view.az && dragged.view.el !== before.view.el,
        `${label}: drag orbits (az ${before.view.az.toFixed(1)} -> ${dragged.view.az.toFixed(1)}, ` +
        `el ${before.view.el.toFixed(1)} -> ${dragged.view.el.toFixed(1)})`);
  check(dragged.frames > before.frames && (await pixelsKey(page)) !== key0, `${label}: drag renders a new image`);

  await page.mouse.move(cx, cy);
  await page.mouse.wheel(0, 240);
  await page.waitForFunction((r) => ecrfViewer.state.view.radius !== r, dragged.view.radius, {timeout: 5000}).catch(() => {});
  const zoomed = await state(page);
  check(zoomed.view.radius > dragged.view.radius, `${label}: wheel zooms out (radius ${dragged.view.radius} -> ${zoomed.view.radius.toFixed(3)})`);

  await page.mouse.click(box.x + 5, box.y + box.height - 5, {button: 'right'});  // focus, no move
  await page.keyboard.press('ArrowLeft');
  await page.keyboard.press('+');
  const keyed = await state(page);
  check(keyed.view.az !== zoomed.view.az && keyed.view.radius < zoomed.view.radius, `${label}: arrow keys orbit, + zooms in`);
  await page.keyboard.press('r');
  await waitIdle(page);
  const reset = await state(page);
  check(reset.view.az === before.view.az && reset.view.radius === before.view.radius, `${label}: r resets the view`);
}

const b = await openBrowser();
try {
  // ---- CPU path ----------------------------------------------------------------------------------
  if (run('cpu')) {
    const {page, consoleCheck} = await open(b, `renderer=cpu&size=64&az=30&el=20&scene=${SCENE}`);
    await waitIdle(page);
    const s = await state(page);
    check(s.renderer === 'cpu' && s.frames >= 1, `cpu: a full frame (${s.last.width}x${s.last.height}, ${s.last.ms.toFixed(0)} ms)`);
    const cmp = await psnrAgainstWasm(page);
    check(cmp.psnr >= 40, `cpu: ${cmp.size} frame vs EcrfDecoder.render of the same camera: PSNR ${cmp.psnr.toFixed(2)} dB`);
    check(s.view.az === 30 && s.view.el === 20, 'cpu: &az= &el= set the view');
    const levels = await page.evaluate(() => ecrfViewer.state.frameLog.map((f) => f.divisor).join(','));
    check(levels === '8,4,2,1', `cpu: progressive, each level drawn whole (levels shown: 1/${levels.replace(/,/g, ', 1/')})`);
    await controlsChecks(page, 'cpu');

    // A bad file after a good one: error shown, old scene gone.
    const error = await dropTruncatedScene(page);
    const cleared = await page.evaluate(() => {
      const c = document.getElementById('view');
      const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      return {blank: d.every((v) => v === 0), workers: ecrfViewer.renderer.workers.length,
              scene: !!ecrfViewer.state.scene, info: document.getElementById('info').rows.length,
              pixels: ecrfViewer.readPixels()};
    });
    check(/truncated\.ecrf/.test(error), `cpu: a dropped 100-byte file shows an error: ${error}`);
    check(cleared.blank && cleared.workers === 0 && !cleared.scene && cleared.info === 0 && !cleared.pixels,
          'cpu: ... and clears the old scene (canvas blank, workers terminated, panel empty)');
    consoleCheck('cpu');
    await page.context().close();
  }

  // ---- a forward-facing scene starts at its reference camera --------------------------------------
  if (run('forward')) {
    const scene = '../tests/conformance/scene_forward.ecrf';
    const {page, consoleCheck} = await open(b, `renderer=cpu&size=48&scene=${scene}`);
    await waitIdle(page);
    const s = await state(page);
    // The vector's frame: reference camera about 4 units from the origin, elevation asin(0.479426),
    // near plane 1.5 (SPEC.md 7.7); the home view orbits a point 2 x 1.5 ahead of it.
    check(Math.abs(s.view.radius - 3) < 1e-3 && Math.abs(s.view.el - 28.65) < 0.05 && Math.abs(s.view.az - 40.1) < 0.1,
          `forward: the home view is the reference camera (az ${s.view.az.toFixed(2)}, el ${s.view.el.toFixed(2)}, r ${s.view.radius.toFixed(3)})`);
    const cmp = await psnrAgainstWasm(page, scene);
    check(cmp.psnr >= 40, `forward: ${cmp.size} frame vs EcrfDecoder.render of the same camera: PSNR ${cmp.psnr.toFixed(2)} dB`);
    // The vector's NDC box is narrower than the reference camera's view: the scene in the middle,
    // the background (1, 0.5, 0) around it.
    const covered = await page.evaluate(() => {
      const img = ecrfViewer.readPixels();
      let scene = 0;
      for (let p = 0; p < img.width * img.height; ++p) {
        const d = img.data;
        scene += Math.abs(d[4 * p] - 255) + Math.abs(d[4 * p + 1] - 128) + d[4 * p + 2] > 12 ? 1 : 0;
      }
      return scene / (img.width * img.height);
    });
    check(covered > 0.2 && covered < 0.9, `forward: the scene fills ${(100 * covered).toFixed(0)}% of the home view, the background the rest`);
    consoleCheck('forward');
    await page.context().close();
  }

  // ---- size cap ----------------------------------------------------------------------------------
  if (run('size')) {
    const {page, consoleCheck} = await open(b, `renderer=cpu&size=300&scene=${SCENE}`, {viewport: {width: 1000, height: 300}});
    await waitIdle(page, 90000);
    const s = await state(page);
    check(Math.max(s.last.width, s.last.height) === 300, `?size=300: a ${s.last.width}x${s.last.height} frame in ${s.last.ms.toFixed(0)} ms`);
    await page.goto(b.url(`${PAGE}?renderer=cpu&size=0`));
    check(await page.evaluate(() => ecrfViewer.state.size) === 16, '?size=0 is clamped to 16');
    consoleCheck('size');
    await page.context().close();
  }

  // ---- the canvas's resolution, a view shared by its address, a screenshot -----------------------
  if (run('share')) {
    // A small window: the CPU path's full frame costs time in proportion to its pixels.
    const viewport = {width: 360, height: 260};
    const {page, consoleCheck} = await open(b, `renderer=cpu&scene=${SCENE}`, {viewport, acceptDownloads: true});
    await waitIdle(page, 120000);
    const s = await state(page);
    const dims = await page.evaluate(() => [document.getElementById('view').width, document.getElementById('view').height]);
    check(s.last.width === dims[0] && s.last.height === dims[1],
          `share: without ?size= the CPU path renders the canvas's ${dims.join('x')} device pixels (${s.last.width}x${s.last.height} in ${s.last.ms.toFixed(0)} ms)`);
    await page.evaluate(() => ecrfViewer.setView({az: 33.3333, el: 12.5, radius: 3.21, target: [0.1, 0, -0.05]}));
    await waitIdle(page, 120000);
    const hash = await page.evaluate(() => location.hash);
    check(hash === '#az=33.3333&el=12.5&r=3.21&t=0.1,0,-0.05', `share: the camera is in the address: ${hash}`);
    const key = await pixelsKey(page);
    const view = (await state(page)).view;
    // Another page at that address: the same view, the same image.
    const other = await b.newPage({viewport});
    await other.goto(await page.evaluate(() => location.href));
    await waitIdle(other, 120000);
    const s2 = await state(other);
    check(JSON.stringify(s2.view) === JSON.stringify(view) && (await pixelsKey(other)) === key,
          `share: the address opens the same view and image elsewhere (${JSON.stringify(s2.view)})`);
    await other.context().close();
    // Editing the hash moves the camera.
    await page.evaluate(() => { location.hash = '#az=90&el=10&r=5'; });
    await page.waitForFunction(() => ecrfViewer.state.view.az === 90, null, {timeout: 5000}).catch(() => {});
    const moved = (await state(page)).view;
    check(moved.az === 90 && moved.el === 10 && moved.radius === 5 && moved.target.every((v) => v === 0),
          `share: an edited hash sets the view (${JSON.stringify(moved)})`);
    await waitIdle(page, 120000);
    // The screenshot button downloads the full frame as PNG.
    const last = (await state(page)).last;
    const [download] = await Promise.all([page.waitForEvent('download', {timeout: 10000}), page.click('#screenshot')]);
    const png = readFileSync(await download.path());
    const name = download.suggestedFilename();
    check(png.subarray(1, 4).toString() === 'PNG' && png.readUInt32BE(16) === last.width && png.readUInt32BE(20) === last.height &&
          /^scene_builtin_az90_el10_\d+x\d+\.png$/.test(name),
          `share: the screenshot button saves ${name} (${png.readUInt32BE(16)}x${png.readUInt32BE(20)}, ${png.length} bytes)`);
    // A pixel budget caps the frame, and the HUD says so.
    await page.goto(b.url(`${PAGE}?renderer=cpu&max-pixels=4000&scene=${SCENE}`));
    await waitIdle(page, 120000);
    const capped = await state(page);
    const hud = await page.evaluate(() => document.getElementById('hud').textContent);
    check(capped.last.width * capped.last.height <= 4000 * 1.05 && /pixel budget/.test(hud),
          `share: ?max-pixels=4000 gives a ${capped.last.width}x${capped.last.height} frame, the HUD says: ${hud}`);
    const row = await page.evaluate(() => document.querySelector('#info tr[data-key="renderer"]').cells[1].textContent);
    check(!/\n/.test(row) && row.length < 120, `share: the renderer row is one line: ${row}`);
    consoleCheck('share');
    await page.context().close();
  }

  // ---- missing URL, file:// ----------------------------------------------------------------------
  if (run('missing')) {
    const missing = '../tests/conformance/no_such_scene.ecrf';
    const {page, consoleCheck} = await open(b, `scene=${missing}`);
    if (hasGpu) {
      const kind = await page.evaluate(() => [ecrfViewer.state.renderer, ecrfViewer.state.softwareGl]);
      check(kind[0] === 'cpu' && /swiftshader/i.test(kind[1]), `default renderer on SwiftShader: ${kind[0]} (${kind[1]})`);
    }
    const error = await waitError(page);
    check(/HTTP 404/.test(error), `a missing ?scene= shows the HTTP error: ${error}`);
    consoleCheck('missing', (e) => /404/.test(e.text) && /no_such_scene/.test(e.url));
    await page.goto(pathToFileURL(join(root, PAGE)).href);
    const hint = await waitError(page);
    check(/python3 -m http\.server/.test(hint) && /localhost:8000\/web\//.test(hint), `file:// shows the hint: ${hint}`);
    await page.context().close();
  }

  // ---- phone -------------------------------------------------------------------------------------
  if (run('phone')) {
    const {page, consoleCheck} = await open(b, `renderer=cpu&size=96&scene=${SCENE}`,
        {viewport: {width: 390, height: 844}, deviceScaleFactor: 2, isMobile: true, hasTouch: true});
    await waitIdle(page, 90000);
    const s = await state(page);
    const layout = await page.evaluate(() => {
      const c = document.getElementById('view'), p = document.getElementById('panel');
      const a = c.getBoundingClientRect(), q = p.getBoundingClientRect();
      const overlap = Math.max(0, Math.min(a.right, q.right) - Math.max(a.left, q.left)) *
                      Math.max(0, Math.min(a.bottom, q.bottom) - Math.max(a.top, q.top));
      return {overlap, canvas: [a.width, a.height, c.width, c.height], panel: [q.width, q.height],
              scroll: document.documentElement.scrollWidth};
    });
    check(s.frames >= 1, `phone (${s.renderer}): renders ${s.last.width}x${s.last.height}`);
    check(layout.overlap === 0 && layout.canvas[0] === 390 && layout.canvas[2] === 780 && layout.scroll <= 390,
          `phone: full-width HiDPI canvas ${layout.canvas.join('/')}, panel below it (overlap ${layout.overlap}), no sideways scroll`);
    // One finger drags (orbit), two fingers spread (zoom in), through real touch events.
    const cdp = await page.context().newCDPSession(page);
    const box = await canvasBox(page);
    const touch = (type, points) => cdp.send('Input.dispatchTouchEvent', {type, touchPoints: points.map(([x, y], id) => ({x, y, id}))});
    const cx = box.x + box.width / 2, cy = box.y + box.height / 2;
    await touch('touchStart', [[cx, cy]]);
    for (let k = 1; k <= 4; ++k) await touch('touchMove', [[cx + 15 * k, cy]]);
    await touch('touchEnd', []);
    const orbited = await state(page);
    check(orbited.view.az !== s.view.az, `phone: one-finger drag orbits (az ${s.view.az} -> ${orbited.view.az.toFixed(1)})`);
    await touch('touchStart', [[cx - 20, cy], [cx + 20, cy]]);
    for (let k = 1; k <= 4; ++k) await touch('touchMove', [[cx - 20 - 15 * k, cy], [cx + 20 + 15 * k, cy]]);
    await touch('touchEnd', []);
    const pinched = await state(page);
    check(pinched.view.radius < orbited.view.radius, `phone: pinch zooms (radius ${orbited.view.radius} -> ${pinched.view.radius.toFixed(3)})`);
    await waitIdle(page, 90000);
    consoleCheck('phone');
    await page.context().close();
  }

  // ---- GPU path ----------------------------------------------------------------------------------
  if (!run('gpu')) {
    // not asked for
  } else if (!hasGpu) {
    console.log('skip GPU path: web/gpu_renderer.js is not there yet');
  } else {
    // SwiftShader runs the fragment shader on the CPU: ~3 s for a 24-px frame on 2 loaded cores,
    // plus the shader compile of the first frame. The viewer's default there is the CPU path.
    const {page, consoleCheck} = await open(b, `renderer=gpu&size=24&az=30&el=20&scene=${SCENE}`);
    await waitIdle(page, 240000);
    const s = await state(page);
    check(s.renderer === 'gpu', `gpu: ?renderer=gpu runs the GPU path (${s.renderer}) ${s.error || ''}`);
    const cmp = await psnrAgainstWasm(page);
    check(cmp.psnr >= 35, `gpu: ${cmp.size} frame vs EcrfDecoder.render of the same camera: PSNR ${cmp.psnr.toFixed(2)} dB`);
    await controlsChecks(page, 'gpu');
    await page.fill('#size', '32');
    await page.press('#size', 'Enter');
    await page.waitForFunction(() => ecrfViewer.state.size === 32);
    await waitIdle(page, 120000);
    const big = await state(page);
    check(Math.max(big.last.width, big.last.height) === 32, `gpu: size cap 32 gives a ${big.last.width}x${big.last.height} frame (${big.last.ms.toFixed(0)} ms)`);
    const error = await dropTruncatedScene(page);
    const cleared = await page.evaluate(() => ({scene: !!ecrfViewer.state.scene, gpu: ecrfViewer.renderer.hasScene,
                                                pixels: ecrfViewer.readPixels()}));
    check(/truncated/.test(error) && !cleared.scene && !cleared.gpu && !cleared.pixels, `gpu: a bad file shows an error and clears the scene: ${error}`);
    consoleCheck('gpu');
    await page.context().close();
  }
} catch (e) {
  check(false, `exception: ${e.stack || e}`);
} finally {
  await b.close();
}
console.log(`${failures ? 'FAILED' : 'passed'} (${failures} failure${failures === 1 ? '' : 's'}) in ${((Date.now() - t0) / 1000).toFixed(0)} s`);
process.exit(failures ? 1 : 0);
