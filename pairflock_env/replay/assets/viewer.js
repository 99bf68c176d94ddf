// ---- viewer.js: playback, colours, panel, timeline and the test hook window.pairflockReplay ----
const COLORS = {
  paired: [79, 195, 161], single: [127, 155, 191], active: [255, 167, 38], strong: [255, 61, 61],
  far: [255, 90, 90, 255], near: [90, 160, 255, 255], target: [124, 255, 140, 255], grid: [36, 44, 56, 255],
  selected: [255, 255, 255, 255], partner: [255, 224, 130, 255], closest: [255, 64, 255, 255],
  leader: [255, 235, 59, 255],
};
const SPEEDS = [0.1, 0.25, 0.5, 1, 2, 4, 8, 16, 32];
const $ = (id) => document.getElementById(id);
const fmt = (x, d = 3) => (x === null || x === undefined || Number.isNaN(x) ? '–'
  : !Number.isFinite(x) ? (x > 0 ? '∞' : '-∞') : Number(x).toFixed(d));

class App {
  constructor(replay) {
    const r = this.replay = replay, N = r.N;
    this.k = 0; this.playing = false; this.speed = 1; this.simTime = r.time(0);
    this.stepsPerFrame = 0; this.loop = false; this.follow = false; this.selected = -1;
    this.pos = new Float32Array(3 * N); this.hidden = new Uint8Array(N);
    this.col = new Uint8Array(4 * N); this.loadedK = -1;
    r.positions(0, this.pos, this.hidden);
    const span = this.span();
    this.camera = new Camera(r.dim, span);
    const targets = r.s.pairs.length ? Array.from(r.s.pair_target).filter((d) => d > 0) : [];
    targets.sort((a, b) => a - b);
    const typical = targets.length ? targets[targets.length >> 1]
      : span / Math.max(1, Math.cbrt(N));
    this.typical = typical;  // a typical pair distance (m): sets the UAVs' drawn size
    this.style = { radius: 0.18 * typical, minPx: N > 3000 ? 2.5 : 4, ringPx: 16, grid: true,
      pairs: true, uavs: true };
    this.renderer = new Renderer($('pf-canvas'), N);
    this.stats0 = { t: performance.now(), frames: 0, js: 0, jsMax: 0 };
    this.recent = [];
    this.dirty = true; this.lastPanel = 0;
    this.buildUi();
    attachInput($('pf-canvas'), this);
    this.loadStep(0);
    requestAnimationFrame((t) => this.frame(t));
  }

  span() {  // the largest extent of the swarm (and leader) now, m
    const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    const add = (x, y, z) => { [x, y, z].forEach((v, d) => { lo[d] = Math.min(lo[d], v);
      hi[d] = Math.max(hi[d], v); }); };
    for (let i = 0; i < this.replay.N; i++) {
      if (!this.hidden[i]) add(this.pos[3 * i], this.pos[3 * i + 1], this.pos[3 * i + 2]);
    }
    const L = this.replay.leader(this.k);
    if (L) add(...L);
    return Math.max(1e-3, ...[0, 1, 2].map((d) => hi[d] - lo[d]).filter(Number.isFinite));
  }

  colorOf(i, level) {
    const base = i >= 0 && this.replay.partner[i] >= 0 ? COLORS.paired : COLORS.single;
    if (!level) return base;
    const a = (level - 1) / 254;
    return COLORS.active.map((c, j) => Math.round(c + (COLORS.strong[j] - c) * a));
  }

  palette() {  // rgba of each safety level 0..255, for unpaired (row 0) and paired (row 1)
    const lut = new Uint8Array(2 * 256 * 4);
    for (let paired = 0; paired < 2; paired++) {
      for (let level = 0; level < 256; level++) {
        const c = this.colorOf(paired ? this.replay.s.pairs[0] : -1, level);
        lut.set([...c, 255], 4 * (256 * paired + level));
      }
    }
    return lut;
  }

  loadStep(k) {
    const r = this.replay, N = r.N, col = this.col, hid = this.hidden;
    r.positions(k, this.pos, hid);
    const lut = this.lut || (this.lut = this.palette());
    const S = r.s.safety, perUav = r.meta.safety_scope === 'uav', partner = r.partner;
    for (let i = 0; i < N; i++) {
      let level = 0;
      if (S) level = perUav ? S[k * N + i] : (r.agentOf[i] < 0 ? 0 : S[k * r.M + r.agentOf[i]]);
      const o = 4 * ((partner[i] >= 0 ? 256 : 0) + level);
      col[4 * i] = lut[o]; col[4 * i + 1] = lut[o + 1]; col[4 * i + 2] = lut[o + 2];
      col[4 * i + 3] = hid[i] ? 0 : 255;
    }
    this.renderer.upload(this.renderer.uavVao, this.pos, col, N);
    this.buildPairLines();
    this.loadedK = k;
  }

  // one line per pair, along the line between its UAVs: green over the length d_m centred on
  // the pair, red beyond it up to the UAVs when they are too far apart, blue beyond them up to
  // d_m when too close: the colour tells the error's sign, the red or blue length its size
  buildPairLines() {
    const r = this.replay, M = r.M, p = r.s.pairs, d = r.s.pair_target, P = this.pos;
    if (!M) return;
    if (!this.lines) {
      this.lines = { pos: new Float32Array(6 * M), col: new Uint8Array(8 * M),
        outer: new Uint8Array(8 * M), aux: new Float32Array(4 * M) };
    }
    const { pos, col, outer, aux } = this.lines, G = COLORS.target;
    let n = 0;
    for (let m = 0; m < M; m++) {
      const a = p[2 * m], b = p[2 * m + 1];
      if (this.hidden[a] || this.hidden[b]) continue;
      const ax = P[3 * a], ay = P[3 * a + 1], az = P[3 * a + 2];
      const ux = P[3 * b] - ax, uy = P[3 * b + 1] - ay, uz = P[3 * b + 2] - az;
      const len = Math.sqrt(ux * ux + uy * uy + uz * uz), dm = d[m];
      const far = len >= dm, frac = far ? (len > 0 ? dm / len : 1) : len / dm;
      const ext = far ? 0 : (len > 0 ? (dm - len) / (2 * len) : 0);  // beyond A and B, in AB
      const O = far ? COLORS.far : COLORS.near;
      for (let e = 0; e < 2; e++, n++) {
        const s = e ? 1 + ext : -ext;
        pos[3 * n] = ax + s * ux; pos[3 * n + 1] = ay + s * uy; pos[3 * n + 2] = az + s * uz;
        col.set(G, 4 * n); outer.set(O, 4 * n); aux[2 * n] = e; aux[2 * n + 1] = frac;
      }
    }
    this.renderer.upload(this.renderer.lineVao, pos, col, n, outer, aux);
  }

  anchor() {  // what the camera looks at (before the user's pan): the picked UAV or the swarm
    if (this.follow && this.selected >= 0 && !this.hidden[this.selected]) {
      const i = this.selected;
      return [this.pos[3 * i], this.pos[3 * i + 1], this.pos[3 * i + 2]];
    }
    let s = [0, 0, 0], n = 0;
    for (let i = 0; i < this.replay.N; i++) {
      if (this.hidden[i]) continue;
      s[0] += this.pos[3 * i]; s[1] += this.pos[3 * i + 1]; s[2] += this.pos[3 * i + 2]; n++;
    }
    return n ? V3.scale(s, 1 / n) : [0, 0, 0];
  }

  cameraNow() {
    const c = this.renderer.canvas;
    this.renderer.resize();
    this.cam = this.camera.matrices(this.anchor(), c.width, c.height);
    return this.cam;
  }

  rings() {  // markers: the leader and the closest pass (large); the picked UAV and partner
    const r = this.replay, marks = [[], []], sel = [[], []];
    const at = (i) => [this.pos[3 * i], this.pos[3 * i + 1], this.pos[3 * i + 2]];
    const add = (list, p, c) => { list[0].push(...p); list[1].push(...c); };
    const L = r.leader(this.k);
    if (L) add(marks, L, COLORS.leader);
    const cp = r.meta.closest_pass;
    if (cp && Math.abs(r.time(this.k) - cp.time) <= 1.0) {
      for (const i of [cp.uav, cp.other]) if (!this.hidden[i]) add(marks, at(i), COLORS.closest);
    }
    if (this.selected >= 0 && !this.hidden[this.selected]) {
      add(sel, at(this.selected), COLORS.selected);
      const j = r.partner[this.selected];
      if (j >= 0 && !this.hidden[j]) add(sel, at(j), COLORS.partner);
    }
    for (const [vao, [p, c]] of [[this.renderer.markVao, marks], [this.renderer.ringVao, sel]]) {
      this.renderer.upload(vao, new Float32Array(p), new Uint8Array(c), p.length / 3);
    }
  }

  grid(cam) {  // a ground grid below the swarm, snapped to its spacing so it reads as still
    const s = 10 ** Math.round(Math.log10(this.camera.span / 4)), n = 20;
    const cx = Math.round(cam.target[0] / s) * s, cy = Math.round(cam.target[1] / s) * s;
    const z = this.replay.dim === 3 ? this.groundZ() : -s;
    const key = `${cx},${cy},${z},${s}`;
    if (key === this.gridKey) return;
    this.gridKey = key;
    const pos = [], col = [];
    for (let i = -n; i <= n; i++) {
      pos.push(cx + i * s, cy - n * s, z, cx + i * s, cy + n * s, z);
      pos.push(cx - n * s, cy + i * s, z, cx + n * s, cy + i * s, z);
      for (let j = 0; j < 4; j++) col.push(...COLORS.grid);
    }
    const count = pos.length / 3;
    this.renderer.upload(this.renderer.gridVao, new Float32Array(pos), new Uint8Array(col), count,
      new Uint8Array(col), new Float32Array(2 * count));
  }

  groundZ() {
    if (this.ground === undefined) {
      let z = Infinity;
      for (let i = 0; i < this.replay.N; i++) if (!this.hidden[i]) z = Math.min(z, this.pos[3 * i + 2]);
      this.ground = Number.isFinite(z) ? z - 0.2 * this.camera.span : 0;
    }
    return this.ground;
  }

  render() {
    const t0 = performance.now();
    if (this.loadedK !== this.k) this.loadStep(this.k);
    const cam = this.cameraNow();
    this.grid(cam);
    this.rings();
    const sel = this.selected >= 0 ? this.pixelSize(this.selected) : 0;
    this.style.ringPx = Math.max(16, 1.8 * sel);
    this.renderer.draw(cam, this.style);
    this.dirty = false;
    return performance.now() - t0;
  }

  pixelSize(i) {
    const cam = this.cam || this.cameraNow();
    const p = M4.transform(cam.view, [this.pos[3 * i], this.pos[3 * i + 1], this.pos[3 * i + 2]]);
    const d = cam.ortho ? 1 : Math.max(-(p[2] + this.style.radius), 1e-6);
    return Math.max(2 * this.style.radius * cam.pxPerUnit / d, this.style.minPx);
  }

  frame(now) {
    const dt = this.lastNow === undefined ? 0 : (now - this.lastNow) / 1000;
    this.lastNow = now;
    if (this.playing) this.advance(dt);
    if (this.dirty || this.loadedK !== this.k) {
      const js = this.render();
      this.stats0.frames++; this.stats0.js += js; this.stats0.jsMax = Math.max(this.stats0.jsMax, js);
      this.recent.push(now);
    }
    while (this.recent.length && now - this.recent[0] > 1000) this.recent.shift();
    if ((this.playing || this.recent.length) && now - this.lastPanel > 100) {
      this.lastPanel = now; this.updatePanel();  // idle pages leave the DOM alone
    }
    requestAnimationFrame((t) => this.frame(t));
  }

  advance(dt) {  // by real time x speed, or by stepsPerFrame recorded steps per frame
    const r = this.replay, last = r.K - 1;
    let k;
    if (this.stepsPerFrame) {
      k = this.k + this.stepsPerFrame;
      if (k > last) k = this.loop ? k % r.K : last;
    } else {
      this.simTime += dt * this.speed;
      if (this.loop && this.simTime > r.time(last)) this.simTime = r.time(0);
      k = r.indexAt(this.simTime);
    }
    if (k === last && !this.loop) this.setPlaying(false);
    if (k !== this.k) { this.k = k; this.dirty = true; }
  }

  seek(k) {
    const r = this.replay;
    this.k = Math.max(0, Math.min(r.K - 1, Math.round(k)));
    this.simTime = r.time(this.k);
    this.render();
    this.updatePanel();
    return this.k;
  }

  setPlaying(on) { this.playing = on; $('pf-play').textContent = on ? '❚❚' : '▶'; }
  toggle() {
    if (!this.playing && this.k >= this.replay.K - 1) this.seek(0);
    this.setPlaying(!this.playing);
  }
  speedBy(step) {
    const i = SPEEDS.indexOf(this.speed) + step;
    if (i >= 0 && i < SPEEDS.length) { this.speed = SPEEDS[i]; $('pf-speed').value = String(this.speed); }
  }
  setFollow(on) { this.follow = on; this.camera.pan = [0, 0, 0]; $('pf-follow').checked = on; this.dirty = true; }
  select(i) {
    this.selected = i >= 0 && i < this.replay.N ? i : -1;
    if (this.selected < 0) this.setFollow(false);
    this.dirty = true; this.updatePanel();
  }
  jumpToClosest() {
    const cp = this.replay.meta.closest_pass;
    if (!cp) return;
    this.setPlaying(false);
    this.select(cp.uav); this.setFollow(true);
    const near = 3 * Math.max(this.typical, cp.distance);  // frame the pass and its neighbours
    if (this.replay.dim === 2) this.camera.halfH = near;
    else this.camera.dist = near / Math.tan(this.camera.fov / 2);
    this.seek(cp.index);
  }

  project(i) {  // CSS pixel position of UAV i's centre, or null
    if (this.hidden[i]) return null;
    const cam = this.cam || this.cameraNow(), c = this.renderer.canvas;
    const p = M4.transform(cam.viewProj, [this.pos[3 * i], this.pos[3 * i + 1], this.pos[3 * i + 2]]);
    if (p[3] <= 0) return null;
    const sx = c.clientWidth, sy = c.clientHeight;
    return [(p[0] / p[3] + 1) / 2 * sx, (1 - p[1] / p[3]) / 2 * sy, p[2] / p[3]];
  }

  pick(x, y) {  // the visible UAV nearest to the click, within its radius + 6 px
    const rect = this.renderer.canvas.getBoundingClientRect();
    let best = -1, bestD = Infinity;
    for (let i = 0; i < this.replay.N; i++) {
      const p = this.project(i);
      if (!p || p[2] < -1 || p[2] > 1) continue;
      const d = Math.hypot(p[0] + rect.left - x, p[1] + rect.top - y);
      if (d < bestD && d <= this.pixelSize(i) / 2 + 6) { best = i; bestD = d; }
    }
    this.select(best);
  }
}
