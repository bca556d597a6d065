// Screenshots of the viewer for docs/web/: a desktop window and a phone, showing a scene.
//
//   node web/test/screenshots.mjs [scene.ecrf]
// The scene (default: the chair of the chair_v2 sweep) is copied under build-web-demo/ (ignored
// by git) so that the test server, which serves the repository root, can hand it to the page.
import {copyFileSync, mkdirSync} from 'node:fs';
import {join} from 'node:path';
import {openBrowser, root} from './browser.mjs';

const source = process.argv[2] || '/work/sweeps/chair_v2/runs/lambda_2e-10_steps4/scene.ecrf';
mkdirSync(join(root, 'build-web-demo'), {recursive: true});
copyFileSync(source, join(root, 'build-web-demo', 'scene.ecrf'));
mkdirSync(join(root, 'docs', 'web'), {recursive: true});
const scene = '../build-web-demo/scene.ecrf';
const size = Number(process.env.SIZE || 640);
const renderer = process.env.RENDERER || 'cpu';  // SwiftShader is much slower than the wasm path

const shots = [
  {file: 'viewer_desktop.png', context: {viewport: {width: 1280, height: 800}}},
  {file: 'viewer_phone.png', context: {viewport: {width: 390, height: 844}, deviceScaleFactor: 2, isMobile: true, hasTouch: true}},
];
const b = await openBrowser();
try {
  for (const shot of shots) {
    const t0 = Date.now();
    const page = await b.newPage(shot.context);
    await page.goto(b.url(`web/index.html?renderer=${renderer}&size=${size}&scene=${scene}`));
    await page.waitForFunction(() => window.ecrfViewer && (ecrfViewer.idle() || ecrfViewer.state.error),
                               null, {timeout: 600000, polling: 250});
    const error = await page.evaluate(() => ecrfViewer.state.error);
    if (error) throw new Error(error);
    await page.screenshot({path: join(root, 'docs', 'web', shot.file)});
    console.log(`docs/web/${shot.file} in ${((Date.now() - t0) / 1000).toFixed(0)} s`);
    b.assertNoConsoleErrors(page);
    await page.context().close();
  }
} finally {
  await b.close();
}
