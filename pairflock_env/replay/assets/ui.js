// ---- ui.js: controls bar, panel, timeline, the test hook, and start-up ----
const esc = (x) => String(x ?? '–').replace(/[&<>"]/g, (c) => `&#${c.charCodeAt(0)};`);
Object.assign(App.prototype, {
  buildUi() {
    const r = this.replay, m = r.meta;
    $('pf-title').textContent = `${m.title} · ${m.controller ?? 'controller ?'} · N = ${r.N}, ${r.dim}-D`;
    if (!m.complete) {
      const w = document.createElement('div');
      w.className = 'warn';
      w.textContent = `incomplete recording (${m.stopped ?? 'cut off'}): ${m.recorded_steps} steps`;
      $('pf-title').after(w);
    }
    const scrub = $('pf-scrub');
    scrub.max = String(r.K - 1);
    scrub.addEventListener('input', () => { this.setPlaying(false); this.seek(+scrub.value); });
    $('pf-play').addEventListener('click', () => this.toggle());
    const speed = $('pf-speed');
    for (const s of SPEEDS) speed.add(new Option(`${s}×`, String(s), s === 1, s === 1));
    speed.addEventListener('change', () => { this.speed = +speed.value; });
    $('pf-closest').disabled = !m.closest_pass;
    $('pf-closest').addEventListener('click', () => this.jumpToClosest());
    $('pf-follow').addEventListener('change', (e) => this.setFollow(e.target.checked));
    $('pf-pairs').addEventListener('change', (e) => { this.style.pairs = e.target.checked; this.dirty = true; });
    $('pf-view').addEventListener('click', () => { this.camera.reset(); this.dirty = true; });
    $('pf-timeline').addEventListener('click', (e) => {
      const rect = e.target.getBoundingClientRect();
      this.setPlaying(false);
      this.seek((e.clientX - rect.left) / rect.width * (r.K - 1));
    });
    const run = [['controller', m.controller], ['seed', JSON.stringify(m.seed)],
      ['dt', `${m.dt} s`], ['recorded', `1 step in ${m.every}, ${m.recorded_steps} steps`],
      ['replayed', `1 recorded step in ${m.stride}, ${r.K} steps`],
      ...Object.entries(m.config).map(([k, v]) => [k, JSON.stringify(v)])];
    $('pf-run').innerHTML = run.map(([a, b]) => `<tr><td>${esc(a)}</td><td>${esc(b)}</td></tr>`).join('');
    const sw = (c) => `<span style="background:rgb(${c.slice(0, 3)})"></span>`;
    $('pf-legend').innerHTML = [
      `${sw(COLORS.paired)}paired UAV`, `${sw(COLORS.single)}unpaired UAV`,
      `${sw(COLORS.active)}…${sw(COLORS.strong)}safety filter active (small … largest change)`,
      `pair line: ${sw(COLORS.target)}d<sub>m</sub> (target distance), ${sw(COLORS.far)}too far, ${sw(COLORS.near)}too close`,
      `${sw(COLORS.closest)}closest pass · ${sw(COLORS.leader)}leader`,
      'drag: orbit · right/shift-drag: pan · wheel: zoom · click: pick',
    ].join('<br>');
  },

  updatePanel() {
    const r = this.replay, k = this.k, m = r.meta;
    $('pf-scrub').value = String(k);
    let active = 0;
    const width = m.safety_scope === 'uav' ? r.N : r.M;
    if (r.s.safety) for (let j = 0; j < width; j++) active += r.s.safety[k * width + j] > 0;
    const cp = m.closest_pass;
    const rows = [
      ['time', `${fmt(r.time(k), 2)} s`],
      ['step', `${r.s.step[k]} (${k + 1} / ${r.K})`],
      ['speed', this.stepsPerFrame ? `${this.stepsPerFrame} step/frame` : `${this.speed}×`],
      ['frames / s', fmt(this.recent.length, 0)],
      ['smallest separation', `${fmt(m.min_separation[k])} m`],
      ['closest pass', cp ? `${fmt(cp.distance)} m at ${fmt(cp.time, 2)} s` : '–'],
    ];
    if (r.s.safety) rows.push([`safety active (${m.safety_scope}s)`, String(active)]);
    $('pf-table').innerHTML = rows.map(([a, b]) => `<tr><td>${a}</td><td>${b}</td></tr>`).join('');
    $('pf-selected').innerHTML = this.selectedHtml();
    $('pf-infos').innerHTML = Object.entries(m.infos)
      .map(([key, v]) => `<tr><td>${esc(key)}</td><td>${fmt(v[k], 4)}</td></tr>`).join('');
    this.drawTimeline();
  },

  selectedHtml() {
    const r = this.replay, i = this.selected, k = this.k;
    if (i < 0) return 'click a UAV to pick it';
    const j = r.partner[i], a = r.agentOf[i];
    const rows = [['UAV', `${i}${this.follow ? ' (followed)' : ''}`],
      ['closest distance', `${fmt(r.closest(k, i))} m`]];
    if (a >= 0) {
      rows.push(['pair', `agent ${a}: UAV ${r.s.pairs[2 * a]} + ${r.s.pairs[2 * a + 1]}`],
        ['partner', String(j)], ['pair distance', `${fmt(r.pairDistance(k, a))} m`],
        ['target d_m', `${fmt(r.s.pair_target[a])} m`], ['pair error', `${fmt(r.pairError(k, a))} m`]);
    }
    const level = r.safety(k, i);
    if (r.s.safety) {
      rows.push(['safety filter', level ? `active, ≈ ${fmt((level - 1) / 254 * r.meta.safety_max, 2)}` : 'idle']);
    }
    return `<table>${rows.map(([x, y]) => `<tr><td>${x}</td><td>${y}</td></tr>`).join('')}</table>`;
  },

  drawTimeline() {
    const c = $('pf-timeline'), r = this.replay, m = r.meta, dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(c.clientWidth * dpr)), h = Math.max(1, Math.round(c.clientHeight * dpr));
    if (c.width !== w || c.height !== h) { c.width = w; c.height = h; }
    const g = c.getContext('2d'), K = r.K, xs = (k) => (K > 1 ? k / (K - 1) : 0) * (w - 1);
    g.clearRect(0, 0, w, h);
    const vals = m.min_separation.filter((v) => v !== null && Number.isFinite(v));
    if (vals.length) {
      const top = Math.max(...vals) || 1;
      g.strokeStyle = '#7f9bbf'; g.beginPath();
      m.min_separation.forEach((v, k) => {
        if (v === null) return;
        const y = h - 2 - (h - 4) * Math.min(v / top, 1);
        if (k === 0) g.moveTo(xs(k), y); else g.lineTo(xs(k), y);
      });
      g.stroke();
    }
    if (m.closest_pass) {
      g.fillStyle = 'rgb(255,64,255)'; g.fillRect(xs(m.closest_pass.index) - 1, 0, 3 * dpr, h);
    }
    g.fillStyle = '#ffffff'; g.fillRect(xs(this.k) - 1, 0, 2 * dpr, h);
  },
});

function installHook(app) {
  const r = app.replay, hook = window.pairflockReplay;
  Object.defineProperties(hook, {
    step: { get: () => app.k }, time: { get: () => r.time(app.k) },
    playing: { get: () => app.playing }, selected: { get: () => app.selected },
  });
  Object.assign(hook, {
    loaded: true, meta: r.meta, steps: r.K, numUavs: r.N, offset: r.meta.offset,
    seek: (k) => app.seek(k),
    play({ speed, stepsPerFrame = 0, loop = false } = {}) {
      if (speed) app.speed = speed;
      app.stepsPerFrame = stepsPerFrame; app.loop = loop; app.setPlaying(true);
    },
    pause: () => app.setPlaying(false),
    viewProjection: () => Array.from((app.cam || app.cameraNow()).viewProj),
    canvasSize() {
      const c = app.renderer.canvas;
      return { width: c.width, height: c.height, cssWidth: c.clientWidth,
        cssHeight: c.clientHeight, dpr: window.devicePixelRatio || 1 };
    },
    // position of UAV i at the current step as decoded, in the recording's frame (m)
    uavPosition: (i) => (app.hidden[i] ? null
      : [0, 1, 2].slice(0, r.dim).map((d) => app.pos[3 * i + d] + r.meta.offset[d])),
    projectUav: (i) => app.project(i),
    uavColor: (i) => app.colorOf(i, r.safety(app.k, i)).slice(0, 3),
    uavPixelSize: (i) => app.pixelSize(i),
    select: (i) => app.select(i), follow: (on) => app.setFollow(on),
    jumpToClosest: () => app.jumpToClosest(),
    fps: () => app.recent.length,
    // render `frames` steps back to back, waiting for the GPU (a pixel read) after each: mean ms per frame
    // spent decoding a step and building its buffers (js), and drawing it to the end (gpu)
    profile(frames = 60) {
      const gl = app.renderer.gl, t = { js: 0, gpu: 0 }, px = new Uint8Array(4);
      for (let f = 0; f < frames; f++) {
        const t0 = performance.now();
        app.k = (app.k + 1) % r.K;
        app.loadStep(app.k);
        const cam = app.cameraNow();
        app.grid(cam); app.rings();
        const t1 = performance.now();
        app.renderer.draw(cam, app.style);
        gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);  // waits for the GPU
        t.js += t1 - t0; t.gpu += performance.now() - t1;
      }
      return { jsMs: t.js / frames, gpuMs: t.gpu / frames };
    },
    // show or hide layers, e.g. {pairs: false}: grid, pairs, uavs (for profiling)
    setLayers(on) {
      Object.assign(app.style, on); app.dirty = true; $('pf-pairs').checked = app.style.pairs;
    },
    resetStats() { app.stats0 = { t: performance.now(), frames: 0, js: 0, jsMax: 0 }; },
    stats() {
      const s = app.stats0, sec = (performance.now() - s.t) / 1000;
      return { frames: s.frames, seconds: sec, fps: s.frames / sec,
        jsMsMean: s.frames ? s.js / s.frames : 0, jsMsMax: s.jsMax };
    },
  });
}

window.pairflockReplay = { loaded: false, error: null };
window.pairflockReplay.ready = (async () => {
  try {
    const app = new App(await loadReplay());
    installHook(app);
    $('pf-message').textContent = '';
    return true;
  } catch (err) {
    window.pairflockReplay.error = String(err && err.stack ? err.stack : err);
    $('pf-message').textContent = `This replay cannot be shown: ${err.message || err}`;
    throw err;
  }
})();
