// ecrf viewer, CPU path: the WebAssembly renderer in a pool of workers (render_worker.js).
//
// A frame is rendered progressively at 1/8, 1/4, 1/2 and full resolution. Each level is cut into
// strips of rows that idle workers take one at a time (so a camera move never waits behind queued
// work of an old frame), composed off-screen and drawn whole when complete (never a torn frame).
// Strips of an older frame that come back late are dropped by their frame id. While the 1/8
// preview of a frame is still missing, a camera move does not restart the frame but is rendered
// next: restarting on every pointer event would never show anything during a drag.
'use strict';

(function () {
  const LEVELS = [8, 4, 2, 1];      // resolution divisors, coarse to fine
  const STRIP_PIXELS = 2048;        // about 50-150 ms of one worker: the latency of a camera move
  const scriptBase = document.currentScript ? document.currentScript.src : location.href;

  class CpuRenderer {
    // budgets: {workBudget, decodeBudget} (SPEC.md 8; omitted: the decoder's defaults).
    constructor(canvas, {workers = 2, onFrame = () => {}, onError = () => {}, budgets = {}} = {}) {
      this.kind = 'cpu';
      this.budgets = budgets;
      this.canvas = canvas;
      this.ctx = canvas.getContext('2d');
      if (!this.ctx) throw new Error('no 2D canvas context');
      this.workerCount = Math.max(1, Math.min(16, workers | 0));
      this.onFrame = onFrame;
      this.onError = onError;
      this.workers = [];      // {worker, ready, busy}
      this.sceneId = 0;
      this.frameIds = 0;
      this.frame = null;
      this.want = null;       // the latest request: {cameraAt, width, height, t}
      this.pending = false;
      this.off = document.createElement('canvas');  // the back buffer
      this.shown = null;      // {width, height, data} drawn last
      this.full = null;       // the last complete full-resolution image
    }

    describe() {
      const n = this.workers.length || this.workerCount;
      return `CPU (WebAssembly, ${n} worker${n > 1 ? 's' : ''})`;
    }

    // Starts the workers on `bytes`; resolves with the first worker's {version, info, decodeMs}.
    load(bytes) {
      this.clear();
      const sceneId = ++this.sceneId;
      return new Promise((resolve, reject) => {
        let settled = false;
        const fail = (message) => {
          if (sceneId !== this.sceneId) return;
          if (!settled) { settled = true; reject(new Error(message)); } else this.onError(new Error(message));
        };
        for (let k = 0; k < this.workerCount; ++k) {
          const w = {worker: new Worker(new URL('render_worker.js', scriptBase)), ready: false, busy: false};
          w.worker.onmessage = (ev) => {
            const msg = ev.data;
            if (msg.sceneId !== this.sceneId || !this.workers.includes(w)) return;  // an older scene
            if (msg.type === 'loaded') {
              w.ready = true;
              if (!settled) { settled = true; resolve(msg); }
              this.dispatch();
            } else if (msg.type === 'error') {
              w.busy = false;
              fail(msg.message);
            } else if (msg.type === 'strip') {
              w.busy = false;
              this.strip(msg);
              this.dispatch();
            }
          };
          w.worker.onerror = (ev) => { ev.preventDefault(); fail(`render worker: ${ev.message || 'failed to start'}`); };
          w.worker.postMessage({type: 'load', sceneId, bytes, budgets: this.budgets});
          this.workers.push(w);
        }
      });
    }

    // Drops the scene: workers terminated (their wasm heaps freed), canvas cleared.
    clear() {
      for (const w of this.workers) w.worker.terminate();
      this.workers = [];
      ++this.sceneId;
      this.frame = null;
      this.want = null;
      this.pending = false;
      this.shown = this.full = null;
      this.ctx.clearRect(0, 0, this.canvas.width, this.canvas.height);
    }

    dispose() { this.clear(); }

    // cameraAt(w, h) gives the camera of a w x h image; width x height is the full resolution.
    // Progressive whether the camera moves or not; a request for the image in progress is a no-op.
    request(cameraAt, width, height, moving = false, key = undefined) {
      if (key !== undefined && this.want && this.want.key === key) return;
      this.want = {cameraAt, width, height, key, t: performance.now()};
      if (this.frame && !this.frame.finished && this.frame.presented < 0) this.pending = true;
      else this.start();
    }

    start() {
      const {cameraAt, width, height, t} = this.want;
      this.pending = false;
      const levels = [];
      for (const div of LEVELS) {
        const w = Math.max(1, Math.round(width / div)), h = Math.max(1, Math.round(height / div));
        if (levels.length && levels[levels.length - 1].w === w && levels[levels.length - 1].h === h) continue;
        const rows = Math.max(1, Math.min(Math.ceil(h / this.workerCount), Math.floor(STRIP_PIXELS / w)));
        levels.push({div, w, h, camera: cameraAt(w, h), rows, strips: Math.ceil(h / rows), next: 0,
                     done: 0, buf: new Uint8ClampedArray(w * h * 4), ms: 0});
      }
      this.frame = {id: ++this.frameIds, t0: t, key: this.want.key, levels, presented: -1, finished: false};
      this.dispatch();
    }

    // Gives every idle worker the next strip, coarse levels first.
    dispatch() {
      const f = this.frame;
      if (!f || f.finished) return;
      for (const w of this.workers) {
        if (!w.ready || w.busy) continue;
        const li = f.levels.findIndex((l) => l.next < l.strips);
        if (li < 0) return;
        const l = f.levels[li];
        const y0 = l.next++ * l.rows;
        w.busy = true;
        w.worker.postMessage({type: 'strip', sceneId: this.sceneId, frame: f.id, level: li,
                              camera: l.camera, y0, rows: Math.min(l.rows, l.h - y0)});
      }
    }

    strip(msg) {
      const f = this.frame;
      if (!f || msg.frame !== f.id) return;  // a strip of an older frame
      const l = f.levels[msg.level];
      l.buf.set(msg.rgba, msg.y0 * l.w * 4);
      l.ms += msg.ms;
      if (++l.done < l.strips || msg.level <= f.presented) return;
      f.presented = msg.level;
      this.draw({width: l.w, height: l.h, data: l.buf});
      const final = msg.level === f.levels.length - 1;
      if (final) {
        f.finished = true;
        this.full = this.shown;
      }
      this.onFrame({final, width: l.w, height: l.h, divisor: l.div, ms: performance.now() - f.t0,
                    workMs: l.ms, level: msg.level, key: f.key});
      if (this.pending) this.start();
    }

    draw(image) {
      this.shown = image;
      const off = this.off;
      if (off.width !== image.width || off.height !== image.height) {
        off.width = image.width;
        off.height = image.height;
      }
      off.getContext('2d').putImageData(new ImageData(image.data, image.width, image.height), 0, 0);
      const c = this.canvas;
      this.ctx.imageSmoothingEnabled = true;
      this.ctx.clearRect(0, 0, c.width, c.height);
      this.ctx.drawImage(off, 0, 0, c.width, c.height);
    }

    // After a canvas resize (which clears it) until the next frame arrives.
    redraw() { if (this.shown) this.draw(this.shown); }

    // The last full-resolution frame, as composed (RGBA, top row first).
    readPixels() {
      return this.full && {width: this.full.width, height: this.full.height, data: new Uint8Array(this.full.data)};
    }

    stats() { return {workers: this.workers.filter((w) => w.ready).length}; }
  }

  globalThis.ecrfCpu = {CpuRenderer};
})();
