// WebGL2 renderer of a decoded ecrf scene (EcrfDecoder.sceneData() of web/viewer.js): the
// reference process of SPEC.md section 7 in one fragment shader per pixel, for every scene model
// (object 7.2; unbounded 7.2.1, contracted sampling; forward-facing 7.2.2, the NDC line), with the
// 7.8 accelerations that keep the image (empty-space skipping) and the optional knobs (early stop,
// step scale, weight threshold; deferred: for a per-sample head, the MLP once per pixel on the
// weight-averaged products, an approximation, off by default). A stream with the deferred head
// (SPEC.md 7.6) is rendered by its own process: the MLP once per pixel on the weighted sum. Shader sources: web/gpu_shaders.js (load it first).
//
//   const r = new ecrfGpu.GpuRenderer(canvas);   r.setScene(decoder.sceneData());
//   r.render(ecrfWeb.orbitCamera(w, h, az, el, 4), {earlyStop: 1e-4});   r.readPixels();
//
// Grids: one RGBA32F 2D texture array per mode (4 ranks per layer, [rows along v][cols along u])
// and one RGBA32F 2D texture per grid for the lines (row = mode's rank group, column = position).
// All interpolation is done by hand with texelFetch, as 7.4 writes it. MLP weights: std140 UBOs
// (uniform reads are broadcast to all lanes), split into blocks of at most MAX_UNIFORM_BLOCK_SIZE;
// one RGBA32F texture instead when the blocks exceed the GPU's limits (or {mlpWeights: 'texture'}).
// render() options beyond the documented ones: deferred (bool), bandRows (draw in bands of rows),
// skipEmptySpace (default true; false: every sample tested one by one, as ecrf --no-skip).
'use strict';

(function () {
  const f32 = Math.fround;
  const shaders = typeof globalThis.ecrfGpuShaders !== 'undefined' ? globalThis.ecrfGpuShaders
      : (typeof require === 'function' ? require('./gpu_shaders.js') : null);
  const BLOCK_LEVELS = [16, 4];  // mask cells per empty-space block edge, coarse to fine (as 7.8)
  const UNITS = {uDP0: 0, uDP1: 1, uDP2: 2, uAP0: 3, uAP1: 4, uAP2: 5, uDL: 6, uAL: 7, uCam: 8,
                 uOcc: 9, uBlk0: 10, uBlk1: 11, uWT: 12};

  function createContext(canvas) {
    return canvas.getContext('webgl2', {antialias: false, depth: false, stencil: false, alpha: false,
                                        premultipliedAlpha: false, preserveDrawingBuffer: false});
  }

  function queryLimits(gl) {
    return {
      maxTextureSize: gl.getParameter(gl.MAX_TEXTURE_SIZE),
      max3DTextureSize: gl.getParameter(gl.MAX_3D_TEXTURE_SIZE),
      maxArrayTextureLayers: gl.getParameter(gl.MAX_ARRAY_TEXTURE_LAYERS),
      maxUniformBlockSize: gl.getParameter(gl.MAX_UNIFORM_BLOCK_SIZE),
      maxFragmentUniformBlocks: gl.getParameter(gl.MAX_FRAGMENT_UNIFORM_BLOCKS),
      maxFragmentUniformVectors: gl.getParameter(gl.MAX_FRAGMENT_UNIFORM_VECTORS),
      maxTextureUnits: gl.getParameter(gl.MAX_TEXTURE_IMAGE_UNITS),
      maxViewport: gl.getParameter(gl.MAX_VIEWPORT_DIMS),
    };
  }

  const groups = (r) => (r + 3) >> 2;

  // MLP weights as UBO blocks. Each layer is stored as 4-row chunks (4 * len4 vec4s) that never
  // straddle a block; a run is a stretch of chunks in one block, looped over by the shader.
  function packMlp(field, params, aRanks, aGroupOff, P4, capVec4) {
    const {features: F, products: P, hidden: H, featureFreqs: Ff, viewdirFreqs: Fv, inputs: In} = field.mlp;
    // Hidden layers (SPEC 6.6): with one, W2 and b2 are absent and W3 reads the first layer.
    const L = field.mlp.layers || 2;
    if (L !== 1 && L !== 2) throw new Error(`MLP: ${L} hidden layers, not 1 or 2`);
    const H2 = L === 2 ? H : 0;
    if (In !== F + 3 + 2 * F * Ff + 6 * Fv) throw new Error(`MLP: ${In} inputs do not match F=${F}, Ff=${Ff}, Fv=${Fv}`);
    if (P !== aRanks[0] + aRanks[1] + aRanks[2]) throw new Error(`MLP: ${P} products, appearance ranks sum to ${aRanks[0] + aRanks[1] + aRanks[2]}`);
    const expect = F * P + H * In + H + H2 * H2 + H2 + 3 * H + 3;
    if (params.length !== expect) throw new Error(`MLP: ${params.length} parameters, expected ${expect}`);
    const F4 = groups(F), H4 = groups(H), IN4 = F4 + 1 + 2 * Ff * F4 + 2 * Fv;
    // Lane of the shader's padded input -> column of the stored matrix (-1: padding, weight 0).
    const prodCol = new Int32Array(4 * P4).fill(-1);
    for (let m = 0, off = 0; m < 3; off += aRanks[m], ++m) {
      for (let r = 0; r < aRanks[m]; ++r) prodCol[4 * aGroupOff[m] + r] = off + r;
    }
    const inCol = new Int32Array(4 * IN4).fill(-1);
    for (let c = 0; c < F; ++c) inCol[c] = c;
    for (let c = 0; c < 3; ++c) inCol[4 * F4 + c] = F + c;
    for (let q = 0; q < Ff; ++q) {
      for (let c = 0; c < F; ++c) {
        inCol[4 * (F4 + 1 + q * F4) + c] = F + 3 + c * Ff + q;
        inCol[4 * (F4 + 1 + Ff * F4 + q * F4) + c] = F + 3 + F * Ff + c * Ff + q;
      }
    }
    for (let q = 0; q < Fv; ++q) {
      for (let c = 0; c < 3; ++c) {
        inCol[4 * (F4 + 1 + 2 * Ff * F4 + q) + c] = F + 3 + 2 * F * Ff + c * Fv + q;
        inCol[4 * (F4 + 1 + 2 * Ff * F4 + Fv + q) + c] = F + 3 + 2 * F * Ff + 3 * Fv + c * Fv + q;
      }
    }
    let p = 0;
    const take = (n) => { const a = params.subarray(p, p + n); p += n; return a; };
    const B = take(F * P), W1 = take(H * In), b1 = take(H), W2 = take(H2 * H2), b2 = take(H2);
    const W3 = take(3 * H), b3 = take(3);
    const blocks = [];  // arrays of numbers (floats), 4 per vec4
    const layer = (rows, cols, W, colMap, len4) => {
      const runs = [];
      const need = 16 * len4;  // floats of one 4-row chunk
      if (need > 4 * capVec4) throw new Error(`MLP: a row of ${len4} vec4s exceeds the uniform block size limit`);
      for (let o4 = 0; o4 < groups(rows); ++o4) {
        let blk = blocks[blocks.length - 1];
        if (!blk || blk.length + need > 4 * capVec4) blocks.push(blk = []);
        const last = runs[runs.length - 1];
        const offset = blk.length / 4;
        if (last && last.block === blocks.length - 1 && last.o4End === o4) ++last.o4End;
        else runs.push({block: blocks.length - 1, offset, o4Begin: o4, o4End: o4 + 1});
        for (let o = 4 * o4; o < 4 * o4 + 4; ++o) {
          for (let l = 0; l < 4 * len4; ++l) {
            const c = colMap ? colMap[l] : (l < cols ? l : -1);
            blk.push(o < rows && c >= 0 ? W[o * cols + c] : 0);
          }
        }
      }
      return {runs, rows};
    };
    const layers = {basis: layer(F, P, B, prodCol, P4), w1: layer(H, In, W1, inCol, IN4),
                    w2: layer(H2, H2, W2, null, H4), w3: layer(3, H, W3, null, H4)};
    const padBias = (b, n4) => { const o = new Float32Array(4 * n4); o.set(b); return o; };
    return {F4, H4, IN4, FF: Ff, FV: Fv, hiddenLayers: L, layers, blocks: blocks.map((b) => new Float32Array(b)),
            b1: padBias(b1, Math.max(H4, 1)), b2: padBias(b2, Math.max(H4, 1)), b3: padBias(b3, 1)};
  }

  class GpuRenderer {
    static isSupported() {
      try {
        const canvas = typeof OffscreenCanvas !== 'undefined' ? new OffscreenCanvas(1, 1)
            : (typeof document !== 'undefined' ? document.createElement('canvas') : null);
        const gl = canvas && createContext(canvas);
        if (!gl || !shaders) return false;
        const l = queryLimits(gl);
        const ok = l.maxTextureUnits >= 13 && l.maxFragmentUniformBlocks >= 1;
        const lose = gl.getExtension('WEBGL_lose_context');
        if (lose) lose.loseContext();
        return ok;
      } catch {
        return false;
      }
    }

    // options.limits overrides queried GL limits (lower only; tests fake a small GPU with it).
    constructor(canvas, options = {}) {
      if (!shaders) throw new Error('GpuRenderer: load web/gpu_shaders.js before gpu_renderer.js');
      const gl = createContext(canvas);
      if (!gl) throw new Error('GpuRenderer: WebGL2 is not available in this browser (or the canvas already has another context)');
      this.canvas = canvas;
      this.gl = gl;
      this.limits = {...queryLimits(gl), ...(options.limits || {})};
      // Where the MLP weights live: UBOs (uniform loads, which GPUs broadcast to all lanes) or one
      // RGBA32F texture. 'auto': UBOs when they fit the GPU's limits (on SwiftShader the texture
      // path is only ~7% faster: not worth a special case).
      this.mlpWeights = options.mlpWeights || 'auto';
      if (!['auto', 'ubo', 'texture'].includes(this.mlpWeights)) throw new Error(`GpuRenderer: mlpWeights '${this.mlpWeights}' is not auto, ubo or texture`);
      if (this.limits.maxTextureUnits < 13) throw new Error(`GpuRenderer: needs 13 texture units, the GPU has ${this.limits.maxTextureUnits}`);
      this.vao = gl.createVertexArray();
      this.display = this._program(shaders.displayShader);
      this.scene = null;
      this.target = null;  // {tex, fbo, width, height}
      this.camTex = gl.createTexture();
      this.stats = {textureBytes: 0, uniformBytes: 0, samplesPerRay: 0};
      // Stand-ins for absent tensors (rank-0 modes, no mask): a sampler must see a complete texture.
      this.dummyArray = this._texture(gl.TEXTURE_2D_ARRAY, gl.RGBA32F, 1, 1, 1, gl.RGBA, gl.FLOAT, new Float32Array(4));
      this.dummy3D = this._texture(gl.TEXTURE_3D, gl.R8UI, 1, 1, 1, gl.RED_INTEGER, gl.UNSIGNED_BYTE, new Uint8Array(1));
    }

    _program(fragmentSource) {
      const gl = this.gl;
      const compile = (type, src) => {
        const sh = gl.createShader(type);
        gl.shaderSource(sh, src);
        gl.compileShader(sh);
        if (!gl.getShaderParameter(sh, gl.COMPILE_STATUS)) {
          const log = gl.getShaderInfoLog(sh);
          gl.deleteShader(sh);
          throw new Error(`GpuRenderer: shader compilation failed${gl.isContextLost() ? ' (WebGL context lost)' : ''}: ${log}`);
        }
        return sh;
      };
      const vs = compile(gl.VERTEX_SHADER, shaders.VERTEX), fs = compile(gl.FRAGMENT_SHADER, fragmentSource);
      const prog = gl.createProgram();
      gl.attachShader(prog, vs);
      gl.attachShader(prog, fs);
      gl.linkProgram(prog);
      gl.deleteShader(vs);
      gl.deleteShader(fs);
      if (!gl.getProgramParameter(prog, gl.LINK_STATUS)) {
        const log = gl.getProgramInfoLog(prog);
        gl.deleteProgram(prog);
        throw new Error(`GpuRenderer: program link failed: ${log}`);
      }
      const loc = new Map();
      return {prog, u: (name) => {
        if (!loc.has(name)) loc.set(name, gl.getUniformLocation(prog, name));
        return loc.get(name);
      }};
    }

    _texture(target, internal, w, h, d, format, type, data) {
      const gl = this.gl;
      const tex = gl.createTexture();
      gl.bindTexture(target, tex);
      // Integer and float32 textures are not filterable: NEAREST keeps them complete for texelFetch.
      gl.texParameteri(target, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
      gl.texParameteri(target, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
      for (const wrap of [gl.TEXTURE_WRAP_S, gl.TEXTURE_WRAP_T, gl.TEXTURE_WRAP_R]) gl.texParameteri(target, wrap, gl.CLAMP_TO_EDGE);
      gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
      if (target === gl.TEXTURE_2D) gl.texImage2D(target, 0, internal, w, h, 0, format, type, data);
      else gl.texImage3D(target, 0, internal, w, h, d, 0, format, type, data);
      return tex;
    }

    // Throws before touching the GPU when the scene exceeds a limit; then replaces the old scene.
    setScene(sceneData) {
      const gl = this.gl, L = this.limits;
      if (!gl || gl.isContextLost()) throw new Error('GpuRenderer.setScene: the WebGL context is lost (disposed, or a GPU reset): create a new renderer');
      while (gl.getError() !== gl.NO_ERROR) { /* errors of earlier calls are not this scene's */ }
      const {info, field, density, appearance, occupancy, mlpParams} = sceneData;
      const res = info.gridRes;
      const check = (ok, what) => { if (!ok) throw new Error(`GpuRenderer.setScene: ${what}`); };
      const model = info.sceneModel || 0;
      check(model >= 0 && model <= 2, `scene model ${model} is not 0 (object), 1 (unbounded) or 2 (forward-facing)`);
      check(model !== 2 || (info.ndcFrame && info.ndcFrame.length === 15), 'a forward-facing scene without its NDC frame (SPEC.md 6.2.1)');
      const head = info.head || 0;
      check(head === 0 || head === 1, `head ${head} is not 0 (per-sample MLP) or 1 (deferred)`);
      const MAT = [[0, 1], [0, 2], [1, 2]], VEC = [2, 1, 0];
      const ranksOf = (g) => g.planes.map((pl) => pl.shape[2]);
      const dRanks = ranksOf(density), aRanks = ranksOf(appearance);
      const dGroups = dRanks.map(groups), aGroups = aRanks.map(groups);
      const aGroupOff = [0, aGroups[0], aGroups[0] + aGroups[1]];
      const P4 = Math.max(1, aGroups[0] + aGroups[1] + aGroups[2]);
      for (const [name, g, rk] of [['density', density, dRanks], ['appearance', appearance, aRanks]]) {
        for (let m = 0; m < 3; ++m) {
          const [rows, cols] = g.planes[m].shape;
          check(rows === res[MAT[m][1]] && cols === res[MAT[m][0]] && g.lines[m].shape[0] === res[VEC[m]] &&
                g.lines[m].shape[1] === rk[m], `${name} mode ${m}: tensor shapes do not match the grid ${res.join('x')}`);
          check(cols <= L.maxTextureSize && rows <= L.maxTextureSize,
                `${name} plane ${m} is ${cols}x${rows}, more than the GPU's texture size limit of ${L.maxTextureSize}`);
          check(groups(rk[m]) <= L.maxArrayTextureLayers,
                `${name} mode ${m} has rank ${rk[m]}, more than 4 x ${L.maxArrayTextureLayers} texture layers`);
        }
        const lineRows = rk.reduce((s, r) => s + groups(r), 0);
        check(Math.max(...res) <= L.maxTextureSize && lineRows <= L.maxTextureSize,
              `${name} lines need a ${Math.max(...res)}x${lineRows} texture, more than the limit of ${L.maxTextureSize}`);
      }
      if (occupancy) {
        check(occupancy.res.every((r) => r >= 2 && r <= L.max3DTextureSize),
              `occupancy mask ${occupancy.res.join('x')} exceeds the GPU's 3D texture size limit of ${L.max3DTextureSize}`);
      }
      let weightTexture = this.mlpWeights === 'texture';
      let mlp = packMlp(field, mlpParams, aRanks, aGroupOff, P4, weightTexture ? Infinity : Math.floor(L.maxUniformBlockSize / 16));
      if (!weightTexture && this.mlpWeights === 'auto' && mlp.blocks.length > L.maxFragmentUniformBlocks) {
        weightTexture = true;
        mlp = packMlp(field, mlpParams, aRanks, aGroupOff, P4, Infinity);
      }
      if (weightTexture) {
        check(Math.ceil(mlp.blocks[0].length / 4 / shaders.WT_WIDTH) <= L.maxTextureSize && shaders.WT_WIDTH <= L.maxTextureSize,
              `the MLP's ${mlp.blocks[0].length / 4} weight texels exceed the texture size limit of ${L.maxTextureSize}`);
      } else {
        check(mlp.blocks.length <= L.maxFragmentUniformBlocks,
              `the MLP needs ${mlp.blocks.length} uniform blocks of ${L.maxUniformBlockSize} bytes, the GPU allows ${L.maxFragmentUniformBlocks}`);
      }
      check(2 * mlp.H4 + 64 <= L.maxFragmentUniformVectors,
            `the MLP's hidden width ${field.mlp.hidden} needs more uniform vectors than the GPU's ${L.maxFragmentUniformVectors}`);

      this.clearScene();
      let bytes = 0;
      const planeTex = (pl, R) => {
        if (R === 0) return null;
        const [rows, cols] = pl.shape, G = groups(R);
        const buf = new Float32Array(cols * rows * G * 4);
        for (let y = 0; y < rows; ++y) {
          for (let x = 0; x < cols; ++x) {
            const src = (y * cols + x) * R;
            for (let r = 0; r < R; ++r) buf[(((r >> 2) * rows + y) * cols + x) * 4 + (r & 3)] = pl.data[src + r];
          }
        }
        bytes += buf.byteLength;
        return this._texture(gl.TEXTURE_2D_ARRAY, gl.RGBA32F, cols, rows, G, gl.RGBA, gl.FLOAT, buf);
      };
      const lineTex = (g, rk) => {
        const width = Math.max(...res), rowsOf = [0, 0, 0];
        let rows = 0;
        for (let m = 0; m < 3; ++m) { rowsOf[m] = rows; rows += groups(rk[m]); }
        const buf = new Float32Array(width * Math.max(1, rows) * 4);
        for (let m = 0; m < 3; ++m) {
          const R = rk[m], len = g.lines[m].shape[0], data = g.lines[m].data;
          for (let i = 0; i < len; ++i) {
            for (let r = 0; r < R; ++r) buf[((rowsOf[m] + (r >> 2)) * width + i) * 4 + (r & 3)] = data[i * R + r];
          }
        }
        bytes += buf.byteLength;
        return {tex: this._texture(gl.TEXTURE_2D, gl.RGBA32F, width, Math.max(1, rows), 1, gl.RGBA, gl.FLOAT, buf), rowsOf};
      };
      const s = {textures: [], buffers: [], programs: new Map()};
      s.planes = [...density.planes.map((pl, m) => planeTex(pl, dRanks[m])),
                  ...appearance.planes.map((pl, m) => planeTex(pl, aRanks[m]))];
      const dl = lineTex(density, dRanks), al = lineTex(appearance, aRanks);
      s.dLines = dl.tex;
      s.aLines = al.tex;
      s.textures.push(...s.planes.filter(Boolean), dl.tex, al.tex);
      if (occupancy) {
        const [X, Y, Z] = occupancy.res, bits = occupancy.bits;
        const vox = new Uint8Array(X * Y * Z);
        for (let i = 0; i < vox.length; ++i) vox[i] = (bits[i >> 3] >> (i & 7)) & 1;
        // Bit 1: any of the cell's 8 corners set, so the shader's common case is a single fetch.
        const at = (x, y, z) => vox[(z * Y + y) * X + x] & 1;
        for (let z = 0; z + 1 < Z; ++z) {
          for (let y = 0; y + 1 < Y; ++y) {
            for (let x = 0; x + 1 < X; ++x) {
              if (at(x, y, z) | at(x + 1, y, z) | at(x, y + 1, z) | at(x + 1, y + 1, z) | at(x, y, z + 1) |
                  at(x + 1, y, z + 1) | at(x, y + 1, z + 1) | at(x + 1, y + 1, z + 1)) vox[(z * Y + y) * X + x] |= 2;
            }
          }
        }
        s.occ = this._texture(gl.TEXTURE_3D, gl.R8UI, X, Y, Z, gl.RED_INTEGER, gl.UNSIGNED_BYTE, vox);
        bytes += vox.byteLength;
        // Max-pooled blocks over closed corner ranges [b B, (b + 1) B] (a corner on a boundary
        // belongs to both blocks), as OccupancyMask::BuildAcceleration.
        s.blk = BLOCK_LEVELS.map((B) => {
          const dims = occupancy.res.map((r) => Math.ceil((r - 1) / B));
          const blk = new Uint8Array(dims[0] * dims[1] * dims[2]);
          for (let z = 0; z < Z; ++z) {
            for (let y = 0; y < Y; ++y) {
              for (let x = 0; x < X; ++x) {
                if (!(vox[(z * Y + y) * X + x] & 1)) continue;
                const c = [x, y, z], lo = [0, 0, 0], hi = [0, 0, 0];
                for (let a = 0; a < 3; ++a) {
                  hi[a] = Math.floor(c[a] / B);
                  lo[a] = c[a] % B === 0 && c[a] > 0 ? hi[a] - 1 : hi[a];
                  hi[a] = Math.min(hi[a], dims[a] - 1);
                }
                for (let bz = lo[2]; bz <= hi[2]; ++bz)
                  for (let by = lo[1]; by <= hi[1]; ++by)
                    for (let bx = lo[0]; bx <= hi[0]; ++bx) blk[(bz * dims[1] + by) * dims[0] + bx] = 1;
              }
            }
          }
          bytes += blk.byteLength;
          return this._texture(gl.TEXTURE_3D, gl.R8UI, dims[0], dims[1], dims[2], gl.RED_INTEGER, gl.UNSIGNED_BYTE, blk);
        });
        s.textures.push(s.occ, ...s.blk);
      }
      let uniformBytes = 0;
      if (weightTexture) {
        const rows = Math.ceil(mlp.blocks[0].length / 4 / shaders.WT_WIDTH);
        const buf = new Float32Array(rows * shaders.WT_WIDTH * 4);
        buf.set(mlp.blocks[0]);
        s.weights = this._texture(gl.TEXTURE_2D, gl.RGBA32F, shaders.WT_WIDTH, rows, 1, gl.RGBA, gl.FLOAT, buf);
        s.textures.push(s.weights);
        bytes += buf.byteLength;
      }
      for (const data of weightTexture ? [] : mlp.blocks) {
        const buf = gl.createBuffer();
        gl.bindBuffer(gl.UNIFORM_BUFFER, buf);
        gl.bufferData(gl.UNIFORM_BUFFER, data, gl.STATIC_DRAW);
        s.buffers.push(buf);
        uniformBytes += data.byteLength;
      }
      gl.bindBuffer(gl.UNIFORM_BUFFER, null);
      s.cfg = {dGroups, aGroups, aGroupOff, dLineRow: dl.rowsOf, aLineRow: al.rowsOf, P4,
               F4: mlp.F4, H4: mlp.H4, IN4: mlp.IN4, FF: mlp.FF, FV: mlp.FV, hiddenLayers: mlp.hiddenLayers, features: field.mlp.features, occupancy: !!occupancy, model, head,
               blockLevels: BLOCK_LEVELS, weightTexture, blockSizes: mlp.blocks.map((b) => b.length / 4), layers: mlp.layers};
      s.mlp = mlp;
      s.info = info;
      s.field = field;
      s.occRes = occupancy ? occupancy.res : [2, 2, 2];
      this.scene = s;
      try {
        if (gl.getError() === gl.OUT_OF_MEMORY) throw new Error(`GpuRenderer.setScene: out of GPU memory for ${bytes} bytes of textures`);
        this._sceneProgram(head === 1);  // compile now: a failure belongs to setScene, not to the first frame
      } catch (e) {
        this.clearScene();
        throw e;
      }
      this.stats = {textureBytes: bytes, uniformBytes, samplesPerRay: info.numSamples, uniformBlocks: s.buffers.length,
                    mlpWeights: weightTexture ? 'texture' : 'ubo',
                    mlpFlopsPerSample: 2 * (4 * mlp.F4 * 4 * P4 + 4 * mlp.H4 * 4 * mlp.IN4 + 16 * mlp.H4 * mlp.H4 + 4 * 4 * mlp.H4)};
    }

    _sceneProgram(deferred, skip = true) {
      const s = this.scene, key = `${deferred} ${skip}`;
      if (s.programs.has(key)) return s.programs.get(key);
      const p = this._program(shaders.fieldShader({...s.cfg, deferred, skip}));
      const gl = this.gl;
      for (let b = 0; b < s.buffers.length; ++b) {
        const idx = gl.getUniformBlockIndex(p.prog, `MlpBlock${b}`);
        if (idx !== gl.INVALID_INDEX) gl.uniformBlockBinding(p.prog, idx, b);
      }
      gl.useProgram(p.prog);
      for (const [name, unit] of Object.entries(UNITS)) gl.uniform1i(p.u(name), unit);
      s.programs.set(key, p);
      return p;
    }

    // camera: {c2w (12, row-major 3x4), fx, fy, cx, cy, width, height}; see the file header.
    render(camera, options = {}) {
      const t0 = performance.now();
      const gl = this.gl, s = this.scene;
      if (!gl || gl.isContextLost()) throw new Error('GpuRenderer.render: the WebGL context is lost (disposed, or a GPU reset): create a new renderer');
      if (!s) throw new Error('GpuRenderer.render: no scene (call setScene first)');
      const W = camera.width | 0, H = camera.height | 0;
      const maxDim = Math.min(this.limits.maxTextureSize, this.limits.maxViewport[0], this.limits.maxViewport[1]);
      if (!(W >= 1 && H >= 1 && W <= maxDim && H <= maxDim)) throw new Error(`GpuRenderer.render: image size ${W}x${H} not in [1, ${maxDim}]`);
      const earlyStop = options.earlyStop === undefined ? 1e-4 : options.earlyStop;
      const stepScale = options.stepScale === undefined ? 1 : options.stepScale;
      if (!(stepScale >= 1 / 16 && stepScale <= 64)) throw new Error(`GpuRenderer.render: stepScale ${stepScale} not in [1/16, 64]`);
      const wthr = options.weightThreshold === undefined ? s.field.weightThreshold : options.weightThreshold;
      const info = s.info;
      const n = stepScale === 1 ? info.numSamples : Math.min(1e9, Math.ceil(info.numSamples / stepScale));
      const step = stepScale === 1 ? info.stepSize : f32(info.stepSize * f32(stepScale));

      if (!this.target || this.target.width !== W || this.target.height !== H) {
        if (this.target) { gl.deleteTexture(this.target.tex); gl.deleteFramebuffer(this.target.fbo); }
        const tex = gl.createTexture();
        gl.bindTexture(gl.TEXTURE_2D, tex);
        gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA8, W, H);
        gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR);
        gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
        gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
        gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
        const fbo = gl.createFramebuffer();
        gl.bindFramebuffer(gl.FRAMEBUFFER, fbo);
        gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, tex, 0);
        this.target = {tex, fbo, width: W, height: H};
      }
      // Camera-space ray components (SPEC 7.1) in float32 on the CPU: exact, and one table per axis.
      const len = Math.max(W, H), cam = new Float32Array(4 * len);
      for (let i = 0; i < len; ++i) {
        cam[4 * i] = f32(f32(f32(i + 0.5) - camera.cx) / camera.fx);
        cam[4 * i + 1] = -f32(f32(f32(i + 0.5) - camera.cy) / camera.fy);
      }
      gl.activeTexture(gl.TEXTURE0 + UNITS.uCam);
      gl.bindTexture(gl.TEXTURE_2D, this.camTex);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
      gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, len, 1, 0, gl.RGBA, gl.FLOAT, cam);

      // A deferred head is its stream's process; the option approximates a per-sample head so.
      const p = this._sceneProgram(s.cfg.head === 1 || !!options.deferred, options.skipEmptySpace !== false);
      gl.useProgram(p.prog);
      const bind = (unit, target, tex) => { gl.activeTexture(gl.TEXTURE0 + unit); gl.bindTexture(target, tex); };
      for (let k = 0; k < 6; ++k) bind(k, gl.TEXTURE_2D_ARRAY, s.planes[k] || this.dummyArray);
      bind(UNITS.uDL, gl.TEXTURE_2D, s.dLines);
      bind(UNITS.uAL, gl.TEXTURE_2D, s.aLines);
      bind(UNITS.uOcc, gl.TEXTURE_3D, s.occ || this.dummy3D);
      bind(UNITS.uBlk0, gl.TEXTURE_3D, s.blk ? s.blk[0] : this.dummy3D);
      bind(UNITS.uBlk1, gl.TEXTURE_3D, s.blk ? s.blk[1] : this.dummy3D);
      if (s.weights) bind(UNITS.uWT, gl.TEXTURE_2D, s.weights);
      s.buffers.forEach((buf, b) => gl.bindBufferBase(gl.UNIFORM_BUFFER, b, buf));
      const c = camera.c2w.map(f32);
      gl.uniform3f(p.u('uC2W0'), c[0], c[4], c[8]);
      gl.uniform3f(p.u('uC2W1'), c[1], c[5], c[9]);
      gl.uniform3f(p.u('uC2W2'), c[2], c[6], c[10]);
      gl.uniform3f(p.u('uOrigin'), c[3], c[7], c[11]);
      const model = s.cfg.model, res = info.gridRes;
      // 7.4: c = (p - min) * ((1 / (max - min)) * 2) - 1, each operation rounded to float32.
      const inv = (a, b) => f32(f32(1 / f32(b - a)) * 2);
      // Unbounded (7.2.1): the grids span the contracted cube [-2, 2]^3, the HEAD box is the
      // region of interest that normalises world points before the contraction.
      const mn = model === 1 ? [-2, -2, -2] : info.aabbMin, mx = model === 1 ? [2, 2, 2] : info.aabbMax;
      if (model === 1) {
        gl.uniform3fv(p.u('uRMin'), info.aabbMin);
        gl.uniform3fv(p.u('uRScale'), [0, 1, 2].map((a) => inv(info.aabbMin[a], info.aabbMax[a])));
      }
      if (model === 2) {
        // Forward-facing (7.2.2): the camera origin in the reference frame, A o + b, is the same
        // for every pixel: here in float32, left to right, every operation rounded.
        const M = info.ndcFrame, ro = [0, 1, 2].map((a) =>
          f32(f32(f32(f32(M[4 * a] * c[3]) + f32(M[4 * a + 1] * c[7])) + f32(M[4 * a + 2] * c[11])) + M[4 * a + 3]));
        gl.uniform3fv(p.u('uNdcRo'), ro);
        for (let a = 0; a < 3; ++a) gl.uniform3fv(p.u(`uNdcA${a}`), M.slice(4 * a, 4 * a + 3));
        gl.uniform2f(p.u('uNdcS'), M[12], M[13]);
        gl.uniform1f(p.u('uNdcN'), M[14]);
      }
      gl.uniform3fv(p.u('uMin'), mn);
      gl.uniform3fv(p.u('uMax'), mx);
      gl.uniform3fv(p.u('uInv'), [0, 1, 2].map((a) => inv(mn[a], mx[a])));
      gl.uniform3fv(p.u('uRes1'), res.map((r) => r - 1));
      gl.uniform3iv(p.u('uRes'), res);
      gl.uniform3fv(p.u('uBg'), info.background);
      const om = s.field.occupancyMin, oM = s.field.occupancyMax, ores = s.occRes;
      if (s.occ) {
        gl.uniform3fv(p.u('uOMin'), om);
        gl.uniform3fv(p.u('uOInv'), [0, 1, 2].map((a) => inv(om[a], oM[a])));
        gl.uniform3fv(p.u('uORes1'), ores.map((r) => r - 1));
        gl.uniform3fv(p.u('uOScale'), [0, 1, 2].map((a) => (ores[a] - 1) / (oM[a] - om[a])));
        gl.uniform3iv(p.u('uORes'), ores);
      }
      // x: skip margin in mask cells, y: relative margin of the box exit (both far above float32
      // rounding of either renderer, far below a sample spacing).
      gl.uniform3f(p.u('uEps'), 0.01, 1e-5, 0);
      gl.uniform1f(p.u('uNear'), info.nearPlane);
      gl.uniform1f(p.u('uFar'), info.farPlane);
      gl.uniform1f(p.u('uStep'), step);
      gl.uniform1i(p.u('uN'), n);
      gl.uniform1f(p.u('uShift'), s.field.densityShift);
      gl.uniform1i(p.u('uRelu'), s.field.densityRelu ? 1 : 0);
      gl.uniform1f(p.u('uDScale'), s.field.distanceScale);
      gl.uniform1f(p.u('uWthr'), wthr);
      gl.uniform1f(p.u('uEarly'), earlyStop);
      gl.uniform1f(p.u('uOne'), 1);
      gl.uniform4fv(p.u('uB1'), s.mlp.b1);
      gl.uniform4fv(p.u('uB2'), s.mlp.b2);
      gl.uniform4fv(p.u('uB3'), s.mlp.b3);
      gl.bindVertexArray(this.vao);
      gl.bindFramebuffer(gl.FRAMEBUFFER, this.target.fbo);
      gl.viewport(0, 0, W, H);
      gl.disable(gl.BLEND);
      // options.bandRows: draw in bands of rows, waiting for each when finish is set, so that one
      // very long draw (software GL) does not trip the browser's GPU watchdog.
      const band = options.bandRows > 0 ? Math.min(H, options.bandRows | 0) : H;
      if (band < H) gl.enable(gl.SCISSOR_TEST);
      for (let y = 0; y < H; y += band) {
        if (band < H) gl.scissor(0, y, W, Math.min(band, H - y));
        gl.drawArrays(gl.TRIANGLES, 0, 3);
        if (band < H && options.finish) gl.readPixels(0, y, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));
      }
      gl.disable(gl.SCISSOR_TEST);

      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
      gl.viewport(0, 0, gl.drawingBufferWidth, gl.drawingBufferHeight);
      gl.useProgram(this.display.prog);
      gl.activeTexture(gl.TEXTURE0);
      gl.bindTexture(gl.TEXTURE_2D, this.target.tex);
      gl.uniform1i(this.display.u('uImage'), 0);
      gl.uniform2f(this.display.u('uCanvas'), gl.drawingBufferWidth, gl.drawingBufferHeight);
      gl.drawArrays(gl.TRIANGLES, 0, 3);
      // Chrome's gl.finish() only flushes: reading one pixel is what waits for the GPU.
      if (options.finish) gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));
      this.stats = {...this.stats, samplesPerRay: n, width: W, height: H};
      return {ms: performance.now() - t0};
    }

    // The last render: width * height * 4 bytes, top row first (RGB = SPEC 7.2 codes, A = acc).
    readPixels() {
      const gl = this.gl, t = this.target;
      if (!t) throw new Error('GpuRenderer.readPixels: nothing rendered yet');
      const out = new Uint8Array(t.width * t.height * 4);
      gl.bindFramebuffer(gl.FRAMEBUFFER, t.fbo);
      gl.readPixels(0, 0, t.width, t.height, gl.RGBA, gl.UNSIGNED_BYTE, out);
      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
      return out;
    }

    clearScene() {
      const s = this.scene, gl = this.gl;
      if (!s) return;
      for (const t of s.textures) gl.deleteTexture(t);
      for (const b of s.buffers) gl.deleteBuffer(b);
      for (const p of s.programs.values()) gl.deleteProgram(p.prog);
      this.scene = null;
      this.stats = {textureBytes: 0, uniformBytes: 0, samplesPerRay: 0};
    }

    dispose() {
      const gl = this.gl;
      if (!gl) return;
      this.clearScene();
      if (this.target) { gl.deleteTexture(this.target.tex); gl.deleteFramebuffer(this.target.fbo); }
      gl.deleteTexture(this.camTex);
      gl.deleteTexture(this.dummyArray);
      gl.deleteTexture(this.dummy3D);
      gl.deleteProgram(this.display.prog);
      gl.deleteVertexArray(this.vao);
      this.target = null;
      this.gl = null;
    }
  }

  const api = {GpuRenderer};
  if (typeof module !== 'undefined' && module.exports) module.exports = api;
  globalThis.ecrfGpu = api;
})();
