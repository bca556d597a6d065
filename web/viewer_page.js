// ecrf viewer, the page: URL parameters, loading (URL, file, drop), the renderer (GPU path when
// WebGL2 has what gpu_renderer.js needs, else the CPU path), the HiDPI canvas, the panel and the
// test hooks (window.ecrfViewer; canvas[data-frame] counts complete full-resolution frames).
'use strict';

(function () {
  const $ = (id) => document.getElementById(id);
  const SIZE_MIN = 16, SIZE_MAX = 4096;
  // Without ?size= both paths render at the canvas's device resolution within a pixel budget
  // (?max-pixels= changes it): the CPU path's final frame costs time in proportion to its pixels
  // (its previews at 1/8, 1/4 and 1/2 come first), the GPU path keeps about the 1024-pixel cap it
  // had.
  const DEFAULT_MAX_PIXELS = {cpu: 1 << 19, gpu: 1 << 20};
  const IDLE_MS = 200;  // no camera change for this long: render at full resolution

  const params = new URLSearchParams(location.search);
  // ?work-budget=N (multiply-adds per pixel) and ?decode-budget=N (units per byte), SPEC.md 8; 0
  // lifts a limit. Omitted: the decoder's defaults.
  const budgets = {};
  for (const [key, name] of [['work-budget', 'workBudget'], ['decode-budget', 'decodeBudget']]) {
    const v = Number(params.get(key));
    if (params.has(key) && Number.isFinite(v) && v >= 0) budgets[name] = v;
  }
  const state = {
    renderer: null, scene: null, view: null, size: 0, maxPixels: 0, loading: false, error: null,
    frames: 0, lastFrame: null, frameLog: [], status: '',
  };
  let canvas = null, renderer = null, controls = null, resizeObserver = null;
  // Whether the page was opened with a camera (?az= &el= &radius= or the #az=&el=&r= hash): a
  // forward-facing scene then keeps it instead of starting at its reference camera. Read once: the
  // viewer writes the hash itself from then on.
  const openedWithView = ['az', 'el', 'radius'].some((k) => params.has(k)) || /(^#|&)(az|el|r)=/.test(location.hash);
  let loadSeq = 0, idleTimer = 0, download = null;

  // An empty parameter, or no number at all, means the default; anything else is clamped.
  function parseSize(value, fallback) {
    if (value === null || String(value).trim() === '') return fallback;
    const n = Math.round(Number(value));
    return Number.isFinite(n) ? Math.min(SIZE_MAX, Math.max(SIZE_MIN, n)) : fallback;
  }

  function status(text, error = false) {
    state.status = text;
    state.error = error ? text : null;
    $('status').textContent = text;
    $('status').className = error ? 'error' : '';
  }

  function progress(received, total) {
    const p = $('progress');
    p.hidden = received < 0;
    if (total) { p.max = total; p.value = received; } else p.removeAttribute('value');
  }

  // ---- canvas and renderer ---------------------------------------------------------------------
  function fitCanvas() {
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(canvas.clientWidth * dpr));
    const h = Math.max(1, Math.round(canvas.clientHeight * dpr));
    if (canvas.width === w && canvas.height === h) return false;
    canvas.width = w;
    canvas.height = h;
    if (renderer) renderer.redraw();
    return true;
  }

  // The full render resolution: the canvas's drawing buffer (device pixels), scaled down to the
  // size cap (?size= or the panel: the long side) or, without one, to the pixel budget.
  function renderSize() {
    const w = canvas.width, h = canvas.height;
    let s = state.size ? state.size / Math.max(w, h) : Math.sqrt(state.maxPixels / (w * h));
    s = Math.min(1, s);
    return [Math.max(1, Math.round(w * s)), Math.max(1, Math.round(h * s))];
  }

  // What limits the frame, for the HUD: nothing (the canvas's resolution), the size cap or the
  // pixel budget.
  function capText(width, height) {
    if (width >= canvas.width && height >= canvas.height) return '';
    const canvasSize = `${canvas.width}×${canvas.height}`;
    if (state.size) return ` (size cap ${state.size} of ${canvasSize})`;
    const budget = state.maxPixels >= 1e5 ? `${(state.maxPixels / 1e6).toFixed(2)} MP` : `${state.maxPixels.toLocaleString()} pixels`;
    return ` (pixel budget ${budget} of ${canvasSize}; ?max-pixels= or the size cap)`;
  }

  function currentCamera() {
    const [w, h] = renderSize();
    return ecrfCamera.viewCamera(controls.view, w, h);
  }

  // Names the full-resolution image of the current view: a renderer skips a request for the image
  // it has (or is making) already, and the tests wait until the image on screen has this key.
  function viewKey() {
    const [w, h] = renderSize();
    return JSON.stringify([controls.view, w, h, canvas.width, canvas.height]);
  }

  function requestRender(moving) {
    if (!state.scene || !renderer) return;
    const [w, h] = renderSize();
    const view = controls.view;
    renderer.request((cw, ch) => ecrfCamera.viewCamera(view, cw, ch), w, h, moving, viewKey());
  }

  // The camera in the URL's hash (#az=&el=&r=&t=x,y,z) so that a view can be shared; four
  // decimals, so that a view read back from its hash gives the same hash and the same image.
  function viewToHash(v) {
    const n = (x) => String(Number(x.toFixed(4)));
    let h = `az=${n(v.az)}&el=${n(v.el)}&r=${n(v.radius)}`;
    if (v.target.some((x) => x !== 0)) h += `&t=${v.target.map(n).join(',')}`;
    return h;
  }

  function viewFromHash(hash) {
    const p = new URLSearchParams(String(hash || '').replace(/^#/, ''));
    if (!['az', 'el', 'r'].some((k) => p.has(k))) return null;
    const d = ecrfCamera.DEFAULT_VIEW;
    const num = (k, v) => (p.has(k) && Number.isFinite(Number(p.get(k))) ? Number(p.get(k)) : v);
    const t = p.has('t') ? p.get('t').split(',').map(Number) : d.target;
    return ecrfCamera.normalizeView({az: num('az', d.az), el: num('el', d.el), radius: num('r', d.radius),
                                     target: t.length === 3 ? t : d.target});
  }

  // At the end of a gesture (not per pointer event: browsers throttle history updates).
  function writeHash(view) {
    const hash = `#${viewToHash(view)}`;
    if (location.hash !== hash) history.replaceState(null, '', `${location.pathname}${location.search}${hash}`);
  }

  function onViewChange(view, interactive) {
    state.view = view;
    if (!interactive) writeHash(view);
    const t = view.target.some((v) => v !== 0) ? `, target ${view.target.map((v) => v.toFixed(2)).join(' ')}` : '';
    $('view-values').textContent = `az ${view.az.toFixed(0)}°, el ${view.el.toFixed(0)}°, r ${view.radius.toFixed(2)}${t}`;
    clearTimeout(idleTimer);
    if (interactive) {
      requestRender(true);
      idleTimer = setTimeout(() => requestRender(false), IDLE_MS);
    } else {
      requestRender(false);
    }
  }

  function onFrame(f) {
    if (state.firstFrame && !state.error) status('');
    state.firstFrame = false;
    state.lastFrame = f;
    state.frameLog.push({...f, t: performance.now()});
    if (state.frameLog.length > 200) state.frameLog.shift();
    let text;
    if (renderer.kind === 'gpu') {
      text = `GPU ${f.width}×${f.height}: ${f.ms.toFixed(1)} ms` +
             (f.first ? ' (with the shader compile)' : f.fps ? `, ${f.fps.toFixed(0)} fps` : '');
    } else {
      text = `CPU ${f.divisor > 1 ? `1/${f.divisor} ` : ''}${f.width}×${f.height} in ${f.ms.toFixed(0)} ms`;
    }
    if (f.final) text += capText(f.width, f.height);
    $('hud').textContent = text;
    setInfoRow('frame', text);
    if (renderer.kind === 'gpu') setInfoRow('GPU textures', gpuTextureText());
    if (f.final) {
      state.renderedKey = f.key;
      ++state.frames;
      canvas.dataset.frame = String(state.frames);
    }
  }

  function onRenderError(e) {
    const last = state.lastLoad;
    if (renderer.kind === 'gpu' && last) {
      makeRenderer('cpu');
      loadBytes(last.name, last.bytes).then(() => { if (!state.error) status(`${e.message}: using the CPU renderer`); });
      return;
    }
    clearScene();
    status(`render failed: ${e.message}`, true);
  }

  function gpuTextureText() {
    const s = renderer && renderer.kind === 'gpu' ? renderer.stats() : {};
    const bytes = s.textureBytes ?? s.gpuBytes ?? s.bytes;
    return Number.isFinite(bytes) ? `${bytes.toLocaleString()} bytes` : JSON.stringify(s);
  }

  function chooseKind() {
    const asked = params.get('renderer');
    if (asked === 'cpu') return 'cpu';
    const gpu = ecrfGpuView.GpuView.isSupported();
    if (asked === 'gpu' && !gpu) status('the GPU renderer is not available here (WebGL2): using the CPU renderer');
    if (asked === 'gpu' || !gpu) return gpu ? 'gpu' : 'cpu';
    const software = ecrfGpuView.GpuView.softwareGl();
    state.softwareGl = software;
    return software ? 'cpu' : 'gpu';  // ?renderer=gpu still forces the GPU path there
  }

  // A canvas keeps the kind of context it got first: a new renderer kind gets a new canvas.
  function makeRenderer(kind) {
    const view = controls ? controls.view : viewFromParams();
    if (renderer) renderer.dispose();
    if (controls) controls.dispose();
    if (resizeObserver) resizeObserver.disconnect();
    const old = $('view');
    canvas = old.cloneNode(false);
    canvas.removeAttribute('data-frame');
    old.replaceWith(canvas);
    fitCanvas();
    if (kind === 'gpu') {
      try {
        renderer = new ecrfGpuView.GpuView(canvas, {onFrame, onError: onRenderError, budgets});
      } catch (e) {
        status(`${e.message}: using the CPU renderer`);
        return makeRenderer('cpu');
      }
    } else {
      const workers = Number(params.get('workers')) || Math.min(navigator.hardwareConcurrency || 2, 4);
      renderer = new ecrfCpu.CpuRenderer(canvas, {workers, onFrame, onError: onRenderError, budgets});
    }
    state.renderer = kind;
    // One line: the driver's own name of a software WebGL2 can be a paragraph (the row's tooltip
    // keeps it whole).
    state.rendererNote = kind === 'cpu' && state.softwareGl ? '; WebGL2 is software here (?renderer=gpu forces it)' : '';
    if (!state.sizeSet) state.size = params.get('size') === null ? 0 : parseSize(params.get('size'), 0);
    const budget = Number(params.get('max-pixels'));
    state.maxPixels = params.has('max-pixels') && budget >= 1 ? budget : DEFAULT_MAX_PIXELS[kind];
    $('size').value = state.size ? String(state.size) : '';
    controls = new ecrfCamera.OrbitControls(canvas, view, onViewChange);
    onViewChange(controls.view, false);
    resizeObserver = new ResizeObserver(() => { if (fitCanvas()) requestRender(false); });
    resizeObserver.observe(canvas);
  }

  function viewFromParams() {
    const fromHash = viewFromHash(location.hash);
    if (fromHash) return fromHash;
    const d = ecrfCamera.DEFAULT_VIEW;
    const num = (k, v) => (params.has(k) && Number.isFinite(Number(params.get(k))) ? Number(params.get(k)) : v);
    return ecrfCamera.normalizeView({az: num('az', d.az), el: num('el', d.el), radius: num('radius', d.radius),
                                     target: d.target});
  }

  // ---- scenes ----------------------------------------------------------------------------------
  function setInfoRow(key, value) {
    const row = document.querySelector(`#info tr[data-key="${key}"]`);
    if (row) row.cells[1].textContent = value;
  }

  function showInfo(name, res) {
    const info = res.info;
    const r3 = (v) => v.join(' × ');
    const fmt = (v) => v.map((x) => x.toFixed(3)).join(', ');
    const rows = [
      ['file', name],
      ['decoder', res.version],
      ['stream', `${info.streamBytes.toLocaleString()} bytes, bitstream ${info.version}`],
      ['grid', r3(info.gridRes)],
      ['density ranks', info.densityRanks.join(', ')],
      ['appearance ranks', info.appearanceRanks.join(', ')],
      ['decoded grids', `${info.gridBytes.toLocaleString()} bytes`],
      ['occupancy', info.hasOccupancy ? r3(info.occupancyRes) : 'none'],
      ['box', `[${fmt(info.aabbMin)}] .. [${fmt(info.aabbMax)}]`],
      ['samples per ray', `${info.numSamples} (step ${info.stepSize.toFixed(4)})`],
      ['decode time', `${res.decodeMs.toFixed(1)} ms` +
                      (res.uploadMs !== undefined ? ` (+ ${res.uploadMs.toFixed(1)} ms upload)` : '')],
      ['renderer', renderer.describe() + (state.rendererNote || '')],
    ];
    const rendererTitle = state.softwareGl && renderer.kind === 'cpu' ? `WebGL2: ${state.softwareGl}` : '';
    if (renderer.kind === 'gpu') rows.push(['GPU textures', gpuTextureText()]);
    rows.push(['frame', '']);
    const table = $('info');
    table.textContent = '';
    for (const [k, v] of rows) {
      const tr = table.insertRow();
      tr.dataset.key = k;
      tr.insertCell().textContent = k;
      tr.insertCell().textContent = v;
      if (k === 'renderer' && rendererTitle) tr.title = rendererTitle;
    }
  }

  // The old scene goes entirely: image, workers or GPU textures, panel.
  function clearScene() {
    clearTimeout(idleTimer);
    if (renderer) renderer.clear();
    state.scene = null;
    state.lastLoad = null;
    state.lastFrame = null;
    state.renderedKey = null;
    $('info').textContent = '';
    $('hud').textContent = '';
    document.body.classList.remove('loaded');
  }

  async function loadBytes(name, bytes, seq = ++loadSeq) {
    clearScene();
    state.loading = true;
    status(`decoding ${name} (${ecrfSource.formatBytes(bytes.length)})…`);
    try {
      const res = await renderer.load(bytes);
      if (seq !== loadSeq) return;
      state.scene = {name, info: res.info, version: res.version};
      state.lastLoad = {name, bytes};  // for a fallback to the CPU path
      showInfo(name, res);
      if (res.info.ndcFrame && !openedWithView) {
        // A forward-facing scene is seen from in front only: start at its reference camera.
        controls.home = ecrfCamera.forwardHomeView(res.info.ndcFrame);
        controls.setView(controls.home);
      }
      // The first GPU frame compiles the shaders: seconds on a software GL, and it blocks the page.
      status(renderer.kind === 'gpu' ? 'compiling the GPU shaders…' : '');
      state.firstFrame = true;
      document.body.classList.add('loaded');
      requestRender(false);
    } catch (e) {
      if (seq !== loadSeq) return;
      if (e.gpuLimit) {
        // The GPU cannot hold this scene: the CPU path can.
        makeRenderer('cpu');
        const note = `${e.message}; using the CPU renderer`;
        await loadBytes(name, bytes, seq);
        if (seq === loadSeq && !state.error) status(note);
        return;
      }
      clearScene();
      status(`${name}: ${e.message}`, true);
    } finally {
      if (seq === loadSeq) state.loading = false;
    }
  }

  async function loadUrl(url) {
    const seq = ++loadSeq;
    if (download) download.abort();
    download = new AbortController();
    const name = decodeURIComponent(url.split(/[?#]/)[0].split('/').pop() || url);
    state.loading = true;
    status(`downloading ${name}…`);
    try {
      const bytes = await ecrfSource.fetchScene(url, (got, total) => {
        if (seq !== loadSeq) return;
        progress(got, total);
        const f = ecrfSource.formatBytes;
        status(`downloading ${name}: ${f(got)}` + (total ? ` / ${f(total)} (${Math.round((100 * got) / total)}%)` : ''));
      }, download.signal);
      if (seq !== loadSeq) return;
      progress(-1);
      await loadBytes(name, bytes, seq);
    } catch (e) {
      if (seq !== loadSeq) return;
      progress(-1);
      clearScene();
      state.loading = false;
      status(e.message, true);
    }
  }

  async function loadFile(file) {
    const seq = ++loadSeq;
    if (download) download.abort();
    try {
      const bytes = await ecrfSource.readFile(file);
      if (seq === loadSeq) await loadBytes(file.name, bytes, seq);
    } catch (e) {
      if (seq !== loadSeq) return;
      clearScene();
      status(`${file.name}: ${e.message}`, true);
    }
  }

  function setSceneParam(url) {
    const p = new URLSearchParams(location.search);
    p.set('scene', url);
    history.replaceState(null, '', `${location.pathname}?${p}`);
  }

  // The last full-resolution frame as a PNG download named after the scene and the view; resolves
  // with {name, width, height, bytes}, or null before the first full frame.
  async function screenshot() {
    const px = renderer && renderer.readPixels();
    if (!px || !state.scene) { status('no full-resolution frame to save yet'); return null; }
    const c = document.createElement('canvas');
    c.width = px.width;
    c.height = px.height;
    c.getContext('2d').putImageData(new ImageData(new Uint8ClampedArray(px.data), px.width, px.height), 0, 0);
    const blob = await new Promise((resolve) => c.toBlob(resolve, 'image/png'));
    if (!blob) { status('the browser could not encode the PNG', true); return null; }
    const v = controls.view;
    const base = state.scene.name.replace(/\.ecrf$/i, '').replace(/[^\w.-]+/g, '_');
    const name = `${base}_az${v.az.toFixed(0)}_el${v.el.toFixed(0)}_${px.width}x${px.height}.png`;
    const a = document.createElement('a');
    a.href = URL.createObjectURL(blob);
    a.download = name;
    document.body.appendChild(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(a.href), 10000);
    return {name, width: px.width, height: px.height, bytes: blob.size};
  }

  // ---- start -----------------------------------------------------------------------------------
  function wireUi() {
    $('panel-toggle').addEventListener('click', () => {
      const collapsed = document.body.classList.toggle('panel-collapsed');
      $('panel-toggle').textContent = collapsed ? 'panel' : 'hide';
      $('panel-toggle').setAttribute('aria-expanded', String(!collapsed));
    });
    $('url-form').addEventListener('submit', (e) => {
      e.preventDefault();
      const url = $('url').value.trim();
      if (!url) return;
      setSceneParam(url);
      loadUrl(url);
    });
    $('builtin').addEventListener('click', () => {
      $('url').value = $('builtin').dataset.url;
      setSceneParam($('url').value);
      loadUrl($('url').value);
    });
    $('file').addEventListener('change', (e) => {
      const file = e.target.files[0];
      e.target.value = '';  // choosing the same file again is a new load
      if (file) loadFile(file);
    });
    $('reset').addEventListener('click', () => controls.reset());
    $('screenshot').addEventListener('click', () => { screenshot(); });
    $('size').addEventListener('change', () => {
      // An empty field goes back to the canvas's resolution (within the pixel budget).
      state.size = $('size').value.trim() === '' ? 0 : parseSize($('size').value, state.size);
      state.sizeSet = true;
      $('size').value = state.size ? String(state.size) : '';
      requestRender(false);
    });
    // A pasted or edited #az=&el=&r= moves the camera.
    window.addEventListener('hashchange', () => {
      const v = viewFromHash(location.hash);
      if (v && controls) controls.setView(v);
    });
    ecrfSource.installDropZone($('drop-overlay'), loadFile);
    window.addEventListener('resize', () => { if (fitCanvas()) requestRender(false); });  // DPR changes
  }

  function start() {
    wireUi();
    makeRenderer(chooseKind());
    window.ecrfViewer = {
      state,
      get renderer() { return renderer; },
      get frames() { return state.frames; },
      camera: currentCamera,
      idle: () => !!state.scene && state.renderedKey === viewKey(),
      readPixels: () => renderer && renderer.readPixels(),
      setView: (v, interactive = false) => controls.setView(v, interactive),
      screenshot, viewToHash, viewFromHash,
      loadUrl, loadFile,
    };
    if (location.protocol === 'file:') {
      status(`Opened from file://: ${ecrfSource.FILE_HINT}`, true);
      return;
    }
    if (!state.error) status('ready: open a .ecrf file, drop one anywhere, or load a URL');
    const scene = params.get('scene');
    if (scene) {
      $('url').value = scene;
      loadUrl(scene);
    }
  }

  if (document.readyState === 'loading') window.addEventListener('DOMContentLoaded', start);
  else start();
})();
