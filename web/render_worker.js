// Render worker of the ecrf viewer (CPU path): its own instance of the WebAssembly decoder and its
// own copy of the decoded scene; renders horizontal strips of a view with one thread. Several of
// these render a view in parallel without pthreads (no SharedArrayBuffer, no special HTTP headers).
// Each worker decodes the stream itself: that costs a decode per worker, but off the main thread.
//
// Messages in:  {type: 'load', sceneId, bytes, budgets}   (budgets: {workBudget, decodeBudget}, optional)
//               {type: 'strip', sceneId, frame, level, camera, y0, rows}   (camera: ecrfWeb's shape)
// Messages out: {type: 'loaded', sceneId, version, info, decodeMs}
//               {type: 'error', sceneId, frame, message}
//               {type: 'strip', sceneId, frame, level, y0, rows, rgba, ms}
'use strict';
importScripts('../build-wasm/ecrf_decoder.js', 'viewer.js');

const wasmDir = new URL('../build-wasm/', self.location.href).href;
const modulePromise = createEcrfDecoder({locateFile: (file) => wasmDir + file});
let decoder = null;
let sceneId = -1;
let renderOptions = {};

self.onmessage = async (ev) => {
  const msg = ev.data;
  try {
    const module = await modulePromise;  // messages are handled in order: one await each
    if (msg.type === 'load') {
      if (decoder) decoder.destroy();
      decoder = null;
      sceneId = msg.sceneId;
      const d = new ecrfWeb.EcrfDecoder(module);
      const budgets = msg.budgets || {};
      renderOptions = budgets.workBudget === undefined ? {} : {workBudget: budgets.workBudget};
      const t0 = performance.now();
      try {
        if (budgets.decodeBudget !== undefined) d.setDecodeBudget(budgets.decodeBudget);
        d.decode(msg.bytes);
        d.checkRender(renderOptions);
      } catch (e) {
        d.destroy();
        throw e;
      }
      decoder = d;
      self.postMessage({type: 'loaded', sceneId, version: d.version(), info: d.info(),
                        decodeMs: performance.now() - t0});
    } else if (msg.type === 'strip') {
      if (!decoder || msg.sceneId !== sceneId) throw new Error('no such scene in this worker');
      const t0 = performance.now();
      const rgba = decoder.render(ecrfWeb.stripCamera(msg.camera, msg.y0, msg.rows), renderOptions);
      for (let k = 3; k < rgba.length; k += 4) rgba[k] = 255;  // the colour has the background
      self.postMessage({type: 'strip', sceneId: msg.sceneId, frame: msg.frame, level: msg.level,
                        y0: msg.y0, rows: msg.rows, rgba, ms: performance.now() - t0}, [rgba.buffer]);
    }
  } catch (e) {
    self.postMessage({type: 'error', sceneId: msg.sceneId, frame: msg.frame,
                      message: String((e && e.message) || e)});
  }
};
