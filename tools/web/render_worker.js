// Render worker of the ecrf viewer: its own instance of the WebAssembly decoder and its own copy
// of the decoded scene; renders horizontal strips of a view with one thread. Several of these
// render a view in parallel without pthreads (no SharedArrayBuffer, no special HTTP headers).
//
// Messages in:  {type: 'load', sceneId, bytes}
//               {type: 'strip', sceneId, frame, size, az, el, y0, rows}   (angles in radians)
// Messages out: {type: 'loaded', sceneId} | {type: 'error', sceneId, message}
//               {type: 'strip', sceneId, frame, y0, rows, rgba, ms}
'use strict';
importScripts('../../build-wasm/ecrf_decoder.js', 'viewer.js');

const wasmDir = new URL('../../build-wasm/', self.location.href).href;
const modulePromise = createEcrfDecoder({locateFile: (file) => wasmDir + file});
let decoder = null;
let sceneId = -1;

self.onmessage = async (ev) => {
  const msg = ev.data;
  const module = await modulePromise;  // messages are handled in order: one await each
  try {
    if (msg.type === 'load') {
      if (decoder) decoder.destroy();
      decoder = null;
      sceneId = msg.sceneId;
      const d = new ecrfWeb.EcrfDecoder(module);
      try {
        d.decode(msg.bytes);
      } catch (e) {
        d.destroy();
        throw e;
      }
      decoder = d;
      self.postMessage({type: 'loaded', sceneId});
    } else if (msg.type === 'strip') {
      if (!decoder || msg.sceneId !== sceneId) throw new Error('no such scene in this worker');
      const t0 = performance.now();
      const camera = ecrfWeb.stripCamera(
          ecrfWeb.orbitCamera(msg.size, msg.size, msg.az, msg.el, 4.0), msg.y0, msg.rows);
      const rgba = decoder.render(camera);
      for (let k = 3; k < rgba.length; k += 4) rgba[k] = 255;  // the colour has the background
      const ms = performance.now() - t0;
      self.postMessage({type: 'strip', sceneId: msg.sceneId, frame: msg.frame, y0: msg.y0,
                        rows: msg.rows, rgba, ms}, [rgba.buffer]);
    }
  } catch (e) {
    self.postMessage({type: 'error', sceneId: msg.sceneId, frame: msg.frame, message: String(e.message || e)});
  }
};
