// ecrf viewer: where scenes come from. Downloads with progress (streamed reads, total from
// Content-Length), local files, and a drop zone over the whole page.
'use strict';

(function () {
  const FILE_HINT = 'this page needs HTTP: serve the repository root over HTTP: python3 -m http.server, ' +
                    'then open http://localhost:8000/web/';

  function formatBytes(n) {
    if (n < 1024) return `${n} B`;
    if (n < 1024 * 1024) return `${(n / 1024).toFixed(1)} KiB`;
    return `${(n / (1024 * 1024)).toFixed(1)} MiB`;
  }

  // Resolves with the body as a Uint8Array; onProgress(received, total or 0) after every chunk.
  async function fetchScene(url, onProgress = () => {}, signal = undefined) {
    let response;
    try {
      response = await fetch(url, {signal});
    } catch (e) {
      if (e.name === 'AbortError') throw e;
      const hint = location.protocol === 'file:' ? FILE_HINT : 'network error, or a server without CORS';
      throw new Error(`${url}: ${e.message} (${hint})`);
    }
    if (!response.ok) throw new Error(`${url}: HTTP ${response.status} ${response.statusText}`.trim());
    const total = Number(response.headers.get('Content-Length')) || 0;
    if (!response.body) {
      const bytes = new Uint8Array(await response.arrayBuffer());
      onProgress(bytes.length, total);
      return bytes;
    }
    const reader = response.body.getReader();
    const chunks = [];
    let received = 0;
    onProgress(0, total);
    for (;;) {
      const {done, value} = await reader.read();
      if (done) break;
      chunks.push(value);
      received += value.length;
      onProgress(received, total);
    }
    if (chunks.length === 1) return chunks[0];
    const bytes = new Uint8Array(received);
    let pos = 0;
    for (const c of chunks) { bytes.set(c, pos); pos += c.length; }
    return bytes;
  }

  async function readFile(file) {
    return new Uint8Array(await file.arrayBuffer());
  }

  // Files dropped anywhere on the page go to onFile(file); `overlay` is shown while dragging.
  function installDropZone(overlay, onFile) {
    let depth = 0;  // dragenter / dragleave pairs of nested elements
    const hasFiles = (e) => e.dataTransfer && [...e.dataTransfer.types].includes('Files');
    const show = (on) => { overlay.hidden = !on; };
    window.addEventListener('dragenter', (e) => {
      if (!hasFiles(e)) return;
      e.preventDefault();
      ++depth;
      show(true);
    });
    window.addEventListener('dragover', (e) => {
      if (!hasFiles(e)) return;
      e.preventDefault();
      e.dataTransfer.dropEffect = 'copy';
    });
    window.addEventListener('dragleave', () => {
      depth = Math.max(0, depth - 1);
      if (!depth) show(false);
    });
    window.addEventListener('drop', (e) => {
      e.preventDefault();  // else the browser navigates to the file
      depth = 0;
      show(false);
      const file = e.dataTransfer && e.dataTransfer.files[0];
      if (file) onFile(file);
    });
  }

  globalThis.ecrfSource = {FILE_HINT, formatBytes, fetchScene, readFile, installDropZone};
})();
