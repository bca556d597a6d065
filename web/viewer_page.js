// ecrf viewer, the page: URL parameters, loading (URL, file, drop), the renderer (GPU path when
// WebGL2 has what gpu_renderer.js needs, else the CPU path), the HiDPI canvas, the panel and the
// test hooks (window.ecrfViewer; canvas[data-frame] counts complete full-resolution frames).
'use strict';

(function () {
  const $ = (id) => document.getElementById(id);
  const SIZE_MIN = 16, SIZE_MAX = 4096;
  const DEFAULT_SIZE = {cpu: 400, gpu: 1024};
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
    renderer: null, scene: null, view: null, size: 0, loading: false, error: null,
    frames: 0, lastFrame: null, frameLog: [], status: '',
  };
  let canvas = null, renderer = null, controls = null, resizeObserver = null;
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

  // The full render resolution: the canvas's drawing buffer, scaled down to the size cap.
  function renderSize() {
    const s = Math.min(1, state.size / Math.max(canvas.width, canvas.height));
    return [Math.max(1, Math.round(canvas.width * s)), Math.max(1, Math.round(canvas.height * s))];
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

  function onViewChange(view, interactive) {
    state.view = view;
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
    state.rendererNote = kind === 'cpu' && state.softwareGl ? ` (WebGL2 is software here: ${state.softwareGl}; ?renderer=gpu forces it)` : '';
    if (!state.sizeSet) state.size = parseSize(params.get('size'), DEFAULT_SIZE[kind]);
    $('size').value = String(state.size);
    controls = new ecrfCamera.OrbitControls(canvas, view, onViewChange);
    onViewChange(controls.view, false);
    resizeObserver = new ResizeObserver(() => { if (fitCanvas()) requestRender(false); });
    resizeObserver.observe(canvas);
  }

  function viewFromParams() {
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
      ['stream', `${info.streamBytes.toLocaleString()} bytes`],
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
    if (renderer.kind === 'gpu') rows.push(['GPU textures', gpuTextureText()]);
    rows.push(['frame', '']);
    const table = $('info');
    table.textContent = '';
    for (const [k, v] of rows) {
      const tr = table.insertRow();
      tr.dataset.key = k;
      tr.insertCell().textContent = k;
      tr.insertCell().textContent = v;
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
      if (res.info.ndcFrame && !['az', 'el', 'radius'].some((k) => params.has(k))) {
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
    $('size').addEventListener('change', () => {
      state.size = parseSize($('size').value, state.size);
      state.sizeSet = true;
      $('size').value = String(state.size);
      requestRender(false);
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
