// ---- math.js: 4x4 matrices, column-major like WebGL (m[col * 4 + row]) ----
const M4 = {
  multiply(a, b) {  // a * b
    const o = new Float64Array(16);
    for (let c = 0; c < 4; c++) {
      for (let r = 0; r < 4; r++) {
        let s = 0;
        for (let k = 0; k < 4; k++) s += a[k * 4 + r] * b[c * 4 + k];
        o[c * 4 + r] = s;
      }
    }
    return o;
  },
  perspective(fovy, aspect, near, far) {
    const f = 1 / Math.tan(fovy / 2), o = new Float64Array(16);
    o[0] = f / aspect; o[5] = f; o[10] = (far + near) / (near - far); o[11] = -1;
    o[14] = 2 * far * near / (near - far);
    return o;
  },
  ortho(halfW, halfH, near, far) {
    const o = new Float64Array(16);
    o[0] = 1 / halfW; o[5] = 1 / halfH; o[10] = -2 / (far - near);
    o[14] = -(far + near) / (far - near); o[15] = 1;
    return o;
  },
  lookAt(eye, target, up) {
    let z = V3.normalize(V3.sub(eye, target));
    let x = V3.cross(up, z);
    if (V3.length(x) < 1e-9) x = V3.cross([0, 1, 0], z);  // looking along up
    x = V3.normalize(x);
    const y = V3.cross(z, x), o = new Float64Array(16);
    o[0] = x[0]; o[4] = x[1]; o[8] = x[2];
    o[1] = y[0]; o[5] = y[1]; o[9] = y[2];
    o[2] = z[0]; o[6] = z[1]; o[10] = z[2];
    o[12] = -V3.dot(x, eye); o[13] = -V3.dot(y, eye); o[14] = -V3.dot(z, eye); o[15] = 1;
    return o;
  },
  transform(m, p) {  // (x, y, z, w) = m * (p, 1)
    const [x, y, z] = p;
    return [0, 1, 2, 3].map((r) => m[r] * x + m[4 + r] * y + m[8 + r] * z + m[12 + r]);
  },
};

const V3 = {
  add: (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]],
  sub: (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]],
  scale: (a, s) => [a[0] * s, a[1] * s, a[2] * s],
  dot: (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2],
  cross: (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
    a[0] * b[1] - a[1] * b[0]],
  length: (a) => Math.hypot(a[0], a[1], a[2]),
  normalize(a) { const l = V3.length(a) || 1; return [a[0] / l, a[1] / l, a[2] / l]; },
};
