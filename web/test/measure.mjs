// Measurements of the viewer (a report, not a test): on a scene (default: the chair scene copied
// to build-web-demo/scene.ecrf by screenshots.mjs), for the CPU path at 400x400 with 2 workers the
// time from a camera move to the 1/8 preview and to the full frame; for the GPU path the frame
// time; for both the peak memory (PSS from /proc of all chromium processes, by process type,
// sampled every 200 ms) and the page's JS heap (CDP Performance.getMetrics JSHeapUsedSize).
//
//   node web/test/measure.mjs [cpu|gpu ...]       GPU_SIZE=64 SCENE=../build-web-demo/scene.ecrf
import {readFileSync, readdirSync} from 'node:fs';
import {openBrowser} from './browser.mjs';

const scene = process.env.SCENE || '../build-web-demo/scene.ecrf';
const kinds = process.argv.slice(2).length ? process.argv.slice(2) : ['cpu', 'gpu'];
const gpuSize = Number(process.env.GPU_SIZE || 64);
const median = (xs) => [...xs].sort((a, b) => a - b)[xs.length >> 1];

function descendants(pid) {
  const children = new Map();
  for (const d of readdirSync('/proc')) {
    if (!/^\d+$/.test(d)) continue;
    try {
      const ppid = Number(readFileSync(`/proc/${d}/stat`, 'utf8').split(') ')[1].split(' ')[1]);
      if (!children.has(ppid)) children.set(ppid, []);
      children.get(ppid).push(Number(d));
    } catch { /* gone */ }
  }
  const out = [], todo = [pid];
  while (todo.length) for (const c of children.get(todo.pop()) || []) { out.push(c); todo.push(c); }
  return out;
}

// PSS in bytes by chromium process type (browser, renderer, gpu-process, utility, ...).
function memory() {
  const by = {};
  for (const pid of descendants(process.pid)) {
    try {
      const cmd = readFileSync(`/proc/${pid}/cmdline`, 'utf8');
      if (!/chrom/.test(cmd)) continue;
      const type = (cmd.match(/--type=([\w-]+)/) || [, 'browser'])[1];
      const pss = Number(readFileSync(`/proc/${pid}/smaps_rollup`, 'utf8').match(/^Pss:\s+(\d+)/m)[1]) * 1024;
      by[type] = (by[type] || 0) + pss;
    } catch { /* gone */ }
  }
  return by;
}

const mib = (n) => `${(n / 1048576).toFixed(0)} MiB`;

for (const kind of kinds) {
  const b = await openBrowser();
  const peak = {};
  const sampler = setInterval(() => {
    const m = memory();
    let total = 0;
    for (const [k, v] of Object.entries(m)) { peak[k] = Math.max(peak[k] || 0, v); total += v; }
    peak.total = Math.max(peak.total || 0, total);
  }, 200);
  try {
    // 340 px of panel: the canvas is 400x400 CSS pixels at DPR 1.
    const page = await b.newPage({viewport: {width: 740, height: 400}});
    const cdp = await page.context().newCDPSession(page);
    await cdp.send('Performance.enable');
    let heapPeak = 0;
    const heap = async () => {
      const {metrics} = await cdp.send('Performance.getMetrics');
      const v = metrics.find((m) => m.name === 'JSHeapUsedSize').value;
      heapPeak = Math.max(heapPeak, v);
      return v;
    };
    const size = kind === 'cpu' ? 400 : gpuSize;
    const t0 = Date.now();
    await page.goto(b.url(`web/index.html?renderer=${kind}&size=${size}&workers=2&scene=${scene}`));
    await page.waitForFunction(() => window.ecrfViewer && (ecrfViewer.idle() || ecrfViewer.state.error), null, {timeout: 900000, polling: 200});
    const first = await page.evaluate(() => ({error: ecrfViewer.state.error, f: ecrfViewer.state.lastFrame, info: document.getElementById('info').innerText}));
    if (first.error) throw new Error(first.error);
    await heap();
    console.log(`${kind}: first full frame ${first.f.width}x${first.f.height} ${((Date.now() - t0) / 1000).toFixed(1)} s after navigation`);
    console.log('  ' + first.info.split('\n').filter((l) => /decode time|renderer|GPU textures/.test(l)).join('; '));
    const preview = [], full = [], frame = [];
    for (let k = 1; k <= 3; ++k) {
      const n = await page.evaluate(() => ecrfViewer.state.frameLog.length);
      await page.evaluate((k) => ecrfViewer.setView({az: 17 + 10 * k}), k);
      await page.waitForFunction(() => ecrfViewer.idle(), null, {timeout: 900000, polling: 100});
      const log = await page.evaluate((n) => ecrfViewer.state.frameLog.slice(n), n);
      await heap();
      if (kind === 'cpu') {
        preview.push(log.find((f) => f.divisor === 8).ms);
        full.push(log.find((f) => f.final).ms);
      } else {
        frame.push(log.find((f) => f.final).ms);
      }
    }
    if (kind === 'cpu') {
      console.log(`  camera move -> 1/8 preview: ${preview.map((x) => x.toFixed(0)).join(', ')} ms (median ${median(preview).toFixed(0)})`);
      console.log(`  camera move -> full 400x400: ${full.map((x) => x.toFixed(0)).join(', ')} ms (median ${median(full).toFixed(0)})`);
    } else {
      console.log(`  warm frame ${first.f.width}x${first.f.height}: ${frame.map((x) => x.toFixed(1)).join(', ')} ms (median ${median(frame).toFixed(1)})`);
    }
    console.log(`  peak JSHeapUsedSize (page main thread): ${mib(heapPeak)}`);
  } finally {
    clearInterval(sampler);
    await b.close();
  }
  console.log(`  peak PSS: ${Object.entries(peak).map(([k, v]) => `${k} ${mib(v)}`).join(', ')}`);
}
