// Screenshots of the viewer for docs/web/: a desktop window and a phone showing a scene, or one
// named shot of a scene on a chosen renderer.
//
//   node web/test/screenshots.mjs SCENE.ecrf                      # viewer_desktop.png, viewer_phone.png
//   node web/test/screenshots.mjs SCENE.ecrf --out NAME.png [--renderer gpu|cpu] [--view '#az=..']
//        [--size N] [--max-pixels N]                              # one 1280x800 desktop shot
// The scene is copied under build-web-demo/ (ignored by git) so that the test server, which serves
// the repository root, can hand it to the page. Without --size the viewer renders at the canvas's
// resolution within its pixel budget (what a user sees); RENDERER (default cpu: SwiftShader is
// much slower than the wasm path) and SIZE in the environment are the defaults of the flags.
import {copyFileSync, mkdirSync} from 'node:fs';
import {join} from 'node:path';
import {openBrowser, root} from './browser.mjs';

const args = process.argv.slice(2);
const flag = (name, fallback) => {
  const i = args.indexOf(name);
  return i >= 0 && i + 1 < args.length ? args[i + 1] : fallback;
};
const source = args[0];
if (!source || source.startsWith('--')) {
  console.error('usage: node web/test/screenshots.mjs SCENE.ecrf [--out NAME.png] [--renderer gpu|cpu] [--view HASH] ' +
                '[--size N] [--max-pixels N]');
  process.exit(2);
}
mkdirSync(join(root, 'build-web-demo'), {recursive: true});
copyFileSync(source, join(root, 'build-web-demo', 'scene.ecrf'));
mkdirSync(join(root, 'docs', 'web'), {recursive: true});
const scene = '../build-web-demo/scene.ecrf';
const size = flag('--size', process.env.SIZE || '');
const renderer = flag('--renderer', process.env.RENDERER || 'cpu');
const view = flag('--view', '');
const out = flag('--out', '');
const maxPixels = flag('--max-pixels', '');

const desktop = {viewport: {width: 1280, height: 800}};
const shots = out ? [{file: out, context: desktop}] : [
  {file: 'viewer_desktop.png', context: desktop},
  {file: 'viewer_phone.png', context: {viewport: {width: 390, height: 844}, deviceScaleFactor: 2, isMobile: true, hasTouch: true}},
];
const b = await openBrowser();
try {
  for (const shot of shots) {
    const t0 = Date.now();
    const page = await b.newPage(shot.context);
    const query = `renderer=${renderer}${size ? `&size=${size}` : ''}` +
                  `${maxPixels ? `&max-pixels=${maxPixels}` : ''}&scene=${scene}`;
    await page.goto(b.url(`web/index.html?${query}${view}`));
    await page.waitForFunction(() => window.ecrfViewer && (ecrfViewer.idle() || ecrfViewer.state.error),
                               null, {timeout: 1800000, polling: 250});
    const error = await page.evaluate(() => ecrfViewer.state.error);
    if (error) throw new Error(error);
    await page.screenshot({path: join(root, 'docs', 'web', shot.file)});
    const frame = await page.evaluate(() => ecrfViewer.state.lastFrame);
    console.log(`docs/web/${shot.file} in ${((Date.now() - t0) / 1000).toFixed(0)} s ` +
                `(${renderer} ${frame.width}x${frame.height} frame: ${frame.ms.toFixed(0)} ms)`);
    b.assertNoConsoleErrors(page);
    await page.context().close();
  }
} finally {
  await b.close();
}
