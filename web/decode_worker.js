// Decode worker of the ecrf viewer (GPU path): decodes a stream once with the WebAssembly decoder
// and posts what a renderer of its own needs (EcrfDecoder.sceneData) back as transferables, so
// that the page never blocks on a decode and never holds a second copy of the grids.
//
// Message in:   {id, bytes, budgets}   (budgets: {workBudget, decodeBudget}, optional; the scene is
//                refused as the CPU renderer would refuse it: SPEC.md 8)
// Messages out: {type: 'decoded', id, version, decodeMs, scene} | {type: 'error', id, message}
'use strict';
importScripts('../build-wasm/ecrf_decoder.js', 'viewer.js');

const wasmDir = new URL('../build-wasm/', self.location.href).href;
const modulePromise = createEcrfDecoder({locateFile: (file) => wasmDir + file});

function transferables(scene) {
  const list = [scene.mlpParams.buffer];
  for (const g of [scene.density, scene.appearance]) {
    for (const t of [...g.planes, ...g.lines]) list.push(t.data.buffer);
  }
  if (scene.occupancy) list.push(scene.occupancy.bits.buffer);
  return list;
}

self.onmessage = async (ev) => {
  const {id, bytes} = ev.data;
  const budgets = ev.data.budgets || {};
  let decoder = null;
  try {
    decoder = new ecrfWeb.EcrfDecoder(await modulePromise);
    const t0 = performance.now();
    if (budgets.decodeBudget !== undefined) decoder.setDecodeBudget(budgets.decodeBudget);
    decoder.decode(bytes);
    const decodeMs = performance.now() - t0;
    decoder.checkRender(budgets.workBudget === undefined ? {} : {workBudget: budgets.workBudget});
    const scene = decoder.sceneData();
    const version = decoder.version();
    decoder.destroy();  // before posting: the wasm heap is the larger copy
    decoder = null;
    self.postMessage({type: 'decoded', id, version, decodeMs, scene}, transferables(scene));
  } catch (e) {
    self.postMessage({type: 'error', id, message: String((e && e.message) || e)});
  } finally {
    if (decoder) decoder.destroy();
  }
};
