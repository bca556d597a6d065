// Helpers shared by gpu_test.mjs and gpu_bench.mjs: PNG reading, image comparison (PSNR and the
// pixel criterion of SPEC.md 7.7), C99 hex-float parsing for the manifest cameras.
import {inflateSync} from 'node:zlib';

// 8-bit grey / RGB / RGBA, not interlaced. Returns {width, height, channels, data}.
export function readPng(bytes) {
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  if (view.getUint32(0) !== 0x89504e47) throw new Error('not a PNG');
  let pos = 8, width = 0, height = 0, channels = 0;
  const idat = [];
  while (pos + 8 <= bytes.length) {
    const len = view.getUint32(pos);
    const type = String.fromCharCode(...bytes.subarray(pos + 4, pos + 8));
    if (type === 'IHDR') {
      width = view.getUint32(pos + 8);
      height = view.getUint32(pos + 12);
      channels = {0: 1, 2: 3, 6: 4}[bytes[pos + 17]];
      if (bytes[pos + 16] !== 8 || !channels || bytes[pos + 20] !== 0) throw new Error('unsupported PNG format');
    } else if (type === 'IDAT') {
      idat.push(bytes.subarray(pos + 8, pos + 8 + len));
    } else if (type === 'IEND') {
      break;
    }
    pos += 12 + len;
  }
  const raw = inflateSync(Buffer.concat(idat));
  const stride = width * channels, out = new Uint8Array(stride * height);
  for (let y = 0; y < height; ++y) {
    const filter = raw[y * (stride + 1)];
    const src = raw.subarray(y * (stride + 1) + 1, (y + 1) * (stride + 1));
    const row = out.subarray(y * stride, (y + 1) * stride);
    const prev = y > 0 ? out.subarray((y - 1) * stride, y * stride) : new Uint8Array(stride);
    for (let i = 0; i < stride; ++i) {
      const a = i >= channels ? row[i - channels] : 0, b = prev[i], c = i >= channels ? prev[i - channels] : 0;
      let p = 0;
      if (filter === 1) p = a;
      else if (filter === 2) p = b;
      else if (filter === 3) p = (a + b) >> 1;
      else if (filter === 4) {
        const pa = Math.abs(b - c), pb = Math.abs(a - c), pc = Math.abs(a + b - 2 * c);
        p = pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      } else if (filter !== 0) throw new Error(`bad PNG filter ${filter}`);
      row[i] = (src[i] + p) & 255;
    }
  }
  return {width, height, channels, data: out};
}

// rgba: RGBA bytes; ref: {width, height, channels, data} or another RGBA byte array of the same
// size. PSNR over RGB; within2 = fraction of pixels whose largest channel difference is <= 2.
export function compare(rgba, ref, width, height) {
  const n = width * height, ch = ref.channels || 4, data = ref.data || ref;
  let se = 0, maxDiff = 0, within2 = 0;
  for (let p = 0; p < n; ++p) {
    let pd = 0;
    for (let k = 0; k < 3; ++k) {
      const d = rgba[4 * p + k] - data[ch * p + (ch === 1 ? 0 : k)];
      se += d * d;
      pd = Math.max(pd, Math.abs(d));
    }
    maxDiff = Math.max(maxDiff, pd);
    if (pd <= 2) ++within2;
  }
  const mse = se / (3 * n);
  return {psnr: mse === 0 ? Infinity : 10 * Math.log10((255 * 255) / mse), maxDiff, within2: within2 / n,
          over2: n - within2, pixels: n};
}

// "0x1.a2f9p+5", "-0x0p+0": exact (the values are binary32, a double holds them exactly).
export function parseHexFloat(s) {
  if (typeof s === 'number') return s;
  const m = /^([+-]?)0x([0-9a-f]*)(?:\.([0-9a-f]*))?p([+-]?\d+)$/i.exec(s.trim());
  if (!m) throw new Error(`not a hex float: ${s}`);
  const frac = m[3] || '';
  const mant = parseInt((m[2] || '0') + frac, 16);
  const v = mant * Math.pow(2, Number(m[4]) - 4 * frac.length);
  return m[1] === '-' ? -v : v;
}

export function manifestCamera(c) {
  return {c2w: c.c2w.map(parseHexFloat), fx: parseHexFloat(c.fx), fy: parseHexFloat(c.fy),
          cx: parseHexFloat(c.cx), cy: parseHexFloat(c.cy), width: c.width, height: c.height};
}

export const fromBase64 = (s) => new Uint8Array(Buffer.from(s, 'base64'));
export const fmtPsnr = (v) => (v === Infinity ? 'inf' : v.toFixed(2));
