// ---- render.js: WebGL2 drawing of the UAVs (points), pair lines, rings and the ground grid ----
const SHADERS = {
  uavVS: `#version 300 es
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec4 a_color;
uniform mat4 u_view, u_proj;
uniform float u_radius, u_pxPerUnit, u_ortho, u_minPx;
out vec3 v_color;
void main() {
  vec4 vp = u_view * vec4(a_pos, 1.0);
  float dist = u_ortho > 0.5 ? 1.0 : max(-vp.z, 1e-6);
  vp.z += u_radius;  // the sprite sits at the sphere's front: lines through its centre hide
  gl_Position = u_proj * vp;
  gl_PointSize = max(2.0 * u_radius * u_pxPerUnit / dist, u_minPx);
  if (a_color.a < 0.5) gl_Position = vec4(0.0, 0.0, 2.0, 1.0);  // hidden: clipped away
  v_color = a_color.rgb;
}`,
  uavFS: `#version 300 es
precision mediump float;
in vec3 v_color;
out vec4 o;
void main() {
  vec2 c = gl_PointCoord * 2.0 - 1.0;
  float r2 = dot(c, c);
  if (r2 > 1.0) discard;
  o = vec4(v_color * (0.55 + 0.45 * sqrt(1.0 - r2)), 1.0);  // the centre keeps its colour
}`,
  // a line whose middle part (|2t - 1| <= frac) has one colour and its ends another
  lineVS: `#version 300 es
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec4 a_color;
layout(location = 2) in vec4 a_outer;
layout(location = 3) in vec2 a_aux;
uniform mat4 u_view, u_proj;
out vec4 v_color, v_outer;
out float v_t;
flat out float v_frac;
void main() {
  gl_Position = u_proj * u_view * vec4(a_pos, 1.0);
  v_color = a_color; v_outer = a_outer; v_t = a_aux.x; v_frac = a_aux.y;
}`,
  lineFS: `#version 300 es
precision mediump float;
in vec4 v_color, v_outer;
in float v_t;
flat in float v_frac;
out vec4 o;
void main() { o = abs(2.0 * v_t - 1.0) <= v_frac ? v_color : v_outer; }`,
  ringVS: `#version 300 es
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec4 a_color;
uniform mat4 u_view, u_proj;
uniform float u_size;
out vec4 v_color;
void main() {
  gl_Position = u_proj * u_view * vec4(a_pos, 1.0);
  gl_PointSize = u_size; v_color = a_color;
}`,
  ringFS: `#version 300 es
precision mediump float;
in vec4 v_color;
out vec4 o;
void main() {
  float r = length(gl_PointCoord * 2.0 - 1.0);
  if (r > 1.0 || r < 0.72) discard;
  o = v_color;
}`,
};

class Renderer {
  constructor(canvas, n) {
    const gl = canvas.getContext('webgl2', { antialias: false, alpha: false,
      preserveDrawingBuffer: false, powerPreference: 'high-performance' });
    if (!gl) throw new Error('this browser has no WebGL2');
    this.gl = gl; this.canvas = canvas;
    this.uav = this.program(SHADERS.uavVS, SHADERS.uavFS);
    this.line = this.program(SHADERS.lineVS, SHADERS.lineFS);
    this.ring = this.program(SHADERS.ringVS, SHADERS.ringFS);
    this.uavVao = this.vao(n, true);
    this.lineVao = this.vao(0, false, true);
    this.ringVao = this.vao(0, false);
    this.markVao = this.vao(0, false);
    this.gridVao = this.vao(0, false, true);
    gl.clearColor(0.063, 0.078, 0.102, 1);
    gl.enable(gl.DEPTH_TEST);
    gl.depthFunc(gl.LEQUAL);
  }

  program(vs, fs) {
    const gl = this.gl, p = gl.createProgram();
    for (const [type, src] of [[gl.VERTEX_SHADER, vs], [gl.FRAGMENT_SHADER, fs]]) {
      const s = gl.createShader(type);
      gl.shaderSource(s, src); gl.compileShader(s);
      if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
      gl.attachShader(p, s);
    }
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
    const loc = {};
    const count = gl.getProgramParameter(p, gl.ACTIVE_UNIFORMS);
    for (let i = 0; i < count; i++) {
      const name = gl.getActiveUniform(p, i).name;
      loc[name] = gl.getUniformLocation(p, name);
    }
    return { p, loc };
  }

  // a vertex array of positions (vec3 float) and colours (rgba uint8, normalised)
  vao(count, staticSize, lines = false) {
    const gl = this.gl, v = { vao: gl.createVertexArray(), pos: gl.createBuffer(),
      col: gl.createBuffer(), count: 0, capacity: 0 };
    if (lines) { v.outer = gl.createBuffer(); v.aux = gl.createBuffer(); }
    gl.bindVertexArray(v.vao);
    gl.bindBuffer(gl.ARRAY_BUFFER, v.pos);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 0, 0);
    gl.bindBuffer(gl.ARRAY_BUFFER, v.col);
    gl.enableVertexAttribArray(1);
    gl.vertexAttribPointer(1, 4, gl.UNSIGNED_BYTE, true, 0, 0);
    if (lines) {
      gl.bindBuffer(gl.ARRAY_BUFFER, v.outer);
      gl.enableVertexAttribArray(2);
      gl.vertexAttribPointer(2, 4, gl.UNSIGNED_BYTE, true, 0, 0);
      gl.bindBuffer(gl.ARRAY_BUFFER, v.aux);
      gl.enableVertexAttribArray(3);
      gl.vertexAttribPointer(3, 2, gl.FLOAT, false, 0, 0);
    }
    gl.bindVertexArray(null);
    if (staticSize) this.reserve(v, count);
    return v;
  }

  reserve(v, count) {
    const gl = this.gl;
    if (count <= v.capacity) return;
    v.capacity = Math.max(count, 2 * v.capacity);
    gl.bindBuffer(gl.ARRAY_BUFFER, v.pos);
    gl.bufferData(gl.ARRAY_BUFFER, v.capacity * 12, gl.DYNAMIC_DRAW);
    gl.bindBuffer(gl.ARRAY_BUFFER, v.col);
    gl.bufferData(gl.ARRAY_BUFFER, v.capacity * 4, gl.DYNAMIC_DRAW);
    if (v.outer) {
      gl.bindBuffer(gl.ARRAY_BUFFER, v.outer);
      gl.bufferData(gl.ARRAY_BUFFER, v.capacity * 4, gl.DYNAMIC_DRAW);
      gl.bindBuffer(gl.ARRAY_BUFFER, v.aux);
      gl.bufferData(gl.ARRAY_BUFFER, v.capacity * 8, gl.DYNAMIC_DRAW);
    }
  }

  upload(v, pos, col, count, outer = null, aux = null) {
    const gl = this.gl;
    this.reserve(v, count);
    if (outer) {
      gl.bindBuffer(gl.ARRAY_BUFFER, v.outer);
      gl.bufferSubData(gl.ARRAY_BUFFER, 0, outer, 0, count * 4);
      gl.bindBuffer(gl.ARRAY_BUFFER, v.aux);
      gl.bufferSubData(gl.ARRAY_BUFFER, 0, aux, 0, count * 2);
    }
    gl.bindBuffer(gl.ARRAY_BUFFER, v.pos);
    gl.bufferSubData(gl.ARRAY_BUFFER, 0, pos, 0, count * 3);
    gl.bindBuffer(gl.ARRAY_BUFFER, v.col);
    gl.bufferSubData(gl.ARRAY_BUFFER, 0, col, 0, count * 4);
    v.count = count;
  }

  resize() {
    const dpr = window.devicePixelRatio || 1, c = this.canvas;
    const w = Math.max(1, Math.round(c.clientWidth * dpr));
    const h = Math.max(1, Math.round(c.clientHeight * dpr));
    if (c.width !== w || c.height !== h) { c.width = w; c.height = h; }
    this.gl.viewport(0, 0, w, h);
  }

  // cam: {view, proj, ortho, pxPerUnit}; style: {radius, minPx, ringPx}
  draw(cam, style) {
    const gl = this.gl;
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    const f32 = (m) => new Float32Array(m);
    const view = f32(cam.view), proj = f32(cam.proj);
    gl.useProgram(this.line.p);
    gl.uniformMatrix4fv(this.line.loc.u_view, false, view);
    gl.uniformMatrix4fv(this.line.loc.u_proj, false, proj);
    for (const [v, on] of [[this.gridVao, style.grid], [this.lineVao, style.pairs]]) {
      if (!v.count || !on) continue;
      gl.bindVertexArray(v.vao);
      gl.drawArrays(gl.LINES, 0, v.count);
    }
    const u = this.uav;
    gl.useProgram(u.p);
    gl.uniformMatrix4fv(u.loc.u_view, false, view);
    gl.uniformMatrix4fv(u.loc.u_proj, false, proj);
    gl.uniform1f(u.loc.u_radius, style.radius);
    gl.uniform1f(u.loc.u_pxPerUnit, cam.pxPerUnit);
    gl.uniform1f(u.loc.u_ortho, cam.ortho ? 1 : 0);
    gl.uniform1f(u.loc.u_minPx, style.minPx);
    gl.bindVertexArray(this.uavVao.vao);
    if (style.uavs) gl.drawArrays(gl.POINTS, 0, this.uavVao.count);
    gl.disable(gl.DEPTH_TEST);  // rings on top of everything
    gl.useProgram(this.ring.p);
    gl.uniformMatrix4fv(this.ring.loc.u_view, false, view);
    gl.uniformMatrix4fv(this.ring.loc.u_proj, false, proj);
    for (const [v, size] of [[this.markVao, 1.45 * style.ringPx], [this.ringVao, style.ringPx]]) {
      if (!v.count) continue;
      gl.uniform1f(this.ring.loc.u_size, size);
      gl.bindVertexArray(v.vao);
      gl.drawArrays(gl.POINTS, 0, v.count);
    }
    gl.enable(gl.DEPTH_TEST);
    gl.bindVertexArray(null);
  }
}
