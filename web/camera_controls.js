// ecrf viewer: the orbit camera (azimuth, elevation, radius, target; +z up, as the reference tools)
// and its mouse / touch / wheel / keyboard controls. Plain script; needs viewer.js (ecrfWeb).
'use strict';

(function () {
  const f32 = Math.fround;
  const FOV = 0.6911112070083618;  // ecrfWeb.orbitCamera's field of view (radians)
  // Three-quarter front view of a scene modelled in Blender's convention (the object faces -y, as
  // in every NeRF-synthetic scene): the camera at azimuth -60 degrees, between the front (-90) and
  // the right side (0). Azimuth 17, the earlier default, showed chair and mic from behind.
  const DEFAULT_VIEW = Object.freeze({az: -60, el: 26, radius: 4, target: Object.freeze([0, 0, 0])});
  const LIMITS = {el: 89, radiusMin: 0.05, radiusMax: 100, pan: 100};

  const clamp = (v, lo, hi) => Math.min(hi, Math.max(lo, v));
  const rad = (d) => (d * Math.PI) / 180;

  function normalizeView(v) {
    const num = (x, d) => (Number.isFinite(Number(x)) ? Number(x) : d);
    const t = Array.isArray(v.target) ? v.target : DEFAULT_VIEW.target;
    let az = num(v.az, DEFAULT_VIEW.az) % 360;
    if (az > 180) az -= 360;
    if (az < -180) az += 360;
    return {
      az,
      el: clamp(num(v.el, DEFAULT_VIEW.el), -LIMITS.el, LIMITS.el),
      radius: clamp(num(v.radius, DEFAULT_VIEW.radius), LIMITS.radiusMin, LIMITS.radiusMax),
      target: [0, 1, 2].map((k) => clamp(num(t[k], 0), -LIMITS.pan, LIMITS.pan)),
    };
  }

  // The camera of `view` for a width x height image. With the target at the origin and
  // width <= height this is ecrfWeb.orbitCamera bit for bit (the conformance camera); the target
  // shifts the position, and a wide image keeps the field of view on its short side so that
  // landscape windows do not crop the scene vertically.
  function viewCamera(view, width, height) {
    const cam = ecrfWeb.orbitCamera(width, height, rad(view.az), rad(view.el), view.radius);
    for (let a = 0; a < 3; ++a) cam.c2w[4 * a + 3] = f32(cam.c2w[4 * a + 3] + f32(view.target[a]));
    if (width > height) cam.fx = cam.fy = f32(f32(0.5 * height) / f32(Math.tan(f32(0.5 * FOV))));
    return cam;
  }

  // The view that starts at a forward-facing scene's reference camera (its NDCP frame: p_ref =
  // A p + b, the camera at the reference origin looking along its -z) and orbits a point twice
  // its near plane ahead: where such captures usually have their subject.
  function forwardHomeView(frame) {
    const A = [[frame[0], frame[1], frame[2]], [frame[4], frame[5], frame[6]], [frame[8], frame[9], frame[10]]];
    const b = [frame[3], frame[7], frame[11]];
    // A^-1 by cofactors (A may scale as well as rotate).
    const c = (r, k) => A[(r + 1) % 3][(k + 1) % 3] * A[(r + 2) % 3][(k + 2) % 3] -
                        A[(r + 1) % 3][(k + 2) % 3] * A[(r + 2) % 3][(k + 1) % 3];
    const det = A[0][0] * c(0, 0) + A[0][1] * c(0, 1) + A[0][2] * c(0, 2);
    if (!Number.isFinite(det) || det === 0) return DEFAULT_VIEW;
    const inv = (r, k) => c(k, r) / det;  // (A^-1)[r][k]
    const centre = [0, 1, 2].map((r) => -(inv(r, 0) * b[0] + inv(r, 1) * b[1] + inv(r, 2) * b[2]));
    const back = [0, 1, 2].map((r) => inv(r, 2));  // the reference +z axis in world units
    const unit = Math.hypot(...back);
    const dir = back.map((v) => v / unit);
    const radius = 2 * frame[14] * unit;
    const target = centre.map((v, a) => v - dir[a] * radius);
    const deg = (r) => (r * 180) / Math.PI;
    return normalizeView({az: deg(Math.atan2(dir[1], dir[0])), el: deg(Math.asin(Math.max(-1, Math.min(1, dir[2])))),
                          radius, target});
  }

  // Pointer events cover mouse, pen and touch alike: one pointer orbits (or pans with the right
  // button / shift), two pointers pinch-zoom and pan with their midpoint.
  class OrbitControls {
    constructor(element, view, onChange) {
      this.el = element;
      this.view = normalizeView(view || DEFAULT_VIEW);
      this.home = normalizeView(this.view);
      this.onChange = onChange;
      this.pointers = new Map();  // pointerId -> {x, y, pan}
      this.pinch = null;          // {dist, mx, my}
      this.enabled = true;
      this.handlers = {
        pointerdown: (e) => this.down(e), pointermove: (e) => this.move(e),
        pointerup: (e) => this.up(e), pointercancel: (e) => this.up(e),
        wheel: (e) => this.wheel(e), contextmenu: (e) => e.preventDefault(),
      };
      for (const [k, h] of Object.entries(this.handlers)) element.addEventListener(k, h, {passive: false});
      this.keyHandler = (e) => this.key(e);
      window.addEventListener('keydown', this.keyHandler);
    }

    dispose() {
      for (const [k, h] of Object.entries(this.handlers)) this.el.removeEventListener(k, h);
      window.removeEventListener('keydown', this.keyHandler);
    }

    setView(v, interactive = false) {
      this.view = normalizeView({...this.view, ...v});
      this.onChange(this.view, interactive);
    }

    reset() { this.setView(this.home); }

    orbit(dx, dy) { this.setView({az: this.view.az - dx * 0.4, el: this.view.el + dy * 0.4}, true); }

    zoom(factor) { this.setView({radius: this.view.radius * factor}, true); }

    // Moves the target in the image plane so that the scene follows the pointer.
    pan(dx, dy) {
      const cam = viewCamera(this.view, 2, 2);
      const size = Math.max(1, Math.min(this.el.clientWidth, this.el.clientHeight));
      const k = (2 * this.view.radius * Math.tan(0.5 * FOV)) / size;
      const t = this.view.target.map((v, a) => v - k * (dx * cam.c2w[4 * a] - dy * cam.c2w[4 * a + 1]));
      this.setView({target: t}, true);
    }

    down(e) {
      if (!this.enabled) return;
      e.preventDefault();
      this.el.focus({preventScroll: true});
      this.el.setPointerCapture(e.pointerId);
      this.pointers.set(e.pointerId, {x: e.clientX, y: e.clientY,
                                      pan: e.button === 2 || e.button === 1 || e.shiftKey});
      this.pinch = this.pointers.size === 2 ? this.twoFinger() : null;
    }

    twoFinger() {
      const [a, b] = [...this.pointers.values()];
      return {dist: Math.hypot(a.x - b.x, a.y - b.y), mx: (a.x + b.x) / 2, my: (a.y + b.y) / 2};
    }

    move(e) {
      const p = this.pointers.get(e.pointerId);
      if (!p) return;
      e.preventDefault();
      const dx = e.clientX - p.x, dy = e.clientY - p.y;
      p.x = e.clientX;
      p.y = e.clientY;
      if (this.pointers.size >= 2) {
        const now = this.twoFinger(), before = this.pinch || now;
        this.pinch = now;
        if (now.dist > 0 && before.dist > 0) this.view.radius *= before.dist / now.dist;
        this.pan(now.mx - before.mx, now.my - before.my);
      } else if (p.pan || e.shiftKey) {
        this.pan(dx, dy);
      } else {
        this.orbit(dx, dy);
      }
    }

    up(e) {
      if (!this.pointers.delete(e.pointerId)) return;
      this.pinch = this.pointers.size === 2 ? this.twoFinger() : null;
      if (this.pointers.size === 0) this.onChange(this.view, false);  // the gesture ended
    }

    wheel(e) {
      if (!this.enabled) return;
      e.preventDefault();
      const px = e.deltaY * (e.deltaMode === 1 ? 16 : e.deltaMode === 2 ? 400 : 1);
      this.zoom(Math.exp(clamp(px, -200, 200) * 0.0015));
    }

    key(e) {
      const t = e.target;
      if (!this.enabled || e.ctrlKey || e.metaKey || e.altKey) return;
      if (t && (t.isContentEditable || /^(INPUT|TEXTAREA|SELECT)$/.test(t.tagName))) return;
      const step = 20;  // pixels of an equivalent drag
      const moves = {ArrowLeft: [-step, 0], ArrowRight: [step, 0], ArrowUp: [0, -step], ArrowDown: [0, step]};
      if (moves[e.key]) {
        const [dx, dy] = moves[e.key];
        if (e.shiftKey) this.pan(dx, dy);
        else this.orbit(dx, dy);
      } else if (e.key === '+' || e.key === '=') {
        this.zoom(1 / 1.15);
      } else if (e.key === '-' || e.key === '_') {
        this.zoom(1.15);
      } else if (e.key === 'r' || e.key === 'R') {
        this.reset();
      } else {
        return;
      }
      e.preventDefault();
    }
  }

  globalThis.ecrfCamera = {DEFAULT_VIEW, normalizeView, viewCamera, forwardHomeView, OrbitControls};
})();
