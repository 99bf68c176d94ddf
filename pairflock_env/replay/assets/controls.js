// ---- controls.js: the camera (orbit in 3-D, top view in 2-D) and mouse / keyboard input ----
class Camera {
  constructor(dim, span) {
    this.dim = dim; this.span = Math.max(span, 1e-3); this.fov = Math.PI / 4;
    this.reset();
  }

  reset() {
    this.pan = [0, 0, 0];  // added to the tracked anchor
    this.yaw = -Math.PI / 2 - 0.7; this.pitch = 0.6;
    this.dist = 0.75 * this.span / Math.tan(this.fov / 2);
    this.halfH = 0.75 * this.span;  // 2-D: half the visible height (m)
  }

  // view, projection and their product for a canvas of w x h pixels, looking at anchor + pan
  matrices(anchor, w, h) {
    const aspect = w / h, target = V3.add(anchor, this.pan);
    let view, proj, eye;
    if (this.dim === 2) {
      eye = V3.add(target, [0, 0, 10 * this.halfH]);
      view = M4.lookAt(eye, target, [0, 1, 0]);
      proj = M4.ortho(this.halfH * aspect, this.halfH, 0.1 * this.halfH, 100 * this.halfH);
    } else {
      const cp = Math.cos(this.pitch);
      const dir = [cp * Math.cos(this.yaw), cp * Math.sin(this.yaw), Math.sin(this.pitch)];
      eye = V3.add(target, V3.scale(dir, this.dist));
      view = M4.lookAt(eye, target, [0, 0, 1]);
      proj = M4.perspective(this.fov, aspect, 0.01 * this.dist, 100 * this.dist + 10 * this.span);
    }
    return { view, proj, viewProj: M4.multiply(proj, view), eye, target,
      ortho: this.dim === 2, pxPerUnit: proj[5] * h / 2 };
  }

  orbit(dx, dy) {
    if (this.dim === 2) return;
    this.yaw -= dx * 0.008;
    this.pitch = Math.min(1.55, Math.max(-1.55, this.pitch + dy * 0.008));
  }

  panBy(dx, dy, h) {  // by a drag of (dx, dy) CSS pixels
    const unit = this.dim === 2 ? 2 * this.halfH / h : 2 * this.dist * Math.tan(this.fov / 2) / h;
    if (this.dim === 2) { this.pan = V3.add(this.pan, [-dx * unit, dy * unit, 0]); return; }
    const right = [Math.sin(this.yaw), -Math.cos(this.yaw), 0];
    const cp = Math.cos(this.pitch), sp = Math.sin(this.pitch);
    const up = [-sp * Math.cos(this.yaw), -sp * Math.sin(this.yaw), cp];
    this.pan = V3.add(this.pan, V3.add(V3.scale(right, dx * unit), V3.scale(up, dy * unit)));
  }

  zoom(factor) {
    if (this.dim === 2) this.halfH *= factor; else this.dist *= factor;
  }
}

// mouse: left drag orbits (pans in 2-D), right or shift drag pans, wheel zooms, click picks
function attachInput(canvas, app) {
  let down = null;
  canvas.addEventListener('contextmenu', (e) => e.preventDefault());
  canvas.addEventListener('pointerdown', (e) => {
    down = { x: e.clientX, y: e.clientY, lastX: e.clientX, lastY: e.clientY, moved: false,
      pan: e.button === 2 || e.shiftKey || app.replay.dim === 2 };
    canvas.setPointerCapture(e.pointerId);
  });
  canvas.addEventListener('pointermove', (e) => {
    if (!down) return;
    const dx = e.clientX - down.lastX, dy = e.clientY - down.lastY;
    down.lastX = e.clientX; down.lastY = e.clientY;
    if (Math.hypot(e.clientX - down.x, e.clientY - down.y) > 3) down.moved = true;
    if (!down.moved) return;
    if (down.pan) app.camera.panBy(dx, dy, canvas.clientHeight); else app.camera.orbit(dx, dy);
    app.dirty = true;
  });
  canvas.addEventListener('pointerup', (e) => {
    if (down && !down.moved) app.pick(e.clientX, e.clientY);
    down = null;
  });
  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    app.camera.zoom(Math.exp(Math.sign(e.deltaY) * Math.min(Math.abs(e.deltaY), 200) * 0.0015));
    app.dirty = true;
  }, { passive: false });
  window.addEventListener('keydown', (e) => {
    if (e.target.tagName === 'INPUT' && e.target.type !== 'checkbox') return;
    const keys = {
      ' ': () => app.toggle(),
      ArrowRight: () => app.seek(app.k + 1), ArrowLeft: () => app.seek(app.k - 1),
      c: () => app.jumpToClosest(), f: () => app.setFollow(!app.follow),
      r: () => { app.camera.reset(); app.dirty = true; },
      p: () => { $('pf-pairs').click(); },
      '+': () => app.speedBy(1), '-': () => app.speedBy(-1),
    };
    if (keys[e.key]) { e.preventDefault(); keys[e.key](); }
  });
}
