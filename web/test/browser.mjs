// Shared harness of the browser tests: serves the repository root on 127.0.0.1 (a random port) and
// starts Debian's chromium headless through playwright-core (which downloads no browser). WebGL2
// runs on SwiftShader, the software GL that chromium ships, so the tests need no GPU.
//
//   const b = await openBrowser();            // {browser, url(path), newPage(options), close()}
//   const page = await b.newPage();           // console errors and page errors are collected
//   await page.goto(b.url('web/index.html?scene=...'));
//   ...; b.assertNoConsoleErrors(page);  await b.close();
import {createServer} from 'node:http';
import {readFile, stat} from 'node:fs/promises';
import {dirname, extname, join, normalize, sep} from 'node:path';
import {fileURLToPath} from 'node:url';
import {chromium} from 'playwright-core';

export const root = join(dirname(fileURLToPath(import.meta.url)), '..', '..');

const TYPES = {
  '.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript', '.wasm': 'application/wasm',
  '.json': 'application/json', '.png': 'image/png', '.css': 'text/css', '.ecrf': 'application/octet-stream',
};

// A static file server over the repository root; only GET, only files under the root.
export function serveRepository() {
  const server = createServer(async (req, res) => {
    try {
      const path = decodeURIComponent(new URL(req.url, 'http://x').pathname);
      const file = normalize(join(root, path));
      if (!file.startsWith(root + sep) || !(await stat(file)).isFile()) throw new Error('not found');
      const body = await readFile(file);
      res.writeHead(200, {'Content-Type': TYPES[extname(file)] || 'application/octet-stream',
                          'Content-Length': body.length, 'Cache-Control': 'no-store'});
      res.end(body);
    } catch {
      res.writeHead(404, {'Content-Type': 'text/plain'});
      res.end('not found');
    }
  });
  return new Promise((resolve) => server.listen(0, '127.0.0.1', () => resolve(server)));
}

export function chromiumPath() {
  return process.env.CHROMIUM || '/usr/bin/chromium';
}

export async function openBrowser({args = []} = {}) {
  const server = await serveRepository();
  const base = `http://127.0.0.1:${server.address().port}/`;
  const browser = await chromium.launch({
    executablePath: chromiumPath(),
    headless: true,
    // SwiftShader WebGL2 in headless mode without a GPU; --no-sandbox for containers run as root.
    args: ['--no-sandbox', '--use-gl=angle', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
           '--ignore-gpu-blocklist', ...args],
  });
  const errors = new Map();  // page -> [messages]
  return {
    browser,
    url: (path) => base + path.replace(/^\//, ''),
    async newPage(options = {}) {
      const context = await browser.newContext(options);
      const page = await context.newPage();
      const list = [];
      errors.set(page, list);
      page.on('console', (msg) => { if (msg.type() === 'error') list.push(`console: ${msg.text()}`); });
      page.on('pageerror', (err) => list.push(`page error: ${err.message}`));
      return page;
    },
    consoleErrors: (page) => errors.get(page) || [],
    assertNoConsoleErrors(page) {
      const list = errors.get(page) || [];
      if (list.length) throw new Error(`errors in the page:\n  ${list.join('\n  ')}`);
    },
    async close() {
      await browser.close();
      await new Promise((resolve) => server.close(resolve));
    },
  };
}

// The viewer's last full frame (read back through its hook, not a screenshot) and
// EcrfDecoder.render of the same camera by the wasm decoder in the page (build-wasm/):
// {frame: RGBA bytes, or null when the frame is missing or of another size, reference: RGBA
// bytes, width, height}.
export async function viewerFrameAndWasmReference(page, scene) {
  if (!(await page.evaluate(() => typeof createEcrfDecoder === 'function'))) {
    await page.addScriptTag({url: '../build-wasm/ecrf_decoder.js'});
  }
  return page.evaluate(async (scene) => {
    const module = await createEcrfDecoder({locateFile: (f) => new URL(`../build-wasm/${f}`, location.href).href});
    const d = new ecrfWeb.EcrfDecoder(module);
    d.decode(new Uint8Array(await (await fetch(scene)).arrayBuffer()));
    const cam = ecrfViewer.camera();
    const ref = d.render(cam);
    d.destroy();
    const img = ecrfViewer.readPixels();
    return {frame: img && img.width === cam.width && img.height === cam.height ? Array.from(img.data) : null,
            reference: Array.from(ref), width: cam.width, height: cam.height};
  }, scene);
}
