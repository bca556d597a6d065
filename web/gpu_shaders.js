// GLSL ES 3.00 sources of the WebGL2 renderer (web/gpu_renderer.js), generated per scene so
// that every grid rank, MLP width and UBO split is a compile-time constant. The ray march follows
// SPEC.md section 7 operation by operation (same order of float32 operations where the GPU lets
// us choose); the sums of the MLP and of the VM products are done four lanes at a time, which only
// reorders float additions (7.7 tolerates that, the reference render is not bit-exact anyway).
//
// Plain script: defines globalThis.ecrfGpuShaders = {fieldShader, displayShader, VERTEX, WT_WIDTH}.
'use strict';

(function () {
  const VERTEX = `#version 300 es
void main() {
  // One triangle covering the viewport: no vertex buffer needed.
  vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}`;

  const displayShader = `#version 300 es
precision highp float;
uniform sampler2D uImage;
uniform vec2 uCanvas;
out vec4 outColor;
void main() {
  // The image is stored top row first (row 0 = image row 0), the canvas counts rows from the bottom.
  vec2 uv = vec2(gl_FragCoord.x / uCanvas.x, 1.0 - gl_FragCoord.y / uCanvas.y);
  outColor = vec4(texture(uImage, uv).rgb, 1.0);
}`;

  const WT_WIDTH = 2048;  // texels per row of the MLP weight texture (a power of two)
  const f = (v) => {
    const s = String(v);
    return /[.eE]/.test(s) || !isFinite(v) ? s : s + '.0';
  };

  // One layer: loops over groups of 4 outputs and over input vec4s, so that the source stays small.
  // Unrolling it (constant UBO offsets, inputs in registers) compiled for 20 s in SwiftShader and
  // ran 3x slower there; desktop drivers unroll these constant-trip loops themselves.
  // Rows live in layer.runs ({block, offset, o4Begin, o4End}, 4 rows of len4 vec4s per o4,
  // row-major); out[o4] = act(bias[o4] + W in).
  function emitLayer(layer, len4, input, outName, biasName, relu, texture) {
    let s = '';
    for (const r of layer.runs) {
      const W = (i) => (texture ? `mlpW(base + ${i})` : `uW${r.block}[base + ${i}]`);
      s += `  for (int o4 = ${r.o4Begin}; o4 < ${r.o4End}; ++o4) {
    int base = ${r.offset} + (o4 - ${r.o4Begin}) * ${4 * len4};
    vec4 acc = ${biasName ? `${biasName}[o4]` : 'vec4(0.0)'};
    for (int k = 0; k < ${len4}; ++k) {
      vec4 xv = ${input('k')};
      acc += vec4(dot(${W('k')}, xv), dot(${W(`${len4} + k`)}, xv),
                  dot(${W(`${2 * len4} + k`)}, xv), dot(${W(`${3 * len4} + k`)}, xv));
    }
    ${outName}[o4] = ${relu ? 'max(acc, vec4(0.0))' : 'acc'};
  }\n`;
    }
    return s;
  }

  // The MLP of SPEC 7.6 on products pr[0..P4-1] and direction d, leaving the colour in `rgb`.
  // The input is laid out in whole vec4s ([feat], [d, 0], sin(feat 2^q) per q, cos, sin(d 2^q) per
  // q, cos); gpu_renderer.js permutes W1's columns to match and zeroes the padding lanes.
  function emitMlp(cfg, pr) {
    const {P4, F4, H4, FF, FV} = cfg;
    if (H4 === 0) return emitSh(cfg, pr);
    const IN4 = cfg.IN4;
    let s = `  vec4 fe[${F4}], h[${H4}], g[${H4}], o[1];\n`;
    s += emitLayer(cfg.layers.basis, P4, (k) => `${pr}[${k}]`, 'fe', null, false, cfg.weightTexture);
    s += `  vec4 x[${IN4}];\n`;
    let k = 0;
    for (let j = 0; j < F4; ++j) s += `  x[${k++}] = fe[${j}];\n`;
    s += `  x[${k++}] = vec4(d, 0.0);\n`;
    for (const fn of ['sin', 'cos']) {
      for (let q = 0; q < FF; ++q) for (let j = 0; j < F4; ++j) s += `  x[${k++}] = ${fn}(fe[${j}] * ${f(2 ** q)});\n`;
    }
    for (const fn of ['sin', 'cos']) {
      for (let q = 0; q < FV; ++q) s += `  x[${k++}] = vec4(${fn}(d * ${f(2 ** q)}), 0.0);\n`;
    }
    s += emitLayer(cfg.layers.w1, IN4, (j) => `x[${j}]`, 'h', 'uB1', true, cfg.weightTexture);
    // One hidden layer (SPEC 6.6 layers 1): W3 reads the first layer's output.
    const last = cfg.hiddenLayers === 1 ? 'h' : 'g';
    if (last === 'g') s += emitLayer(cfg.layers.w2, H4, (j) => `h[${j}]`, 'g', 'uB2', true, cfg.weightTexture);
    s += emitLayer(cfg.layers.w3, H4, (j) => `${last}[${j}]`, 'o', 'uB3', false, cfg.weightTexture);
    return s + `  rgb = 1.0 / (1.0 + exp(-o[0].xyz));\n`;
  }

  // The spherical-harmonics colour of SPEC 7.6.2 (hidden 0): the basis, then per channel c the
  // sigmoid of b3[c] + sum_k Y_k(d) feature[c K + k], the degree's K = F / 3 functions of d.
  const SH_BASIS = [
    '0.28209479177387814', '-0.4886025119029199 * d.y', '0.4886025119029199 * d.z',
    '-0.4886025119029199 * d.x', '1.0925484305920792 * xy', '-1.0925484305920792 * yz',
    '0.31539156525252005 * ((2.0 * zz - xx) - yy)', '-1.0925484305920792 * xz',
    '0.5462742152960396 * (xx - yy)', '(-0.5900435899266435 * d.y) * (3.0 * xx - yy)',
    '(2.890611442640554 * xy) * d.z', '(-0.4570457994644658 * d.y) * ((4.0 * zz - xx) - yy)',
    '(0.3731763325901154 * d.z) * ((2.0 * zz - 3.0 * xx) - 3.0 * yy)',
    '(-0.4570457994644658 * d.x) * ((4.0 * zz - xx) - yy)', '(1.445305721320277 * d.z) * (xx - yy)',
    '(-0.5900435899266435 * d.x) * (xx - 3.0 * yy)'];
  function emitSh(cfg, pr) {
    const {P4, F4} = cfg;
    const K = cfg.features / 3;
    // In a block of its own: its names must not clash with the marching loop's around it.
    let s = `  {\n  vec4 fe[${F4}];\n`;
    s += emitLayer(cfg.layers.basis, P4, (k) => `${pr}[${k}]`, 'fe', null, false, cfg.weightTexture);
    s += '  float xx = d.x * d.x, yy = d.y * d.y, zz = d.z * d.z, xy = d.x * d.y, yz = d.y * d.z, xz = d.x * d.z;\n';
    s += `  float sh[${K}];\n`;
    for (let k = 0; k < K; ++k) s += `  sh[${k}] = ${SH_BASIS[k]};\n`;
    s += '  vec3 z = uB3[0].xyz;\n';
    for (let c = 0; c < 3; ++c) {
      for (let k = 0; k < K; ++k) {
        const i = c * K + k;
        s += `  z[${c}] += sh[${k}] * fe[${i >> 2}][${i & 3}];\n`;
      }
    }
    return s + '  rgb = 1.0 / (1.0 + exp(-z));\n  }\n';
  }

  // cfg: {dGroups[3], aGroups[3] (rank groups of 4 per mode), aGroupOff[3], dLineRow[3], aLineRow[3]
  //       (first row of each mode in the line textures), P4, F4, H4, IN4 (vec4 counts), FF, FV,
  //       occupancy, blockLevels [2] (mask cells per block edge), weightTexture, blockSizes[]
  //       (vec4s per UBO), layers: {basis, w1, w2, w3} ({runs, rows}), hiddenLayers (1: no w2),
  //       deferred, slots,
  //       model (HEAD scene_model: 0 object, 1 unbounded, 2 forward-facing), head (the MLPW head:
  //       1 deferred, whose MLP sees the weighted sum itself, not the deferred option's average),
  //       skip (false: no empty-space skipping, the samples tested one by one)}
  function fieldShader(cfg) {
    const {dGroups, aGroups, aGroupOff, dLineRow, aLineRow, P4, F4, H4, IN4, FF, FV} = cfg;
    const K = cfg.slots || 8;
    let s = `#version 300 es
precision highp float;
precision highp int;
precision highp sampler2D;
precision highp sampler2DArray;
precision highp usampler3D;
`;
    if (cfg.weightTexture) {
      s += `uniform sampler2D uWT;\nvec4 mlpW(int i) { return texelFetch(uWT, ivec2(i & ${WT_WIDTH - 1}, i >> ${Math.log2(WT_WIDTH)}), 0); }\n`;
    } else {
      for (let b = 0; b < cfg.blockSizes.length; ++b) s += `uniform MlpBlock${b} { vec4 uW${b}[${cfg.blockSizes[b]}]; };\n`;
    }
    s += `uniform sampler2DArray uDP0, uDP1, uDP2, uAP0, uAP1, uAP2;
uniform sampler2D uDL, uAL, uCam;
uniform usampler3D uOcc, uBlk0, uBlk1;
uniform vec4 uB1[${Math.max(H4, 1)}], uB2[${Math.max(H4, 1)}], uB3[1];
uniform vec3 uC2W0, uC2W1, uC2W2, uOrigin;   // columns of c2w[:3,:3], and c2w[:3,3]
uniform vec3 uMin, uMax, uInv, uRes1, uBg;
uniform ivec3 uRes;
uniform vec3 uOMin, uOInv, uORes1, uOScale, uEps;
uniform ivec3 uORes;
uniform float uNear, uFar, uStep, uShift, uDScale, uWthr, uEarly, uOne;
uniform bool uRelu;  // HEAD density_activation 1 (SPEC.md 7.4), else softplus
uniform int uN;
uniform vec3 uRMin, uRScale;                  // unbounded (7.2.1): HEAD box min, (1 / size) * 2
uniform vec3 uNdcRo, uNdcA0, uNdcA1, uNdcA2;  // forward (7.2.2): A o + b, rows of A
uniform vec2 uNdcS;
uniform float uNdcN;
out vec4 outColor;

// log1p(exp(x)) of PyTorch's softplus; log(1 + y) alone loses most digits of the small y that a
// density shift of -10 produces, so small y use the alternating series (error < y^8 / 8).
float softplus(float x) {
  if (x > 20.0) return x;
  float y = exp(x);
  if (y < 0.1) return y * (1.0 + y * (-0.5 + y * (1.0 / 3.0 + y * (-0.25 + y * (0.2 + y * (-1.0 / 6.0 + y * (1.0 / 7.0)))))));
  return log(1.0 + y);
}
`;
    // Per-mode interpolation: plane of mode m spans u = MatMode[m][0] (columns), v = MatMode[m][1]
    // (rows), line spans w = VecMode[m].
    const MAT = [[0, 1], [0, 2], [1, 2]], VEC = [2, 1, 0], AX = ['x', 'y', 'z'];
    const modeTaps = (m) => {
      const u = AX[MAT[m][0]], v = AX[MAT[m][1]], w = AX[VEC[m]];
      return `    ivec2 q${m} = ivec2(i0.${u}, i0.${v});
    float w00_${m} = (1.0 - fr.${u}) * (1.0 - fr.${v}), w01_${m} = fr.${u} * (1.0 - fr.${v});
    float w10_${m} = (1.0 - fr.${u}) * fr.${v}, w11_${m} = fr.${u} * fr.${v};
    float wl0_${m} = 1.0 - fr.${w}, wl1_${m} = fr.${w};
    int l${m} = i0.${w};\n`;
    };
    const planeLine = (tex, lines, m, k, row) => `w00_${m} * texelFetch(${tex}, ivec3(q${m}, ${k}), 0) + ` +
        `w01_${m} * texelFetch(${tex}, ivec3(q${m}.x + 1, q${m}.y, ${k}), 0) + ` +
        `w10_${m} * texelFetch(${tex}, ivec3(q${m}.x, q${m}.y + 1, ${k}), 0) + ` +
        `w11_${m} * texelFetch(${tex}, ivec3(q${m} + 1, ${k}), 0)) * ` +
        `(wl0_${m} * texelFetch(${lines}, ivec2(l${m}, ${row}), 0) + wl1_${m} * texelFetch(${lines}, ivec2(l${m} + 1, ${row}), 0)`;

    s += `float densityFeature(ivec3 i0, vec3 fr) {\n  float total = 0.0;\n`;
    for (let m = 0; m < 3; ++m) {
      if (!dGroups[m]) continue;
      s += `  {\n${modeTaps(m)}    float sum = 0.0;
    for (int k = 0; k < ${dGroups[m]}; ++k) {
      vec4 pl = (${planeLine(`uDP${m}`, 'uDL', m, 'k', `${dLineRow[m]} + k`)});
      sum += dot(pl, vec4(1.0));
    }
    total += sum;\n  }\n`;
    }
    s += `  return total;\n}\n\n`;

    // Appearance products into pr[0..P4-1], unrolled so that every texture layer is a constant.
    const emitProducts = (pr) => {
      let out = '';
      for (let m = 0; m < 3; ++m) {
        if (!aGroups[m]) continue;
        out += modeTaps(m).replace(/^    /gm, '      ');
        for (let k = 0; k < aGroups[m]; ++k) {
          out += `      ${pr}[${aGroupOff[m] + k}] = (${planeLine(`uAP${m}`, 'uAL', m, k, aLineRow[m] + k)});\n`;
        }
      }
      for (let k = aGroups[0] + aGroups[1] + aGroups[2]; k < P4; ++k) out += `      ${pr}[${k}] = vec4(0.0);\n`;
      return out;
    };

    if (cfg.occupancy) {
      s += `
// SPEC 7.3: occupied when a corner with nonzero trilinear weight is set. Bit 0 of uOcc is the
// voxel, bit 1 the OR of the cell's 8 corners (the usual case: every fraction nonzero).
bool occupied(vec3 idx) {
  vec3 lo = floor(idx);
  ivec3 ilo = ivec3(lo);
  ivec3 ihi = ilo + ivec3(greaterThan(idx, lo));
  ilo = max(ilo, ivec3(0));
  ihi = min(ihi, uORes - 1);
  if (any(greaterThan(ilo, ihi))) return false;
  if (all(equal(ihi - ilo, ivec3(1)))) return (texelFetch(uOcc, ilo, 0).r & 2u) != 0u;
  for (int z = ilo.z; z <= ihi.z; ++z)
    for (int y = ilo.y; y <= ihi.y; ++y)
      for (int x = ilo.x; x <= ihi.x; ++x)
        if ((texelFetch(uOcc, ivec3(x, y, z), 0).r & 1u) != 0u) return true;
  return false;
}

// The all-empty block of mask corners, coarse level first, that holds mask index idx at least
// margin cells inside its faces: its corner range [lo, hi]; false when there is none (an
// occupied block at every level, or idx outside the mask).
bool emptyBlock(vec3 idx, float margin, out vec3 lo, out vec3 hi) {
  lo = hi = vec3(0.0);
  if (any(lessThan(idx, vec3(0.0))) || any(greaterThan(idx, uORes1))) return false;
  for (int level = 0; level < 2; ++level) {
    int B = level == 0 ? ${cfg.blockLevels[0]} : ${cfg.blockLevels[1]};
    ivec3 dims = level == 0 ? textureSize(uBlk0, 0) : textureSize(uBlk1, 0);
    ivec3 b = min(ivec3(idx) / B, dims - 1);
    uint v = level == 0 ? texelFetch(uBlk0, b, 0).r : texelFetch(uBlk1, b, 0).r;
    if (v != 0u) continue;
    lo = vec3(b * B);
    hi = min(lo + float(B), uORes1);
    if (any(lessThan(idx, lo + margin)) || any(greaterThan(idx, hi - margin))) continue;
    return true;
  }
  return false;
}

// Sample i (mask index idx) in an all-empty block of mask corners: the first sample index past
// the samples that provably stay in the block (margin uEps.x cells covers both renderers' rounding).
int skipEmpty(int i, float t, vec3 idx, vec3 o, vec3 d, float t0) {
  vec3 lo, hi;
  // No margin: idx lies in its own block (b = floor(idx / B)); the margin goes into the exit
  // parameters below.
  if (!emptyBlock(idx, 0.0, lo, hi)) return i;
  float tlo = -3.0e38, thi = 3.0e38;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0) continue;
    float A = (o[a] - uOMin[a]) * uOScale[a], D = d[a] * uOScale[a];
    float ta = (lo[a] + uEps.x - A) / D, tb = (hi[a] - uEps.x - A) / D;
    tlo = max(tlo, min(ta, tb));
    thi = min(thi, max(ta, tb));
  }
  if (!(t >= tlo)) return i;
  int j = int(min(floor((thi - t0) / uStep), float(uN))) - 1;
  return j >= i ? j + 1 : i;
}
`;
    }

    if (cfg.model === 1) {
      s += `
// SPEC 7.2.1: the world point normalised by the region of interest, and its per-axis contraction
// into the cube [-2, 2]^3 that the grids and the mask span. uOne (see main) keeps the products
// out of fused multiply-adds: the sample positions depend on the last bit of every step.
vec3 normalised(vec3 p) { return ((p - uRMin) * uRScale) * uOne - 1.0; }
float contract(float v) {
  if (v >= -1.0 && v <= 1.0) return v;
  return v > 0.0 ? 2.0 - 1.0 / v : -2.0 - 1.0 / v;
}
// increment(): step_size divided by the speed of the contracted point; +infinity at the edge.
float increment(vec3 q, vec3 d) {
  float sum = 0.0;
  for (int a = 0; a < 3; ++a) {
    float qq = q[a] * q[a];
    float g = d[a] * uRScale[a] / (qq > 1.0 ? qq : 1.0);
    sum = sum + (g * g) * uOne;
  }
  return uStep / sqrt(sum);
}
bool finite(float v) { return abs(v) <= 3.4028235e38; }  // false for NaN too
`;
      if (cfg.occupancy) {
        s += `
// SPEC 7.8 in the contracted cube. The ray is curved there, but each contracted coordinate is
// monotone in t (and so is its float evaluation), so the samples stay in an axis-aligned block of
// mask corners until the first axis crosses the block's exit face; inverting the contraction on
// that axis gives the ray parameter of the crossing. Returns the parameter below which the samples
// stay in the all-empty block of the sample at mask index idx (margin uEps.x cells, far above the
// float error of the inversion), or -3e38 when there is no such block.
float skipContracted(vec3 idx, vec3 o, vec3 d) {
  vec3 lo, hi;
  if (!emptyBlock(idx, uEps.x, lo, hi)) return -3.0e38;
  lo += uEps.x;
  hi -= uEps.x;
  float tEnd = 3.0e38;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0) continue;  // p[a] == o[a] for every sample
    float X = uOMin[a] + (d[a] > 0.0 ? hi[a] : lo[a]) / uOScale[a];  // exit face, contracted
    if (abs(X) >= 2.0) continue;  // outside the cube: never reached
    float q = abs(X) <= 1.0 ? X : (X > 0.0 ? 1.0 / (2.0 - X) : -1.0 / (2.0 + X));
    tEnd = min(tEnd, ((q + 1.0) / uRScale[a] + uRMin[a] - o[a]) / d[a]);
  }
  return tEnd;
}
`;
      }
    }
    if (cfg.model === 2) {
      s += `
// SPEC 7.2.2 ndc_ray(): the world ray (o, d) in the normalised device coordinates of the NDCP
// reference camera, (O, u); false when it never reaches the far side or is not finite. The
// reference-frame origin uNdcRo = A o + b is the same for every pixel: computed on the CPU.
bool ndcRay(vec3 d, out vec3 O, out vec3 u) {
  vec3 ro = uNdcRo;
  vec3 rd = vec3(((uNdcA0.x * d.x) * uOne + (uNdcA0.y * d.y) * uOne) + (uNdcA0.z * d.z) * uOne,
                 ((uNdcA1.x * d.x) * uOne + (uNdcA1.y * d.y) * uOne) + (uNdcA1.z * d.z) * uOne,
                 ((uNdcA2.x * d.x) * uOne + (uNdcA2.y * d.y) * uOne) + (uNdcA2.z * d.z) * uOne);
  if (!(rd.z < 0.0)) return false;
  float n = uNdcN;
  float s = -(n + ro.z) / rd.z;
  vec3 on = ro + (s * rd) * uOne;
  float x = on.x / on.z, y = on.y / on.z;
  O = vec3(-uNdcS.x * x, -uNdcS.y * y, 1.0 + (2.0 * n) / on.z);
  vec3 v = vec3(-uNdcS.x * (rd.x / rd.z - x), -uNdcS.y * (rd.y / rd.z - y), -(2.0 * n) / on.z);
  float len2 = ((v.x * v.x) * uOne + (v.y * v.y) * uOne) + (v.z * v.z) * uOne;
  u = v * (1.0 / sqrt(len2));
  return all(lessThanEqual(abs(O), vec3(3.4028235e38))) && all(lessThanEqual(abs(u), vec3(3.4028235e38))) && len2 > 0.0;
}
`;
    }

    // One evaluated sample at grid-box point p with interval dist (SPEC 7.2, 7.5): colour samples
    // are recorded in the slots (deferred: their products summed).
    const composite = `      ivec3 i0;
      vec3 fr;
      locate(p, i0, fr);
      float densityIn = densityFeature(i0, fr) + uShift;
      float sigma = uRelu ? max(densityIn, 0.0) : softplus(densityIn);
      float alpha = 1.0 - exp(-sigma * (dist * uDScale));
      float weight = alpha * T;
      T = T * ((1.0 - alpha) + 1e-10);
      acc += weight;
      if (weight > uWthr) {
${cfg.deferred ? `        vec4 pr[${P4}];
${emitProducts('pr').replace(/^  /gm, '    ')}        for (int k = 0; k < ${P4}; ++k) ps[k] += weight * pr[k];
        wSum += weight;
` : `        slotP[cnt] = p;
        slotW[cnt] = weight;
        ++cnt;
`}      }
`;
    // The MLP over the recorded slots; its view direction is the world direction d (all models).
    const flush = cfg.deferred ? '' : `    for (int sl = 0; sl < cnt; ++sl) {
      ivec3 i0;
      vec3 fr;
      locate(slotP[sl], i0, fr);
      vec4 pr[${P4}];
${emitProducts('pr')}      vec3 rgb;
${emitMlp(cfg, 'pr').replace(/^  /gm, '      ')}      C += slotW[sl] * rgb;
    }
`;
    // SPEC 7.2 (object model) and 7.2.2 (forward-facing: the same on the ray's NDC image): the
    // straight line ro + rd t from the box entry, uStep apart.
    const marchStraight = `  vec3 ro = o, rd = d;
  bool miss = false;
${cfg.model === 2 ? '  miss = !ndcRay(d, ro, rd);\n' : ''}  float tmin = -3.0e38;
  for (int a = 0; a < 3; ++a) {
    float dv = rd[a] == 0.0 ? 1e-6 : rd[a];
    tmin = max(tmin, min((uMax[a] - ro[a]) / dv, (uMin[a] - ro[a]) / dv));
  }
  float t0 = min(max(tmin, uNear), uFar);
  // Beyond tx every sample is outside the box: the exact exit, widened by a bound on the rounding
  // of the sample positions over the ray's span (as the reference's slab test of 7.8).
  float tspan = abs(t0) + uStep * float(uN), tx = 3.0e38;
  for (int a = 0; a < 3; ++a) {
    if (rd[a] == 0.0) {
      miss = miss || ro[a] < uMin[a] || ro[a] > uMax[a];
    } else {
      float err = uEps.y * (abs(ro[a]) + abs(uMin[a]) + abs(uMax[a]) + tspan * abs(rd[a]) + 1.0) / abs(rd[a]);
      tx = min(tx, max((uMax[a] - ro[a]) / rd[a], (uMin[a] - ro[a]) / rd[a]) + err);
    }
  }
  int i = miss ? uN : 0;
  while (i < uN) {
    int cnt = 0;
    while (i < uN && cnt < ${K}) {
      float t = t0 + (uStep * float(i)) * uOne;
      if (t > tx) { i = uN; break; }
      vec3 p = ro + (rd * t) * uOne;
      if (any(lessThan(p, uMin)) || any(greaterThan(p, uMax))) { ++i; continue; }
${cfg.occupancy ? `      vec3 oidx = ((p - uOMin) * uOInv - 1.0 + 1.0) * 0.5 * uORes1;
${cfg.skip === false ? '' : `      int j = skipEmpty(i, t, oidx, ro, rd, t0);
      if (j > i) { i = j; continue; }
`}      if (!occupied(oidx)) { ++i; continue; }
` : ''}      float dist = i + 1 < uN ? (t0 + (uStep * float(i + 1)) * uOne) - t : 0.0;
${composite}      ++i;
      if (T < uEarly) i = uN;
    }
${flush}  }
`;
    // SPEC 7.2.1: from t = near, each step uStep in contracted distance, until the sample limit or
    // the edge of the cube; p is the contracted point.
    const marchUnbounded = `  float t = uNear;
  int i = 0;
  while (i < uN) {
    int cnt = 0;
    while (i < uN && cnt < ${K}) {
      vec3 q = normalised(o + (d * t) * uOne);
      vec3 p = vec3(contract(q.x), contract(q.y), contract(q.z));
      float next = t + increment(q, d);
      bool last = i + 1 >= uN || !finite(next);
      float dist = last ? 0.0 : next - t;
${cfg.occupancy ? `      vec3 oidx = ((p - uOMin) * uOInv - 1.0 + 1.0) * 0.5 * uORes1;
      float tEnd = ${cfg.skip === false ? '-3.0e38' : 'skipContracted(oidx, o, d)'};
      if (t < tEnd) {
        // This sample and the next ones below tEnd are in an empty block: only their positions.
        while (!last) {
          t = next;
          ++i;
          if (!(t < tEnd)) break;
          next = t + increment(normalised(o + (d * t) * uOne), d);
          last = i + 1 >= uN || !finite(next);
        }
        if (last) i = uN;
        continue;
      }
      if (!occupied(oidx)) {
        if (last) i = uN; else { t = next; ++i; }
        continue;
      }
` : ''}${composite}      if (last) i = uN; else { t = next; ++i; }
      if (T < uEarly) i = uN;
    }
${flush}  }
`;

    s += `
// SPEC 7.4 locate(): grid cell i0 and fractions fr of a point of the box.
void locate(vec3 p, out ivec3 i0, out vec3 fr) {
  vec3 idx = ((p - uMin) * uInv - 1.0 + 1.0) * 0.5 * uRes1;
  idx = max(idx, vec3(0.0));   // maps NaN and negatives to 0
  idx = min(idx, uRes1);
  i0 = min(ivec3(floor(idx)), uRes - 2);
  fr = idx - vec3(i0);
}

void main() {
  ivec2 px = ivec2(gl_FragCoord.xy);  // row px.y of the framebuffer holds image row px.y (top first)
  vec2 cam = vec2(texelFetch(uCam, ivec2(px.x, 0), 0).x, texelFetch(uCam, ivec2(px.y, 0), 0).y);
  vec3 D = (uC2W0 * cam.x + uC2W1 * cam.y) + uC2W2 * -1.0;
  float sc = 1.0 / sqrt((D.x * D.x + D.y * D.y) + D.z * D.z);
  vec3 d = D * sc, o = uOrigin;  // the world ray; d is also the MLP's view direction
  float T = 1.0, acc = 0.0;
  vec3 C = vec3(0.0);
${cfg.deferred ? `  vec4 ps[${P4}];\n  for (int k = 0; k < ${P4}; ++k) ps[k] = vec4(0.0);\n  float wSum = 0.0;\n` : ''}
  // Colour samples are batched: the march records up to ${K} (point, weight) pairs, then the MLP
  // runs over them in a loop of its own, so the SIMD lanes of neighbouring rays share MLP
  // iterations instead of each sample's MLP running whenever any lane needs one. Same sums, same
  // order. uOne (= 1.0, unknown to the compiler) keeps products such as d * t out of fused
  // multiply-adds: the closed box and mask tests are discontinuous in the last bit of p.
  vec3 slotP[${K}];
  float slotW[${K}];
${cfg.model === 1 ? marchUnbounded : marchStraight}${cfg.deferred ? `  if (wSum > 0.0) {
    vec4 pq[${P4}];
    for (int k = 0; k < ${P4}; ++k) pq[k] = ${cfg.head === 1 ? 'ps[k]' : 'ps[k] / wSum'};
    vec3 rgb;
${emitMlp(cfg, 'pq').replace(/^  /gm, '    ')}    C = wSum * rgb;
  }
` : ''}  vec3 v = clamp(C + (1.0 - acc) * uBg, 0.0, 1.0);
  // The 8-bit code of SPEC 7.2, exactly representable through the RGBA8 target.
  outColor = vec4(floor(v * 255.0 + 0.5), floor(clamp(acc, 0.0, 1.0) * 255.0 + 0.5)) / 255.0;
}
`;
    return s;
  }

  const api = {fieldShader, displayShader, VERTEX, WT_WIDTH};
  if (typeof module !== 'undefined' && module.exports) module.exports = api;
  globalThis.ecrfGpuShaders = api;
})();
