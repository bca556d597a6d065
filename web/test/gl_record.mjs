// Records the GL calls of the viewer's WebGL2 renderer (web/gpu_renderer.js + web/gpu_shaders.js,
// unchanged) into binary traces that benchmarks/gl_replay.cc replays on a GPU without a browser.
// The renderer gets a mock WebGL2 context that answers its queries (typical desktop limits, every
// shader compiles) and writes down every call: shader sources, programs, textures with their
// data, uniforms, UBOs, draws, viewports, framebuffer binds, readPixels.
//
// Per scene: NAME.setup.glt (new GpuRenderer + setScene: textures, UBOs, programs) and per size
// NAME_WxH.frame.glt (render(camera, options) twice: the first is the warm-up that creates the
// render target, the second, between two marks, is the frame the replay times; then readPixels()),
// NAME_WxH.camera.json (the camera, also in the transforms.json form of `ecrf render --path`).
// Each size is recorded on a fresh renderer; its setup must come out byte-identical (checked), so
// the setup is stored once per scene.
//
//   node web/test/gl_record.mjs SCENE.ecrf --out DIR [--name NAME] [--sizes 800x800,1920x1080]
//        [--manifest (the camera of SCENE in tests/conformance/manifest.json; its own size is
//         "manifest" in --sizes) | --camera FILE.json|'{"c2w":[..],"fx":..}' | --view '{"az":-60,"el":26,"radius":4}']
//        [--options '{"earlyStop":0}'] [--renderer-options '{"mlpWeights":"texture"}' (GpuRenderer's)]
//
// Cameras at other sizes keep the base camera's intrinsics, scaled by min(W / W0, H / H0) and
// centred (the viewer's rule: a wide image keeps the field of view of its short side). Without a
// camera: the viewer's default view (ecrfCamera.DEFAULT_VIEW, or the reference camera's home
// view of a forward-facing scene). Options: the viewer's ({finish: true}, default early stop)
// merged with --options. Scene data: EcrfDecoder.sceneData() of web/viewer.js on the WebAssembly
// decoder (build-wasm/, scripts/build-wasm.sh), as the page's decode worker does.
import {createHash} from 'node:crypto';
import {mkdirSync, readFileSync, writeFileSync, existsSync} from 'node:fs';
import {createRequire} from 'node:module';
import {basename, dirname, join} from 'node:path';
import {fileURLToPath} from 'node:url';
import {manifestCamera, parseHexFloat} from './gpu_common.mjs';

const require = createRequire(import.meta.url);
const root = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
const f32 = Math.fround;

// ---- trace format (little-endian; must match benchmarks/gl_replay.cc) ----
export const MAGIC = 'ECRFGLT1';
export const KIND = {setup: 1, frame: 2};
export const OP = {
  END: 0, CREATE: 1, DELETE: 2, SHADER_SOURCE: 3, COMPILE_SHADER: 4, ATTACH_SHADER: 5, LINK_PROGRAM: 6,
  USE_PROGRAM: 7, UNIFORM_BLOCK_BINDING: 8, UNIFORM: 9, ACTIVE_TEXTURE: 10, BIND_TEXTURE: 11,
  TEX_PARAMETERI: 12, PIXEL_STOREI: 13, TEX_IMAGE: 14, TEX_STORAGE_2D: 15, BIND_BUFFER: 16,
  BUFFER_DATA: 17, BIND_BUFFER_BASE: 18, BIND_FRAMEBUFFER: 19, FRAMEBUFFER_TEXTURE_2D: 20,
  BIND_VERTEX_ARRAY: 21, VIEWPORT: 22, SCISSOR: 23, ENABLE: 24, DISABLE: 25, DRAW_ARRAYS: 26,
  READ_PIXELS: 27, MARK: 28,
};
export const OBJ = {texture: 1, buffer: 2, framebuffer: 3, vertexArray: 4, program: 5, shader: 6};
export const MARK = {frameBegin: 2, frameEnd: 3};

// The limits the mock reports (a desktop GPU through ANGLE/Chrome; the replay checks the real GPU
// has at least these).
export const LIMITS = {
  MAX_TEXTURE_SIZE: 32768, MAX_3D_TEXTURE_SIZE: 16384, MAX_ARRAY_TEXTURE_LAYERS: 2048,
  MAX_UNIFORM_BLOCK_SIZE: 65536, MAX_FRAGMENT_UNIFORM_BLOCKS: 14, MAX_FRAGMENT_UNIFORM_VECTORS: 1024,
  MAX_TEXTURE_IMAGE_UNITS: 16, MAX_VIEWPORT_DIMS: [32768, 32768],
};

// WebGL2 = GLES 3.0 enum values (only those gpu_renderer.js reads).
const GL = {
  NO_ERROR: 0, OUT_OF_MEMORY: 0x0505, INVALID_INDEX: 0xffffffff, TRIANGLES: 0x0004, BLEND: 0x0be2,
  SCISSOR_TEST: 0x0c11, CLAMP_TO_EDGE: 0x812f, NEAREST: 0x2600, LINEAR: 0x2601, COLOR_ATTACHMENT0: 0x8ce0,
  FRAMEBUFFER: 0x8d40, COMPILE_STATUS: 0x8b81, LINK_STATUS: 0x8b82, VERTEX_SHADER: 0x8b31,
  FRAGMENT_SHADER: 0x8b30, FLOAT: 0x1406, UNSIGNED_BYTE: 0x1401, RGBA: 0x1908, RGBA32F: 0x8814,
  RGBA8: 0x8058, R8UI: 0x8232, RED_INTEGER: 0x8d94, TEXTURE0: 0x84c0, TEXTURE_2D: 0x0de1,
  TEXTURE_2D_ARRAY: 0x8c1a, TEXTURE_3D: 0x806f, TEXTURE_MAG_FILTER: 0x2800, TEXTURE_MIN_FILTER: 0x2801,
  TEXTURE_WRAP_S: 0x2802, TEXTURE_WRAP_T: 0x2803, TEXTURE_WRAP_R: 0x8072, UNIFORM_BUFFER: 0x8a11,
  STATIC_DRAW: 0x88e4, UNPACK_ALIGNMENT: 0x0cf5,
  MAX_TEXTURE_SIZE: 0x0d33, MAX_3D_TEXTURE_SIZE: 0x8073, MAX_ARRAY_TEXTURE_LAYERS: 0x88ff,
  MAX_UNIFORM_BLOCK_SIZE: 0x8a30, MAX_FRAGMENT_UNIFORM_BLOCKS: 0x8a2d, MAX_FRAGMENT_UNIFORM_VECTORS: 0x8dfd,
  MAX_TEXTURE_IMAGE_UNITS: 0x8872, MAX_VIEWPORT_DIMS: 0x0d3a,
};

class Writer {
  constructor() { this.chunks = []; this.calls = 0; }
  u32(v) { const b = Buffer.alloc(4); b.writeUInt32LE(v >>> 0); this.chunks.push(b); }
  i32(v) { const b = Buffer.alloc(4); b.writeInt32LE(v | 0); this.chunks.push(b); }
  str(s) { const b = Buffer.from(s, 'utf8'); this.u32(b.length); this.chunks.push(b); }
  bytes(view) {  // a copy: the renderer may reuse its arrays
    const b = Buffer.from(new Uint8Array(view.buffer, view.byteOffset, view.byteLength));
    this.u32(b.length);
    this.chunks.push(b);
  }
  // One call: u32 op, u32 payload length, payload.
  call(op, fill) {
    const sub = new Writer();
    fill(sub);
    const body = Buffer.concat(sub.chunks);
    this.u32(op);
    this.u32(body.length);
    this.chunks.push(body);
    ++this.calls;
  }
  buffer() { return Buffer.concat(this.chunks); }
}

// The mock WebGL2 context. Objects are small ids (per kind, from 1); every call goes to `rec`,
// a Writer that the recorder swaps between the setup and the frame files.
function mockContext(canvas, state) {
  const next = {};
  const make = (kind, extra = {}) => {
    const id = (next[kind] = (next[kind] || 0) + 1);
    return {kind, id, ...extra};
  };
  const idOf = (o, kind) => {
    if (o === null || o === undefined) return 0;
    if (o.kind !== kind) throw new Error(`mock WebGL2: expected a ${Object.keys(OBJ).find((k) => OBJ[k] === kind)}, got ${JSON.stringify(o)}`);
    return o.id;
  };
  const rec = (op, fill = () => {}) => state.rec.call(op, fill);
  const create = (kind, shaderType = 0) => () => {
    const o = make(kind, kind === OBJ.program ? {blocks: []} : {});
    rec(OP.CREATE, (w) => { w.u32(kind); w.u32(o.id); w.u32(shaderType); });
    return o;
  };
  const del = (kind) => (o) => {
    if (!o) return;
    rec(OP.DELETE, (w) => { w.u32(kind); w.u32(idOf(o, kind)); });
  };
  const uniform = (type, comps, vector) => (loc, ...args) => {
    if (loc === null || loc === undefined) return;
    const vals = vector ? Array.from(args[0]) : args;
    if (vals.length === 0 || vals.length % comps !== 0) throw new Error(`mock WebGL2: uniform ${loc.name}: ${vals.length} values for ${comps} components`);
    const arr = type === 0 ? Float32Array.from(vals) : Int32Array.from(vals);
    rec(OP.UNIFORM, (w) => {
      w.u32(loc.prog); w.str(loc.name); w.u32(type); w.u32(comps); w.u32(vals.length / comps); w.bytes(arr);
    });
  };
  const dataOf = (data) => {
    if (data === null || data === undefined) return null;
    if (!ArrayBuffer.isView(data)) throw new Error('mock WebGL2: pixel data must be a typed array');
    return data;
  };
  const gl = {
    ...GL,
    canvas,
    get drawingBufferWidth() { return canvas.width; },
    get drawingBufferHeight() { return canvas.height; },
    getParameter(p) {
      for (const [name, v] of Object.entries(LIMITS)) if (GL[name] === p) return Array.isArray(v) ? Int32Array.from(v) : v;
      throw new Error(`mock WebGL2: getParameter(0x${p.toString(16)}) is not mocked`);
    },
    getExtension: () => null,
    getError: () => GL.NO_ERROR,
    isContextLost: () => false,
    createShader: (type) => create(OBJ.shader, type)(),
    shaderSource(sh, src) { rec(OP.SHADER_SOURCE, (w) => { w.u32(idOf(sh, OBJ.shader)); w.str(src); }); },
    compileShader(sh) { rec(OP.COMPILE_SHADER, (w) => w.u32(idOf(sh, OBJ.shader))); },
    getShaderParameter: () => true,
    getShaderInfoLog: () => '',
    deleteShader: del(OBJ.shader),
    createProgram: create(OBJ.program),
    attachShader(p, sh) { rec(OP.ATTACH_SHADER, (w) => { w.u32(idOf(p, OBJ.program)); w.u32(idOf(sh, OBJ.shader)); }); },
    linkProgram(p) { rec(OP.LINK_PROGRAM, (w) => w.u32(idOf(p, OBJ.program))); },
    getProgramParameter: () => true,
    getProgramInfoLog: () => '',
    deleteProgram: del(OBJ.program),
    useProgram(p) { rec(OP.USE_PROGRAM, (w) => w.u32(idOf(p, OBJ.program))); },
    getUniformLocation: (p, name) => ({prog: idOf(p, OBJ.program), name}),
    // Block indices are resolved by name in the replay: the mock hands out its own indices.
    getUniformBlockIndex(p, name) {
      idOf(p, OBJ.program);
      p.blocks.push(name);
      return p.blocks.length - 1;
    },
    uniformBlockBinding(p, index, binding) {
      const name = p.blocks[index];
      if (name === undefined) throw new Error(`mock WebGL2: uniformBlockBinding of unknown block index ${index}`);
      rec(OP.UNIFORM_BLOCK_BINDING, (w) => { w.u32(idOf(p, OBJ.program)); w.str(name); w.u32(binding); });
    },
    uniform1i: uniform(1, 1, false), uniform1f: uniform(0, 1, false), uniform2f: uniform(0, 2, false),
    uniform3f: uniform(0, 3, false), uniform3fv: uniform(0, 3, true), uniform3iv: uniform(1, 3, true),
    uniform4fv: uniform(0, 4, true),
    createTexture: create(OBJ.texture),
    deleteTexture: del(OBJ.texture),
    activeTexture(unit) { rec(OP.ACTIVE_TEXTURE, (w) => w.u32(unit)); },
    bindTexture(target, t) { rec(OP.BIND_TEXTURE, (w) => { w.u32(target); w.u32(idOf(t, OBJ.texture)); }); },
    texParameteri(target, pname, v) { rec(OP.TEX_PARAMETERI, (w) => { w.u32(target); w.u32(pname); w.i32(v); }); },
    pixelStorei(pname, v) { rec(OP.PIXEL_STOREI, (w) => { w.u32(pname); w.i32(v); }); },
    texImage2D(target, level, internal, width, height, border, format, type, data) {
      if (arguments.length !== 9) throw new Error(`mock WebGL2: texImage2D with ${arguments.length} arguments is not mocked`);
      const d = dataOf(data);
      rec(OP.TEX_IMAGE, (w) => {
        for (const v of [target, level, internal, width, height, 1, border, format, type]) w.u32(v);
        w.u32(d ? 1 : 0);
        if (d) w.bytes(d);
      });
    },
    texImage3D(target, level, internal, width, height, depth, border, format, type, data) {
      if (arguments.length !== 10) throw new Error(`mock WebGL2: texImage3D with ${arguments.length} arguments is not mocked`);
      const d = dataOf(data);
      rec(OP.TEX_IMAGE, (w) => {
        for (const v of [target, level, internal, width, height, depth, border, format, type]) w.u32(v);
        w.u32(d ? 1 : 0);
        if (d) w.bytes(d);
      });
    },
    texStorage2D(target, levels, internal, width, height) {
      rec(OP.TEX_STORAGE_2D, (w) => { for (const v of [target, levels, internal, width, height]) w.u32(v); });
    },
    createBuffer: create(OBJ.buffer),
    deleteBuffer: del(OBJ.buffer),
    bindBuffer(target, b) { rec(OP.BIND_BUFFER, (w) => { w.u32(target); w.u32(idOf(b, OBJ.buffer)); }); },
    bufferData(target, data, usage) {
      if (!ArrayBuffer.isView(data)) throw new Error('mock WebGL2: bufferData with a size is not mocked');
      rec(OP.BUFFER_DATA, (w) => { w.u32(target); w.u32(usage); w.bytes(data); });
    },
    bindBufferBase(target, index, b) { rec(OP.BIND_BUFFER_BASE, (w) => { w.u32(target); w.u32(index); w.u32(idOf(b, OBJ.buffer)); }); },
    createFramebuffer: create(OBJ.framebuffer),
    deleteFramebuffer: del(OBJ.framebuffer),
    bindFramebuffer(target, f) { rec(OP.BIND_FRAMEBUFFER, (w) => { w.u32(target); w.u32(idOf(f, OBJ.framebuffer)); }); },
    framebufferTexture2D(target, attachment, textarget, t, level) {
      rec(OP.FRAMEBUFFER_TEXTURE_2D, (w) => { for (const v of [target, attachment, textarget, idOf(t, OBJ.texture), level]) w.u32(v); });
    },
    createVertexArray: create(OBJ.vertexArray),
    deleteVertexArray: del(OBJ.vertexArray),
    bindVertexArray(v) { rec(OP.BIND_VERTEX_ARRAY, (w) => w.u32(idOf(v, OBJ.vertexArray))); },
    viewport(x, y, width, height) { rec(OP.VIEWPORT, (w) => { for (const v of [x, y, width, height]) w.i32(v); }); },
    scissor(x, y, width, height) { rec(OP.SCISSOR, (w) => { for (const v of [x, y, width, height]) w.i32(v); }); },
    enable(cap) { rec(OP.ENABLE, (w) => w.u32(cap)); },
    disable(cap) { rec(OP.DISABLE, (w) => w.u32(cap)); },
    drawArrays(mode, first, count) { rec(OP.DRAW_ARRAYS, (w) => { w.u32(mode); w.i32(first); w.i32(count); }); },
    readPixels(x, y, width, height, format, type, out) {
      rec(OP.READ_PIXELS, (w) => { for (const v of [x, y, width, height, format, type]) w.i32(v); });
      if (out && out.fill) out.fill(0);  // the mock has no pixels
    },
  };
  // Anything the renderer calls that is not above is an error, not a silent no-op.
  return new Proxy(gl, {
    get(t, prop) {
      if (prop in t || typeof prop === 'symbol') return t[prop];
      throw new Error(`mock WebGL2: gl.${String(prop)} is not mocked`);
    },
  });
}

function header(kind, meta, fields) {
  const w = new Writer();
  w.chunks.push(Buffer.from(MAGIC, 'latin1'));
  w.u32(kind);
  w.str(JSON.stringify(meta));
  fields(w);
  return w.buffer();
}

// The calls of a trace file: u32 count (the end marker included), the calls, the end marker.
function callSection(calls) {
  const end = new Writer();
  end.call(OP.END, () => {});
  const n = Buffer.alloc(4);
  n.writeUInt32LE(calls.calls + 1);
  return Buffer.concat([n, calls.buffer(), end.buffer()]);
}

// ---- cameras ----
function scaledCamera(base, W, H) {
  if (W === base.width && H === base.height) return {...base, c2w: [...base.c2w]};
  const s = Math.min(W / base.width, H / base.height);
  return {c2w: [...base.c2w], fx: f32(base.fx * s), fy: f32(base.fy * s),
          cx: f32(base.cx * s + (W - base.width * s) / 2), cy: f32(base.cy * s + (H - base.height * s) / 2),
          width: W, height: H};
}

// c: {c2w, fx, fy, cx, cy, width, height} (numbers or C99 hex floats), or a NAME_WxH.camera.json
// of this script ({camera: ...}).
function parseCamera(c) {
  if (c && c.camera) c = c.camera;
  if (!c || !Array.isArray(c.c2w)) throw new Error('--camera: needs {c2w: 12 numbers (3x4 row-major), fx, fy, cx, cy, width, height}');
  const num = (v) => (typeof v === 'string' ? parseHexFloat(v) : Number(v));
  const cam = {c2w: c.c2w.map(num), fx: num(c.fx), fy: num(c.fy), cx: num(c.cx), cy: num(c.cy),
               width: c.width | 0, height: c.height | 0};
  if (cam.c2w.length !== 12 || ![cam.fx, cam.fy, cam.cx, cam.cy].every(Number.isFinite) || cam.width < 1 || cam.height < 1) {
    throw new Error('--camera: needs {c2w: 12 numbers (3x4 row-major), fx, fy, cx, cy, width, height}');
  }
  return cam;
}

// `ecrf render --path` input (transforms.json convention) for exactly this camera.
function transformsJson(cam) {
  const c = cam.c2w;
  return {fl_x: cam.fx, fl_y: cam.fy, cx: cam.cx, cy: cam.cy, w: cam.width, h: cam.height,
          frames: [{transform_matrix: [c.slice(0, 4), c.slice(4, 8), c.slice(8, 12), [0, 0, 0, 1]]}]};
}

// ---- main ----
function parseArgs(argv) {
  const a = {sizes: null, out: null, name: null, manifest: false, camera: null, view: null, options: {},
             rendererOptions: {}, file: null};
  for (let i = 0; i < argv.length; ++i) {
    const k = argv[i], v = () => { if (i + 1 >= argv.length) throw new Error(`${k} needs a value`); return argv[++i]; };
    if (k === '--out') a.out = v();
    else if (k === '--name') a.name = v();
    else if (k === '--sizes') a.sizes = v().split(',');
    else if (k === '--manifest') a.manifest = true;
    else if (k === '--camera') { const s = v(); a.camera = JSON.parse(s.trim().startsWith('{') ? s : readFileSync(s, 'utf8')); }
    else if (k === '--view') a.view = JSON.parse(v());
    else if (k === '--options') a.options = JSON.parse(v());
    else if (k === '--renderer-options') a.rendererOptions = JSON.parse(v());
    else if (k === '-h' || k === '--help') { console.log(readFileSync(fileURLToPath(import.meta.url), 'utf8').split('\n').filter((l) => l.startsWith('//')).join('\n')); process.exit(0); }
    else if (k.startsWith('-')) throw new Error(`unknown flag ${k}`);
    else if (!a.file) a.file = k;
    else throw new Error(`unexpected argument ${k}`);
  }
  if (!a.file || !a.out) throw new Error('usage: node web/test/gl_record.mjs SCENE.ecrf --out DIR [--name NAME] [--sizes WxH,...] [--manifest | --camera JSON | --view JSON] [--options JSON]');
  return a;
}

async function main() {
  const args = parseArgs(process.argv.slice(2));
  const wasmJs = join(root, 'build-wasm', 'ecrf_decoder.js');
  if (!existsSync(wasmJs)) throw new Error(`${wasmJs} is missing: bash scripts/build-wasm.sh`);
  const createEcrfDecoder = require(wasmJs);
  const web = require(join(root, 'web', 'viewer.js'));
  globalThis.ecrfWeb = web;
  require(join(root, 'web', 'camera_controls.js'));
  const cameraLib = globalThis.ecrfCamera;
  const shaders = require(join(root, 'web', 'gpu_shaders.js'));
  globalThis.ecrfGpuShaders = shaders;
  const {GpuRenderer} = require(join(root, 'web', 'gpu_renderer.js'));

  const module = await createEcrfDecoder({wasmBinary: readFileSync(join(root, 'build-wasm', 'ecrf_decoder.wasm'))});
  const stream = new Uint8Array(readFileSync(args.file));
  const dec = new web.EcrfDecoder(module);
  dec.decode(stream);
  const sceneData = dec.sceneData();
  const info = sceneData.info;
  const name = args.name || basename(args.file).replace(/\.ecrf$/, '');

  // The base camera and the sizes.
  let base = null, view = null, sizes = args.sizes;
  if (args.manifest) {
    const manifest = JSON.parse(readFileSync(join(root, 'tests/conformance/manifest.json'), 'utf8'));
    const v = manifest.scene_vectors.find((x) => x.file === basename(args.file));
    if (!v) throw new Error(`${basename(args.file)} is not a scene vector of tests/conformance/manifest.json`);
    base = manifestCamera(v.render.camera);
    sizes = sizes || ['manifest'];
  } else if (args.camera) {
    base = parseCamera(args.camera);
  } else {
    view = cameraLib.normalizeView(args.view || (info.sceneModel === 2 && info.ndcFrame
      ? cameraLib.forwardHomeView(info.ndcFrame) : cameraLib.DEFAULT_VIEW));
  }
  sizes = (sizes || ['800x800', '1920x1080']).map((s) => {
    if (s === 'manifest') {
      if (!base) throw new Error('size "manifest" needs --manifest or --camera');
      return [base.width, base.height];
    }
    const m = /^(\d+)x(\d+)$/.exec(s);
    if (!m) throw new Error(`bad size ${s} (WxH)`);
    return [Number(m[1]), Number(m[2])];
  });
  const options = {finish: true, ...args.options};
  mkdirSync(args.out, {recursive: true});

  let setupBytes = null, setupFile = null, setupId = null;
  const written = [];
  for (const [W, H] of sizes) {
    const camera = base ? scaledCamera(base, W, H) : cameraLib.viewCamera(view, W, H);
    const canvas = {width: W, height: H};
    const state = {rec: new Writer()};
    canvas.getContext = (type) => (type === 'webgl2' ? (canvas.gl ||= mockContext(canvas, state)) : null);
    const r = new GpuRenderer(canvas, args.rendererOptions);
    r.setScene(sceneData);
    const setupBody = state.rec;
    // Setup: identical for every size (a fresh renderer each time), stored once.
    const meta = {scene: basename(args.file), name, sceneModel: info.sceneModel, gridRes: info.gridRes,
                  limits: LIMITS, rendererOptions: args.rendererOptions, stats: r.stats, recorder: 'web/test/gl_record.mjs'};
    const body = callSection(setupBody);
    if (setupBytes === null) {
      setupId = createHash('sha256').update(body).digest('hex').slice(0, 32);
      setupBytes = body;
      setupFile = `${name}.setup.glt`;
      const limitPairs = Object.entries(LIMITS).map(([k, v]) => [GL[k], Array.isArray(v) ? Math.min(...v) : v]);
      const head = header(KIND.setup, meta, (w) => {
        w.str(setupId);
        w.u32(limitPairs.length);
        for (const [e, v] of limitPairs) { w.u32(e); w.i32(v); }
      });
      writeFileSync(join(args.out, setupFile), Buffer.concat([head, body]));
      written.push(setupFile);
    } else if (!body.equals(setupBytes)) {
      throw new Error(`${name}: the setup at ${W}x${H} differs from the first size's (the renderer's setScene depends on the size?)`);
    }
    // Frame: the warm-up render (creates the render target), the timed render, the image.
    state.rec = new Writer();
    r.render(camera, options);
    state.rec.call(OP.MARK, (w) => w.u32(MARK.frameBegin));
    r.render(camera, options);
    state.rec.call(OP.MARK, (w) => w.u32(MARK.frameEnd));
    r.readPixels();
    const frameFile = `${name}_${W}x${H}.frame.glt`;
    const frameMeta = {...meta, width: W, height: H, camera, options, setup: setupFile};
    const head = header(KIND.frame, frameMeta, (w) => {
      w.str(setupFile);
      w.str(setupId);
      for (const v of [W, H, canvas.width, canvas.height]) w.u32(v);
    });
    writeFileSync(join(args.out, frameFile), Buffer.concat([head, callSection(state.rec)]));
    writeFileSync(join(args.out, `${name}_${W}x${H}.camera.json`),
                  JSON.stringify({name, scene: args.file, camera, options, transforms: transformsJson(camera)}, null, 1) + '\n');
    written.push(frameFile);
  }
  dec.destroy();
  console.log(JSON.stringify({scene: args.file, name, sceneModel: info.sceneModel, out: args.out, files: written,
                              setupBytes: setupBytes.length, options}));
}

main().catch((e) => {
  console.error(`gl_record: ${e.message}`);
  process.exit(1);
});
