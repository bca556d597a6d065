// ecrf viewer, GPU path: decodes in decode_worker.js (once, off the main thread), uploads the scene
// to ecrfGpu.GpuRenderer (gpu_renderer.js) and renders on demand in requestAnimationFrame. While
// the camera moves, the render resolution follows the measured frame time (dynamic resolution);
// when it stops, one frame at full resolution.
'use strict';

(function () {
  const TARGET_MS = 30;           // frame time aimed at while the camera moves
  const MIN_SCALE = 1 / 8;
  const scriptBase = document.currentScript ? document.currentScript.src : location.href;

  class GpuView {
    static isSupported() {
      return typeof ecrfGpu !== 'undefined' && ecrfGpu.GpuRenderer.isSupported();
    }

    // The name of the GL implementation if it runs on the CPU (SwiftShader, llvmpipe), else ''.
    // There the fragment shader is far slower than the wasm renderer (a 96-px frame of
    // scene_builtin: ~50 s against ~1 s on 2 loaded cores), so the page prefers the CPU path.
    static softwareGl() {
      try {
        const gl = document.createElement('canvas').getContext('webgl2');
        if (!gl) return '';
        const ext = gl.getExtension('WEBGL_debug_renderer_info');
        const name = String(gl.getParameter(ext ? ext.UNMASKED_RENDERER_WEBGL : gl.RENDERER));
        const lose = gl.getExtension('WEBGL_lose_context');
        if (lose) lose.loseContext();
        return /swiftshader|llvmpipe|softpipe|software/i.test(name) ? name : '';
      } catch {
        return '';
      }
    }

    // budgets: {workBudget, decodeBudget} (SPEC.md 8): the decode worker refuses what the CPU
    // renderer would refuse.
    constructor(canvas, {onFrame = () => {}, onError = () => {}, budgets = {}} = {}) {
      this.kind = 'gpu';
      this.budgets = budgets;
      this.canvas = canvas;
      this.r = new ecrfGpu.GpuRenderer(canvas);
      this.onFrame = onFrame;
      this.onError = onError;
      this.decoder = null;    // the decode worker of the load in progress
      this.loadId = 0;
      this.hasScene = false;
      this.want = null;
      this.raf = 0;
      this.scale = 0.5;       // of the full resolution while moving; adapted to the frame time
      this.last = null;       // {width, height, final}
      this.times = [];        // timestamps of recent frames, for the fps
      // A lost context (driver reset, or the GPU watchdog during a long shader compile on a software
      // GL) renders nothing from then on: the page falls back to the CPU path.
      this.lost = (e) => {
        e.preventDefault();
        this.hasScene = false;
        const err = new Error('the WebGL context was lost');
        err.contextLost = true;
        this.onError(err);
      };
      canvas.addEventListener('webglcontextlost', this.lost);
    }

    describe() { return 'GPU (WebGL2)'; }

    load(bytes) {
      this.clear();
      const id = ++this.loadId;
      return new Promise((resolve, reject) => {
        const worker = new Worker(new URL('decode_worker.js', scriptBase));
        this.decoder = worker;
        const done = () => { worker.terminate(); if (this.decoder === worker) this.decoder = null; };
        worker.onerror = (ev) => { ev.preventDefault(); done(); reject(new Error(`decode worker: ${ev.message || 'failed to start'}`)); };
        worker.onmessage = (ev) => {
          const msg = ev.data;
          done();
          if (id !== this.loadId) return reject(new Error('superseded'));
          if (msg.type === 'error') return reject(new Error(msg.message));
          try {
            const t0 = performance.now();
            this.r.setScene(msg.scene);
            this.hasScene = true;
            this.warm = false;
            resolve({version: msg.version, info: msg.scene.info, decodeMs: msg.decodeMs,
                     uploadMs: performance.now() - t0});
          } catch (e) {
            const err = new Error(`GPU renderer: ${e.message || e}`);
            err.gpuLimit = true;
            reject(err);
          }
        };
        // A copy: the page may fall back to the CPU path with it.
        worker.postMessage({id, bytes, budgets: this.budgets});
      });
    }

    clear() {
      if (this.decoder) this.decoder.terminate();
      this.decoder = null;
      ++this.loadId;
      if (this.raf) cancelAnimationFrame(this.raf);
      this.raf = 0;
      this.want = this.last = null;
      if (this.hasScene) this.r.clearScene();
      this.hasScene = false;
      // Resizing clears the drawing buffer whatever the context, without touching the GL state.
      this.canvas.width = this.canvas.width;  // eslint-disable-line no-self-assign
    }

    dispose() {
      this.canvas.removeEventListener('webglcontextlost', this.lost);
      this.clear();
      this.r.dispose();
    }

    request(cameraAt, width, height, moving, key = undefined) {
      const last = this.last;
      if (!moving && key !== undefined && last && last.final && last.key === key && !this.want) return;
      this.want = {cameraAt, width, height, moving, key, t: performance.now()};
      if (this.raf) return;
      // The first render of a scene compiles its shaders and blocks: one frame later, so that the
      // page has painted its "compiling" status first.
      this.raf = requestAnimationFrame(() => {
        this.raf = this.warm ? (this.tick(), 0) : requestAnimationFrame(() => this.tick());
      });
    }

    tick() {
      this.raf = 0;
      const want = this.want;
      if (!want || !this.hasScene) return;
      this.want = null;
      const scale = want.moving ? this.scale : 1;
      const w = Math.max(1, Math.round(want.width * scale)), h = Math.max(1, Math.round(want.height * scale));
      let ms;
      const first = !this.warm;
      try {
        ({ms} = this.r.render(want.cameraAt(w, h), {finish: true}));  // finish: a true frame time
      } catch (e) {
        this.onError(e);
        return;
      }
      this.warm = true;
      if (want.moving) {
        // Square root: the cost grows with the pixel count, the scale is per axis.
        const k = Math.min(1.25, Math.max(0.5, Math.sqrt(TARGET_MS / Math.max(ms, 0.1))));
        this.scale = Math.min(1, Math.max(MIN_SCALE, this.scale * k));
      }
      const now = performance.now();
      this.times.push(now);
      while (this.times.length > 1 && now - this.times[0] > 1000) this.times.shift();
      this.last = {width: w, height: h, final: !want.moving, key: want.key};
      this.onFrame({final: !want.moving, key: want.key, width: w, height: h, ms, latencyMs: now - want.t, first,
                    fps: this.times.length > 1 ? (this.times.length - 1) * 1000 / (now - this.times[0]) : 0});
    }

    redraw() {}  // the page requests a new frame after a resize

    readPixels() {
      if (!this.last || !this.last.final) return null;
      return {width: this.last.width, height: this.last.height, data: this.r.readPixels()};
    }

    stats() { return this.r.stats || {}; }
  }

  globalThis.ecrfGpuView = {GpuView};
})();
