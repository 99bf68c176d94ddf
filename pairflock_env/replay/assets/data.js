// ---- data.js: the embedded payload (deflated, base64) decoded into typed arrays ----
const HIDDEN = 65535;  // uint16 code of a non-finite position

function base64Bytes(text) {
  if (Uint8Array.fromBase64) return Uint8Array.fromBase64(text.trim());
  const clean = text.trim(), out = new Uint8Array(Math.floor(clean.length * 3 / 4));
  const CH = 1 << 20;  // decode 1 MiB of text at a time (a multiple of 4 characters)
  let n = 0;
  for (let i = 0; i < clean.length; i += CH) {
    const bin = atob(clean.slice(i, i + CH));
    for (let k = 0; k < bin.length; k++) out[n++] = bin.charCodeAt(k);
  }
  return out.subarray(0, n);
}

async function inflate(bytes) {
  const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream('deflate'));
  return new Response(stream).arrayBuffer();
}

const TYPED = { float64: Float64Array, float32: Float32Array, int32: Int32Array,
  uint16: Uint16Array, float16: Uint16Array, int8: Int8Array, uint8: Uint8Array };

let HALF = null;  // float16 bits -> number, built on first use
function halfTable() {
  if (HALF) return HALF;
  HALF = new Float32Array(65536);
  for (let h = 0; h < 65536; h++) {
    const s = h & 0x8000 ? -1 : 1, e = (h >> 10) & 31, f = h & 1023;
    HALF[h] = e === 0 ? s * f * 2 ** -24 : e === 31 ? (f ? NaN : s * Infinity)
      : s * (1 + f / 1024) * 2 ** (e - 15);
  }
  return HALF;
}

class Replay {
  constructor(meta, buffer) {
    this.meta = meta;
    this.N = meta.num_uavs; this.dim = meta.dim; this.M = meta.num_pairs;
    this.K = meta.steps;
    this.s = {};
    for (const sec of meta.sections) {
      const T = TYPED[sec.dtype];
      const count = sec.nbytes / T.BYTES_PER_ELEMENT;
      this.s[sec.name] = new T(buffer, sec.offset, count);
    }
    this.undelta();
    this.partner = new Int32Array(this.N).fill(-1);
    this.agentOf = new Int32Array(this.N).fill(-1);
    const p = this.s.pairs;
    for (let m = 0; m < this.M; m++) {
      const a = p[2 * m], b = p[2 * m + 1];
      this.partner[a] = b; this.partner[b] = a; this.agentOf[a] = m; this.agentOf[b] = m;
    }
  }

  undelta() {  // stored as differences from the previous step (mod 2^16): sum them up
    const v = this.s.positions, row = this.N * this.dim;
    for (let k = 1; k < this.K; k++) {
      const a = k * row, b = a - row;
      for (let i = 0; i < row; i++) v[a + i] += v[b + i];
    }
  }

  time(k) { return this.s.time[k]; }

  // positions of step k relative to the scene offset, (N, 3) (z = 0 in 2-D); hidden[i] = 1
  // for a UAV whose position is not finite. Returns the number of visible UAVs.
  positions(k, out, hidden) {
    const d = this.dim, N = this.N, v = this.s.positions, base = k * N * d;
    const q = 2 ** this.s.exp[k], o = this.s.origin;
    const o0 = o[k * d], o1 = o[k * d + 1], o2 = d === 3 ? o[k * d + 2] : 0;
    let shown = 0;
    for (let i = 0; i < N; i++) {
      const j = base + i * d, x = v[j];
      if (x === HIDDEN) { hidden[i] = 1; out[3 * i] = out[3 * i + 1] = out[3 * i + 2] = 0; continue; }
      hidden[i] = 0; shown++;
      out[3 * i] = o0 + q * x; out[3 * i + 1] = o1 + q * v[j + 1];
      out[3 * i + 2] = d === 3 ? o2 + q * v[j + 2] : 0;
    }
    return shown;
  }

  leader(k) {
    const L = this.s.leader;
    if (!L) return null;
    const d = this.dim;
    return [L[k * d], L[k * d + 1], d === 3 ? L[k * d + 2] : 0];
  }

  // the safety level of UAV i at step k: 0 inactive, 1..255 the correction's share
  safety(k, i) {
    const S = this.s.safety;
    if (!S) return 0;
    if (this.meta.safety_scope === 'uav') return S[k * this.N + i];
    const m = this.agentOf[i];
    return m < 0 ? 0 : S[k * this.M + m];
  }

  half(name, k, j, width) {
    const a = this.s[name];
    return a ? halfTable()[a[k * width + j]] : NaN;
  }

  closest(k, i) { return this.half('closest_distance', k, i, this.N); }
  pairDistance(k, m) { return this.half('pair_distance', k, m, this.M); }
  pairError(k, m) { return this.half('pair_error', k, m, this.M); }

  // the recorded step whose time is the last <= t (binary search)
  indexAt(t) {
    const T = this.s.time;
    let lo = 0, hi = this.K - 1;
    if (t <= T[0]) return 0;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if (T[mid] <= t) lo = mid; else hi = mid - 1;
    }
    return lo;
  }
}

async function loadReplay() {
  const meta = JSON.parse(document.getElementById('pf-meta').textContent);
  if (meta.payload_version !== 1) throw new Error(`payload version ${meta.payload_version}`);
  const node = document.getElementById('pf-data');
  const bytes = base64Bytes(node.textContent);
  node.textContent = '';  // let the text go
  return new Replay(meta, await inflate(bytes));
}
